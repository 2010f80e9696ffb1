"""Sequential tests of a probability bound (``fretc estimate``): after each run, decide
``holds``, ``fails`` or go on, so a campaign stops as soon as the runs say enough.

A run gives the test its trials (:meth:`SPRT.observe`): ``k`` satisfied of ``n`` of known
outcome and ``u`` of unknown outcome; per trigger (the default unit, FRET's per-trigger
bound) a run's triggers, per run one trial. As the fleet statistics do
(:mod:`fretc.audit.fleet.intervals`), the trials are counted with runs as clusters, at the
effective sample size ``n* = M^2 / sum(m_i^2)`` of the runs so far (``m_i`` a run's trials,
``M`` their sum; one trial a run: ``n*`` is the number of runs), and every decision counts
the unknown outcomes against it: ``holds`` is decided with them all going against the
bound, ``fails`` with them all going its way.

Design notes: ARCHITECTURE.md, `sim/sequential.py`."""

from __future__ import annotations

import math

from fretc.audit.fleet.intervals import Counts, cluster_interval, decide

__all__ = ["SPRT", "SequentialCP", "effective_delta", "make_test", "TESTS", "check_parameters"]

TESTS = ("sprt", "cp")


def effective_delta(p: float, delta: float) -> float:
    """The indifference half-width used for a bound ``p``: ``delta``, shrunk to half the
    distance to 0 or 1 when ``p +- delta`` would leave [0, 1] (``p`` of 0 or 1 keeps
    ``delta``: the rate at the bound is then 0 or 1 and one run can refute it)."""
    d = delta
    if 0 < p < 1:
        d = min(d, p / 2, (1 - p) / 2)
    return d


def check_parameters(delta: float, alpha: float, beta: float) -> None:
    """``ValueError`` unless ``delta`` is in (0, 0.5] and ``alpha``, ``beta`` in (0, 0.5)
    (NaN and infinities never are)."""
    ok = (isinstance(delta, (int, float)) and 0 < delta <= 0.5
          and all(isinstance(x, (int, float)) and 0 < x < 0.5 for x in (alpha, beta)))
    if not ok:
        raise ValueError("the sequential tests need delta in (0, 0.5] and alpha, beta in "
                         f"(0, 0.5); got delta={delta}, alpha={alpha}, beta={beta}")


def _log(x: float) -> float:
    return math.log(x) if x > 0 else -math.inf


class _Test:
    """What both tests share: the runs' trials (``counts``), ``n`` runs seen, ``decision``
    (None / ``holds`` / ``fails``) and ``at``, the run that decided."""

    name = ""

    def __init__(self, op: str, p: float):
        self.op, self.p = op, p
        self.counts = Counts()
        self.n = 0
        self.decision: str | None = None
        self.at: int | None = None

    def update(self, satisfied: bool | None) -> str | None:
        """One run as one trial: satisfied (True), not (False), or of unknown outcome
        (None); as :meth:`observe`."""
        if satisfied is None:
            return self.observe(0, 0, 1)
        return self.observe(int(bool(satisfied)), 1)

    def observe(self, k: int, n: int, u: int = 0) -> str | None:
        """Add one run: ``k`` satisfied of ``n`` trials of known outcome and ``u`` of
        unknown outcome; returns the decision (None while undecided). Runs after the
        decision are not counted."""
        if self.decision is not None:
            return self.decision
        self.n += 1
        self.counts.add(k, n, u)
        self._decide()
        return self.decision

    def _decide(self) -> None:
        raise NotImplementedError


