"""Peak memory and CPU of ``fretc audit`` of a long CSV trace, against the C monitors' runner.

    python bench/bench_csv_memory.py                       # 10^6 rows, 2 and 10 requirements
    python bench/bench_csv_memory.py --rows 1000000 10000000 --requirements 2
    python bench/bench_csv_memory.py --rows 1000000 --trace   # where the bytes go (tracemalloc)
    python bench/bench_csv_memory.py --nan first last --no-runner  # one NaN linear_speed
    python bench/bench_csv_memory.py --gap middle --no-runner      # one gap row
    python bench/bench_csv_memory.py --gap middle --cut --no-runner  # and a cut row at the end

1. Writes a plain CSV trace (``time`` in seconds every 100 ms, then the Safe-ROS variables;
   obstacles come and go, the robot stops within 0.5 s, speeds under their limits: every
   requirement satisfied, so the whole trace is judged) of each ``--rows`` (kept in
   ``--workdir`` and reused), and the requirements (2: R2, R4; 10: R1..R6 and four more).
2. Runs, one at a time, ``python -m fretc audit -r REQ.fret TRACE.csv --json -`` under
   ``/usr/bin/time -v`` (peak RSS, user + system CPU of the process, start-up included: the
   requirements judged as the rows are read, :mod:`fretc.audit.streamed`), the same command
   with the whole-trace judge (``fretc.audit.streamed.ENABLED`` off: the columns of every
   tick kept and judged at once, as every audit did before), and the runner of ``fretc
   REQ.fret --emit c`` (``cc -O2``) over the same file, checks that the three give the same
   verdicts and the two audits the same JSON, and prints them and the ratios.
   ``--nan first``/``last``: the same trace with ``linear_speed`` NaN in its first or last
   row (R4 and the others reading it have an unknown tick: judged in three-valued
   semantics, :mod:`fretc.audit.streamed_three`, against the whole-trace three-valued judge).
   ``--gap middle``: the same trace with a ``gap`` row in its middle (a gap tick, one tick
   or more: every requirement judged in three-valued semantics). ``--cut``: a last row of
   ``cut`` cells (the trace cut short: the verdict at a cut reads the obligations still
   open at its last tick, from the columns: known problem KP-001).
3. ``--trace``: the audit in this process under :mod:`tracemalloc`: the peak of Python
   allocations and the 15 largest allocation sites at the peak (numpy arrays included).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

REQUIREMENTS = {
    2: """@tick_period 100 ms
R2: upon too_close agilex_agent shall within 1 second satisfy stopped
R4: the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5
""",
    10: """@tick_period 100 ms
