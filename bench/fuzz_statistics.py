"""The ``statistics`` class of ``bench/fuzz_hostile.py`` (its docstring): hostile fleets, campaigns
and option values against the statistics of probability requirements (``audit/fleet/statistics.py``,
``audit/fleet/intervals.py``, ``sim/sequential.py``, the ``--confidence``, ``--trial``,
``--unknown-runs``, ``--delta``, ``--alpha`` and ``--beta`` options).

Each input is one of:

* ``fleet``: runs of every verdict (errors, unknown runs, vacuous ones, log errors), with
  trigger counts from 0 to a million, unknown, cut and hidden triggers, any bound (``= !=``,
  p of 0, 1 and next to them), confidence, policy and unit; :func:`fleet_statistics`;
* ``campaign``: a stream of runs' trials (0 to a million each, unknown ones) into the SPRT or
  the repeated Clopper-Pearson test with any valid parameters, and ``fretc estimate``'s exit
  code of a campaign whose every run is an error;
* ``options``: ``fretc audit`` of a small fleet and ``fretc estimate`` (into a folder that is
  not empty: no simulation) with hostile option values (NaN, infinities, 1e-9, 0, 1,
  1e309, words).

The oracle: no traceback, no internal error, and never a bound decided that the trials do
not support: a decision is recomputed here from the raw trials, independently (scipy's beta
quantiles at the effective sample size of runs as clusters; Wald's log-likelihood ratio),
for the completion of the unknown outcomes that goes against it, and must stand; an error
run decides no per-trigger bound; one run no per-trigger bound; an ``=`` bound never holds,
a ``!=`` bound never fails; a hostile option value is a usage error (exit 2).
"""

from __future__ import annotations

import math
import random
from pathlib import Path

from fretc.audit.fleet.statistics import fleet_statistics
from fretc.audit.trials import Trials
from fretc.audit.verdict import LogAudit, Verdict
from fretc.compiler.ir import BOUND_OPS, ProbabilityBound

ROOT = Path(__file__).resolve().parents[1]
HOSTILE = ["nan", "NaN", "inf", "-inf", "1e-9", "0", "1", "0.5", "0.95", "0.9999999999",
           "-0.0", "1e309", "abc", "", "0.25", "0.49", "0.499999", "2", "-1", "1e-300"]
SIZES = [0, 1, 1, 2, 3, 5, 10, 50, 10**6]


def _p(rng: random.Random) -> str:
    return rng.choice(["0", "1", "0.5", "0.9", "0.999999", "0.000001", "0.99",
                       f"{rng.random():.6f}"])


def _bound(rng: random.Random) -> ProbabilityBound:
    op = rng.choice(BOUND_OPS)
    p = _p(rng)
    if (op, p) in ((">", "1"), ("<", "0")):
        p = "0.5"
    return ProbabilityBound(op, p)


def _run(rng: random.Random, i: int) -> LogAudit:
    kind = rng.choice(["satisfied", "violated", "vacuous", "unknown", "error", "log", "none"])
    if kind == "log":
        return LogAudit(f"l{i}", error="unreadable", verdicts=[])
    if kind == "none":  # the requirement has no verdict on this log
        return LogAudit(f"l{i}", verdicts=[])
    n = rng.choice(SIZES)
    ok = rng.randint(0, n)
    t = None if kind == "error" or rng.random() < 0.05 else Trials(
        satisfied=ok, violated=n - ok, cut=rng.choice([0, 0, 1, 7]),
        unknown=rng.choice([0, 0, 0, 1, 3, 10**5]), hidden=rng.random() < 0.2)
    return LogAudit(f"l{i}", verdicts=[Verdict(f"l{i}", "P", verdict=kind, trials=t)])


# --------------------------------------------------------------------------- the oracle
def _interval(k: float, m: float, ne: float, confidence: float) -> tuple[float, float]:
    """Clopper-Pearson at ``k/m`` of ``ne`` effective trials, by scipy's beta quantiles."""
    from scipy.stats import beta

    if m == 0:
        return 0.0, 1.0
    ks = ne * k / m
    a = 1 - confidence
    lo = 0.0 if ks <= 0 else float(beta.ppf(a / 2, ks, ne - ks + 1))
    hi = 1.0 if ks >= ne else float(beta.ppf(1 - a / 2, ks + 1, ne - ks))
    return lo, hi


def _decides(op: str, p: float, lo: float, hi: float, eps: float = 1e-9) -> str:
    """The decision of ``OP p`` on ``[lo, hi]``, written out again (a margin ``eps`` kept for
    quantiles computed in another order)."""
    above, below = lo >= p + eps, hi <= p - eps
    if op in (">=", ">"):
        return "holds" if above else "fails" if below else "undecided"
    if op in ("<=", "<"):
        return "holds" if below else "fails" if above else "undecided"
    outside = above or below
    return ("holds" if op == "!=" else "fails") if outside else "undecided"


