"""Crude Monte Carlo over a scenario space: N runs of ``fretc estimate``'s sampling (the same
runs, seed for seed, as the campaign's first N), no sequential stop; per run its verdicts and
robustness as one JSON line. The reference the estimate's interval and ``--rare`` are
compared with (docs/guide/statistics.md "Measured").

    python bench/statistics/crude_mc.py --space sim/spaces/interceptor_delay.toml \\
        --requirements bench/statistics/r2_p90.fret --seed 1 -n 1000 -o /tmp/crude.jsonl
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--space", required=True)
    ap.add_argument("--requirements", required=True)
    ap.add_argument("--bindings", default=str(ROOT / "requirements" / "safe_ros.bindings.toml"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-n", type=int, default=1000)
    ap.add_argument("--start", type=int, default=1, help="first run index (to resume)")
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()

    from fretc.audit import AuditConfig, load_plan
    from fretc.sim.estimate import Runner, sample_point
    from fretc.sim.space import load_space

    plan = load_plan(AuditConfig(requirements=(a.requirements,), bindings=(a.bindings,)))
    space = load_space(a.space)
    tmp = Path(tempfile.mkdtemp(prefix="crude-"))
    runner = Runner(plan, space, tmp)
    cpu0, wall0 = time.process_time(), time.time()
    with open(a.output, "a", encoding="utf-8") as out:
        for i in range(a.start, a.start + a.n):
            (run,) = runner.run([(i, *sample_point(space, a.seed, i))])
            Path(runner.path(i)).unlink(missing_ok=True)
            out.write(json.dumps({"index": i, "parameters": run.parameters,
                                  "verdicts": run.verdicts,
                                  "robustness": {k: (None if v is None else
                                                     (v if abs(v) != float("inf") else
                                                      ("inf" if v > 0 else "-inf")))
                                                 for k, v in run.robustness.items()}},
                                 sort_keys=True) + "\n")
            out.flush()
    shutil.rmtree(tmp, ignore_errors=True)
    print(f"{a.n} runs: CPU {time.process_time() - cpu0:.1f} s, wall {time.time() - wall0:.1f} s")


if __name__ == "__main__":
    main()
