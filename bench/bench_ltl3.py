"""Cold construction of the LTL3 automata for every template key with a bound, at every bound
up to 12 ticks: the issue's ceiling is 1 s CPU per requirement.

    python bench/bench_ltl3.py [--bounds 1 12]

For each bound n, one fresh Python process with an empty fretc cache (``FRETC_CACHE_DIR`` a
new folder) times ``compiler.codegen.monitor_source`` requirement by requirement (CPU time)
on the 72 sentences with a bounded timing (8 scopes x 3 conditions x ``within`` / ``for`` /
``after n ticks``), and prints the slowest and how many took over 1 s.
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
CEILING_S = 1.0


def sentences(n: int) -> list[str]:
    """The 72 sentences with a bounded timing at bound ``n``."""
    timings = [f"within {n} ticks", f"for {n} ticks", f"after {n} ticks"]
    return [" ".join(p for p in (s, c, "the sw shall", t, "satisfy r") if p)
            for s in SCOPES for c in CONDITIONS for t in timings]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bounds", type=int, nargs=2, default=(1, 12), metavar=("LO", "HI"))
    args = ap.parse_args()
    worst_all = (0.0, "")
    over_all = 0
    with tempfile.TemporaryDirectory(prefix="bench_ltl3_") as tmp_s:
        tmp = Path(tmp_s)
        for n in range(args.bounds[0], args.bounds[1] + 1):
            f = write_fret(tmp / f"b{n}.fret", sentences(n), "K")
            cpu, per, worst = _per_requirement(ROOT, f, tmp)
            over = [(round(t, 2), s) for t, s in per if t > CEILING_S]
            over_all += len(over)
            worst_all = max(worst_all, tuple(worst))
            print(f"bound {n:2d}: {len(per)} requirements, cold child {cpu:.2f} s CPU, slowest "
                  f"{worst[0]:.3f} s ({worst[1]!r}); over {CEILING_S:.0f} s: {len(over)}"
                  + (f" {over}" if over else ""), flush=True)
    print(f"all bounds: slowest {worst_all[0]:.3f} s ({worst_all[1]!r}); over "
          f"{CEILING_S:.0f} s: {over_all}")


if __name__ == "__main__":
    main()
