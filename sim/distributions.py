"""Distributions of scenario parameters (``fretc estimate``): what a space file's
``[parameters]`` entry says about how often each value occurs in operation.

Design notes: ARCHITECTURE.md, `sim/distributions.py`."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

__all__ = ["Distribution", "parse_distribution", "DistributionError", "DISTRIBUTIONS"]

DISTRIBUTIONS = ("uniform", "normal", "choice")


class DistributionError(ValueError):
    """A distribution the sampler cannot use: the message says which key and why."""


@dataclass(frozen=True)
class Distribution:
    """One parameter's distribution (module docstring). ``kind`` in :data:`DISTRIBUTIONS`;
    ``low``/``high`` the support (uniform) or the truncation (normal, +-inf without one);
    ``mean``/``sd`` (normal); ``values``/``weights`` (choice, weights summing to 1);
    ``fault``: the share of runs with the parameter at all (None: every run)."""

    name: str
    kind: str
    low: float = -math.inf
    high: float = math.inf
    mean: float = 0.0
    sd: float = 1.0
    values: tuple[float, ...] = ()
    weights: tuple[float, ...] = ()
    fault: float | None = None

    @property
    def latent_dims(self) -> int:
        """Latent coordinates this parameter uses: 1, or 2 for a fault (occurrence, value)."""
        return 2 if self.fault is not None else 1

    @property
    def range(self) -> tuple[float, float]:
        """The finite range ``fretc falsify`` searches (module docstring)."""
        if self.kind == "choice":
            return min(self.values), max(self.values)
        lo = self.low if math.isfinite(self.low) else self.mean - 4 * self.sd
        hi = self.high if math.isfinite(self.high) else self.mean + 4 * self.sd
        return lo, hi

    def value(self, z: Sequence[float] | np.ndarray) -> float | None:
        """The parameter's value at the latent coordinates ``z`` (``latent_dims`` of them,
        standard normal): None when a fault does not happen; else the value rounded to
        1e-6 (1 us, 1 um)."""
        from scipy.stats import norm  # lazy: scipy only for estimate campaigns

        if self.fault is not None:
            if not z[0] < norm.ppf(self.fault):
                return None
            z = z[1:]
        u = float(norm.cdf(z[0]))
        if self.kind == "uniform":
            x = self.low + u * (self.high - self.low)
        elif self.kind == "normal":
            a = norm.cdf((self.low - self.mean) / self.sd)
            b = norm.cdf((self.high - self.mean) / self.sd)
            x = self.mean + self.sd * float(norm.ppf(a + u * (b - a)))
            x = min(max(x, self.low), self.high)
        else:
            acc, x = 0.0, self.values[-1]
            for v, w in zip(self.values, self.weights):
                acc += w
                if u < acc:
                    x = v
                    break
        return round(x, 6)


def _num(spec: dict, key: str, fail: Callable[[str], None], default=None) -> float:
    v = spec.get(key, default)
    if v is None:
        fail(f"needs {key}")
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
        fail(f"{key} must be a finite number")
    return float(v)


def parse_distribution(name: str, spec: Any, nonnegative: bool,
                       fail: Callable[[str], None]) -> Distribution:
    """The :class:`Distribution` of one ``[parameters]`` entry (a ``[low, high]`` list or
    a table, module docstring). ``nonnegative``: the parameter cannot be below 0 (a normal
    is truncated there). ``fail(message)`` raises (the space file's positioned error): for
    an unknown ``dist``, a missing or non-finite number, and every *degenerate*
    distribution (uniform with ``low >= high``, ``sd <= 0``, a normal whose truncation
    leaves no mass, a choice of fewer than two values or with weights that are negative,
    do not sum to a positive number or put all mass on one value, a fault share outside
    (0, 1])."""
    def bad(msg: str) -> None:
        fail(f"{name}: {msg}")

    if isinstance(spec, list):
        lo, hi = float(spec[0]), float(spec[1])
        if not lo < hi:
            bad(f"the range [{lo:g}, {hi:g}] is a single value: a degenerate distribution "
                "(widen it, or fix the value in the scenario)")
        return Distribution(name, "uniform", lo, hi)
    known = {"dist", "low", "high", "mean", "sd", "values", "weights", "fault"}
    extra = sorted(set(spec) - known)
    if extra:
        bad(f"unknown key {extra[0]!r}; known: {', '.join(sorted(known))}")
    kind = spec.get("dist")
    if kind not in DISTRIBUTIONS:
        bad(f"dist must be one of {', '.join(DISTRIBUTIONS)} (got {kind!r})")
    fault = None
    if "fault" in spec:
        fault = _num(spec, "fault", bad)
        if not 0 < fault <= 1:
            bad(f"fault = {fault:g} is not a share of runs in (0, 1]")
    if kind == "uniform":
        lo, hi = _num(spec, "low", bad), _num(spec, "high", bad)
        if not lo < hi:
            bad(f"uniform on [{lo:g}, {hi:g}] is degenerate: low must be < high")
        return Distribution(name, kind, lo, hi, fault=fault)
    if kind == "normal":
        mean, sd = _num(spec, "mean", bad), _num(spec, "sd", bad)
        if not sd > 0:
            bad(f"normal with sd = {sd:g} is degenerate: sd must be > 0")
        lo = _num(spec, "low", bad, -math.inf) if "low" in spec else -math.inf
        hi = _num(spec, "high", bad, math.inf) if "high" in spec else math.inf
        if nonnegative:
            lo = max(lo, 0.0)
        from scipy.stats import norm
        if not lo < hi or norm.cdf((hi - mean) / sd) - norm.cdf((lo - mean) / sd) < 1e-12:
            bad(f"normal({mean:g}, {sd:g}) truncated to [{lo:g}, {hi:g}] has no mass: "
                "degenerate")
        return Distribution(name, kind, lo, hi, mean, sd, fault=fault)
    values, weights = spec.get("values"), spec.get("weights")
    if not isinstance(values, list) or len(values) < 2 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in values):
        bad("choice needs values = [at least two finite numbers]")
    if weights is None:
        weights = [1.0] * len(values)
    if not isinstance(weights, list) or len(weights) != len(values) or not all(
            isinstance(w, (int, float)) and not isinstance(w, bool) and math.isfinite(w)
            and w >= 0 for w in weights) or not sum(weights) > 0:
        bad("choice weights must be one non-negative number per value, with a positive sum")
    total = float(sum(weights))
    if sum(1 for v, w in zip(values, weights) if w > 0 and v == v) < 2 or \
            len({v for v, w in zip(values, weights) if w > 0}) < 2:
        bad("choice puts all its weight on one value: a degenerate distribution")
    return Distribution(name, kind, values=tuple(float(v) for v in values),
                        weights=tuple(w / total for w in weights), fault=fault)
