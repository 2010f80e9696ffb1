"""Same outputs before and after a refactor: fretc's outputs of a git revision against this tree.

Usage::

    python bench/same_outputs.py [--ref arch-base] [--keep DIR] [--skip-audit]

The revision ``--ref`` is exported with ``git archive`` into a temporary folder; both trees
then run the same commands with the same Python (this virtual environment; each tree's own
package first on ``PYTHONPATH``: its ``src/`` where the package's root is there, so that an
editable install of this clone does not answer for the reference), in their own folder, on
the same inputs:

* ``fretc FILE --emit ltl --json``, ``--emit monitor``, ``--emit psl`` for every requirement
  file in ``requirements/`` and for FRET's vectors (``../shared/fretish/fret_vectors.jsonl``,
  ``fret_vectors_functions.jsonl`` and the 696 sentences of ``fret_trace_verdicts.jsonl``,
  written as ``.fret`` files of 100 requirements);
* ``fretc audit`` (JSON, JUnit XML, terminal text) and ``fretc report`` (HTML, Markdown) on the
  shipped traces (``traces/``) and on the two real logs of ``../shared/data/logs`` with
  ``requirements/real_logs/``.

The reference's outputs are computed once per commit and kept in
``/tmp/fretc-same/<commit>/`` (``--ref-cache``; a lock lets several runs share it); the
inputs live in ``/tmp/fretc-same/inputs`` so that messages naming them are equal.

Each command's exit status, standard output, standard error and written files are compared
byte for byte; ``SOURCE_DATE_EPOCH`` fixes the reports' generated-at line. Prints one line per
compared output and a unified diff excerpt of each difference; exits 1 when any output
differs, 0 when all are identical. This is the acceptance check of a refactor (behaviour
unchanged by the restructuring).
"""

from __future__ import annotations

import argparse
import difflib
import fcntl
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SHARED = (REPO.parent / "shared").resolve()
CHUNK = 100


def _vector_files(folder: Path) -> list[Path]:
    """FRET's vector sentences as .fret files of CHUNK requirements each."""
    texts: list[str] = []
    for name in ("fret_vectors.jsonl", "fret_vectors_functions.jsonl"):
        for line in (SHARED / "fretish" / name).read_text().splitlines():
            texts.append(json.loads(line)["text"])
    seen: set[str] = set()
    for line in (SHARED / "fretish" / "fret_trace_verdicts.jsonl").read_text().splitlines():
        for case in json.loads(line)["cases"]:
            if case["sentence"] not in seen:
                seen.add(case["sentence"])
                texts.append(case["sentence"])
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for start in range(0, len(texts), CHUNK):
        path = folder / f"vectors_{start // CHUNK:02d}.fret"
        body = "".join(f"V{start + i + 1}: {' '.join(t.split())}\n"
                       for i, t in enumerate(texts[start:start + CHUNK]))
        path.write_text(body)
        paths.append(path)
    return paths


def _commands(inputs: list[Path], audit: bool) -> list[tuple[str, list[str]]]:
    """(name, fretc arguments) of every compared command; paths relative to the tree."""
    cmds: list[tuple[str, list[str]]] = []
    reqs = sorted(str(p.relative_to(REPO)) for p in (REPO / "requirements").rglob("*.fret"))
    for i, f in enumerate(reqs + [str(p) for p in inputs]):
        tag = Path(f).stem + f"_{i}"
        cmds.append((f"ltl_{tag}", [f, "--emit", "ltl", "--json"]))
        cmds.append((f"ltl_text_{tag}", [f, "--emit", "ltl"]))
        cmds.append((f"monitor_{tag}", [f, "--emit", "monitor"]))
        cmds.append((f"psl_{tag}", [f, "--emit", "psl"]))
    if audit:
        logs = sorted(str(p) for p in (SHARED / "data" / "logs").iterdir())
        for name, reqdir, paths in (("shipped", "requirements/", ["traces/"]),
                                    ("real", "requirements/real_logs/", logs)):
            out = f"_same/{name}"
            cmds.append((f"audit_{name}", ["audit", "-r", reqdir, *paths, "--no-progress",
                                           "--json", f"{out}/audit.json",
                                           "--junit", f"{out}/junit.xml"]))
            cmds.append((f"audit_verbose_{name}", ["audit", "-r", reqdir, *paths,
                                                   "--no-progress", "--verbose"]))
            cmds.append((f"report_{name}", ["report", "-r", reqdir, *paths,
                                            "-o", f"{out}/report"]))
    return cmds


