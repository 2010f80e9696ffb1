"""The intervals and decisions of the fleet statistics (:mod:`fretc.audit.fleet.statistics`) and of
``fretc estimate``'s tests (:mod:`fretc.sim.sequential`): exact binomial intervals, their
form for triggers clustered in runs, and the widening over trials of unknown outcome.

Design notes: ARCHITECTURE.md, `audit/fleet/intervals.py`."""

from __future__ import annotations

import math
from typing import Any
from dataclasses import dataclass

__all__ = ["clopper_pearson", "effective_clopper_pearson", "Counts", "cluster_interval",
           "decide", "more_runs", "MAX_MORE_RUNS", "check_confidence"]

#: further runs are searched up to this many (beyond it: None, "more than")
MAX_MORE_RUNS = 10**9


def check_confidence(confidence: Any) -> float:
    """``confidence`` as a float in (0, 1); ``ValueError`` for anything else (NaN, inf, a
    string, 0, 1)."""
    try:
        c = float(confidence)
    except (TypeError, ValueError):
        raise ValueError(f"confidence {confidence!r} is not a number") from None
    if not (math.isfinite(c) and 0 < c < 1):
        raise ValueError(f"confidence {confidence} is not in (0, 1)")
    return c


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The exact two-sided interval ``(lo, hi)`` of a binomial proportion with ``k``
    successes in ``n`` trials at ``confidence`` (in (0, 1)) (Clopper & Pearson 1934; module
    docstring). ``n == 0``: ``(0.0, 1.0)``. Raises ``ValueError`` for ``k`` outside [0, n] or
    a confidence outside (0, 1)."""
    check_confidence(confidence)
    if n == 0:
        return 0.0, 1.0
    if not 0 <= k <= n:
        raise ValueError(f"{k} successes in {n} trials")
    return _beta_interval(float(k), float(n), confidence)


def effective_clopper_pearson(k: float, n: float, confidence: float) -> tuple[float, float]:
    """Clopper-Pearson's interval at a non-integer count: ``k`` successes of ``n`` trials
    (``0 <= k <= n``, ``n > 0``), its ends the same beta quantiles as at integer counts
    (``beta.ppf(a/2, k, n - k + 1)``, ``beta.isf(a/2, k + 1, n - k)``; 0 at ``k = 0``,
    1 at ``k = n``), so integer counts give :func:`clopper_pearson`'s interval."""
    check_confidence(confidence)
    if n <= 0:
        return 0.0, 1.0
    return _beta_interval(min(max(float(k), 0.0), float(n)), float(n), confidence)


def _beta_interval(k: float, n: float, confidence: float) -> tuple[float, float]:
    """The Clopper-Pearson ends of ``0 <= k <= n`` successes of ``n > 0`` trials."""
    from scipy.stats import beta  # lazy: scipy only when statistics are asked

    a = (1 - confidence) / 2
    lo = 0.0 if k <= 0 else float(beta.ppf(a, k, n - k + 1))
    hi = 1.0 if k >= n else float(beta.isf(a, k + 1, n - k))
    return lo, hi


@dataclass
class Counts:
    """Trials grouped in runs (module docstring): ``successes`` (K), ``trials`` (N, the
    trials of known outcome), ``unknown`` (U), and of the runs with any trial their number
    ``runs`` (R), ``size`` (``M = N + U``) and ``size2`` (``sum(m_i^2)``)."""

    successes: int = 0
    trials: int = 0
    unknown: int = 0
    runs: int = 0
    size: int = 0
    size2: int = 0

    def add(self, k: int, n: int, u: int = 0) -> None:
        """Add one run's ``k`` successes of ``n`` trials and ``u`` of unknown outcome (a run
        with none changes nothing)."""
        m = n + u
        if m == 0:
            return
        self.successes += k
        self.trials += n
        self.unknown += u
        self.runs += 1
        self.size += m
        self.size2 += m * m

    @property
    def effective(self) -> float:
        """The effective sample size ``n* = M^2 / sum(m_i^2)`` (0 without trials)."""
        return self.size * self.size / self.size2 if self.size2 else 0.0

    @property
    def estimate(self) -> float | None:
        """``K / N``, the share of satisfied trials among those of known outcome."""
        return self.successes / self.trials if self.trials else None


def cluster_interval(c: Counts, confidence: float) -> tuple[float, float]:
    """The interval of :class:`Counts` ``c`` (module docstring): Clopper-Pearson at the
    effective sample size, widened over the unknown outcomes; ``(0, 1)`` without trials."""
    if c.size == 0:
        return 0.0, 1.0
    ne = c.effective
    if ne.is_integer() and c.size == c.runs:  # one trial a run: integer counts
        ne = int(ne)
    lo, _ = effective_clopper_pearson(_scaled(c.successes, c.size, ne), ne, confidence)
    _, hi = effective_clopper_pearson(_scaled(c.successes + c.unknown, c.size, ne), ne,
                                      confidence)
    return lo, hi


def _scaled(k: int, m: int, ne: float) -> float:
    """``k / m`` of ``ne`` trials, exactly ``k`` when ``ne == m``."""
    return k if ne == m else ne * k / m


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


def more_runs(op: str, p: float, c: Counts, confidence: float) -> int | None:
    """The smallest number ``j`` of further runs after which :func:`decide` would no longer
    say ``undecided``, if each were an average run of ``c`` (``M / R`` trials, the observed
    share ``K / N`` satisfied, none unknown); None when that never happens (the observed
    share is p, an ``=`` bound, no trials) or it takes more than :data:`MAX_MORE_RUNS`."""
    if c.trials == 0 or op == "=" or c.successes / c.trials == p:
        return None
    rate, mean = c.successes / c.trials, c.size / c.runs

    def decided(j: int) -> bool:
        grown = Counts(successes=c.successes + round(rate * j * mean), trials=c.trials + round(
            j * mean), unknown=c.unknown, runs=c.runs + j)
        grown.size = grown.trials + grown.unknown
        grown.size2 = c.size2 + j * mean * mean  # type: ignore[assignment]  # (a projection: a float)
        return decide(op, p, *cluster_interval(grown, confidence)) != "undecided"

    hi_j = 1
    while not decided(hi_j):
        hi_j *= 2
        if hi_j > MAX_MORE_RUNS:
            return None
    lo_j = hi_j // 2  # undecided at lo_j (or 0), decided at hi_j
    while hi_j - lo_j > 1:
        mid = (lo_j + hi_j) // 2
        if decided(mid):
            hi_j = mid
        else:
            lo_j = mid
    return hi_j
