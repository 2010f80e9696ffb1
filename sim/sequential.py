"""Sequential tests of a probability bound (``fretc estimate``): after each run, decide
``holds``, ``fails`` or go on, so a campaign stops as soon as the runs say enough.

:class:`SPRT` is Wald's sequential probability ratio test (A. Wald, "Sequential tests of
statistical hypotheses", Ann. Math. Statist. 16(2), 1945), as statistical model checkers use
it (Younes & Simmons 2002): for ``P(satisfied) >= p`` it tests ``H_holds: P >= p + delta``
against ``H_fails: P <= p - delta`` (the *indifference region* ``(p - delta, p + delta)``,
where either answer is acceptable). Each run adds ``log(P_h(x) / P_f(x))`` to the
log-likelihood ratio ``llr`` (``x`` satisfied or not, ``P_h``/``P_f`` the Bernoulli laws at
the two hypotheses' rates); the test says ``holds`` once ``llr >= log((1 - beta) / alpha)``,
``fails`` once ``llr <= log(beta / (1 - alpha))``. Wald's bounds: the probability of
``holds`` when ``P <= p - delta`` is at most about ``alpha``, of ``fails`` when
``P >= p + delta`` at most about ``beta``. ``<=``/``<`` bounds swap the two rates.

:class:`SequentialCP` is a repeated Clopper-Pearson test: at looks ``n = 10, 15, 23, ...``
(x1.5 each) it computes the exact interval with error ``alpha / 2^(j+1)`` at look ``j``
(so the errors of all looks add up to at most ``alpha``, a union bound) and decides as
:func:`fretc.audit.statistics.decide` does. Slower to decide than the SPRT, but with no
indifference region.

An ``=`` bound is never accepted by either (no finite sample confirms an equality).
"""

from __future__ import annotations

import math

from fretc.audit.statistics import clopper_pearson, decide

__all__ = ["SPRT", "SequentialCP", "effective_delta", "make_test", "TESTS"]

TESTS = ("sprt", "cp")


def effective_delta(p: float, delta: float) -> float:
    """The indifference half-width used for a bound ``p``: ``delta``, shrunk to half the
    distance to 0 or 1 when ``p +- delta`` would leave [0, 1] (``p`` of 0 or 1 keeps
    ``delta``: the rate at the bound is then 0 or 1 and one run can refute it)."""
    d = delta
    if 0 < p < 1:
        d = min(d, p / 2, (1 - p) / 2)
    return d


def _log(x: float) -> float:
    return math.log(x) if x > 0 else -math.inf


