"""Verdicts on every log of ``../shared/data``: this tree against a git revision.

Usage::

    python bench/verdict_changes.py [--ref REV] [--out FILE]

The revision is exported with ``git archive``; both trees audit, with the same Python, each
log of ``../shared/data`` (the real logs with ``requirements/real_logs``, every foreign log
and MCAP conformance file with the requirement set ``tests/audit/_metamorphic.py`` draws for
it with seed 1, written once into a folder both trees read) and print per requirement the
verdict of each tree where they differ, then the counts. ``--out`` writes the comparison as
JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "tests" / "audit"), str(REPO / "tests")]


def _inputs(folder: Path) -> list[tuple[str, Path, Path]]:
    """(id, log, requirement file) of every log, the sets written into ``folder``."""
    import _metamorphic as M

    out = []
    for case in M.real_cases():
        out.append((case.id, case.log, M.write(folder / case.id.replace("/", "_"), case)))
    for log in M.foreign_logs() + M.conformance_logs():
        case = M.generated_case(log, 1)
        if case is not None:
            out.append((case.id, log, M.write(folder / case.id.replace("/", "_"), case)))
    return out


def _audit(tree: Path, fret: Path, log: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    proc = subprocess.run([sys.executable, "-m", "fretc", "audit", "-r", str(fret), str(log),
                           "--no-progress", "--json", "-"], cwd=tree, env=env,
                          capture_output=True, text=True)
    start = proc.stdout.find("{")
    if start < 0:
        return {"_error": proc.stderr[-500:]}
    doc = json.loads(proc.stdout[start:])
    return {v["requirement"]: v["verdict"] for la in doc["logs"] for v in la["verdicts"]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", default="80c7a84", help="git revision to compare against")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="fretc-verdicts-") as name:
        tmp = Path(name)
        ref = tmp / "ref"
        ref.mkdir()
        archive = subprocess.run(["git", "archive", args.ref], cwd=REPO, check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(ref)], input=archive, check=True)
        rows, total, changed = [], 0, 0
        for cid, log, fret in _inputs(tmp / "sets"):
            before, after = _audit(ref, fret, log), _audit(REPO, fret, log)
            for rid in sorted(set(before) | set(after)):
                total += 1
                a, b = before.get(rid), after.get(rid)
                rows.append({"log": cid, "requirement": rid, "before": a, "after": b})
                if a != b:
                    changed += 1
                    print(f"{cid} {rid}: {a} -> {b}", flush=True)
    print(f"{changed} of {total} verdicts changed")
    if args.out:
        args.out.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
