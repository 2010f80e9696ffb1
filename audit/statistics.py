"""Fleet statistics: per requirement, how the runs of an audit of several logs came out, the
estimate of P(satisfied) with its exact (Clopper-Pearson) interval, and for a requirement
``with probability OP p`` the statistical verdict.

Counting (one run = one log): ``satisfied`` and ``vacuous`` runs satisfy the requirement
(FRET's vacuous verdict is a satisfied one); ``violated`` runs do not; ``unknown`` runs
(damaged logs that decide nothing) and ``error`` runs (not audited) are never counted as
satisfied. The ``unknown`` policy says what they are: ``"fail"`` (the default, a conservative
bound: each counts as a run that did not satisfy) or ``"exclude"`` (left out of the count,
which assumes they fail and succeed at the fleet's rate).

Interval: scipy's exact binomial interval (``scipy.stats.binomtest(k, n)
.proportion_ci(confidence_level, method="exact")``, Clopper & Pearson 1934), two-sided at
``confidence``. Statistical verdict of ``OP p`` (``>=``/``>``: the rate must be at least /
above p; ``<=``/``<`` at most / below):

* ``holds``: the whole interval is on the bound's side of p;
* ``fails``: the whole interval is on the other side;
* ``undecided``: p is inside the interval; ``more_runs`` is the smallest number of further
  runs after which the interval would exclude p if the observed rate stayed the same (None
  when the rate equals p, or ``=`` bounds: no finite number of runs confirms an equality).

The independence assumption: the interval is only right when the runs are independent
draws from one distribution of operating conditions (docs/guide/statistics.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["RequirementStatistics", "fleet_statistics", "plan_statistics", "clopper_pearson", "decide",
           "more_runs", "UNKNOWN_POLICIES", "STAT_VERDICTS"]

UNKNOWN_POLICIES = ("fail", "exclude")
STAT_VERDICTS = ("holds", "fails", "undecided")
#: further runs are searched up to this many (beyond it: None, "more than")
MAX_MORE_RUNS = 10**9


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The exact two-sided interval ``(lo, hi)`` of a binomial proportion with ``k``
    successes in ``n`` trials at ``confidence`` (in (0, 1)), by scipy (Clopper & Pearson
    1934). ``n == 0``: ``(0.0, 1.0)``. Raises ``ValueError`` for ``k`` outside [0, n] or
    a confidence outside (0, 1)."""
    if not 0 < confidence < 1:
        raise ValueError(f"confidence {confidence} is not in (0, 1)")
    if n == 0:
        return 0.0, 1.0
    if not 0 <= k <= n:
        raise ValueError(f"{k} successes in {n} trials")
    from scipy.stats import binomtest  # lazy: scipy only when statistics are asked

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence, method="exact")
    return float(ci.low), float(ci.high)


def decide(op: str, p: float, lo: float, hi: float) -> str:
    """The statistical verdict of the bound ``OP p`` given an interval ``[lo, hi]``
    (module docstring): ``holds``, ``fails`` or ``undecided``."""
    if op == ">=":
        return "holds" if lo >= p else "fails" if hi < p else "undecided"
    if op == ">":
        return "holds" if lo > p else "fails" if hi <= p else "undecided"
    if op == "<=":
        return "holds" if hi <= p else "fails" if lo > p else "undecided"
    if op == "<":
        return "holds" if hi < p else "fails" if lo >= p else "undecided"
    outside = p < lo or p > hi
    if op == "!=":  # shown when p is outside; never refuted (no sample confirms P = p)
        return "holds" if outside else "undecided"
    # "=": an equality is never confirmed by sampling; refuted when p is outside
    return "fails" if outside else "undecided"


def more_runs(op: str, p: float, k: int, n: int, confidence: float) -> int | None:
    """The smallest number ``m`` of further runs after which :func:`decide` would no
    longer say ``undecided``, if ``k/n`` of them satisfied as before (``round``ed counts);
    None when that never happens (the observed rate equals p, an ``=`` bound, no runs) or
    it takes more than :data:`MAX_MORE_RUNS`."""
    if n == 0 or op == "=" or k / n == p:
        return None
    rate = k / n

    def decided(m: int) -> bool:
        total = n + m
        lo, hi = clopper_pearson(min(total, round(rate * total)), total, confidence)
        return decide(op, p, lo, hi) != "undecided"

    hi_m = 1
    while not decided(hi_m):
        hi_m *= 2
        if hi_m > MAX_MORE_RUNS:
            return None
    lo_m = hi_m // 2  # undecided at lo_m (or 0), decided at hi_m
    while hi_m - lo_m > 1:
        mid = (lo_m + hi_m) // 2
        if decided(mid):
            hi_m = mid
        else:
            lo_m = mid
    return hi_m