def _either(op: str, p: float, lo: float, hi: float) -> set[str]:
    """The decisions of ``OP p`` on ``[lo, hi]`` within a rounding margin either way."""
    return {_decides(op, p, lo, hi, 1e-9), _decides(op, p, lo, hi, -1e-9)}


def _raw(logs: list, policy: str, trial: str):
    """``(runs, blind)``: per run ``(k, n, u)`` as the policy and unit count them, and the
    runs that give no trigger counts."""
    runs, blind = [], 0
    for la in logs:
        v = None if la.error else next((x for x in la.verdicts if x.requirement == "P"), None)
        if v is not None and v.verdict == "error":
            v = None
        if trial == "run":
            verdict = "error" if v is None else v.verdict
            if verdict in ("satisfied", "vacuous", "violated"):
                runs.append((int(verdict != "violated"), 1, 0))
            elif policy != "exclude":
                runs.append((0, 0, 1))
            continue
        t = None if v is None else v.trials
        if t is None:
            blind += 1
            continue
        runs.append((t.satisfied, t.trials, t.unknown if policy != "exclude" else 0))
    return [r for r in runs if r[1] + r[2]], blind


def check_fleet(rng: random.Random) -> list[str]:
    """One hostile fleet (module docstring); the problems found."""
    logs = [_run(rng, i) for i in range(rng.choice([0, 1, 2, 3, 5, 20, 60]))]
    b = _bound(rng)
    conf = rng.choice([0.5, 0.95, 0.999999, 0.5 + rng.random() / 2.0001])
    policy = rng.choice(["worst-case", "exclude", "fail"])
    trial = rng.choice(["trigger", "run"])
    (st,) = fleet_statistics(logs, {"P": b}, conf, policy, trial)
    lo, hi = st.interval
    bad = []
    if not (0 <= lo <= hi <= 1) or (st.estimate is not None and not 0 <= st.estimate <= 1):
        bad.append(f"interval {st.interval} or estimate {st.estimate} out of [0, 1]")
    if st.verdict not in ("holds", "fails", "undecided"):
        bad.append(f"verdict {st.verdict!r}")
    if st.verdict == "undecided":
        return bad
    runs, blind = _raw(logs, policy, trial)
    where = f"{b.op} {b.text}, {policy}, {trial}, {len(runs)} runs"
    if trial == "trigger" and ((blind and policy != "exclude") or len(runs) < 2):
        bad.append(f"{st.verdict} per trigger with {blind} runs not judged, {len(runs)} "
                   f"with trials ({where})")
    if (b.op, st.verdict) in (("=", "holds"), ("!=", "fails")):
        bad.append(f"'{b.op}' decided {st.verdict}")
    m = sum(n + u for _, n, u in runs)
    ne = m * m / sum((n + u) ** 2 for _, n, u in runs) if runs else 0
    for fill in (0, 1):  # the unknown outcomes all failures, all successes
        k = sum(k + fill * u for k, _, u in runs)
        d = _either(b.op, b.p, *_interval(k, m, ne, conf))
        if st.verdict not in d:
            bad.append(f"{st.verdict}, but with the unknown trials {'met' if fill else 'failed'}"
                       f" the trials say {d} ({where})")
    return bad


def _llr(counts: list, fill: int, win: float, loss: float) -> float:
    """Wald's log-likelihood ratio at the effective sample size, written out again."""
    m = sum(n + u for _, n, u in counts)
    if m == 0:
        return 0.0
    ne = m * m / sum((n + u) ** 2 for _, n, u in counts if n + u)
    q = sum(k + fill * u for k, _, u in counts) / m
    s = (q * win if q else 0.0) + ((1 - q) * loss if q < 1 else 0.0)
    return ne * s