R1: whenever too_close agilex_agent shall eventually satisfy stopped
R2: upon too_close agilex_agent shall within 1 second satisfy stopped
R3: whenever stop_requested cmd_vel_interceptor shall immediately satisfy forwarded_zero
R4: the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5
R5: the scout_mini shall always satisfy clearance > 0
R6: whenever scan_stale safety_system shall within 500 milliseconds satisfy stop_requested
R7: the scout_mini shall always satisfy linear_speed < 0.6
R8: upon stop_requested cmd_vel_interceptor shall at the next timepoint satisfy forwarded_zero
R9: in stop_requested mode the scout_mini shall always satisfy linear_speed <= 0.5
R10: after too_close the safety_system shall eventually satisfy stopped
""",
}
COLUMNS = ["time", "too_close", "stopped", "stop_requested", "forwarded_zero", "linear_speed",
           "angular_speed", "clearance", "scan_stale"]


def write_trace(path: Path, rows: int) -> None:
    """``rows`` ticks 100 ms apart: every 50 ticks an obstacle for 5 ticks, stopped 2 ticks
    after it came until 10 ticks after; a stop requested (and zero forwarded) while too close;
    speeds 0.3 .. 0.45 when moving, clearance 1 .. 2 m, the scan never stale."""
    import numpy as np

    tmp = path.with_suffix(".tmp")
    with open(tmp, "w", encoding="ascii") as f:
        f.write(",".join(COLUMNS) + "\n")
        step = 200_000
        for lo in range(0, rows, step):
            k = np.arange(lo, min(rows, lo + step))
            ph = k % 50
            close = ph < 5
            stopped = (ph >= 2) & (ph < 15)
            speed = np.where(stopped, 0.0, 0.3 + 0.15 * ((k * 7919) % 101) / 100)
            turn = np.where(stopped, 0.0, 0.1 + 0.2 * ((k * 104729) % 97) / 96)
            clear = 1.0 + ((k * 31) % 100) / 100
            b = np.where
            lines = [f"{t / 10:.1f},{c},{s},{c},{c},{v:.3f},{w:.3f},{d:.2f},0"
                     for t, c, s, v, w, d in zip(k.tolist(), b(close, 1, 0).tolist(),
                                                 b(stopped, 1, 0).tolist(), speed.tolist(),
                                                 turn.tolist(), clear.tolist())]
            f.write("\n".join(lines) + "\n")
    tmp.rename(path)


def with_nan(trace: Path, where: str) -> Path:
    """A copy of ``trace`` (beside it, reused) with ``linear_speed`` NaN in its first or
    last row (``where``)."""
    out = trace.with_name(f"{trace.stem}_nan_{where}.csv")
    if out.exists():
        return out
    col = COLUMNS.index("linear_speed")

    def nan(line: str) -> str:
        cells = line.rstrip("\n").split(",")
        cells[col] = "nan"
        return ",".join(cells) + "\n"

    with open(trace, encoding="ascii") as f, open(out, "w", encoding="ascii") as g:
        g.write(f.readline())
        row = f.readline()
        if where == "first":
            g.write(nan(row))
            shutil.copyfileobj(f, g)
        else:
            for nxt in f:
                g.write(row)
                row = nxt
            g.write(nan(row))
    return out


def with_gap(trace: Path) -> Path:
    """A copy of ``trace`` (beside it, reused) with a ``gap`` row between its two middle
    rows (its time between theirs, every other cell ``gap``)."""
    out = trace.with_name(f"{trace.stem}_gap_middle.csv")
    if out.exists():
        return out
    with open(trace, encoding="ascii") as f:
        rows = sum(1 for _ in f) - 1
    with open(trace, encoding="ascii") as f, open(out, "w", encoding="ascii") as g:
        g.write(f.readline())
        for i, line in enumerate(f):
            g.write(line)
            if i == rows // 2:
                t = float(line.split(",", 1)[0]) + 0.05
                g.write(",".join([f"{t:.2f}"] + ["gap"] * (len(COLUMNS) - 1)) + "\n")
    return out


def with_cut(trace: Path) -> Path:
    """A copy of ``trace`` (beside it, reused) ending with a row of ``cut`` cells (its time
    50 ms after the last row's)."""
    out = trace.with_name(f"{trace.stem}_cut.csv")
    if out.exists():
        return out
    last = ""
    with open(trace, encoding="ascii") as f, open(out, "w", encoding="ascii") as g:
        for line in f:
            g.write(line)
            last = line
    with open(out, "a", encoding="ascii") as g:
        t = float(last.split(",", 1)[0]) + 0.05
        g.write(",".join([f"{t:.2f}"] + ["cut"] * (len(COLUMNS) - 1)) + "\n")
    return out


def measured(cmd: list[str], env: dict | None = None) -> tuple[int, float, str, int]:
    """(peak RSS kB, user + system CPU s, stdout, exit status) of ``cmd`` under time -v."""
    got = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True,
                         env=env)
    err = got.stderr
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", err).group(1))
    user = float(re.search(r"User time \(seconds\): ([\d.]+)", err).group(1))
    system = float(re.search(r"System time \(seconds\): ([\d.]+)", err).group(1))
    return rss, user + system, got.stdout, got.returncode


def build_runner(fret: Path, out: Path) -> Path:
    """The C runner of ``fret``'s requirements (``--emit c``, ``cc -O2``)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    if out.exists():
        shutil.rmtree(out)
    subprocess.run([sys.executable, "-m", "fretc", str(fret), "--emit", "c", "-o", str(out)],
                   check=True, env=env, capture_output=True)
    cc = os.environ.get("CC") or shutil.which("cc") or "gcc"
    sources = sorted(str(p) for p in out.glob("*.c"))
    subprocess.run([cc, "-std=c99", "-O2", "-o", str(out / "runner"), *sources, "-lm"],
                   check=True)
    return out / "runner"


#: the command with the whole-trace judge (streaming off), as a user would run it otherwise
_WHOLE = ("import sys, fretc.audit.streamed as s; s.ENABLED = False; "
          "from fretc.cli import main; main(sys.argv[1:])")


def audit_figures(fret: Path, trace: Path, whole: bool = False
                  ) -> tuple[int, float, dict[str, str], str]:
    """(peak RSS kB, CPU s, requirement -> verdict, the JSON) of the audit command."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    head = [sys.executable, "-c", _WHOLE] if whole else [sys.executable, "-m", "fretc"]
    rss, cpu, out, code = measured([*head, "audit", "-r", str(fret), str(trace), "--json",
                                    "-"], env)
    if code not in (0, 1, 3):
        raise SystemExit(f"fretc audit exited {code}")
    doc = json.loads(out)
    verdicts = {v["requirement"]: v["verdict"] for la in doc["logs"] for v in la["verdicts"]}
    for la in doc["logs"]:  # (the time the audit took is no verdict)
        la.pop("elapsed_s", None)
    return rss, cpu, verdicts, json.dumps(doc, sort_keys=True)


