"""Benchmark of ``fretc audit`` on a long recorded run.

    python bench/bench_audit.py                      # quick: 5-minute log, memory 2 vs 10 min
    python bench/bench_audit.py --minutes 60 --memory 10 60   # the one-hour run

1. Writes a synthetic but faithful Safe-ROS recording (``bench/synthetic_run.py``: ``/scan``
   10 Hz with 722 beams, ``/odom`` 20 Hz, ``/cmd_vel`` and ``/cmd_vel_filtered`` 10 Hz,
   ``/gwendolen_control`` on change; ROS 2 CDR, zstd chunks) of ``--minutes`` minutes (kept
   in ``--workdir`` and reused).
2. Times, in one run, a plain ``mcap`` iteration with decoding over the same file (the
   ``mcap`` reader and rosbags' CDR deserializer with types from the embedded schemas: the
   floor for anything that reads the messages) and the audit of the file against 10
   requirements (``audit.audit_log``: read, sample every 100 ms, monitor, evidence),
   and prints both CPU times and their ratio (aim: <= 0.5x; the audit decodes only the
   fields its bindings read, a chunk's messages at once, :mod:`fretc.logs.ros.columnar`);
   then the same two as commands in fresh processes (start-up included; bytecode cached as
   in an installed fretc, after one untimed run of each). Compiling the requirements (Spot) is timed
   apart: it does not depend on the log.
3. Windows over time (``--windows``, docs/bindings.md): a 2-second mean, a count per minute
   and a 95th percentile audited on the same log, CPU time against the plain read, and their
   verdicts and first violations checked equal to a pandas recomputation (rolling windows at
   the tick grid over an independent read: mcap + rosbags).
4. One verdict per entity (``--entities [N]``): a per-entity requirement over N tracked
   obstacles (default 100,000: ``bench/tracks_run.py``'s ``write_many_tracks``, five
   tracked at a time, each for five messages at 10 Hz), its CPU time against the same
   requirement without entities (its variables over every track of the message) and the
   plain read of that log, in one run (each timed run from the same state: the previous
   run's verdicts released and collected); the per-obstacle verdicts checked equal to a
   recomputation from the generated values (exits 1 on a difference); then the two
   ``fretc audit`` commands in fresh processes (start-up included, best of ``--repeat``).
   Every entity of the requirement is judged in one read of the log.
5. Peak memory (max RSS of a fresh process auditing the log) for two log lengths
   (``--memory A B`` minutes): memory must stay flat in the log's length.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

REQUIREMENTS = """# 10 requirements over the Safe-ROS topics of the benchmark log.
@tick_period 100 ms
B1: whenever too_close agilex_agent shall eventually satisfy stopped
B2: upon too_close agilex_agent shall within 1 second satisfy stopped
B3: whenever stop_requested cmd_vel_interceptor shall immediately satisfy forwarded_zero
B4: the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5
B5: whenever scan_stale safety_system shall within 500 milliseconds satisfy stop_requested
B6: in stop_requested mode the scout_mini shall always satisfy measured_speed < 0.6
B7: upon stop_requested cmd_vel_interceptor shall at the next timepoint satisfy stopped
B8: whenever commanded_speed > 0.3 the scout_mini shall within 1 second satisfy measured_speed > 0.1
B9: after too_close the safety_system shall eventually satisfy stop_requested
B10: the scout_mini shall always satisfy min_range > 0.05
"""

# same layout as SYN_BINDINGS in tests/_logs.py (kept: a bindings file is data; the
# bench binds the robot's topics)
BINDINGS = """[tick]
period = "100 ms"
[variables]
too_close = "min(/scan.ranges) < 0.9"
min_range = "min(/scan.ranges)"
stopped = "abs(/cmd_vel_filtered.linear.x) < 1e-3 & abs(/cmd_vel_filtered.angular.z) < 1e-3"
stop_requested = "/gwendolen_control.data"
forwarded_zero = "/cmd_vel_filtered.linear.x = 0 & /cmd_vel_filtered.linear.y = 0 & /cmd_vel_filtered.linear.z = 0 & /cmd_vel_filtered.angular.x = 0 & /cmd_vel_filtered.angular.y = 0 & /cmd_vel_filtered.angular.z = 0"
linear_speed = "abs(/cmd_vel_filtered.linear.x)"
angular_speed = "abs(/cmd_vel_filtered.angular.z)"
scan_stale = "age(/scan) > 0.3"
measured_speed = "abs(/odom.twist.twist.linear.x)"
commanded_speed = "abs(/cmd_vel.linear.x)"
"""


WINDOW_REQUIREMENTS = """# windows over time on the benchmark log's topics
@tick_period 100 ms
W1: the scout_mini shall always satisfy mean_speed_2s < 0.4
W2: the safety_system shall always satisfy stops_per_minute <= 1
W3: the scout_mini shall always satisfy p95_speed_10s < 0.4
"""
WINDOW_BINDINGS = """[tick]
period = "100 ms"
[variables]
mean_speed_2s = "mean(/odom.twist.twist.linear.x, 2s)"
stops_per_minute = "count(/gwendolen_control.data, 1min)"
p95_speed_10s = "percentile(abs(/odom.twist.twist.linear.x), 95, 10s)"
"""
#: requirement -> (topic, value of a decoded message, span ns, pandas aggregation, bound
#: holds) for the recomputation
WINDOW_REFERENCE = {
    "W1": ("/odom", lambda m: m.twist.twist.linear.x, 2_000_000_000, lambda r: r.mean(),
           lambda x: x < 0.4),
    "W2": ("/gwendolen_control", lambda m: float(m.data), 60_000_000_000, lambda r: r.sum(),
           lambda x: x <= 1),
    "W3": ("/odom", lambda m: abs(m.twist.twist.linear.x), 10_000_000_000,
           lambda r: r.quantile(0.95), lambda x: x < 0.4),
}


def ensure_log(workdir: Path, minutes: float) -> Path:
    from synthetic_run import write_run

    path = workdir / f"safe_ros_{minutes:g}min.mcap"
    if not path.exists():
        t = time.perf_counter()
        tmp = path.with_suffix(".tmp")
        counts = write_run(tmp, minutes)
        tmp.rename(path)
        print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB, "
              f"{sum(counts.values())} messages) in {time.perf_counter() - t:.1f} s")
    return path


def ensure_requirements(workdir: Path) -> Path:
    fret = workdir / "bench.fret"
    fret.write_text(REQUIREMENTS)
    (workdir / "bench.bindings.toml").write_text(BINDINGS)
    return fret


def plain_iteration(path: Path) -> tuple[float, int]:
    """CPU seconds to read and decode every message with mcap + rosbags."""
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    t = time.process_time()
    n = 0
    stores = {}
    with open(path, "rb") as f:
        for schema, _channel, message in make_reader(f).iter_messages(log_time_order=True):
            st = stores.get(schema.id)
            if st is None:
                st = get_typestore(Stores.EMPTY)
                st.register(get_types_from_msg(schema.data.decode(), schema.name))
                stores[schema.id] = st
            st.deserialize_cdr(message.data, schema.name)
            n += 1
    return time.process_time() - t, n


def audit_once(path: Path, fret: Path):
    from fretc.audit import AuditConfig, audit_log, load_plan
    from fretc.logs import decoding

    decoding._build_typestore.cache_clear()  # each run builds the log's types, as a new process

    t = time.process_time()
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    t_plan = time.process_time() - t
    t = time.process_time()
    la = audit_log(plan, str(path))
    return t_plan, time.process_time() - t, la


def child_memory(path: Path, fret: Path) -> dict:
    """Audit in a fresh process: its peak RSS; then, in another, the peak of the Python heap
    allocated by the audit itself (tracemalloc, started after the requirements compiled)."""
    out = subprocess.run([sys.executable, __file__, "--child", str(path), str(fret)],
                         capture_output=True, text=True, check=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    out = subprocess.run([sys.executable, __file__, "--child-heap", str(path), str(fret)],
                         capture_output=True, text=True, check=True)
    res.update(json.loads(out.stdout.strip().splitlines()[-1]))
    return res


def _child_cpu(cmd: list) -> float:
    # as installed: bytecode cached (an environment that forbids writing it recompiles every
    # module at each start, which no installed fretc does); one untimed run warms the caches
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run(cmd, capture_output=True, check=False, env=env)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, capture_output=True, check=False, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def command_cpu(log: Path, fret: Path) -> tuple[float, float]:
    """CPU seconds (user + system) of a fresh process doing the plain read, and of the
    ``fretc audit`` command on the same log (start-up and requirement compilation
    included)."""
    plain = _child_cpu([sys.executable, __file__, "--child-plain", str(log)])
    fretc = Path(sys.executable).with_name("fretc")
    cmd = ([str(fretc)] if fretc.exists() else [sys.executable, "-m", "fretc"])
    audit = _child_cpu(cmd + ["audit", "-r", str(fret), str(log), "--no-progress"])
    return plain, audit


def _decoded(path: Path, topics: set) -> dict:
    """Topic -> [(log time, decoded message)], read by mcap + rosbags (not fretc)."""
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    out: dict = {t: [] for t in topics}
    stores: dict = {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(topics=sorted(topics),
                                                                     log_time_order=True):
            st = stores.get(schema.id)
            if st is None:
                st = stores[schema.id] = get_typestore(Stores.EMPTY)
                st.register(get_types_from_msg(schema.data.decode(), schema.name))
            out[channel.topic].append((message.log_time,
                                       st.deserialize_cdr(message.data, schema.name)))
    return out


def pandas_window_verdicts(path: Path, period_ns: int = 100_000_000) -> dict:
    """Requirement -> (verdict, first violation tick ns) of :data:`WINDOW_REQUIREMENTS`
    recomputed by pandas: the tick grid of the requirement's topic (multiples of the period
    from its first message to its last), warm-up until the window starts at or after the
    first message, the time-based rolling window ``(t - span, t]`` at each tick."""
    import math

    import numpy as np
    import pandas as pd

    msgs = _decoded(path, {ref[0] for ref in WINDOW_REFERENCE.values()})
    out = {}
    for req, (topic, value, span, how, holds) in WINDOW_REFERENCE.items():
        mt = np.array([t for t, _m in msgs[topic]], dtype=np.int64)
        mx = [value(m) for _t, m in msgs[topic]]
        ticks = np.arange(-(-mt[0] // period_ns) * period_ns, mt[-1] + 1, period_ns)
        rows = sorted([(int(t), 0, x) for t, x in zip(mt, mx)]
                      + [(int(t), 1, math.nan) for t in ticks])
        df = pd.DataFrame(rows, columns=["t", "tick", "x"])
        df.index = pd.to_datetime(df["t"], unit="ns")
        vals = how(df["x"].rolling(pd.Timedelta(span, "ns"), closed="right", min_periods=0))
        vals = vals[df["tick"].to_numpy() == 1].to_numpy()
        first = next((int(t) for t, x in zip(ticks, vals)
                      if t - span >= mt[0] and not holds(x)), None)
        out[req] = ("violated" if first is not None else "satisfied", first)
    return out


def bench_windows(log: Path, workdir: Path, t_plain: float, repeat: int) -> None:
    """Time the audit of :data:`WINDOW_REQUIREMENTS` on ``log`` (best of ``repeat``), print
    its ratio to the plain read ``t_plain`` (CPU s) and check its verdicts against
    :func:`pandas_window_verdicts` (exits 1 on a difference)."""
    wdir = workdir / "windows"
    wdir.mkdir(exist_ok=True)
    fret = wdir / "windows.fret"
    fret.write_text(WINDOW_REQUIREMENTS)
    (wdir / "windows.bindings.toml").write_text(WINDOW_BINDINGS)
    runs = []
    for _ in range(repeat):
        _t_plan, t_audit, la = audit_once(log, fret)
        runs.append(t_audit)
    got = {v.requirement: (v.verdict, v.first_violation.at.time_ns if v.first_violation
                           else None) for v in la.verdicts}
    want = pandas_window_verdicts(log)
    print(f"fretc audit, 3 window requirements (2 s mean, count per minute, 95th percentile "
          f"over 10 s): {min(runs):.2f} s CPU, ratio to the plain read "
          f"{min(runs) / t_plain:.2f} x")
    for req in sorted(want):
        print(f"  {req}: fretc {got[req][0]} (first violation {got[req][1]}), pandas "
              f"{want[req][0]} ({want[req][1]}): {'equal' if got[req] == want[req] else 'DIFFER'}")
    if got != want:
        sys.exit(1)


ENTITY_REQUIREMENTS = """@tick_period 100 ms
T: in present mode the robot shall always satisfy dist > 1
"""
ENTITY_BINDINGS = """[tick]
period = "100 ms"
[entities]
track = "/tracks.tracks[:].id"
[variables]
dist = 'min(/tracks.tracks[:]{id==$track}.distance)'
present = 'count(/tracks.tracks[:]{id==$track}.distance >= 0) = 1'
"""


PLAIN_BINDINGS = """[tick]
period = "100 ms"
[variables]
dist = 'min(/tracks.tracks[:].distance)'
present = 'count(/tracks.tracks[:].distance >= 0) >= 1'
"""


def bench_entities(workdir: Path, entities: int, repeat: int) -> None:
    """Time the per-entity audit of :data:`ENTITY_REQUIREMENTS` on a log of ``entities``
    obstacles (best of ``repeat``) against the same requirement without entities
    (:data:`PLAIN_BINDINGS`) and the plain read, print the ratios, and check each obstacle's
    verdict against :func:`tracks_run.many_reference` (exits 1 on a difference)."""
    from tracks_run import many_reference, write_many_tracks

    edir = workdir / "entities"
    (edir / "plain").mkdir(parents=True, exist_ok=True)
    log = edir / f"many_tracks_{entities}.mcap"
    if not log.exists():
        write_many_tracks(log, entities)
    fret = edir / "tracks.fret"
    fret.write_text(ENTITY_REQUIREMENTS)
    (edir / "tracks.bindings.toml").write_text(ENTITY_BINDINGS)
    plain_fret = edir / "plain" / "tracks.fret"
    plain_fret.write_text(ENTITY_REQUIREMENTS)
    (edir / "plain" / "tracks.bindings.toml").write_text(PLAIN_BINDINGS)
    reads, plains, runs, kept = [], [], [], None
    for _ in range(repeat):
        # each run from the same state: the previous run's 100,001 verdicts released and
        # collected first (kept alive, every collection of the next run walked them)
        kept = None
        gc.collect()
        reads.append(plain_iteration(log)[0])
        gc.collect()
        plains.append(audit_once(log, plain_fret)[1])
        gc.collect()
        _t_plan, t_audit, kept = audit_once(log, fret)
        runs.append(t_audit)
    la = kept
    want = many_reference(entities, bound=1.0)
    got = {int(v.requirement.split("=")[1][:-1]): v for v in la.verdicts if "[" in v.requirement}
    same = sorted(got) == sorted(want) and all(
        (got[i].verdict == ("violated" if want[i] is not None else "satisfied"))
        and (want[i] is None or got[i].first_violation.at.time_ns == want[i]) for i in want)
    best, plain, read = min(runs), min(plains), min(reads)
    print(f"per-entity requirement over {len(got):,} tracked obstacles ({log.name}, one read): "
          f"{best:.2f} s CPU; without entities {plain:.2f} s (ratio {best / plain:.2f} x); "
          f"the plain read {read:.2f} s (ratio {best / read:.2f} x); verdicts "
          f"{'equal' if same else 'DIFFER from'} the recomputation "
          f"({sum(w is not None for w in want.values()):,} obstacles violated)")
    if not same:
        sys.exit(1)
    fretc = Path(sys.executable).with_name("fretc")
    cmd = ([str(fretc)] if fretc.exists() else [sys.executable, "-m", "fretc"])
    one, without = [], []
    for _ in range(repeat):  # alternated: a machine whose speed drifts slows both alike
        one.append(_child_cpu(cmd + ["audit", "-r", str(fret), str(log), "--no-progress"]))
        without.append(_child_cpu(cmd + ["audit", "-r", str(plain_fret), str(log),
                                         "--no-progress"]))
    print(f"the commands (fretc audit, a fresh process each, start-up included, best of "
          f"{repeat}): {min(one):.2f} s CPU with entities, {min(without):.2f} s without "
          f"(ratio {min(one) / min(without):.2f} x)")


def _arguments() -> argparse.Namespace:
    """The command line (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=5.0, help="length of the timed log")
    ap.add_argument("--memory", type=float, nargs=2, default=(2.0, 10.0), metavar=("A", "B"),
                    help="two log lengths (minutes) whose peak memory is compared")
    ap.add_argument("--workdir", default="/tmp/fretc-bench", help="where logs are kept")
    ap.add_argument("--repeat", type=int, default=3, help="alternated runs of each (best kept)")
    ap.add_argument("--windows", action="store_true",
                    help="only the window requirements: time and pandas check")
    ap.add_argument("--entities", type=int, nargs="?", const=100_000, default=None,
                    metavar="N",
                    help="only the per-entity requirement: time and recomputation check")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    ap.add_argument("--child-plain", help=argparse.SUPPRESS)
    ap.add_argument("--child-heap", nargs=2, help=argparse.SUPPRESS)
    return ap.parse_args()