def check_campaign(rng: random.Random) -> list[str]:
    """One hostile campaign (module docstring); the problems found."""
    from fretc.sim.sequential import SPRT, SequentialCP

    b = _bound(rng)
    delta = rng.choice([0.5, 0.05, 1e-6, rng.uniform(1e-9, 0.5)])
    alpha, beta = (rng.choice([0.4999, 0.05, 1e-9, rng.uniform(1e-9, 0.4999)]) for _ in "ab")
    test = (SPRT(b.op, b.p, delta, alpha, beta) if rng.random() < 0.6
            else SequentialCP(b.op, b.p, alpha))
    seen = []
    for _ in range(rng.choice([1, 5, 40, 300])):
        n = rng.choice(SIZES)
        obs = (rng.randint(0, n), n, rng.choice([0, 0, 0, 1, 50]))
        seen.append(obs)
        if test.observe(*obs) is not None:
            break
    d = test.decision
    bad = []
    if d is None:
        return bad
    if (b.op, d) in (("=", "holds"), ("!=", "fails")) or (test.name == "sprt"
                                                         and b.op in ("=", "!=")):
        bad.append(f"{test.name} decided {d} of '{b.op}'")
    if test.name == "sprt":
        ratios = [_llr(seen, f, test.win, test.loss) for f in (0, 1)]
        ok = (min(ratios) >= test.upper - 1e-9 if d == "holds"
              else max(ratios) <= test.lower + 1e-9)
        if not ok:
            bad.append(f"sprt {d} at run {test.at} with ratios {ratios} "
                       f"(thresholds {test.lower}, {test.upper})")
    else:
        err = alpha / 2 ** test.looks
        m = sum(n + u for _, n, u in seen)
        ne = m * m / sum((n + u) ** 2 for _, n, u in seen if n + u) if m else 0
        for fill in (0, 1):
            k = sum(k + fill * u for k, _, u in seen)
            got = _either(b.op, b.p, *_interval(k, m, ne, 1 - err))
            if d not in got:
                bad.append(f"cp {d} at run {test.at}; unknown trials "
                           f"{'met' if fill else 'failed'}: {got}")
    return bad


def check_errors_campaign() -> list[str]:
    """A campaign whose every run is an error is an error (exit 2), whatever its bound."""
    from fretc.reports.estimate import exit_code_of

    doc = {"statistics": [{"id": "P", "verdict": "holds", "bound": {"op": "<=", "p": 0.5},
                           "violated": 0, "error": 24}],
           "errors": [{"run": i, "requirement": "P", "error": "x"} for i in range(24)]}
    return [] if exit_code_of(doc) == 2 else ["a campaign of errors does not exit 2"]


# --------------------------------------------------------------------------- options
def _fleet_dir(tmp: Path) -> Path:
    d = tmp / "stat_fleet"
    if not d.exists():
        (d / "runs").mkdir(parents=True)
        (d / "p.fret").write_text("P: upon c the robot shall with probability >= 0.5 within "
                                  "1 ticks satisfy r\n")
        for i in range(3):
            rows = ["c,r", "0,0", "1,0", f"0,{int(i != 2)}", "0,0"]  # run 2 misses
            (d / "runs" / f"r{i}.csv").write_text("\n".join(rows) + "\n")
        (d / "out").mkdir()
        (d / "out" / "x").write_text("not empty")
    return d


def _valid(option: str, value: str) -> bool:
    try:
        x = float(value)
    except ValueError:
        return False
    if not math.isfinite(x):
        return False
    if option == "--confidence":
        return 0.5 <= x < 1
    if option == "--delta":
        return 0 < x <= 0.5
    return 0 < x < 0.5


def check_options(rng: random.Random, tmp: Path) -> list[str]:
    """``fretc audit`` or ``fretc estimate`` with a hostile option value."""
    from click.testing import CliRunner

    from fretc.cli import main

    d = _fleet_dir(tmp)
    value = rng.choice(HOSTILE)
    if rng.random() < 0.5:
        option = "--confidence"
        args = ["audit", "-r", str(d / "p.fret"), str(d / "runs"), "--no-progress",
                option, value, "--trial", rng.choice(["trigger", "run"]),
                "--unknown-runs", rng.choice(["worst-case", "exclude", "fail"])]
        allowed = {0, 1, 3, 5}
    else:
        option = rng.choice(["--confidence", "--delta", "--alpha", "--beta"])
        args = ["estimate", "-r", str(ROOT / "requirements" / "r1.fret"), "--space",
                str(ROOT / "sim" / "spaces" / "interceptor_delay.toml"), "-o",
                str(d / "out"), option, value]
        allowed = {2}  # the folder is not empty: refused before any run
    res = CliRunner().invoke(main, args)
    bad = []
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        bad.append(f"{args[0]} {option} {value!r}: {type(res.exception).__name__}: "
                   f"{res.exception}")
    elif not _valid(option, value):
        if res.exit_code != 2 or f"Invalid value for '{option}'" not in res.output:
            bad.append(f"{args[0]} {option} {value!r}: exit {res.exit_code}, not a usage "
                       f"error: {res.output[-300:]!r}")
    elif res.exit_code not in allowed:
        bad.append(f"{args[0]} {option} {value!r}: exit {res.exit_code}: "
                   f"{res.output[-300:]!r}")
    return bad


def run_statistics(rng: random.Random, tmp: Path) -> list[str]:
    """One input of the class (module docstring): the problems found (tracebacks raise)."""
    kind = rng.choices(["fleet", "campaign", "options", "errors"], [10, 10, 2, 1])[0]
    if kind == "fleet":
        return check_fleet(rng)
    if kind == "campaign":
        return check_campaign(rng)
    if kind == "errors":
        return check_errors_campaign()
    return check_options(rng, tmp)
