"""Formula construction + printing: per-template-key instantiation against the full IR build,
in one run on the same sentences.

    python bench/bench_instantiate.py [--n 1000] [--repeat 5]

The sentences are bench_formalize.py's (all 288 template keys), parsed once outside the
timings. For each requirement both paths produce what ``fretc FILE --emit ltl --json``
prints: ft, ft_inf, pt (FRET/SMV) and the Spot text of ft and ft_inf.

* full: :func:`compiler.semantics.formalize` then the printers (the path before
  :mod:`compiler.instantiate`);
* template: :func:`compiler.instantiate.instantiate` then
  :func:`compiler.instantiate.formula_text`; "cold" is the first pass of a fresh process
  (templates built or read from fretc's disk cache), "warm" the best later pass.

CPU time (``time.process_time``), best of ``--repeat`` passes, the cyclic garbage collector
paused as ``fretc --emit ltl`` pauses it; the ratio full/template is printed.
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bench_formalize import sentences  # noqa: E402
from compiler.instantiate import InstantiatedFormalization, formula_text, instantiate  # noqa: E402
from compiler.printers import to_smv, to_spot  # noqa: E402
from compiler.semantics import formalize  # noqa: E402
from fretish import parse  # noqa: E402

FORMS = ("ft", "ft_inf", "pt", "ft_spot", "ft_inf_spot")


def full(reqs) -> None:
    for r in reqs:
        f = formalize(r)
        to_smv(f.ft), to_smv(f.ft_inf), to_smv(f.pt, ftp="(Z FALSE)")
        to_spot(f.ft), to_spot(f.ft_inf)


def template(reqs) -> None:
    for r in reqs:
        f = instantiate(r)
        for which in FORMS:
            formula_text(f, which)


def timed(fn, reqs) -> float:
    t0 = time.process_time()
    fn(reqs)
    return time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    reqs = [parse(t) for t in sentences(args.n)]
    gc.collect()
    gc.disable()
    cold = timed(template, reqs)
    runs = {"full": [], "template": []}
    for _ in range(args.repeat):
        runs["full"].append(timed(full, reqs))
        runs["template"].append(timed(template, reqs))
    used = sum(isinstance(instantiate(r), InstantiatedFormalization) for r in reqs)
    bf, bt = min(runs["full"]), min(runs["template"])
    n = args.n
    print(f"{n} sentences, {used} from a template ({n - used} fell back to the full build)")
    print(f"full build + printers: {bf * 1e3:.1f} ms CPU = {bf / n * 1e6:.0f} µs/sentence")
    print(f"template, warm:        {bt * 1e3:.1f} ms CPU = {bt / n * 1e6:.0f} µs/sentence")
    print(f"template, cold (first pass of this process): {cold * 1e3:.1f} ms CPU")
    print(f"ratio full/template (warm): {bf / bt:.2f}x; (cold): {bf / cold:.2f}x")


if __name__ == "__main__":
    main()
