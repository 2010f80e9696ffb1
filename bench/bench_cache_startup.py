"""What fretc's sealed cache costs at start-up, this tree against a git revision.

Usage::

    python bench/bench_cache_startup.py [--ref REV] [--runs N]

Two parts, each in fresh processes:

* **Commands** (``python -m fretc ...`` from a folder outside the checkout, CPU = user +
  system of the child, median of ``--runs`` after one warm-up run), for ``ref`` (the
  revision ``--ref`` exported by ``git archive``, on ``PYTHONPATH``) and ``this`` (this
  tree's ``src/``), each with a cache folder of its own: ``fretc r1.fret --emit ltl`` warm
  (the file's entries from the cache); the same with the file's entries removed before each
  run (the FRETish parser's tables read from the cache); the same with the cache off (the
  tables built in memory); ``fretc audit -r r1.fret nominal.mcap`` warm.
* **Parser tables** (this tree only, CPU of the call in a fresh process, median): the
  FRETish parser built in memory (``build_lark``); loaded from Lark's own cache file (Lark's
  ``cache=PATH``: a pickle, what fretc used before); loaded from fretc's sealed entry
  (:mod:`fretc.common.lark_tables`: ``marshal`` data and ``Lark._load_from_dict``).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_startup import _time  # noqa: E402  (median CPU and wall of a command's runs)

_TABLES = {
    "built in memory": "from fretc.fretish import parser as P; P.build_lark()",
    "Lark's pickle cache": "from fretc.fretish import parser as P; P.build_lark(cache=CACHE)",
    "fretc's sealed entry": "from fretc.fretish import parser as P; P.cached_lark()",
}


def _table_cpu(setup: str, cache_dir: Path, runs: int) -> float:
    """Median CPU seconds of ``setup`` (one parser made) in a fresh process, after a warm-up
    that fills the caches."""
    code = ("import time; CACHE = %r\n" % str(cache_dir / "lark-own.lark")
            + "import lark, fretc.fretish.parser, fretc.common.lark_tables\n"
            + "t = time.process_time()\n" + setup + "\nprint(time.process_time() - t)")
    env = dict(os.environ, FRETC_CACHE_DIR=str(cache_dir), PYTHONPATH=str(REPO / "src"))
    got = []
    for i in range(runs + 1):
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, check=True).stdout
        if i:
            got.append(float(out))
    return statistics.median(got)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", help="git revision to compare against (none: this tree only)")
    ap.add_argument("--runs", type=int, default=11)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="fretc-cache-startup-") as name:
        tmp = Path(name)
        work = tmp / "work"
        work.mkdir()
        shutil.copy(REPO / "requirements" / "r1.fret", work / "r1.fret")
        shutil.copy(REPO / "requirements" / "safe_ros.bindings.toml", work)
        shutil.copy(REPO / "traces" / "nominal.mcap", work)
        installs = {"this": REPO / "src"}
        if args.ref:
            tree = tmp / "ref"
            tree.mkdir()
            archive = subprocess.run(["git", "archive", args.ref], cwd=REPO, check=True,
                                     capture_output=True).stdout
            subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
            installs = {"ref": tree / "src", **installs}
        rows = []
        ltl = [sys.executable, "-m", "fretc", "r1.fret", "--emit", "ltl"]
        for install, src in installs.items():
            cache_dir = tmp / f"cache-{install}"
            env = dict(os.environ, FRETC_CACHE_DIR=str(cache_dir), PYTHONPATH=str(src))
            rows.append(("r1.fret --emit ltl, warm", install, *_time(ltl, work, env, args.runs)))
            cold_entries = ["sh", "-c", f"rm -rf {cache_dir}/fret-entries; exec \"$@\"", "sh",
                            *ltl]
            rows.append(("  entries removed (tables read)", install,
                         *_time(cold_entries, work, env, args.runs)))
            rows.append(("  cache off (tables built)", install,
                         *_time(ltl, work, dict(env, FRETC_CACHE_DIR=""), args.runs)))
            audit = [sys.executable, "-m", "fretc", "audit", "-r", "r1.fret", "nominal.mcap",
                     "--no-progress"]
            rows.append(("audit r1.fret nominal.mcap, warm", install,
                         *_time(audit, work, env, args.runs)))
        (tmp / "tables").mkdir()
        tables = {label: _table_cpu(setup, tmp / "tables", args.runs)
                  for label, setup in _TABLES.items()}
    base = {label: cpu for label, install, cpu, _wall in rows if install == "ref"}
    print(f"median of {args.runs} runs; CPU = user + system of the command")
    print(f"{'command':36} {'tree':5} {'CPU s':>7} {'wall s':>7} {'CPU/ref':>8}")
    for label, install, cpu, wall in rows:
        ratio = f"{cpu / base[label]:8.2f}" if label in base else ""
        print(f"{label:36} {install:5} {cpu:7.3f} {wall:7.3f} {ratio}")
    print("\nthe FRETish parser made in a fresh process (CPU of the call, this tree)")
    for label, cpu in tables.items():
        print(f"{label:24} {cpu * 1000:7.1f} ms  {cpu / tables['built in memory']:5.3f}x built")
    return 0


if __name__ == "__main__":
    sys.exit(main())
