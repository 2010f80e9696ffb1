"""Benchmark of the robustness behind every verdict (:mod:`fretc.monitors.robustness`):
what it adds to ``fretc audit``.

    python bench/bench_robustness.py            # the shipped traces/, 3 repetitions

In one run: the CPU time of auditing every log of ``traces/`` against ``requirements/``
(``audit.audit_log``) as shipped, and with the judge's robustness switched off
(patched to nothing, the audit as before robustness), and their ratio; then the CPU time of
the command a user runs (``fretc audit requirements traces``, start-up included, a fresh
process).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))


def _audit_cpu(plan, logs, reps: int) -> float:
    from fretc.audit import audit_log
    best = float("inf")
    for _ in range(reps):
        t0 = time.process_time()
        for p in logs:
            audit_log(plan, str(p))
        best = min(best, time.process_time() - t0)
    return best


def main() -> None:
    """Print the CPU times and the ratio (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    from fretc.audit import AuditConfig, load_plan
    from fretc.monitors import judge as judge_mod

    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))
    logs = sorted((ROOT / "traces").glob("*.mcap"))
    _audit_cpu(plan, logs[:1], 1)  # warm-up: generated monitors, caches
    with_rob = _audit_cpu(plan, logs, args.reps)
    real = judge_mod.robustness
    judge_mod.robustness = lambda *a, **k: None
    try:
        without = _audit_cpu(plan, logs, args.reps)
    finally:
        judge_mod.robustness = real
    print(f"audit of {len(logs)} logs x {len(plan.requirements)} requirements (best of "
          f"{args.reps}, CPU): with robustness {with_rob:.3f} s, without {without:.3f} s, "
          f"ratio {with_rob / without:.3f}x")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-m", "fretc.cli", "audit", "--no-progress", "-r",
                    str(ROOT / "requirements"), str(ROOT / "traces")],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    print(f"fretc audit requirements traces (fresh process, start-up included): "
          f"{cpu:.3f} s CPU")


if __name__ == "__main__":
    main()
