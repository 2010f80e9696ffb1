"""The measured figures of docs/guide/statistics.md ("Measured"), one section per argument:

    python bench/statistics/figures.py fleet      # 630 of 1,000 CSV runs: interval vs scipy
    python bench/statistics/figures.py estimate   # fretc estimate of R2p (SPRT), CPU time
    python bench/statistics/figures.py crude FILE # the crude Monte Carlo lines of crude_mc.py
    python bench/statistics/figures.py analytic   # --rare's splitting at 1e-5 vs closed form
    python bench/statistics/figures.py rare-sim   # --rare on C10 (about 1e-2) vs crude MC

CPU times are of this process and its children (``resource.getrusage``).
"""

from __future__ import annotations

import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
HERE = Path(__file__).resolve().parent
SPACE = ROOT / "sim" / "spaces" / "interceptor_delay.toml"
BINDINGS = ROOT / "requirements" / "safe_ros.bindings.toml"


def _cpu() -> float:
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def _fretc(*args: str) -> tuple[int, float, float]:
    cpu0, wall0 = _cpu(), time.time()
    rc = subprocess.run([sys.executable, "-m", "fretc", *args], cwd=ROOT,
                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    return rc, _cpu() - cpu0, time.time() - wall0


def fleet() -> None:
    from scipy.stats import binomtest
    d = Path(tempfile.mkdtemp(prefix="fleet-"))
    (d / "runs").mkdir()
    for i in range(1000):
        (d / "runs" / f"run{i:04d}.csv").write_text("ok\n1\n1\n" + ("1\n" if i < 630 else "0\n"))
    ci = binomtest(630, 1000).proportion_ci(method="exact")
    for p in ("0.5", "0.7"):
        (d / "p.fret").write_text(f"P1: the robot shall with probability >= {p} always satisfy ok\n")
        rc, cpu, wall = _fretc("audit", "-r", str(d / "p.fret"), str(d / "runs"), "--no-progress",
                               "--json", str(d / "a.json"))
        st = json.loads((d / "a.json").read_text())["statistics"][0]
        err = max(abs(st["interval"][0] - ci.low), abs(st["interval"][1] - ci.high))
        print(f"fleet >= {p}: exit {rc}, estimate {st['estimate']}, interval {st['interval']}, "
              f"|diff to scipy| {err:.1e}, verdict {st['verdict']}, CPU {cpu:.1f} s, wall {wall:.1f} s")


def estimate() -> None:
    out = Path(tempfile.mkdtemp(prefix="estimate-")) / "out"
    rc, cpu, wall = _fretc("estimate", "-r", str(HERE / "r2_p90.fret"), "-b", str(BINDINGS),
                           "--space", str(SPACE), "--seed", "1", "-o", str(out))
    doc = json.loads((out / "estimate.json").read_text())
    st = doc["statistics"][0]
    print(f"estimate R2p: exit {rc}, {doc['runs_used']} runs, estimate {st['estimate']:.4f}, "
          f"interval [{st['interval'][0]:.4f}, {st['interval'][1]:.4f}], verdict {st['verdict']}, "
          f"CPU {cpu:.1f} s, wall {wall:.1f} s ({out})")


def crude(path: str) -> None:
    from scipy.stats import binomtest
    rows = [json.loads(line) for line in open(path, encoding="utf-8")]
    n = len(rows)
    k = sum(r["verdicts"]["R2p"] in ("satisfied", "vacuous") for r in rows)
    ci = binomtest(k, n).proportion_ci(method="exact")
    print(f"crude R2p: {k}/{n} satisfied = {k / n:.4f}, interval [{ci.low:.4f}, {ci.high:.4f}]")
    c = sum(isinstance(r["robustness"]["R5"], float) and r["robustness"]["R5"] < 0.1 for r in rows)
    ci = binomtest(c, n).proportion_ci(method="exact")
    print(f"crude C10 (clearance below 0.1 m): {c}/{n} = {c / n:.4f}, "
          f"interval [{ci.low:.4f}, {ci.high:.4f}]")


def analytic(seeds: int = 20) -> None:
    from scipy.stats import norm

    from fretc.sim.splitting import adaptive_multilevel_splitting
    p = 1e-5
    c = float(norm.isf(p))

    def f(zs):
        return [c - (z[0] + z[1]) / math.sqrt(2) for z in zs]

    cpu0 = _cpu()
    res = [adaptive_multilevel_splitting(f, 2, s, particles=200, kill=20, moves=5)
           for s in range(seeds)]
    est = sorted(r.estimate for r in res)
    rel = sum(r.relative_error for r in res) / seeds
    emp = (sum((r.estimate - p) ** 2 for r in res) / seeds) ** 0.5 / p
    samples = sum(r.samples for r in res) / seeds
    crude = (1 - p) / (p * rel ** 2)
    inside = sum(r.interval[0] <= p <= r.interval[1] for r in res)
    print(f"analytic p = 1e-5, {seeds} seeds: estimates {est[0]:.3g} .. {est[-1]:.3g} (median "
          f"{est[seeds // 2]:.3g}), within a factor 2: {sum(p / 2 <= e <= 2 * p for e in est)}/"
          f"{seeds}; relative error stated {rel:.3f}, measured {emp:.3f}; interval covers p: "
          f"{inside}/{seeds}; samples {samples:.0f} vs crude {crude:.3g} for the same relative "
          f"error ({crude / samples:.0f}x); CPU {(_cpu() - cpu0) / seeds:.2f} s per run")


def rare_sim() -> None:
    out = Path(tempfile.mkdtemp(prefix="rare-")) / "out"
    rc, cpu, wall = _fretc("estimate", "--rare", "-r", str(HERE / "c10.fret"), "-b",
                           str(BINDINGS), "--space", str(SPACE), "--seed", "1", "--particles",
                           "50", "--kill", "10", "--moves", "3", "--budget", "2000", "-o",
                           str(out))
    doc = json.loads((out / "estimate.json").read_text())
    r = doc["rare"]["requirements"]["C10"]
    print(f"rare C10: exit {rc}, estimate {r['estimate']:.4g}, relative error "
          f"{r['relative_error']:.3g}, interval [{r['interval'][0]:.4g}, {r['interval'][1]:.4g}], "
          f"{len(r['levels'])} levels, {r['samples']} runs, acceptance {r['acceptance']:.2f}, "
          f"CPU {cpu:.1f} s, wall {wall:.1f} s ({out})")


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else ""
    {"fleet": fleet, "estimate": estimate, "analytic": analytic, "rare-sim": rare_sim,
     "crude": lambda: crude(sys.argv[2])}.get(what, lambda: print(__doc__))()