def runner_figures(runner: Path, trace: Path) -> tuple[int, float, dict[str, str]]:
    rss, cpu, out, code = measured([str(runner), str(trace)])
    if code not in (0, 1, 3):
        raise SystemExit(f"runner exited {code}")
    return rss, cpu, {ln.split("\t")[0]: ln.split("\t")[1] for ln in out.splitlines() if ln}


def trace_allocations(fret: Path, trace: Path) -> None:
    """The audit under tracemalloc; a thread takes a snapshot whenever the traced memory
    passes its highest so far by 5 %: the largest allocation sites of the last one (near
    the peak)."""
    import threading
    import time
    import tracemalloc

    sys.path.insert(0, str(ROOT / "src"))
    from fretc.audit.config import AuditConfig
    from fretc.audit.log import audit_log
    from fretc.audit.plan import load_plan

    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    tracemalloc.start(4)
    best = [0, None]
    done = threading.Event()

    def watch() -> None:
        while not done.is_set():
            cur = tracemalloc.get_traced_memory()[0]
            if cur > best[0] * 1.05:
                best[:] = [cur, tracemalloc.take_snapshot()]
            time.sleep(0.05)

    th = threading.Thread(target=watch)
    th.start()
    la = audit_log(plan, str(trace))
    done.set()
    th.join()
    _cur, peak = tracemalloc.get_traced_memory()
    print(f"tracemalloc: peak {peak / 1e6:.1f} MB; snapshot at {best[0] / 1e6:.1f} MB "
          f"({[v.verdict for v in la.verdicts]})")
    if best[1] is not None:
        for st in best[1].statistics("traceback")[:15]:
            print(f"  {st.size / 1e6:8.1f} MB  " + " <- ".join(
                f"{Path(f.filename).name}:{f.lineno}" for f in reversed(st.traceback)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[1_000_000])
    ap.add_argument("--requirements", type=int, nargs="+", choices=sorted(REQUIREMENTS),
                    default=[2, 10])
    ap.add_argument("--workdir", default=os.path.join(tempfile.gettempdir(), "fretc-bench-csv"))
    ap.add_argument("--trace", action="store_true", help="tracemalloc instead of the runs")
    ap.add_argument("--no-runner", action="store_true", help="skip the C runner")
    ap.add_argument("--no-whole", action="store_true", help="skip the whole-trace judge")
    ap.add_argument("--nan", nargs="+", choices=["none", "first", "last"], default=["none"],
                    help="a NaN linear_speed in the trace's first or last row")
    ap.add_argument("--gap", choices=["none", "middle"], default="none",
                    help="a gap row in the middle of the trace")
    ap.add_argument("--cut", action="store_true", help="a cut row at the trace's end")
    args = ap.parse_args()
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    print("| rows | NaN | requirements | fretc audit peak RSS | CPU | whole-trace judge peak RSS "
          "| CPU | C runner peak RSS | CPU | peak: audit / whole | audit / C |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for rows, nan in [(r, x) for r in args.rows for x in args.nan]:
        trace = work / f"trace_{rows}.csv"
        if not trace.exists():
            write_trace(trace, rows)
        if nan != "none":
            trace = with_nan(trace, nan)
        if args.gap != "none":
            trace = with_gap(trace)
        if args.cut:
            trace = with_cut(trace)
        for n in args.requirements:
            fret = work / f"req{n}.fret"
            fret.write_text(REQUIREMENTS[n])
            if args.trace:
                trace_allocations(fret, trace)
                continue
            warm = work / "trace_10.csv"  # (the requirements' caches filled, as a user's
            if not warm.exists():         # second run: every measured run alike)
                write_trace(warm, 10)
            audit_figures(fret, warm)
            rss, cpu, verdicts, doc = audit_figures(fret, trace)
            w_rss = w_cpu = c_rss = c_cpu = None
            if not args.no_whole:
                w_rss, w_cpu, w_verdicts, w_doc = audit_figures(fret, trace, whole=True)
                if w_doc != doc:
                    raise SystemExit("the streamed audit's JSON differs from the whole-trace "
                                     "judge's")
            if not args.no_runner:
                runner = build_runner(fret, work / f"c{n}")
                c_rss, c_cpu, c_verdicts = runner_figures(runner, trace)
                if c_verdicts != verdicts:
                    raise SystemExit(f"verdicts differ: audit {verdicts}, runner {c_verdicts}")

            def mb(kb):
                return f"{kb / 1024:.0f} MB" if kb is not None else "-"

            def sec(s):
                return f"{s:.2f} s" if s is not None else "-"

            print(f"| {rows:,} | {nan} | {n} | {mb(rss)} | {sec(cpu)} | {mb(w_rss)} | {sec(w_cpu)} | "
                  f"{mb(c_rss)} | {sec(c_cpu)} | "
                  f"{f'{rss / w_rss:.2f}x' if w_rss else '-'} | "
                  f"{f'{rss / c_rss:.2f}x' if c_rss else '-'} |", flush=True)


if __name__ == "__main__":
    main()
