"""Start-up of the ``fretc`` command as a user runs it, this tree against a git revision.

Usage::

    python bench/bench_startup.py [--ref REV] [--runs N]

Times ``fretc --version`` and ``fretc r1.fret --emit ltl`` (``python -m fretc ...``, start-up
included) in three installs, each from a folder outside the checkout so that only the
install is on ``sys.path``:

* ``ref``: the revision ``--ref`` exported by ``git archive``, on ``PYTHONPATH`` (how an
  editable install of the layout before the one-package rename put the checkout on
  ``sys.path``: a plain path in a ``.pth`` file);
* ``wheel``: this tree's wheel (``pip wheel``) unpacked by ``pip install --target``, on
  ``PYTHONPATH`` (a regular install);
* ``editable``: this virtual environment's install of this tree (``pip install -e``: since
  the rename, setuptools' import finder maps ``fretc.*`` to the repository's folders).

Each command runs once to warm fretc's cache (its Lark tables) and the file system, then
``--runs`` times; the table gives the median CPU time (user + system of the child) and wall
time, and each install's ratio to ``ref``. All runs share this Python and its site-packages
(the dependencies); fretc's cache is one folder per install.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _time(cmd: list[str], cwd: Path, env: dict, runs: int) -> tuple[float, float]:
    """Median (CPU seconds, wall seconds) of ``runs`` runs of ``cmd``, after one warm-up."""
    cpu, wall = [], []
    for i in range(runs + 1):
        c0, w0 = _child_cpu(), time.perf_counter()
        proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True)
        c1, w1 = _child_cpu(), time.perf_counter()
        if proc.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} (in {cwd}) exited {proc.returncode}:\n"
                             + proc.stderr.decode(errors="replace")[-2000:])
        if i:
            cpu.append(c1 - c0)
            wall.append(w1 - w0)
    return statistics.median(cpu), statistics.median(wall)


def _installs(tmp: Path, ref: str | None) -> dict[str, dict]:
    """name -> extra environment of each install measured."""
    out: dict[str, dict] = {}
    if ref:
        tree = tmp / "ref"
        tree.mkdir()
        archive = subprocess.run(["git", "archive", ref], cwd=REPO, check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
        out["ref"] = {"PYTHONPATH": str(tree)}
    wheels, site = tmp / "wheels", tmp / "site"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(wheels),
                    str(REPO)], check=True, capture_output=True)
    (wheel,) = wheels.glob("fretc-*.whl")
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target",
                    str(site), str(wheel)], check=True, capture_output=True)
    out["wheel"] = {"PYTHONPATH": str(site)}
    out["editable"] = {}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", help="git revision to compare against (e.g. the commit before "
                                  "the rename); none: this tree's installs only")
    ap.add_argument("--runs", type=int, default=15)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="fretc-startup-") as name:
        tmp = Path(name)
        work = tmp / "work"
        work.mkdir()
        shutil.copy(REPO / "requirements" / "r1.fret", work / "r1.fret")
        commands = {"fretc --version": ["--version"],
                    "fretc r1.fret --emit ltl": ["r1.fret", "--emit", "ltl"]}
        rows = []
        for install, extra in _installs(tmp, args.ref).items():
            env = dict(os.environ, FRETC_CACHE_DIR=str(tmp / f"cache-{install}"), **extra)
            env.pop("PYTHONPATH", None) if not extra else None
            for label, cmd in commands.items():
                cpu, wall = _time([sys.executable, "-m", "fretc", *cmd], work, env, args.runs)
                rows.append((label, install, cpu, wall))
    base = {label: (cpu, wall) for label, install, cpu, wall in rows if install == "ref"}
    print(f"median of {args.runs} runs; CPU = user + system of the command")
    print(f"{'command':28} {'install':9} {'CPU s':>7} {'wall s':>7} {'CPU/ref':>8} {'wall/ref':>8}")
    for label, install, cpu, wall in rows:
        ratio = (f"{cpu / base[label][0]:8.2f} {wall / base[label][1]:8.2f}" if label in base
                 else f"{'':8} {'':8}")
        print(f"{label:28} {install:9} {cpu:7.3f} {wall:7.3f} {ratio}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