def main() -> None:
    args = _arguments()
    if args.child_plain:
        plain_iteration(Path(args.child_plain))
        return
    if args.child_heap:
        import tracemalloc

        from fretc.audit import AuditConfig, audit_log, load_plan

        plan = load_plan(AuditConfig(requirements=(args.child_heap[1],)))
        tracemalloc.start()
        audit_log(plan, args.child_heap[0])
        print(json.dumps({"heap_peak_mb": tracemalloc.get_traced_memory()[1] / 2**20}))
        return
    if args.child:
        _, t_audit, la = audit_once(Path(args.child[0]), Path(args.child[1]))
        rss_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print(json.dumps({"ticks": la.ticks_evaluated, "seconds": t_audit,
                          "max_rss_mb": rss_kb / 1024, "engine": la.engine}))
        return
    workdir = Path(args.workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    fret = ensure_requirements(workdir)
    if args.entities:
        bench_entities(workdir, args.entities, args.repeat)
        return
    log = ensure_log(workdir, args.minutes)
    if args.windows:
        t_plain = min(plain_iteration(log)[0] for _ in range(args.repeat))
        print(f"log: {log.name}; plain mcap read + rosbags decode: {t_plain:.2f} s CPU")
        bench_windows(log, workdir, t_plain, args.repeat)
        return

    plains, audits = [], []
    for _ in range(args.repeat):  # alternated, best of each: CPU time is less noisy than wall
        t_plain, n = plain_iteration(log)
        t_plan, t_audit, la = audit_once(log, fret)
        plains.append(t_plain)
        audits.append(t_audit)
    t_plain, t_audit = min(plains), min(audits)
    print(f"\nlog: {log.name}, {n} messages, {la.ticks_evaluated} ticks (engine {la.engine}); "
          f"CPU time, best of {args.repeat}")
    print(f"plain mcap read + rosbags decode of every message: {t_plain:8.2f} s   "
          f"(runs: {', '.join(f'{x:.2f}' for x in plains)})")
    print(f"fretc audit, 10 requirements:                      {t_audit:8.2f} s   "
          f"(runs: {', '.join(f'{x:.2f}' for x in audits)}; + {t_plan:.2f} s compiling the "
          "requirements, once)")
    print(f"ratio audit / plain:                               {t_audit / t_plain:8.2f} x   "
          "(aim <= 0.5x)")
    c_plain, c_audit = command_cpu(log, fret)
    print(f"as commands (fresh processes, start-up included): plain read {c_plain:.2f} s, "
          f"fretc audit {c_audit:.2f} s CPU, ratio {c_audit / c_plain:.2f} x")
    verdicts = ", ".join(f"{v.requirement} {v.verdict}" for v in la.verdicts)
    print(f"verdicts: {verdicts}")
    bench_windows(log, workdir, t_plain, args.repeat)

    print("\npeak memory of a fresh process auditing a log (max RSS):")
    rows = []
    for minutes in args.memory:
        path = ensure_log(workdir, minutes)
        m = child_memory(path, fret)
        rows.append(m)
        print(f"  {minutes:5g} min  {path.stat().st_size / 1e6:7.1f} MB file  {m['ticks']:6d} ticks"
              f"  max RSS {m['max_rss_mb']:7.1f} MB  audit heap peak {m['heap_peak_mb']:6.1f} MB"
              f"  ({m['seconds']:.1f} s, engine {m['engine']})")
    a, b = rows
    print(f"  length x{args.memory[1] / args.memory[0]:g} -> max RSS x"
          f"{b['max_rss_mb'] / a['max_rss_mb']:.2f}, audit heap x"
          f"{b['heap_peak_mb'] / a['heap_peak_mb']:.2f} (messages are streamed; only the "
          "compact per-tick columns grow: 8 B time + 8 B per topic + 1 or 8 B per variable")


if __name__ == "__main__":
    main()
