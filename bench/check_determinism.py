"""``fretc check --json`` on the benchmark's sets, idle and under CPU load, byte for byte.

The sets are :mod:`bench.bench_check`'s (docs/guide/check.md's tables): the consistent,
conflicting and vacuous sets of the bound table at 10, 50, 100, 250 and 1000 ticks, and the
realizability sets (realizable, unrealizable, eventually, eventually-lost) at 10 ... 1000
ticks with ``--inputs p,m --outputs q,r,speed``.

    python bench/check_determinism.py --out DIR [--hog N] [--root CHECKOUT]
    python bench/check_determinism.py --compare DIR_A DIR_B

``--out``: write the sets into one folder of the system's temporary folder (the same for
every run: the JSON names the files), run each and write ``DIR/NAME.json`` (the command's standard output) and
``DIR/times.txt`` (wall seconds per set); ``--hog N``: N busy-looping processes run beside
the whole time (a loaded machine); ``--root``: the checkout whose ``fretc`` runs
(default this one). ``--compare``: the sets whose JSON differ byte for byte, and the answers
decided in A that B does not give the same (a satisfiable / non-vacuous / redundant status
or a component's realizability that is not ``unknown`` in A). Exit 1 when either is found.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from bench_check import BOUNDED, REALIZE  # noqa: E402

IO = ["--inputs", "p,m", "--outputs", "q,r,speed"]


def sets(folder: Path) -> dict[str, tuple[Path, list[str]]]:
    """Write the benchmark's sets into ``folder``: name -> (file, extra arguments)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    bounded = {"consistent": ([BOUNDED[0], BOUNDED[1], BOUNDED[3], BOUNDED[4]], -3),
               "conflict": (BOUNDED[:3], 3),
               "vacuous": ([BOUNDED[0], BOUNDED[1], BOUNDED[3].replace("0.4", "0.6"),
                            BOUNDED[4]], -3)}
    for n in (10, 50, 100, 250, 1000):
        for name, (lines, shift) in bounded.items():
            path = folder / f"bound_{name}_{n}.fret"
            path.write_text("\n".join(x.format(n=n, m=n + shift) for x in lines) + "\n",
                            encoding="utf-8")
            out[path.stem] = (path, [])
    for n in (10, 50, 100, 200, 250, 1000):
        for name, lines in REALIZE.items():
            path = folder / f"realize_{name}_{n}.fret"
            path.write_text("\n".join(x.format(n=n, m=n - 3) for x in lines) + "\n",
                            encoding="utf-8")
            out[path.stem] = (path, IO)
    return out


def _hog() -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", "while True: pass"])


#: where the sets are written (one folder for every run: the JSON names the files)
SETS = Path(tempfile.gettempdir()) / "fretc_check_determinism_sets"


def run(out: Path, hogs: int, root: Path) -> None:
    """Run every set (module docstring), ``hogs`` busy loops beside."""
    out.mkdir(parents=True, exist_ok=True)
    procs = [_hog() for _ in range(hogs)]
    times = []
    try:
        for name, (path, extra) in sets(SETS).items():
            t0 = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "fretc", "check", str(path),
                                   "--json", *extra], cwd=root, capture_output=True)
            dt = time.perf_counter() - t0
            (out / f"{name}.json").write_bytes(proc.stdout)
            times.append(f"{name} {dt:.2f} s exit {proc.returncode}")
            print(times[-1], flush=True)
    finally:
        for p in procs:
            p.kill()
            p.wait()
    (out / "times.txt").write_text("\n".join(times) + "\n", encoding="utf-8")


def _answers(doc: dict) -> dict:
    got = {}
    for r in doc.get("requirements", []):
        for k in ("satisfiable", "non_vacuous", "redundant"):
            got[(r["id"], k)] = r[k]
    for c in (doc.get("realizability") or {}).get("groups", []):
        got[(",".join(c["requirements"]), "realizable")] = c["realizable"]
    return got


def compare(a: Path, b: Path) -> int:
    """Print the sets whose JSON differ and the answers of ``a`` that ``b`` lost."""
    bad = 0
    names = sorted(p.stem for p in a.glob("*.json"))
    for name in names:
        x, y = (a / f"{name}.json").read_bytes(), (b / f"{name}.json").read_bytes()
        if x != y:
            print(f"{name}: JSON differs")
            bad += 1
        try:
            old, new = _answers(json.loads(x)), _answers(json.loads(y))
        except json.JSONDecodeError:
            print(f"{name}: no JSON")
            bad += 1
            continue
        for key, v in old.items():
            if v not in ("unknown", None) and new.get(key) != v:
                print(f"{name}: {key} was {v}, now {new.get(key)}")
                bad += 1
    print(f"{len(names)} sets compared, {bad} differences")
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path)
    ap.add_argument("--hog", type=int, default=0)
    ap.add_argument("--root", type=Path, default=ROOT)
    ap.add_argument("--compare", nargs=2, type=Path, metavar=("A", "B"))
    args = ap.parse_args()
    if args.compare:
        return compare(*args.compare)
    if args.out is None:
        ap.error("--out or --compare is required")
    run(args.out, args.hog, args.root.resolve())
    return 0


if __name__ == "__main__":
    sys.exit(main())
