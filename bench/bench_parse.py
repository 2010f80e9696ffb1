"""Parse-rate sanity check (not a test): generate 1000 varied FRETish sentences and print
how many the parser handles per second.

    python3 bench/bench_parse.py [--n 1000] [--rounds 5] [--seed 0]
"""

from __future__ import annotations

import argparse
import random
import sys
import time
import timeit
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fretish import parse  # noqa: E402

SCOPES = ["", "in m", "during flight mode", "when in mode m", "if not in m", "unless in m",
          "except during m", "except while alt > 10", "only in m", "only while x < 3",
          "after m", "before alt > 10", "only after m", "only before m", "while ready"]
QUALIFIERS = ["upon", "when", "if", "where", "unless", "whenever"]
TIMINGS = ["", "immediately", "initially", "at the first timepoint", "at the same timepoint",
           "at the next timepoint", "finally", "at the last timepoint", "eventually",
           "always", "never", "within 5 ticks", "for 2 seconds", "after 3 ticks",
           "until stop", "before done & ok"]
ATOMS = ["p", "q", "too_close", "ROS.state = 2", "x > 3", "speed <= 0.5", "persisted(3, p)",
         "occurred(2, q)", "preBool(false, p)", "absReal(x - y) < 1e-3", "FTP", "true"]
OPS = ["&", "|", "->", "xor", "<->"]


def expression(rng: random.Random, depth: int = 0) -> str:
    if depth > 2 or rng.random() < 0.4:
        atom = rng.choice(ATOMS)
        return f"!{atom}" if rng.random() < 0.15 and " " not in atom else atom
    left, right = expression(rng, depth + 1), expression(rng, depth + 1)
    text = f"{left} {rng.choice(OPS)} {right}"
    return f"({text})" if rng.random() < 0.5 else text


def sentence(rng: random.Random) -> str:
    parts = [rng.choice(SCOPES)]
    if rng.random() < 0.6:
        conds = [f"{rng.choice(QUALIFIERS)} {expression(rng, 2)}"
                 for _ in range(rng.choice([1, 1, 1, 2]))]
        parts.append(" and ".join(conds))
    parts.append(rng.choice(["the sw", "agilex_agent", "the controller"]) + " shall")
    if rng.random() < 0.05:
        parts.append("with probability >= 0.9")
    parts.append(rng.choice(TIMINGS))
    parts.append("satisfy " + expression(rng))
    return " ".join(p for p in parts if p) + rng.choice(["", "."])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    sentences = [sentence(rng) for _ in range(args.n)]
    t0 = time.perf_counter()
    parse(sentences[0])                        # builds the Lark parser once
    build = time.perf_counter() - t0
    best = best_cpu = float("inf")
    for _ in range(args.rounds):
        t0, c0 = time.perf_counter(), time.process_time()
        for s in sentences:
            parse(s)
        best = min(best, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    chars = sum(map(len, sentences)) / len(sentences)
    calib = min(timeit.repeat("sum(range(1000))", number=2000, repeat=5)) / 2000 * 1e6
    print(f"parser build: {build * 1000:.0f} ms")
    print(f"{len(sentences)} sentences (mean {chars:.0f} chars), best of {args.rounds}: "
          f"{len(sentences) / best:,.0f} sentences/s ({best / len(sentences) * 1e6:.0f} us each); "
          f"CPU time: {len(sentences) / best_cpu:,.0f} sentences/s "
          f"({best_cpu / len(sentences) * 1e6:.0f} us each)")
    print(f"machine speed: sum(range(1000)) takes {calib:.1f} us here "
          "(about 5-10 us on an idle modern x86 core)")


if __name__ == "__main__":
    main()