def _run_tree(tree: Path, cmds, dest: Path, cache_dir: Path) -> None:
    """Run every command in ``tree``; results go to ``dest/<name>/``; fretc's disk cache
    (whose keys name the code they depend on) in ``cache_dir``."""
    # (the tree's own package: its src/ since the package's root moved there, which an
    # editable install of this clone would shadow otherwise)
    own = tree / "src" if (tree / "src" / "fretc").is_dir() else tree
    env = dict(os.environ, PYTHONPATH=str(own), SOURCE_DATE_EPOCH="1700000000",
               FRETC_CACHE_DIR=str(cache_dir), COLUMNS="120", NO_COLOR="1",
               PYTHONHASHSEED="0")
    for name, args in cmds:
        work = tree / "_same"
        if work.exists():
            subprocess.run(["rm", "-rf", str(work)], check=True)
        for sub in ("shipped", "real"):  # the folders the audit commands write into
            (work / sub).mkdir(parents=True, exist_ok=True)
        proc = subprocess.run([sys.executable, "-m", "fretc", *args], cwd=tree, env=env,
                              capture_output=True)
        out = dest / name
        out.mkdir(parents=True)
        (out / "exit").write_text(f"{proc.returncode}\n")
        (out / "stdout").write_bytes(proc.stdout)
        (out / "stderr").write_bytes(proc.stderr)
        if work.exists():
            subprocess.run(["cp", "-r", str(work), str(out / "files")], check=True)
        print(f"  {tree.name}: {name} exit {proc.returncode}", flush=True)


def _compare(a: Path, b: Path) -> int:
    """Number of differing files between result folders ``a`` (ref) and ``b`` (this tree)."""
    names = sorted({p.relative_to(a) for p in a.rglob("*") if p.is_file()}
                   | {p.relative_to(b) for p in b.rglob("*") if p.is_file()})
    names = [n for n in names if n.parts[0] != "_cache"]  # older runs kept fretc's cache here
    differ = 0
    for n in names:
        pa, pb = a / n, b / n
        if not pa.exists() or not pb.exists():
            differ += 1
            print(f"DIFFER {n}: only in {'this tree' if pb.exists() else 'the ref'}")
            continue
        ta, tb = pa.read_bytes(), pb.read_bytes()
        if ta == tb:
            continue
        differ += 1
        print(f"DIFFER {n}")
        lines = difflib.unified_diff(ta.decode("utf-8", "replace").splitlines(),
                                     tb.decode("utf-8", "replace").splitlines(),
                                     "ref", "tree", lineterm="", n=1)
        for i, line in enumerate(lines):
            if i >= 20:
                print("    ...")
                break
            print("    " + line[:200])
    print(f"{len(names)} outputs compared, {differ} differ")
    return differ


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", default="arch-base", help="git revision to compare against")
    ap.add_argument("--keep", type=Path, help="keep the results in this folder")
    ap.add_argument("--skip-audit", action="store_true", help="compiler outputs only")
    ap.add_argument("--ref-cache", type=Path, default=Path("/tmp/fretc-same"),
                    help="folder of the reference outputs, one sub-folder per commit")
    args = ap.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", args.ref], cwd=REPO, check=True,
                            capture_output=True, text=True).stdout.strip()
    cache = args.ref_cache.resolve()
    cache.mkdir(parents=True, exist_ok=True)
    with open(cache / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # one run builds the inputs and the reference
        inputs = _vector_files(cache / "inputs")
        cmds = _commands(inputs, not args.skip_audit)
        ref_out = _reference(commit, cache / (commit + ("-noaudit" if args.skip_audit else "")),
                             cmds)
    with tempfile.TemporaryDirectory(prefix="fretc-same-") as tmp:
        root = Path(args.keep or tmp).resolve()
        _run_tree(REPO, cmds, root / "out_tree", cache / "fretc-cache")
        differ = _compare(ref_out, root / "out_tree")
    return 1 if differ else 0


def _reference(commit: str, folder: Path, cmds) -> Path:
    """The reference's result folder, computed unless a complete one is there."""
    out = folder / "out_ref"
    if (folder / "complete").exists():
        print(f"reference outputs of {commit[:12]} from {folder}")
        return out
    subprocess.run(["rm", "-rf", str(folder)], check=True)
    ref_tree = folder / "ref"
    ref_tree.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=REPO, check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(ref_tree)], input=archive, check=True)
    _run_tree(ref_tree, cmds, out, folder / "fretc-cache")
    (folder / "complete").write_text(commit + "\n")
    return out


if __name__ == "__main__":
    sys.exit(main())
