"""The generated Safety System beside the hand-written one on the simulator's scenarios: every
scenario, seeds 1..N, each run with the hand-written SIF and ``cmd_vel_interceptor`` and with
the shield in DIR (``fretc shield ... --emit python -b BINDINGS -o DIR``).

    python bench/shield_scenarios.py --shield DIR [--shield DIR2 ...] [--seeds 20] [--jobs 1]
                                     [--scenario S]...

Per scenario and Safety System (the SIF, then each shield): how many runs completed the
mission, were aborted (the SRAS made no progress, or ran out of time) or ended in contact
(ground-truth clearance <= 0), the least clearance over the runs, the mean mission time of
the completed runs (s of sim time), and for a shield the ticks it overrode. Then each run the
hand-written SIF completed and the shield did not (scenario, seed, outcome), and each
contact, and each run in which an assumption of the environment of the shield broke (a
shield generated with ``--assume``). Exit 1 when the shield has a contact or leaves a mission the SIF completes
uncompleted, else 0. The runs are those of ``python -m fretc.sim record -s S --seed K
[--safety shield:DIR]``, in memory.

With ``--fault KIND`` (repeatable, :mod:`fretc.sim.faults`) every scenario and seed is run
again with the fault injected at each time of ``--fault-at S[,S...]`` (s of sim time: pick
some before and some during an approach) for ``--fault-duration S`` (a sector fault on
``--fault-sector LO:HI`` degrees, the 90 degrees ahead by default), with both Safety Systems
(``safety_restart``: the shield's node, or the hand-written SIF's agent); with
``--no-sif-faults`` the hand-written SIF runs without a fault only (about half the runs):

    python bench/shield_scenarios.py --shield DIR --seeds 2 --scenario nominal \
        --fault all_nan --fault frozen --fault-at 10,27 --fault-duration 3

Then per fault class (``none``: the runs without a fault) and Safety System: the runs,
missions completed, aborted and ended in contact, the least clearance, the shield's
overridden ticks; and each run that ended in contact under a fault (scenario, seed, the
fault's start), and per fault class how many of the missions the SIF completes without a
fault the shield completed under it. Then the fault modes and effects as measured (the FMEA of docs/guide/shield.md,
"Sensor faults", written by this command; ``--markdown`` prints it as that page's table): per
fault class, the requirements whose reasons the shield gave at its first override from the
fault's start on, the latest of those first overrides after the start over the runs (s), the
outputs that override changed, and the runs with no override during the fault (a fault the
shield did not answer: the robot stood still, or nothing was enforced). With faults the exit code is 1 when the shield has a contact in any run, or
leaves uncompleted a mission the SIF completes without a fault (a fault the shield answers
by stopping the robot may cost a mission: that is failing safe), else 0.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

from fretc.sim.faults import FAULT_KINDS, SECTOR_KINDS, Fault, parse_sector
from fretc.sim.run import record_scenario, shield_of
from fretc.sim.scenarios import SCENARIOS
from fretc.sim.space import DEFAULT_SECTOR


def _one(args: tuple) -> tuple:
    """(scenario, seed, safety, outcome, least clearance m, overrides, shield ticks, first
    override in the fault's window or None) of ``(scenario, seed, shield folder or None[,
    fault or None])``; the first override is ``(s after the fault's start, reasons, changed
    outputs)``."""
    name, seed, shield = args[:3]
    fault = args[3] if len(args) > 3 else None
    sc = SCENARIOS[name] if fault is None else replace(SCENARIOS[name], faults=(fault,))
    res = record_scenario(sc, seed=seed,
                          shield=shield_of(f"shield:{shield}") if shield else None)
    outcome = "contact" if res.contact is not None else res.outcome
    first = None
    if fault is not None:
        first = next(((t - fault.start, reasons, changed) for t, reasons, changed
                      in res.overrides if fault.start <= t <= fault.start + fault.duration),
                     None)
    return (name, seed, shield or "sif", outcome, res.min_clearance,
            len(res.overrides), res.shield_ticks, first, res.duration)


def main() -> int:
    """Run the comparison (module docstring); the exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shield", required=True, action="append",
                    help="the shield folder (--safety shield:DIR); repeatable: each shield "
                         "a row beside the SIF's (with --fault: the first)")
    ap.add_argument("--seeds", type=int, default=20, help="seeds 1..N per scenario")
    ap.add_argument("--jobs", type=int, default=1, help="runs in parallel processes")
    ap.add_argument("--scenario", action="append", choices=list(SCENARIOS),
                    help="only these scenarios (repeatable; default: all)")
    ap.add_argument("--fault", action="append", choices=list(FAULT_KINDS),
                    help="also run every scenario and seed with this fault (repeatable)")
    ap.add_argument("--fault-at", default="", metavar="S[,S...]",
                    help="the fault's start times [s of sim time]")
    ap.add_argument("--fault-duration", type=float, default=None, metavar="S",
                    help="how long each fault lasts [s]")
    ap.add_argument("--markdown", action="store_true",
                    help="with --fault: print the FMEA as a Markdown table")
    ap.add_argument("--no-sif-faults", action="store_true",
                    help="with --fault: run the hand-written SIF without a fault only (the "
                         "shield under every fault; about half the runs)")
    ap.add_argument("--fault-sector", default=None, metavar="LO:HI",
                    help="the sector [degrees, REP 103] of sector_nan and near_returns "
                         "(default -45:45, the 90 degrees ahead)")
    a = ap.parse_args()
    names = a.scenario or list(SCENARIOS)
    if a.fault:
        a.shield = a.shield[0]
        return _faults(ap, a, names)
    systems = [None, *a.shield]
    work = [(n, k, s) for n in names for k in range(1, a.seeds + 1) for s in systems]
    if a.jobs > 1:
        with ProcessPoolExecutor(a.jobs) as pool:
            rows = list(pool.map(_one, work, chunksize=4))
    else:
        rows = [_one(w) for w in work]
    by = {(n, k, s): (o, c, ov, t, d) for n, k, s, o, c, ov, t, _first, d in rows}
    width = max(7, *(len(s) for s in a.shield))
    print(f"{'scenario':20s} {'safety':{width}s} completed aborted contact  least clearance  "
          "mission time (s, completed)  overridden ticks")
    for n in names:
        for s in ("sif", *a.shield):
            runs = [by[(n, k, s)] for k in range(1, a.seeds + 1)]
            done, aborted, contact, least, over = _outcomes([r[:4] for r in runs], s != "sif")
            times = [r[4] for r in runs if r[0] == "completed"]
            mean = f"{sum(times) / len(times):.1f}" if times else "-"
            print(f"{n:20s} {s:{width}s} {done:9d} {aborted:7d} {contact:7d}  "
                  f"{least:15.3f}  {mean:>27s}  {over}")
    lost = [(n, k, s, by[(n, k, s)][0]) for s in a.shield for n in names
            for k in range(1, a.seeds + 1)
            if by[(n, k, "sif")][0] == "completed" and by[(n, k, s)][0] != "completed"]
    contacts = [(n, k, s) for s in a.shield for n in names for k in range(1, a.seeds + 1)
                if by[(n, k, s)][0] == "contact"]
    for n, k, s, o in lost:
        print(f"completed by the SIF, not by {s}: {n} seed {k}: {o}")
    for n, k, s in contacts:
        print(f"{s} contact: {n} seed {k}")
    print(f"{len(names) * a.seeds} runs per Safety System; shields: {len(contacts)} contacts, "
          f"{len(lost)} missions the SIF completes left uncompleted")
    return 1 if lost or contacts else 0


