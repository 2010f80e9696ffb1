"""Formalization throughput: parse + formalize + print ft, ft_inf and pt for 1000 generated
FRETish sentences covering all 288 template keys.

    python bench/bench_formalize.py [--n 1000]

FRET's own formalizer takes about 35 ms per sentence (shared/fretish/README.md); the printed
ratio compares against that figure (a published number, not a measurement here).
"""

from __future__ import annotations

import argparse
import random
import time

from compiler.printers import to_smv
from compiler.semantics import formalize
from fretish import parse

SCOPES = ["", "in m", "when not in m", "only in m", "after m", "before m", "only after m",
          "only before m", "while alt > 10", "during flight mode"]
CONDITIONS = ["", "upon c", "whenever c", "when c & !d", "upon p, or when r", "if x > 3"]
TIMINGS = ["", "immediately", "at the next timepoint", "finally", "eventually", "always",
           "never", "within 5 ticks", "for 3 ticks", "after 2 ticks", "until s", "before s"]
RESPONSES = ["r", "!r | q", "x + 2 * y <= 10", "persisted(3, p) -> q", "a xor b & c",
             "occurs(2, q)"]


def sentences(n: int, seed: int = 1) -> list:
    rnd = random.Random(seed)
    out = []
    for _ in range(n):
        parts = [rnd.choice(SCOPES), rnd.choice(CONDITIONS), "the sw shall",
                 rnd.choice(TIMINGS), "satisfy", rnd.choice(RESPONSES)]
        out.append(" ".join(p for p in parts if p))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5,
                    help="runs over the same sentences; the best one is reported (the "
                         "others measure the machine's noise)")
    args = ap.parse_args()
    texts = sentences(args.n)
    parse(texts[0])  # build the parser once, outside the timing
    runs = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        for text in texts:
            f = formalize(parse(text))
            to_smv(f.ft), to_smv(f.ft_inf), to_smv(f.pt, ftp="(Z FALSE)")
        runs.append(time.perf_counter() - t0)
    elapsed = min(runs)
    rate = args.n / elapsed
    print(f"sentences:            {args.n}")
    print(f"time (best of {args.repeat}):     {elapsed:.3f} s  (runs: "
          + ", ".join(f"{r:.3f}" for r in runs) + ")")
    print(f"fretc:                {rate:.0f} sentences/s ({1000 * elapsed / args.n:.3f} ms each)")
    print(f"FRET (35 ms each):    {1000 / 35:.0f} sentences/s")
    print(f"ratio fretc/FRET:     {rate / (1000 / 35):.0f}x")


if __name__ == "__main__":
    main()