class SPRT:
    """Wald's SPRT of ``P(satisfied) OP p`` (module docstring).

    Args:
        op, p: the bound (``>= > <= <``; ``=`` never decides).
        delta: the indifference half-width (> 0), see :func:`effective_delta`.
        alpha: the error of deciding ``holds`` when the bound is false by ``delta`` or more;
        beta: of deciding ``fails`` when it is true by ``delta`` or more (both in (0, 0.5)).

    Attributes: ``n`` runs seen, ``llr`` the log-likelihood ratio, ``path`` its value after
    each run, ``decision`` None / ``holds`` / ``fails`` and ``at`` the run that decided.
    Raises ``ValueError`` for parameters outside those ranges.
    """

    name = "sprt"

    def __init__(self, op: str, p: float, delta: float = 0.05, alpha: float = 0.05,
                 beta: float = 0.05):
        if not delta > 0 or not 0 < alpha < 0.5 or not 0 < beta < 0.5:
            raise ValueError("the SPRT needs delta > 0 and alpha, beta in (0, 0.5)")
        self.op, self.p = op, p
        self.delta = effective_delta(p, delta)
        up, down = min(p + self.delta, 1.0), max(p - self.delta, 0.0)
        self.p_holds, self.p_fails = (up, down) if op in (">=", ">") else (down, up)
        self.upper = math.log((1 - beta) / alpha)   # holds at or above
        self.lower = math.log(beta / (1 - alpha))   # fails at or below
        self.win = _log(self.p_holds) - _log(self.p_fails)          # a satisfied run
        self.loss = _log(1 - self.p_holds) - _log(1 - self.p_fails)  # a run that did not
        self.n, self.llr, self.path = 0, 0.0, []
        self.decision: str | None = None
        self.at: int | None = None

    def update(self, satisfied: bool) -> str | None:
        """Add one run; returns the decision (None while undecided). Runs after the
        decision are not counted."""
        if self.decision is not None:
            return self.decision
        self.n += 1
        two_sided = self.op in ("=", "!=")
        if not two_sided:
            self.llr += self.win if satisfied else self.loss
        self.path.append(self.llr)
        if not two_sided and self.llr >= self.upper:
            self.decision, self.at = "holds", self.n
        elif not two_sided and self.llr <= self.lower:
            self.decision, self.at = "fails", self.n
        return self.decision

    def why_undecided(self) -> str:
        """Why there is no decision yet, in a sentence."""
        if self.op == "=":
            return "the SPRT never accepts an equality bound (write >= or <=)"
        if self.op == "!=":
            return "the SPRT tests one-sided bounds: decide '!=' with --test cp"
        return (f"after {self.n} runs the log-likelihood ratio is {self.llr:.3g}, between "
                f"the thresholds {self.lower:.3g} (fails) and {self.upper:.3g} (holds)")

    def to_json(self) -> dict:
        """The test's parameters, decision and path (for the report)."""
        return {"test": "sprt", "delta": self.delta, "p_holds": self.p_holds,
                "p_fails": self.p_fails, "upper": self.upper, "lower": self.lower,
                "decision": self.decision, "at": self.at,
                "path": [x if math.isfinite(x) else ("inf" if x > 0 else "-inf")
                         for x in self.path]}


class SequentialCP:
    """The repeated Clopper-Pearson test (module docstring); same interface as
    :class:`SPRT` (``path``: ``(n, lo, hi)`` at each look)."""

    name = "cp"

    def __init__(self, op: str, p: float, alpha: float = 0.05, first: int = 10,
                 growth: float = 1.5):
        if not 0 < alpha < 0.5:
            raise ValueError("alpha must be in (0, 0.5)")
        self.op, self.p, self.alpha = op, p, alpha
        self.k = self.n = 0
        self.next_look, self.looks, self.growth = first, 0, growth
        self.path: list[tuple[int, float, float]] = []
        self.decision: str | None = None
        self.at: int | None = None

    def update(self, satisfied: bool) -> str | None:
        """Add one run; returns the decision (None while undecided)."""
        if self.decision is not None:
            return self.decision
        self.n += 1
        self.k += bool(satisfied)
        if self.n >= self.next_look:
            err = self.alpha / 2 ** (self.looks + 1)
            lo, hi = clopper_pearson(self.k, self.n, 1 - err)
            self.path.append((self.n, lo, hi))
            self.looks += 1
            self.next_look = max(self.n + 1, math.ceil(self.next_look * self.growth))
            d = decide(self.op, self.p, lo, hi)
            if d != "undecided":
                self.decision, self.at = d, self.n
        return self.decision

    def why_undecided(self) -> str:
        """Why there is no decision yet, in a sentence."""
        if not self.path:
            return f"only {self.n} runs: the first look is at {self.next_look}"
        n, lo, hi = self.path[-1]
        return (f"at the last look ({n} runs) {self.p:g} was inside the interval "
                f"[{lo:.4g}, {hi:.4g}]")

    def to_json(self) -> dict:
        """The test's parameters, decision and looks (for the report)."""
        return {"test": "cp", "alpha": self.alpha, "decision": self.decision, "at": self.at,
                "path": [list(x) for x in self.path]}


def make_test(kind: str, op: str, p: float, delta: float, alpha: float, beta: float):
    """An :class:`SPRT` (``kind="sprt"``) or :class:`SequentialCP` (``"cp"``) of the bound."""
    if kind == "sprt":
        return SPRT(op, p, delta, alpha, beta)
    if kind == "cp":
        return SequentialCP(op, p, alpha)
    raise ValueError(f"unknown sequential test {kind!r}: one of {', '.join(TESTS)}")