def _outcomes(runs: list[tuple], shield: bool) -> tuple[int, int, int, float, str]:
    """Of runs ``(outcome, least clearance m, overrides, shield ticks)``: how many completed,
    were aborted, ended in contact, the least clearance, and (for the shield) the ticks
    overridden of its ticks ("-" for the SIF)."""
    done = sum(o == "completed" for o, *_ in runs)
    contact = sum(o == "contact" for o, *_ in runs)
    least = min(c for _o, c, *_ in runs)
    over = (f"{sum(ov for _o, _c, ov, _t in runs)} of {sum(t for *_x, t in runs)}"
            if shield else "-")
    return done, len(runs) - done - contact, contact, least, over


def _fault_list(ap: argparse.ArgumentParser, a: argparse.Namespace) -> list[Fault]:
    """The faults of ``--fault``, ``--fault-at``, ``--fault-duration`` and
    ``--fault-sector``: each kind at each time (exit 2 on a bad value)."""
    try:
        times = [float(x) for x in a.fault_at.split(",") if x.strip()]
        if not times or a.fault_duration is None:
            raise ValueError("--fault needs --fault-at S[,S...] and --fault-duration S")
        sector = parse_sector(a.fault_sector) if a.fault_sector else DEFAULT_SECTOR
        return [Fault(k, t, a.fault_duration, sector if k in SECTOR_KINDS else None)
                for k in a.fault for t in times]
    except ValueError as exc:
        ap.error(str(exc))


