"""Cold construction of the LTL3 automata for every scope, condition and timing, at every
bound up to 12 ticks: the issue's ceiling is 1 s CPU per requirement.

    python bench/bench_ltl3.py [--bounds 1 12] [--simple]

For each bound n, one fresh Python process with an empty fretc cache (``FRETC_CACHE_DIR`` a
new folder) times ``compiler.codegen.monitor_source`` requirement by requirement (CPU time)
on the sentences with a bounded timing: 8 scopes x 6 conditions (none, ``upon c``,
``whenever c`` and the compound ``whenever c & d``, ``upon c or when d``, ``upon c and
whenever d``) x ``within`` / ``for`` / ``after n ticks`` (144 sentences); then, once, the
same scopes and conditions with every unbounded timing (``immediately``, ``at the next
timepoint``, ``eventually``, ``always``, ``never``, ``until s``, ``before s``: 336
sentences). Prints the slowest and how many took over 1 s. Requirements of one shape share
their automata (``compiler.automata``), so each one's time is cold for its shape when it is
the first of that shape in its process; the first requirement of a process also pays the
import of Spot. ``--simple``: the 72 bounded
sentences of the three simple conditions only, no unbounded timings.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_codegen import ROOT, _per_requirement, write_fret  # noqa: E402

SCOPES = ["", "in m", "when not in m", "only in m", "after m", "before m", "only after m",
          "only before m"]
CONDITIONS = ["", "upon c", "whenever c"]
#: FRET's compound conditions (several condition keywords joined by and/or) and a boolean one
COMPOUND = ["whenever c & d", "upon c or when d", "upon c and whenever d"]
UNBOUNDED = ["immediately", "at the next timepoint", "eventually", "always", "never",
             "until s", "before s"]
CEILING_S = 1.0


def sentences(n: int | None, conditions: list[str]) -> list[str]:
    """The sentences with a bounded timing at bound ``n`` (None: every unbounded timing)."""
    timings = (UNBOUNDED if n is None
               else [f"within {n} ticks", f"for {n} ticks", f"after {n} ticks"])
    return [" ".join(p for p in (s, c, "the sw shall", t, "satisfy r") if p)
            for s in SCOPES for c in conditions for t in timings]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bounds", type=int, nargs=2, default=(1, 12), metavar=("LO", "HI"))
    ap.add_argument("--simple", action="store_true",
                    help="simple conditions and bounded timings only (72 per bound)")
    args = ap.parse_args()
    conditions = CONDITIONS + ([] if args.simple else COMPOUND)
    runs: list = list(range(args.bounds[0], args.bounds[1] + 1))
    if not args.simple:
        runs.append(None)
    worst_all = (0.0, "")
    over_all = 0
    with tempfile.TemporaryDirectory(prefix="bench_ltl3_") as tmp_s:
        tmp = Path(tmp_s)
        for n in runs:
            f = write_fret(tmp / f"b{n}.fret", sentences(n, conditions), "K")
            cpu, per, worst = _per_requirement(ROOT, f, tmp)
            over = [(round(t, 2), s) for t, s in per if t > CEILING_S]
            over_all += len(over)
            worst_all = max(worst_all, tuple(worst))
            label = f"bound {n:2d}" if n is not None else "unbounded"
            print(f"{label}: {len(per)} requirements, cold child {cpu:.2f} s CPU, slowest "
                  f"{worst[0]:.3f} s ({worst[1]!r}); over {CEILING_S:.0f} s: {len(over)}"
                  + (f" {over}" if over else ""), flush=True)
    print(f"all bounds: slowest {worst_all[0]:.3f} s ({worst_all[1]!r}); over "
          f"{CEILING_S:.0f} s: {over_all}")


if __name__ == "__main__":
    main()
