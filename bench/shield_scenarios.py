"""The generated Safety System beside the hand-written one on the simulator's scenarios: every
scenario, seeds 1..N, each run with the hand-written SIF and ``cmd_vel_interceptor`` and with
the shield in DIR (``fretc shield ... --emit python -b BINDINGS -o DIR``).

    python bench/shield_scenarios.py --shield DIR [--seeds 20] [--jobs 1] [--scenario S]...

Per scenario and Safety System: how many runs completed the mission, were aborted (the SRAS
made no progress, or ran out of time) or ended in contact (ground-truth clearance <= 0), the
least clearance over the runs, and for the shield the ticks it overrode. Then each run the
hand-written SIF completed and the shield did not (scenario, seed, outcome), and each
contact, and each run in which an assumption of the environment of the shield broke (a
shield generated with ``--assume``). Exit 1 when the shield has a contact or leaves a mission the SIF completes
uncompleted, else 0. The runs are those of ``python -m fretc.sim record -s S --seed K
[--safety shield:DIR]``, in memory.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor

from fretc.sim.run import record_scenario, shield_of
from fretc.sim.scenarios import SCENARIOS


def _one(args: tuple[str, int, str | None]) -> tuple[str, int, str, str, float, int, int]:
    """(scenario, seed, safety, outcome, least clearance m, overrides, shield ticks)."""
    name, seed, shield = args
    res = record_scenario(SCENARIOS[name], seed=seed,
                          shield=shield_of(f"shield:{shield}") if shield else None)
    outcome = "contact" if res.contact is not None else res.outcome
    return (name, seed, "shield" if shield else "sif", outcome, res.min_clearance,
            len(res.overrides), res.shield_ticks)


def main() -> int:
    """Run the comparison (module docstring); the exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shield", required=True, help="the shield folder (--safety shield:DIR)")
    ap.add_argument("--seeds", type=int, default=20, help="seeds 1..N per scenario")
    ap.add_argument("--jobs", type=int, default=1, help="runs in parallel processes")
    ap.add_argument("--scenario", action="append", choices=list(SCENARIOS),
                    help="only these scenarios (repeatable; default: all)")
    a = ap.parse_args()
    names = a.scenario or list(SCENARIOS)
    work = [(n, k, s) for n in names for k in range(1, a.seeds + 1) for s in (None, a.shield)]
    if a.jobs > 1:
        with ProcessPoolExecutor(a.jobs) as pool:
            rows = list(pool.map(_one, work, chunksize=4))
    else:
        rows = [_one(w) for w in work]
    by = {(n, k, s): (o, c, ov, t) for n, k, s, o, c, ov, t in rows}
    print(f"{'scenario':20s} {'safety':7s} completed aborted contact  least clearance  "
          "overridden ticks")
    for n in names:
        for s in ("sif", "shield"):
            runs = [by[(n, k, s)] for k in range(1, a.seeds + 1)]
            done = sum(o == "completed" for o, *_ in runs)
            contact = sum(o == "contact" for o, *_ in runs)
            least = min(c for _o, c, *_ in runs)
            over = (f"{sum(ov for _o, _c, ov, _t in runs)} of "
                    f"{sum(t for *_x, t in runs)}") if s == "shield" else "-"
            print(f"{n:20s} {s:7s} {done:9d} {len(runs) - done - contact:7d} {contact:7d}  "
                  f"{least:15.3f}  {over}")
    lost = [(n, k, by[(n, k, 'shield')][0]) for n in names for k in range(1, a.seeds + 1)
            if by[(n, k, "sif")][0] == "completed" and by[(n, k, "shield")][0] != "completed"]
    contacts = [(n, k) for n in names for k in range(1, a.seeds + 1)
                if by[(n, k, "shield")][0] == "contact"]
    for n, k, o in lost:
        print(f"completed by the SIF, not by the shield: {n} seed {k}: {o}")
    for n, k in contacts:
        print(f"shield contact: {n} seed {k}")
    print(f"{len(work) // 2} runs per Safety System; shield: {len(contacts)} contacts, "
          f"{len(lost)} missions the SIF completes left uncompleted")
    return 1 if lost or contacts else 0


if __name__ == "__main__":
    sys.exit(main())