def _faults(ap: argparse.ArgumentParser, a: argparse.Namespace, names: list[str]) -> int:
    """The comparison under faults (module docstring); the exit code."""
    faults = _fault_list(ap, a)
    seeds = range(1, a.seeds + 1)
    work = [(n, k, s, f) for f in [None, *faults] for n in names for k in seeds
            for s in (None, a.shield) if not (a.no_sif_faults and s is None and f)]
    if a.jobs > 1:
        with ProcessPoolExecutor(a.jobs) as pool:
            rows = list(pool.map(_one, work, chunksize=4))
    else:
        rows = [_one(w) for w in work]
    by = {(w[0], w[1], w[2] and "shield" or "sif", w[3]): r[3:7] for w, r in zip(work, rows)}
    firsts = {(w[0], w[1], w[3]): r[7] for w, r in zip(work, rows) if w[2] and w[3]}
    print(f"faults of {a.fault_duration:g} s at {a.fault_at} s; scenarios: "
          f"{', '.join(names)}; seeds 1..{a.seeds}")
    print(f"{'fault':15s} {'safety':7s} {'runs':>5s} completed aborted contact  "
          "least clearance  overridden ticks")
    for kind in ["none", *a.fault]:
        fs = [None] if kind == "none" else [f for f in faults if f.kind == kind]
        for s in ("sif", "shield"):
            if s == "sif" and kind != "none" and a.no_sif_faults:
                print(f"{kind:15s} {s:7s}     - (not run: --no-sif-faults)")
                continue
            runs = [by[(n, k, s, f)] for f in fs for n in names for k in seeds]
            done, aborted, contact, least, over = _outcomes(runs, s == "shield")
            print(f"{kind:15s} {s:7s} {len(runs):5d} {done:9d} {aborted:7d} "
                  f"{contact:7d}  {least:15.3f}  {over}")
    contacts = [(n, k, s, f) for (n, k, s, f), r in by.items() if r[0] == "contact"]
    for n, k, s, f in contacts:
        where = "no fault" if f is None else f"{f.kind} at {f.start:g} s"
        print(f"contact: {s} {n} seed {k}: {where}")
    _fmea(a.fault, faults, firsts, a.markdown)
    shield_contacts = [c for c in contacts if c[2] == "shield"]
    lost = [(n, k) for n in names for k in seeds
            if by[(n, k, "sif", None)][0] == "completed"
            and by[(n, k, "shield", None)][0] != "completed"]
    for n, k in lost:
        print(f"completed by the SIF, not by the shield (no fault): {n} seed {k}")
    sif_done = [(n, k) for n in names for k in seeds
                if by[(n, k, "sif", None)][0] == "completed"]
    for kind in a.fault:
        fs = [f for f in faults if f.kind == kind]
        kept = sum(by[(n, k, "shield", f)][0] == "completed" for f in fs for n, k in sif_done)
        print(f"under {kind}: the shield completed {kept} of the {len(fs) * len(sif_done)} "
              "missions the SIF completes without a fault")
    shield_runs = sum(1 for w in work if w[2])
    print(f"{shield_runs} shielded runs; shield: {len(shield_contacts)} contacts, "
          f"{len(lost)} missions the SIF completes without a fault left uncompleted")
    return 1 if shield_contacts or lost else 0


def _fmea(kinds: list[str], faults: list[Fault], firsts: dict, markdown: bool) -> None:
    """Print the fault modes and effects measured (module docstring): ``firsts`` maps
    (scenario, seed, fault) to the shield's first override in the fault's window."""
    rows = []
    for kind in kinds:
        got = [v for (_n, _k, f), v in firsts.items() if f.kind == kind]
        answered = [v for v in got if v is not None]
        reqs = sorted({r for _d, reasons, _c in answered for r in reasons},
                      key=lambda r: (len(r), r))
        outs = sorted({o for _d, _r, changed in answered for o in changed})
        late = max((d for d, _r, _c in answered), default=None)
        rows.append((kind, ", ".join(reqs) or "-", "-" if late is None else f"{late:.1f}",
                     ", ".join(outs) or "-", f"{len(got) - len(answered)} of {len(got)}"))
    head = ("fault class", "answered by (first override)", "latest first override (s)",
            "outputs it changed", "runs not overridden")
    if markdown:
        print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
        for r in rows:
            print("| " + " | ".join(r) + " |")
        return
    print("fault modes and effects (the shield's first override in each fault's window):")
    for r in rows:
        print(f"  {r[0]:15s} by {r[1]}; latest {r[2]} s after the start; changed {r[3]}; "
              f"{r[4]} runs not overridden")


if __name__ == "__main__":
    sys.exit(main())
