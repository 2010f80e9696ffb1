"""R2U2's C engine (on fretc's ``--emit c2po``, compiled by C2PO) beside fretc's C monitors
(``--emit c``, its generated ``runner.c``, ``cc -O2``): CPU time per step of each, as
whole processes reading the same trace from a CSV file, measured in one run.

    python bench/bench_r2u2.py [-r requirements/safe_ros.fret] [--trace traces/nominal.csv]
                               [--ticks 200000] [--repeat 3]

The trace's ticks (``bench_c_monitors.read_trace``) are repeated to ``--ticks`` rows and
written twice, in each program's CSV dialect (R2U2: a ``#`` header, Booleans 0/1, numbers
with a decimal point; the runner: a header row, the same cells). Each program is run on it
and on its first row alone (its start-up: loading the specification or nothing, the first
read, the output); CPU time is user + system of the child (``os.wait4``), the least of
``--repeat`` runs. Per step = (CPU on the trace - CPU on one row) / ticks. R2U2 writes a
verdict line per formula and tick (to /dev/null here), fretc's runner one line per
requirement at the end: both are counted, as a user of either program pays them.

Before timing, R2U2's verdict at every tick of the first 2,000 rows is checked equal to
fretc's Python monitors' pt verdict, and its verdict at the last row to the runner's
(satisfied or vacuous: true). Requirements whose formula has ``S`` or ``T`` are left out
(R2U2's ``S`` and ``T`` are wrong at the pinned commit: tests/_r2u2.py ``SINCE_DEFECT``).
Needs ``tools/r2u2/build.sh`` and a C compiler.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "bench"))

from _c_monitors import c_compiler  # noqa: E402
from _monitor_helpers import load_source  # noqa: E402
from _r2u2 import (compile_batches, locate, per_tick, read_spec, run,  # noqa: E402
                   write_trace)
from bench_c_monitors import read_trace  # noqa: E402

#: ticks whose R2U2 verdicts are checked against the Python monitors before timing
CHECKED_TICKS = 2000


def cpu_seconds(cmd: list[str]) -> float:
    """User + system CPU seconds of running ``cmd`` (stdout to /dev/null); RuntimeError if
    it exits with a status other than 0 to 3 (the runner's verdict statuses)."""
    with open(os.devnull, "wb") as null:
        proc = subprocess.Popen(cmd, stdout=null, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        err = proc.stderr.read().decode() if proc.stderr else ""
        if proc.stderr:
            proc.stderr.close()
    if proc.returncode not in (0, 1, 3):
        raise RuntimeError(f"{cmd[0]} exit {proc.returncode}: {err[-400:]}")
    return usage.ru_utime + usage.ru_stime


def runner_csv(path: Path, names: list[str], states: list[dict]) -> None:
    """fretc's runner CSV of ``states``: a header row of ``names``, Booleans 0/1, numbers as
    Python writes floats."""
    rows = [",".join(names)]
    for s in states:
        rows.append(",".join(str(int(s[n])) if isinstance(s[n], bool) else repr(float(s[n]))
                             for n in names))
    path.write_text("\n".join(rows) + "\n")


def build_runner(fret: Path, folder: Path) -> Path:
    """``fretc FRET --emit c -o folder`` built with ``cc -std=c99 -O2`` (runner.c's own
    command): the runner's path."""
    subprocess.run([sys.executable, "-m", "fretc", "compile", str(fret), "--emit", "c", "-o",
                    str(folder)], check=True, capture_output=True)
    sources = sorted(str(p) for p in folder.glob("*.c"))
    exe = folder / "runner"
    subprocess.run([c_compiler() or "cc", "-std=c99", "-O2", "-o", str(exe), *sources, "-lm"],
                   check=True)
    return exe


def check(tool, spec, batch, py, states, folder: Path, runner: Path, names) -> None:
    """R2U2 against the Python monitors at every tick of the first :data:`CHECKED_TICKS`
    rows, and against the runner's final verdicts on the whole trace (module docstring)."""
    binary, ids = batch
    head = states[:CHECKED_TICKS]
    write_trace(folder / "head.csv", spec, head)
    for i, stream in run(tool, binary, folder / "head.csv").items():
        m = py.MONITORS[ids[i]]()
        assert per_tick(stream, len(head)) == [bool(m.step(s)) for s in head], ids[i]
    last = {ids[i]: per_tick(s, len(states))[-1]
            for i, s in run(tool, binary, folder / "r2u2.csv").items()}
    runner_csv(folder / "runner.csv", names, states)
    out = subprocess.run([str(runner), str(folder / "runner.csv")], capture_output=True,
                         text=True).stdout
    words = dict(line.split("\t")[:2] for line in out.splitlines() if "\t" in line)
    for rid, verdict in last.items():
        assert verdict == (words[rid] in ("satisfied", "vacuous")), (rid, words[rid])


def measure(cmds: dict, repeat: int) -> dict:
    """``{name: (start-up s, whole s)}``: the least CPU of ``repeat`` runs of each
    ``name: (command on one row, command on the trace)``."""
    out = {}
    for name, (one, whole) in cmds.items():
        out[name] = (min(cpu_seconds(one) for _ in range(repeat)),
                     min(cpu_seconds(whole) for _ in range(repeat)))
    return out


def setup(args, folder: Path):
    """The trace, fretc's C2PO text read apart and compiled by C2PO (one binary), the Python
    monitors and the runner: what :func:`main` times."""
    tool = locate()
    if tool is None or c_compiler() is None:
        raise SystemExit("R2U2 not built (run tools/r2u2/build.sh) or no C compiler")
    base = read_trace(Path(args.trace))
    states = [base[i % len(base)] for i in range(args.ticks)]
    fret = Path(args.requirements)
    subprocess.run([sys.executable, "-m", "fretc", "compile", str(fret), "--emit", "c2po",
                    "-o", str(folder / "spec.c2po")], check=True, capture_output=True)
    subprocess.run([sys.executable, "-m", "fretc", "compile", str(fret), "--emit", "monitor",
                    "-o", str(folder / "monitors.py")], check=True, capture_output=True)
    spec = read_spec((folder / "spec.c2po").read_text())
    labels = [x for x in spec.entries if not spec.since_or_trigger(x)]
    (batch,) = compile_batches(tool, spec, args.ticks, folder / "c2po", labels,
                               size=len(labels))
    py = load_source((folder / "monitors.py").read_text())
    runner = build_runner(fret, folder / "c")
    return tool, spec, batch, py, states, runner, labels


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-r", "--requirements", default=str(ROOT / "requirements/safe_ros.fret"))
    ap.add_argument("--trace", default=str(ROOT / "traces/nominal.csv"))
    ap.add_argument("--ticks", type=int, default=200_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        tool, spec, batch, py, states, runner, labels = setup(args, folder)
        names = [spec.fret_names[s] for s, _ in spec.signals]
        write_trace(folder / "r2u2.csv", spec, states)
        write_trace(folder / "r2u2_one.csv", spec, states[:1])
        check(tool, spec, batch, py, states, folder, runner, names)
        runner_csv(folder / "runner_one.csv", names, states[:1])
        got = measure({
            "R2U2: C engine, C2PO binary": (
                [str(tool.engine), str(batch[0]), str(folder / "r2u2_one.csv")],
                [str(tool.engine), str(batch[0]), str(folder / "r2u2.csv")]),
            "C monitors: --emit c runner, cc -O2": (
                [str(runner), str(folder / "runner_one.csv")],
                [str(runner), str(folder / "runner.csv")])}, args.repeat)
    print(f"{Path(args.requirements).name}: {', '.join(labels)} ({len(labels)} formulas); "
          f"trace {Path(args.trace).name} repeated to {args.ticks} ticks; R2U2 "
          f"{tool.commit[:10]}; CPU time (user+sys), least of {args.repeat} runs")
    print(f"{'':36} {'start-up':>10} {'whole run':>10} {'per step':>10}")
    per = {}
    for name, (one, whole) in got.items():
        per[name] = (whole - one) / args.ticks
        print(f"{name:36} {one * 1e3:8.2f}ms {whole:9.3f}s {per[name] * 1e6:8.3f}µs")
    (r2u2, fretc), (whole_r2u2, whole_fretc) = per.values(), [w for _, w in got.values()]
    print(f"ratio R2U2 / fretc C: {r2u2 / fretc:.1f}x per step, "
          f"{whole_r2u2 / whole_fretc:.1f}x whole run")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
