"""Benchmark: record a full nominal mission and report sim time, wall time and speed-up.

Usage: ``python bench/bench_sim.py [--scenario nominal] [--seed 1] [--repeat 1] [--ros1]``.
Prints one line per run and a summary line ``sim_s wall_s speedup``.
"""

from __future__ import annotations

import argparse
import io
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fretc.sim.run import record  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="nominal")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--ros1", action="store_true")
    args = ap.parse_args(argv)
    best = None
    for i in range(args.repeat):
        buf = io.BytesIO()
        t0 = time.perf_counter()
        c0 = time.process_time()
        res = record(args.scenario, seed=args.seed, output=buf, ros1=args.ros1)
        wall = time.perf_counter() - t0
        cpu = time.process_time() - c0
        size = len(buf.getvalue())
        print(f"run {i + 1}: {args.scenario} seed {args.seed}: {res.outcome}; "
              f"sim {res.duration:.2f} s, wall {wall:.2f} s, cpu {cpu:.2f} s, "
              f"speed-up {res.duration / wall:.1f}x, {size / 1e6:.2f} MB")
        if best is None or wall < best[1]:
            best = (res.duration, wall)
    sim_s, wall_s = best
    print(f"sim_s={sim_s:.2f} wall_s={wall_s:.2f} speedup={sim_s / wall_s:.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