@dataclass
class RequirementStatistics:
    """One requirement over the runs of an audit.

    Attributes:
        id: the requirement's id.
        runs: logs audited for it; ``satisfied``, ``vacuous``, ``violated``, ``unknown``,
            ``error``: the runs of each verdict (they add up to ``runs``).
        successes, trials: the binomial counts used (``satisfied + vacuous`` of ``trials``
            runs: the judged runs, plus ``unknown + error`` under the ``fail`` policy).
        estimate: ``successes / trials`` (None without trials); ``interval``: the
            Clopper-Pearson interval ``[lo, hi]`` at ``confidence``.
        unknown_policy: ``fail`` or ``exclude`` (module docstring).
        bound: ``{"op", "p"}`` of a probability requirement, else None; ``verdict``:
            ``holds`` / ``fails`` / ``undecided`` for those (None otherwise);
            ``more_runs``: for ``undecided``, further runs that would decide it at the
            observed rate; ``why``: a sentence for ``undecided``.
    """

    id: str
    runs: int = 0
    satisfied: int = 0
    vacuous: int = 0
    violated: int = 0
    unknown: int = 0
    error: int = 0
    successes: int = 0
    trials: int = 0
    estimate: float | None = None
    interval: tuple[float, float] = (0.0, 1.0)
    confidence: float = 0.95
    unknown_policy: str = "fail"
    bound: dict[str, Any] | None = None
    verdict: str | None = None
    more_runs: int | None = None
    why: str | None = None

    def to_json(self) -> dict:
        """The object of the audit JSON's ``statistics`` list (docs/reference/audit-json.md):
        every attribute, ``interval`` as ``[lo, hi]``."""
        return {"id": self.id, "runs": self.runs, "satisfied": self.satisfied,
                "vacuous": self.vacuous, "violated": self.violated, "unknown": self.unknown,
                "error": self.error, "successes": self.successes, "trials": self.trials,
                "estimate": self.estimate, "interval": [self.interval[0], self.interval[1]],
                "confidence": self.confidence, "unknown_policy": self.unknown_policy,
                "bound": self.bound, "verdict": self.verdict, "more_runs": self.more_runs,
                "why": self.why}


def judge_counts(st: RequirementStatistics, op: str | None, p: float | None) -> None:
    """Fill ``st``'s estimate, interval and (with a bound ``op p``) verdict from its counts
    (``successes`` of ``trials``); shared by the fleet audit and ``fretc estimate``."""
    k, n = st.successes, st.trials
    st.estimate = k / n if n else None
    st.interval = clopper_pearson(k, n, st.confidence)
    if op is None:
        return
    st.bound = {"op": op, "p": p}
    st.verdict = decide(op, p, *st.interval)
    if st.verdict != "undecided":
        return
    if n == 0:
        st.why = "no run was judged: no estimate"
        return
    st.more_runs = more_runs(op, p, k, n, st.confidence)
    pct = f"{100 * st.confidence:g} %"
    if op == "=":
        st.why = (f"{p:g} is inside the {pct} interval; no finite number of runs confirms an "
                  "equality (write >= or <=)")
    elif st.more_runs is None:
        st.why = (f"the observed rate {k}/{n} is the bound itself (or too close to it): no "
                  "number of runs at this rate decides it")
    else:
        st.why = (f"{p:g} is inside the {pct} interval after {n} runs; about "
                  f"{st.more_runs} more runs at the observed rate {k}/{n} would decide it")


def fleet_statistics(logs: list, bounds: dict[str, Any], confidence: float = 0.95,
                     unknown: str = "fail") -> list[RequirementStatistics]:
    """Per requirement (in ``bounds``' order: id -> :class:`fretc.compiler.ir.ProbabilityBound`
    or None), its :class:`RequirementStatistics` over ``logs`` (:class:`fretc.audit.verdict.LogAudit`
    list: one run each). Raises ``ValueError`` for an unknown policy or a confidence
    outside (0, 1)."""
    if unknown not in UNKNOWN_POLICIES:
        raise ValueError(f"unknown-run policy {unknown!r}: one of {', '.join(UNKNOWN_POLICIES)}")
    if not 0 < confidence < 1 or not math.isfinite(confidence):
        raise ValueError(f"confidence {confidence} is not in (0, 1)")
    out = []
    for rid, bound in bounds.items():
        st = RequirementStatistics(rid, confidence=confidence, unknown_policy=unknown)
        for la in logs:
            v = next((v for v in la.verdicts if v.requirement == rid), None)
            kind = "error" if v is None or la.error else v.verdict
            setattr(st, kind, getattr(st, kind) + 1)
            st.runs += 1
        st.successes = st.satisfied + st.vacuous
        st.trials = st.successes + st.violated + (
            st.unknown + st.error if unknown == "fail" else 0)
        judge_counts(st, None if bound is None else bound.op,
                     None if bound is None else bound.p)
        out.append(st)
    return out


def plan_statistics(plan, logs: list, confidence: float = 0.95,
                    unknown: str = "fail") -> list[RequirementStatistics] | None:
    """The fleet statistics of an audit plan's requirements (:class:`fretc.audit.model.AuditPlan`)
    over ``logs``, or None when the audit is of one log and no requirement has a
    probability bound (the audit JSON then has no ``statistics``)."""
    bounds = {r.id: getattr(r.compiled, "probability", None) for r in plan.requirements}
    if len(logs) <= 1 and not any(bounds.values()):
        return None
    return fleet_statistics(logs, bounds, confidence, unknown)


def statistical_exit(stats: list[RequirementStatistics] | None) -> tuple[bool, bool]:
    """``(failed, undecided)``: a probability requirement's statistical verdict is
    ``fails``, or ``undecided`` (for :func:`fretc.audit.verdict.exit_code`)."""
    stats = stats or []
    return (any(s.verdict == "fails" for s in stats),
            any(s.verdict == "undecided" for s in stats))