class SPRT(_Test):
    """Wald's SPRT of ``P OP p`` (module docstring).

    Args:
        op, p: the bound (``>= > <= <``; ``=`` and ``!=`` never decide).
        delta: the indifference half-width (in (0, 0.5]), see :func:`effective_delta`.
        alpha: the error of deciding ``holds`` when the bound is false by ``delta`` or more;
        beta: of deciding ``fails`` when it is true by ``delta`` or more (both in (0, 0.5)).

    Attributes: as :class:`_Test`, ``llr`` the log-likelihood ratio for ``holds`` (unknown
    trials against the bound), ``path`` its value after each run and ``path_fails`` the
    ratio for ``fails`` (unknown trials for the bound) when it differs.
    Raises ``ValueError`` for parameters outside those ranges (NaN included).
    """

    name = "sprt"

    def __init__(self, op: str, p: float, delta: float = 0.05, alpha: float = 0.05,
                 beta: float = 0.05):
        check_parameters(delta, alpha, beta)
        super().__init__(op, p)
        self.delta = effective_delta(p, delta)
        up, down = min(p + self.delta, 1.0), max(p - self.delta, 0.0)
        self.p_holds, self.p_fails = (up, down) if op in (">=", ">") else (down, up)
        self.upper = math.log((1 - beta) / alpha)   # holds at or above
        self.lower = math.log(beta / (1 - alpha))   # fails at or below
        self.win = _log(self.p_holds) - _log(self.p_fails)          # a satisfied trial
        self.loss = _log(1 - self.p_holds) - _log(1 - self.p_fails)  # one that was not
        self.llr = 0.0
        self.path: list[float] = []
        self.path_fails: list[float] = []

    def _ratio(self, q: float) -> float:
        """``n* (q win + (1 - q) loss)``, a zero share of an infinite term being zero."""
        c = self.counts
        s = (q * self.win if q else 0.0) + ((1 - q) * self.loss if q < 1 else 0.0)
        return c.effective * s if s == s else 0.0

    def _decide(self) -> None:
        c = self.counts
        two_sided = self.op in ("=", "!=")
        if c.size == 0 or two_sided:
            hold = fail = 0.0
        else:
            ends = (self._ratio(c.successes / c.size),
                    self._ratio((c.successes + c.unknown) / c.size))
            hold, fail = min(ends), max(ends)
        self.llr = hold
        self.path.append(hold)
        self.path_fails.append(fail)
        if not two_sided and hold >= self.upper:
            self.decision, self.at = "holds", self.n
        elif not two_sided and fail <= self.lower:
            self.decision, self.at = "fails", self.n

    def why_undecided(self) -> str:
        """Why there is no decision yet, in a sentence."""
        if self.op == "=":
            return "the SPRT never accepts an equality bound (write >= or <=)"
        if self.op == "!=":
            return "the SPRT tests one-sided bounds: decide '!=' with --test cp"
        return (f"after {self.n} runs the log-likelihood ratio is {self.llr:.3g}, between "
                f"the thresholds {self.lower:.3g} (fails) and {self.upper:.3g} (holds)")

    def to_json(self) -> dict:
        """The test's parameters, decision and path (for the report; infinities as
        strings)."""
        def enc(xs):
            return [x if math.isfinite(x) else ("inf" if x > 0 else "-inf") for x in xs]

        out = {"test": "sprt", "delta": self.delta, "p_holds": self.p_holds,
               "p_fails": self.p_fails, "upper": self.upper, "lower": self.lower,
               "decision": self.decision, "at": self.at, "path": enc(self.path)}
        if self.path_fails != self.path:
            out["path_fails"] = enc(self.path_fails)
        return out


class SequentialCP(_Test):
    """The repeated Clopper-Pearson test (module docstring); same interface as
    :class:`SPRT` (``path``: ``(runs, lo, hi)`` at each look). Raises ``ValueError`` for
    an ``alpha`` outside (0, 0.5)."""

    name = "cp"

    def __init__(self, op: str, p: float, alpha: float = 0.05, first: int = 10,
                 growth: float = 1.5):
        check_parameters(0.5, alpha, 0.25)
        super().__init__(op, p)
        self.alpha = alpha
        self.next_look, self.looks, self.growth = first, 0, growth
        self.path: list[tuple[int, float, float]] = []

    def _decide(self) -> None:
        if self.n < self.next_look:
            return
        err = self.alpha / 2 ** (self.looks + 1)
        lo, hi = cluster_interval(self.counts, 1 - err)
        self.path.append((self.n, lo, hi))
        self.looks += 1
        self.next_look = max(self.n + 1, math.ceil(self.next_look * self.growth))
        d = decide(self.op, self.p, lo, hi)
        if d != "undecided":
            self.decision, self.at = d, self.n

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


def make_test(kind: str, op: str, p: float, delta: float, alpha: float, beta: float
              ) -> SPRT | SequentialCP:
    """An :class:`SPRT` (``kind="sprt"``) or :class:`SequentialCP` (``"cp"``) of the bound;
    ``ValueError`` for another kind or parameters out of range."""
    if kind == "sprt":
        return SPRT(op, p, delta, alpha, beta)
    if kind == "cp":
        return SequentialCP(op, p, alpha)
    raise ValueError(f"unknown sequential test {kind!r}: one of {', '.join(TESTS)}")
