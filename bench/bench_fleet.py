"""Benchmark of fleet audits: many logs with ``-j 1``, ``-j 2`` and ``--ray``.

    python bench/bench_fleet.py                       # 40 logs of 5 minutes
    python bench/bench_fleet.py --logs 8 --minutes 1  # quick

1. Writes one synthetic Safe-ROS recording of ``--minutes`` minutes
   (``bench/synthetic_run.py``, as ``bench_audit.py``) and ``--logs`` copies of it (in
   ``--workdir``, reused).
2. Times, in one run, the sum of the raw reads (a plain ``mcap`` read + rosbags decode of
   every message of every copy: the floor for anything that reads them, CPU time) and the
   audit of all copies against the 10 requirements of ``bench_audit.py``:

   * in-process: ``audit_logs(jobs=1)``, ``audit_logs(jobs=2)`` and ``audit_logs_ray`` on a
     local Ray of 2 CPUs already started (its start-up is timed apart): wall and CPU time
     (CPU of this process and its reaped children; Ray's workers are not our children, so
     their CPU is not counted - compare wall times for Ray);
   * as commands, start-up included: ``fretc audit -j 2`` and ``fretc audit --ray`` (which
     starts and stops its own local Ray): wall time.

   and asserts that every way gives the same JSON document.
3. Prints the ratios: each to the sum of the raw reads, and ``--ray`` to ``-j 2``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))


def _cpu() -> float:
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def measure(fn):
    """(wall s, CPU s, result) of ``fn()``."""
    w, c = time.perf_counter(), _cpu()
    out = fn()
    return time.perf_counter() - w, _cpu() - c, out


def make_logs(workdir: Path, n: int, minutes: float) -> list[str]:
    from bench_audit import ensure_log

    src = ensure_log(workdir, minutes)
    folder = workdir / f"fleet_{minutes:g}min"
    folder.mkdir(exist_ok=True)
    paths = []
    for i in range(n):
        p = folder / f"run_{i:03d}.mcap"
        if not p.exists() or p.stat().st_size != src.stat().st_size:
            shutil.copyfile(src, p)
        paths.append(str(p))
    return paths


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--logs", type=int, default=40, help="number of logs (N)")
    ap.add_argument("--minutes", type=float, default=5.0, help="minutes per log")
    ap.add_argument("--workdir", default="/tmp/fretc-bench", help="where logs are kept")
    ap.add_argument("--no-commands", action="store_true",
                    help="skip the command-line runs (start-up included)")
    args = ap.parse_args()

    from bench_audit import ensure_requirements, plain_iteration
    from fretc.audit.fleet import ray as fleet
    from fretc.audit import AuditConfig, audit_logs, load_plan
    from fretc.audit.verdict import audit_json

    workdir = Path(args.workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    fret = ensure_requirements(workdir)
    paths = make_logs(workdir, args.logs, args.minutes)
    plan = load_plan(AuditConfig(requirements=(str(fret),)))

    def doc(results) -> str:
        return audit_json(results, plan.requirements_json(), plan.bindings_json())

    raw_cpu = sum(plain_iteration(Path(p))[0] for p in paths)
    print(f"{len(paths)} logs of {args.minutes:g} min ({Path(paths[0]).stat().st_size / 1e6:.1f} MB"
          f" each); 10 requirements; machine: {os.cpu_count()} CPUs")
    print(f"sum of raw reads (mcap read + rosbags decode of every message): {raw_cpu:8.2f} s CPU")
    rows = []
    w1, c1, r1 = measure(lambda: audit_logs(plan, paths, jobs=1))
    reference = doc(r1)
    rows.append(("-j 1", w1, c1))
    w2, c2, r2 = measure(lambda: audit_logs(plan, paths, jobs=2))
    assert doc(r2) == reference, "-j 2 differs from -j 1"
    rows.append(("-j 2", w2, c2))
    ws, cs, started = measure(lambda: fleet.connect(num_cpus=2))
    try:
        wr, cr, rr = measure(lambda: fleet.audit_logs_ray(plan, paths))
        assert doc(rr) == reference, "--ray differs from -j 1"
    finally:
        if started:
            import ray
            ray.shutdown()
    rows.append(("--ray (local, 2 CPUs)", wr, cr))
    print(f"\n{'in-process':24s} {'wall s':>8s} {'CPU s':>8s} {'wall / raw':>11s} "
          f"{'CPU / raw':>10s}")
    for name, w, c in rows:
        cpu_col = f"{c:8.2f}" if not name.startswith("--ray") else "   (n/a)"
        ratio = f"{c / raw_cpu:10.2f}" if not name.startswith("--ray") else "     (n/a)"
        print(f"{name:24s} {w:8.2f} {cpu_col} {w / raw_cpu:11.2f} {ratio}")
    print(f"(local Ray start-up: {ws:.2f} s wall, not included above)")
    print(f"--ray / -j 2 wall time: {wr / w2:.2f} x   (aim <= 1.3x)")
    print("identical JSON: -j 1, -j 2, --ray")

    if args.no_commands:
        return
    fretc = Path(sys.executable).with_name("fretc")
    cmd = [str(fretc)] if fretc.exists() else [sys.executable, "-m", "fretc"]
    base = cmd + ["audit", "-r", str(fret), *paths, "--no-progress"]
    out = {}
    print(f"\n{'command (start-up included)':40s} {'wall s':>8s}")
    for name, extra in (("fretc audit -j 2", ["-j", "2"]), ("fretc audit --ray", ["--ray"])):
        target = workdir / f"fleet_{name.split()[-1].strip('-')}.json"
        # measure calls the lambda at once: extra and target are this iteration's
        w, _c, proc = measure(lambda: subprocess.run(base + extra + ["--json", str(target)],  # noqa: B023
                                                     capture_output=True, text=True))
        if proc.returncode not in (0, 1):
            print(proc.stderr[-2000:])
            raise SystemExit(f"{name} failed with exit code {proc.returncode}")
        out[name] = json.loads(target.read_text())
        print(f"{name:40s} {w:8.2f}")
    assert out["fretc audit -j 2"] == out["fretc audit --ray"] == json.loads(reference)
    print("identical JSON: the commands and the in-process runs")


if __name__ == "__main__":
    main()
