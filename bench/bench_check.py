"""Benchmark of ``fretc check``.

1. The 198 case-study requirements of ``../shared/corpora/fret_casestudies.jsonl``, grouped by
   project (the id's part before ``#``), checked for satisfiability and non-vacuity
   (redundancy off): CPU time per group and in total, and the findings per group.
2. Realizability of the Safe-ROS set (``requirements/*.fret``, ``too_close`` input,
   ``stopped`` output) and of generated Safe-ROS-sized sets (<= 10 requirements, bounds <= 10
   ticks): CPU time each (aim: under 5 s).
3. The command a user runs, start-up included: ``fretc check requirements/ --inputs
   too_close --outputs stopped`` (CPU of the process and its Spot worker).
4. Time against the bound (10, 50, 100, 250, 1000 ticks): satisfiability and non-vacuity of
   a consistent set, the conflicts of an inconsistent one, by Spot (``--engine spot``) and
   by z3 (``--engine smt``) on the same files.
5. Realizability against the bound (10 ... 1000 ticks): a realizable and an unrealizable
   set, by Spot's game (``--engine spot``) and by the symbolic safety game (``--engine
   auto``), and the command a user runs (``fretc check FILE --inputs p,m --outputs
   q,r,speed``, start-up and every check included).

8. With ``--redundancy [GROUP]`` (only this): the command ``fretc check FILE --json`` on one
   project of the corpus (default FRET's Lift+Cruise set, 57 requirements in one component),
   redundancy included, beside the same command with the ``satisfiable`` query's probe off
   (``SPOT_PROBE_STATES = 0``: each redundancy query builds the product of the others
   first, as before the probe): CPU of each (the process and its Spot worker), their ratio,
   and whether the two JSON reports are the same.

7. With ``--large`` (only this): the 20-requirement set with deadlines near 10^6 ticks
   (``@inputs r0, r1, r2``, ``@outputs a0..a3``): the command ``fretc check FILE --json``
   twice, its CPU (the process and its worker), peak memory and answers, and whether the two
   JSON reports are the same (the budget counts work: loaded or idle, the same answer).

6. With ``--against DIR`` (only this): the command ``fretc check FILE`` of this checkout
   beside the same command of the checkout at DIR (e.g. a ``git worktree`` of the base
   commit) on the sets of part 4 and the consistent set with B4 asking ``speed > 0.6`` (a
   vacuity), at 250 and 1000 ticks: CPU of each, their ratio and the checks each answered
   unknown; then the same with ``--witness-dir`` (the witness CSVs written).

Times are CPU seconds of this process plus its Spot worker (``resource`` RUSAGE_CHILDREN);
queries run with the default work budget (:mod:`fretc.check.budget`; ``--budget`` sets it, in work
units; a query past it is counted as unknown).

    python bench/bench_check.py [--corpus PATH] [--bounds-only] [--realizability-only]
                                [--budget UNITS] [--against DIR]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fretc.compiler.build import compile_entries  # noqa: E402
from fretc.check.analysis import check_requirements  # noqa: E402
from fretc.check.budget import DEFAULT_WORK, Budget  # noqa: E402
from fretc.fretish.files import RequirementEntry, load_requirements  # noqa: E402
from fretc.fretish.parser import parse  # noqa: E402
from fretc.common.errors import FretishError  # noqa: E402


def cpu() -> float:
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def corpus_groups(path: Path):
    groups = {}
    for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        d = json.loads(line)
        group, _, rid = d["id"].partition("#")
        e = RequirementEntry(id=rid, text=d["text"], source=f"{path.name}", line=n, column=1)
        try:
            e.requirement = parse(d["text"], source=path.name, line=n, column=1)
        except FretishError as exc:
            e.error = exc
        groups.setdefault(group, []).append(e)
    return groups


SIZED = [
    "S1: upon too_close the robot shall within {a} ticks satisfy stopped",
    "S2: whenever stopped the robot shall immediately satisfy !moving",
    "S3: in docking upon too_close the robot shall for {b} ticks satisfy slow",
    "S4: whenever slow the robot shall immediately satisfy speed <= 0.2",
    "S5: the robot shall always satisfy speed <= 0.5",
    "S6: upon !too_close the robot shall within {b} ticks satisfy moving | docking",
    "S7: whenever scan_stale the robot shall within {a} ticks satisfy stopped",
    "S8: whenever stopped the robot shall immediately satisfy speed <= 0.01",
    "S9: in docking the robot shall always satisfy speed <= 0.1",
    "S10: upon moving the robot shall at the next timepoint satisfy !stopped | too_close",
]


BOUNDED = [
    "B1: whenever p the sw shall within {n} ticks satisfy q",
    "B2: upon p the sw shall for {m} ticks satisfy !q",
    "B3: the sw shall eventually satisfy p",
    "B4: in m mode upon p the sw shall within {n} ticks satisfy speed > 0.4",
    "B5: in m mode the sw shall always satisfy speed <= 0.5",
]


def _timed(path: Path, engine: str, budget: int, **kw) -> tuple[float, str]:
    t0 = cpu()
    r = check_requirements(compile_entries(load_requirements([path])), engine=engine,
                           budget=Budget(budget), redundancy=False, **kw)
    kinds = sorted({f.kind for f in r.findings})
    rz = r.realizability
    if rz:
        kinds.append("realizable=" + ",".join(str(c["realizable"]) for c in rz["groups"]))
    return cpu() - t0, " ".join(kinds) or "no findings"


def bound_sweep(budget: float) -> None:
    """Time against the bound: a consistent set (B1, B2 with a shorter `for`, B4, B5), a
    conflict (B1, B2 longer than B1's window, B3), by Spot, by z3 (:mod:`fretc.check.smt`) and by
    the default engine (the pt monitors, :mod:`fretc.check.monitor_sat`, past 16 ticks) in one
    run, and the ``fretc check FILE`` command (start-up included); then the realizability
    table (:func:`realizability_sweep`)."""
    print(f"4. time against the bound (CPU s; budget {budget} work units per query)")
    print(f"  {'bound':>5} {'check':<14} {'Spot':>8} {'z3':>8} {'monitors':>8} {'command':>8}"
          "  answers (Spot | z3 | monitors)")
    for n in (10, 50, 100, 250, 1000):
        sets = {"consistent": [BOUNDED[0], BOUNDED[1], BOUNDED[3], BOUNDED[4]],
                "conflict": BOUNDED[:3]}
        for name, lines in sets.items():
            m = n - 3 if name == "consistent" else n + 3
            path = Path("/tmp") / f"fretc_bench_bound_{name}_{n}.fret"
            path.write_text("\n".join(x.format(n=n, m=m) for x in lines) + "\n",
                            encoding="utf-8")
            ts, a = _timed(path, "spot", budget)
            tz, b = _timed(path, "smt", budget)
            tm, c = _timed(path, "auto", budget)
            tc = _command(path, [])
            print(f"  {n:>5} {name:<14} {ts:8.2f} {tz:8.2f} {tm:8.2f} {tc:8.2f}  {a} | {b} | {c}",
                  flush=True)
    realizability_sweep(budget)


#: realizability sets (p, m inputs): a realizable one (the response the same tick, speeds in
#: (0.2, 0.5]), an unrealizable one (the environment re-triggers the hold before the
#: deadline), and two with an ``eventually`` (the Büchi game): beside a deadline
#: (realizable), and against a hold the environment re-triggers every other tick (not)
REALIZE = {
    "realizable": ["R1: whenever p the sw shall within {n} ticks satisfy q",
                   "R2: whenever q the sw shall immediately satisfy speed <= 0.5",
                   "R3: in m mode the sw shall always satisfy speed > 0.2",
                   "R4: upon p the sw shall for {m} ticks satisfy !r"],
    "unrealizable": ["U1: whenever p the sw shall within {n} ticks satisfy q",
                     "U2: upon p the sw shall for {m} ticks satisfy !q"],
    "eventually": ["E1: whenever p the sw shall eventually satisfy q",
                   "E2: upon p the sw shall within {n} ticks satisfy q",
                   "E3: in m mode the sw shall always satisfy speed > 0.2"],
    "eventually-lost": ["L1: whenever p the sw shall eventually satisfy q",
                        "L2: upon m the sw shall for {m} ticks satisfy !q"],
}


def _realizability(path: Path, engine: str, budget: int) -> tuple[float, str]:
    """CPU seconds of the realizability check alone (minimal subsets included)."""
    from fretc.check.analysis import Checker, CheckResult, make_item
    from fretc.check.realizability import check_realizability
    from fretc.check.solver import SpotWorker

    items = [make_item(k, c) for k, c in
             enumerate(compile_entries(load_requirements([path])))]
    t0 = cpu()
    with SpotWorker(Budget(budget)) as worker:
        summary = check_realizability(Checker(items, worker, engine=engine), CheckResult(),
                                      ["p", "m"], ["q", "r", "speed"])
    comp = summary["groups"][0]
    what = str(comp["realizable"])
    if comp["realizable"] is False:
        env = comp["environment"]
        what += (f" ({len(env['prefix'])}+{len(env['cycle'])}-tick input lasso)"
                 if "prefix" in env else " (no fixed inputs)")
    return cpu() - t0, what


def _command(path: Path, io: list[str] | None = None, root: Path = ROOT,
             out: list | None = None) -> float:
    """CPU seconds of ``fretc check FILE`` (by default with ``--inputs p,m --outputs
    q,r,speed``), start-up and every check included (the process and its children), run
    from the checkout ``root`` (``python -m fretc`` there takes its code); its standard
    output is appended to ``out``."""
    io = ["--inputs", "p,m", "--outputs", "q,r,speed"] if io is None else io
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([sys.executable, "-m", "fretc", "check", str(path), *io], cwd=root,
                          capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out is not None:
        out.append(proc.stdout)
    return (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def against(other: Path) -> None:
    """Part 6 (module docstring): the command here and in the checkout ``other``."""
    print(f"6. fretc check FILE here and in {other} (CPU s, start-up included; the checks "
          "answered unknown)")
    print(f"  {'bound':>5} {'set':<11} {'here':>8} {'there':>8} {'ratio':>6}  unknown "
          f"(here | there)   {'witnesses: here':>15} {'there':>8} {'ratio':>6}  unknown")
    sets = {"consistent": [BOUNDED[0], BOUNDED[1], BOUNDED[3], BOUNDED[4]],
            "conflict": BOUNDED[:3],
            "vacuous": [BOUNDED[0], BOUNDED[1], BOUNDED[3].replace("0.4", "0.6"), BOUNDED[4]]}
    for n in (250, 1000):
        for name, lines in sets.items():
            m = n + 3 if name == "conflict" else n - 3
            path = Path("/tmp") / f"fretc_bench_against_{name}_{n}.fret"
            path.write_text("\n".join(x.format(n=n, m=m) for x in lines) + "\n",
                            encoding="utf-8")
            row = f"  {n:>5} {name:<11}"
            for io in ([], ["--witness-dir", str(path.with_suffix(""))]):
                texts: list[str] = []
                here, there = (_command(path, io, root, texts) for root in (ROOT, other))
                unknown = [sum(x.startswith("UNKNOWN") for x in t.splitlines())
                           for t in texts]
                row += (f" {here:8.2f} {there:8.2f} {here / there:6.2f}  {unknown[0]:>4} | "
                        f"{unknown[1]:<4}")
            print(row, flush=True)


def realizability_sweep(budget: float) -> None:
    """Realizability against the bound: Spot's game (``--engine spot``) and the symbolic
    games (``--engine auto``: safety, or Büchi with an ``eventually``) on the same files,
    and the whole command."""
    print(f"5. realizability against the bound (CPU s; budget {budget} work units per "
          "query)")
    print(f"  {'bound':>5} {'set':<13} {'Spot':>8} {'game':>8} {'command':>8}  answers "
          "(Spot | game)")
    for n in (10, 50, 100, 200, 250, 1000):
        for name, lines in REALIZE.items():
            path = Path("/tmp") / f"fretc_bench_realize_{name}_{n}.fret"
            path.write_text("\n".join(x.format(n=n, m=n - 3) for x in lines) + "\n",
                            encoding="utf-8")
            ts, a = _realizability(path, "spot", budget)
            tg, b = _realizability(path, "auto", budget)
            tc = _command(path)
            print(f"  {n:>5} {name:<13} {ts:8.2f} {tg:8.2f} {tc:8.2f}  {a} | {b}", flush=True)


#: ``fretc check`` with the ``satisfiable`` query's probe off (part 8's baseline); the
#: query worker is forked from this process, so it keeps the setting
NO_PROBE = ("import sys; import fretc.check.solver as s; s.SPOT_PROBE_STATES = 0; "
            "from fretc.cli import main; sys.argv[0] = 'fretc'; main()")


def redundancy(corpus: Path, group: str) -> None:
    """Part 8 (module docstring)."""
    import tempfile

    rows = [json.loads(line) for line in corpus.read_text(encoding="utf-8").splitlines()]
    reqs = [{"reqid": d["id"].partition("#")[2], "fulltext": d["text"]} for d in rows
            if d["id"].partition("#")[0] == group]
    if not reqs:
        raise SystemExit(f"no project {group!r} in {corpus}")
    print(f"8. redundancy of {group} ({len(reqs)} requirements): fretc check FILE --json")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "requirements.json"
        path.write_text(json.dumps(reqs, indent=1), encoding="utf-8")
        reports, times = [], []
        for cmd in ([sys.executable, "-m", "fretc"], [sys.executable, "-c", NO_PROBE]):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            proc = subprocess.run([*cmd, "check", str(path), "--json", "--no-progress"],
                                  cwd=ROOT, capture_output=True, text=True)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            if proc.returncode not in (0, 1):
                raise SystemExit(f"fretc check failed ({proc.returncode}): {proc.stderr[-500:]}")
            times.append((after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime))
            reports.append(json.loads(proc.stdout))
    redundant = sum(r.get("redundant") is True for r in reports[0].get("requirements", []))
    print(f"  probe {times[0]:.1f} s CPU, without it {times[1]:.1f} s CPU: ratio "
          f"{times[0] / times[1]:.2f}; reports {'equal' if reports[0] == reports[1] else 'DIFFER'}"
          f" ({redundant} redundant)")
    if reports[0] != reports[1]:
        sys.exit(1)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default=str(ROOT / ".." / "shared" / "corpora" /
                                            "fret_casestudies.jsonl"))
    ap.add_argument("--bounds-only", action="store_true",
                    help="Only the time-against-the-bound tables (parts 4 and 5).")
    ap.add_argument("--realizability-only", action="store_true",
                    help="Only the realizability table (part 5).")
    ap.add_argument("--budget", type=int, default=DEFAULT_WORK,
                    help="Work units per query in parts 4 and 5 (check.budget).")
    ap.add_argument("--large", action="store_true",
                    help="Only part 7: the 20-requirement set near 10^6 ticks.")
    ap.add_argument("--against", metavar="DIR",
                    help="Only part 6: the command here beside the checkout at DIR.")
    ap.add_argument("--redundancy", metavar="GROUP", nargs="?",
                    const="LiftPlusCruise/LPC_full_reqts_and_vars.json",
                    help="Only part 8: redundancy of one corpus project, probe on and off.")
    args = ap.parse_args()
    if args.redundancy:
        redundancy(Path(args.corpus), args.redundancy)
    elif args.large:
        large_set()
    elif args.against:
        against(Path(args.against).resolve())
    elif args.realizability_only:
        realizability_sweep(args.budget)
    elif args.bounds_only:
        bound_sweep(args.budget)
    else:
        every_part(args)
    return 0


#: the 20-requirement set of part 7: deadlines and holds near 10^6 ticks over 3 inputs and
#: 4 outputs (the hostile input that ran for an hour)
LARGE = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "check" / "deadlines_near_1e6.fret"


def large_set() -> None:
    """Part 7 (module docstring)."""
    import tempfile

    print("7. 20 requirements with deadlines near 10^6 ticks: fretc check FILE --json")
    with tempfile.TemporaryDirectory() as tmp:
        path = LARGE
        docs = []
        for run in (1, 2):
            out = Path(tmp) / f"h20.{run}.json"
            t0, w0 = cpu(), time.perf_counter()
            cmd = [sys.executable, "-m", "fretc", "check", str(path), "--json", "-o", str(out)]
            code = subprocess.run(cmd, capture_output=True).returncode
            peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
            doc = json.loads(out.read_text())
            docs.append(out.read_text())
            answers = {k: sorted({str(r[k]) for r in doc["requirements"]})
                       for k in ("satisfiable", "non_vacuous", "redundant")}
            real = [c["realizable"] for c in doc["realizability"]["groups"]]
            print(f"  run {run}: {cpu() - t0:.1f} s CPU ({time.perf_counter() - w0:.1f} s "
                  f"wall), peak {peak:.0f} MB, exit {code}; answers {answers}, realizable "
                  f"{real}; unknown queries {doc['unknown_queries']} of {doc['queries']}")
        print(f"  same JSON both runs: {docs[0] == docs[1]}")


def every_part(args) -> None:
    """Parts 1 to 5 (module docstring)."""
    print("1. case-study corpus: satisfiability + non-vacuity per project")
    total0 = cpu()
    w0 = time.perf_counter()
    count = 0
    for group, entries in corpus_groups(Path(args.corpus)).items():
        t0 = cpu()
        r = check_requirements(compile_entries(entries), redundancy=False)
        dt = cpu() - t0
        count += len(entries)
        kinds = {}
        for f in r.findings:
            kinds[f.kind] = kinds.get(f.kind, 0) + 1
        print(f"  {group:<45} {len(entries):3d} reqs {len(r.groups):3d} groups "
              f"{dt:6.2f} s CPU  findings {kinds or '-'}  input errors "
              f"{len(r.input_errors)}  queries {r.queries} (unknown {r.unknown_queries})")
        for f in r.findings:
            print(f"      {f.kind}: {f.message[:150]}")
    print(f"  total: {count} requirements in {cpu() - total0:.2f} s CPU "
          f"({time.perf_counter() - w0:.2f} s wall)")

    print("2. realizability of Safe-ROS-sized sets (too_close, scan_stale inputs)")
    files = sorted(str(p) for p in (ROOT / "requirements").glob("*.fret"))
    t0 = cpu()
    r = check_requirements(compile_entries(load_requirements(files)),
                           inputs=['too_close', 'clearance', 'scan_stale'],
                           outputs=['stopped', 'stop_requested', 'forwarded_zero', 'linear_speed', 'angular_speed'])
    print(f"  Safe-ROS R1-R6: {cpu() - t0:.2f} s CPU, "
          + "; ".join(f"{','.join(c['requirements'])}: realizable={c['realizable']}"
                      for c in r.realizability["groups"]))
    for a, b in [(3, 3), (5, 5), (10, 10)]:
        text = "\n".join(s.format(a=a, b=b) for s in SIZED) + "\n"
        path = Path("/tmp") / f"fretc_bench_check_{a}_{b}.fret"
        path.write_text(text, encoding="utf-8")
        io = dict(inputs=["too_close", "scan_stale"],
                  outputs=["stopped", "moving", "slow", "speed", "docking"])
        t0 = cpu()
        check_requirements(compile_entries(load_requirements([path])), vacuity=False,
                           redundancy=False)
        t1 = cpu()
        r = check_requirements(compile_entries(load_requirements([path])), vacuity=False,
                               redundancy=False, **io)
        t2 = cpu()
        full = check_requirements(compile_entries(load_requirements([path])), **io)
        t3 = cpu()
        rz = r.realizability["groups"]
        print(f"  10 requirements, bounds {a}/{b} ticks: realizability {max(0.0, (t2 - t1) - (t1 - t0)):.2f} s "
              f"CPU (satisfiability alone {t1 - t0:.2f} s; every check {t3 - t2:.2f} s), "
              + "; ".join(f"{len(c['requirements'])} reqs realizable={c['realizable']}"
                          for c in rz) + f", findings {[f.kind for f in full.findings]}")

    print("3. the command, start-up included")
    t0 = cpu()
    w0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "fretc", "check", "requirements/", "--inputs",
                           "too_close,clearance,scan_stale", "--outputs",
                           "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed"], cwd=ROOT,
                          capture_output=True, text=True)
    print(f"  fretc check requirements/ --inputs too_close,clearance,scan_stale --outputs stopped,stop_requested,forwarded_zero,linear_speed,angular_speed: exit "
          f"{proc.returncode}, {cpu() - t0:.2f} s CPU ({time.perf_counter() - w0:.2f} s wall)")
    bound_sweep(args.budget)


if __name__ == "__main__":
    sys.exit(main())
