"""Long run of the differential test: random FRETish sentences over the whole grammar, with
fretc's ft, pt and ft_inf checked against the independent interval-semantics oracle of
tests/differential.py on random traces.

    python bench/differential_long.py --sentences 5000 [--traces 20] [--seed 0] [--depth 2]

Prints the number of sentences and traces checked, the CPU time, and each disagreement
(sentence, formula, trace); exits 1 if there was any."""

from __future__ import annotations

import argparse
import random
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from differential import check_requirement, random_requirement  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sentences", type=int, default=1000)
    ap.add_argument("--traces", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--depth", type=int, default=2)
    ap.add_argument("--show", type=int, default=10, help="disagreements to print")
    args = ap.parse_args(argv)
    rnd = random.Random(args.seed)
    t0 = time.process_time()
    bad = 0
    for i in range(args.sentences):
        text, meaning = random_requirement(rnd, args.depth)
        problem = check_requirement(text, meaning, rnd, traces=args.traces)
        if problem is not None:
            bad += 1
            if bad <= args.show:
                print(f"DISAGREE #{i}: {text}\n    {problem}")
    cpu = time.process_time() - t0
    print(f"{args.sentences} sentences x {args.traces} traces (ft, pt, ft_inf each) "
          f"checked in {cpu:.1f} s CPU: {bad} disagreement(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
