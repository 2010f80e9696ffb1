"""Rare violations (``fretc estimate --rare``): adaptive multilevel splitting over the latent
coordinates of a scenario space, with levels on the robustness every verdict carries.

The rule (F. Cérou and A. Guyader, "Adaptive multilevel splitting for rare event analysis",
Stochastic Analysis and Applications 25(2), 2007), in our words. A run is a point ``z`` of
``R^d`` drawn from ``N(0, I)`` (:mod:`fretc.sim.distributions`); ``r(z)`` its robustness for one
requirement, negative exactly when violated. To estimate ``P(r(z) < 0)``:

Design notes: ARCHITECTURE.md, `sim/splitting.py`."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

__all__ = ["SplittingResult", "SplittingError", "adaptive_multilevel_splitting"]


class SplittingError(ValueError):
    """The robustness gives no levels (boolean or constant), or bad parameters."""


@dataclass
class SplittingResult:
    """The result of :func:`adaptive_multilevel_splitting`.

    ``estimate`` of the violation probability; ``relative_error`` (idealized, module
    docstring); ``interval`` ``[lo, hi]`` at ``confidence``; ``levels`` the robustness
    levels crossed; ``samples`` the robustness evaluations (simulator runs) used;
    ``acceptance`` the share of accepted moves; ``final_share`` the share of the last
    particles violating; ``reached``: the levels reached 0 before ``max_levels`` or the
    budget (False: ``estimate`` is an upper bound of what the levels showed, ``why`` says)."""

    estimate: float
    relative_error: float
    interval: tuple[float, float]
    confidence: float
    levels: list[float] = field(default_factory=list)
    samples: int = 0
    acceptance: float = 0.0
    final_share: float = 0.0
    reached: bool = True
    why: str | None = None
    violating: list[list[float]] = field(default_factory=list)

    def to_json(self) -> dict:
        """Plain values for the report (``violating``: up to 10 latent points)."""
        return {"estimate": self.estimate,
                "relative_error": (self.relative_error if math.isfinite(self.relative_error)
                                   else None),
                "interval": list(self.interval), "confidence": self.confidence,
                "levels": self.levels, "samples": self.samples,
                "acceptance": self.acceptance, "final_share": self.final_share,
                "reached": self.reached, "why": self.why}


def _score(x: float | None) -> float:
    """Robustness used for levels: None/NaN (unknown, error) is a violation (-inf)."""
    return -math.inf if x is None or x != x else float(x)


def _resample(robustness, rng, z, r, dead, level: float, moves: int, rho: float) -> int:
    """Step 3 of the module docstring, in place on ``z``/``r``: the ``dead`` particles
    become copies of survivors (``r < level``) moved by ``moves`` pCN steps restricted to
    ``r < level``; returns the accepted moves."""
    import numpy as np

    alive = np.flatnonzero(r < level)
    parents = rng.choice(alive, size=dead.size)
    z[dead], r[dead] = z[parents], r[parents]
    accepted = 0
    for _ in range(moves):
        noise = rng.standard_normal((dead.size, z.shape[1]))
        prop = rho * z[dead] + math.sqrt(1 - rho * rho) * noise
        rp = np.array([_score(x) for x in robustness(prop.tolist())])
        ok = rp < level
        z[dead[ok]], r[dead[ok]] = prop[ok], rp[ok]
        accepted += int(ok.sum())
    return accepted


def adaptive_multilevel_splitting(
        robustness: Callable[[Sequence[Sequence[float]]], Sequence[float | None]],
        dim: int, seed: int, *, particles: int = 100, kill: int = 10, moves: int = 5,
        rho: float = 0.8, confidence: float = 0.95, max_levels: int = 200,
        budget: int | None = None) -> SplittingResult:
    """Estimate ``P(r(z) < 0)`` for ``z ~ N(0, I_dim)`` (module docstring).

    Args:
        robustness: scores a batch of latent points (a list of ``dim``-lists) and returns
            their robustness values, in order (None/NaN: unknown, a violation); one call per
            batch (the simulator's runs may go in parallel).
        seed: the splitting's own seed (numpy ``default_rng([seed, 7])``): same seed, same
            result.
        particles, kill, moves: ``n``, ``k`` and ``m``; rho: the pCN correlation in (0, 1).
        max_levels, budget: stop after that many levels or robustness evaluations.

    Raises:
        SplittingError: ``1 <= kill < particles``, ``moves >= 1``, ``0 < rho < 1`` not met,
            or the first particles' robustness is boolean (every value +-inf) or constant.
    """
    import numpy as np
    from scipy.stats import norm

    if not (1 <= kill < particles and moves >= 1 and 0 < rho < 1 and dim >= 1):
        raise SplittingError("splitting needs 1 <= kill < particles, moves >= 1, 0 < rho < 1")
    rng = np.random.default_rng([int(seed), 7])
    z = rng.standard_normal((particles, dim))
    r = np.array([_score(x) for x in robustness(z.tolist())])
    samples = particles
    finite = r[np.isfinite(r)]
    if finite.size == 0:
        raise SplittingError("the robustness of this requirement is boolean (+-inf on every "
                             "run): splitting has no levels; estimate it by crude Monte Carlo "
                             "(fretc estimate without --rare)")
    log_p, var, levels = 0.0, 0.0, list[float]()
    accepted = proposed = 0
    reached, why = True, None
    while True:
        order = np.sort(r)[::-1]
        level = order[kill - 1]
        if level < 0:
            break
        if len(levels) >= max_levels or (budget is not None and samples >= budget):
            reached = False
            why = (f"stopped at level {level:.4g} after {len(levels)} levels and {samples} "
                   "runs (max levels or budget): the estimate is the product so far times "
                   "the share below 0")
            break
        dead = np.flatnonzero(r >= level)
        if dead.size >= particles:
            reached = False
            why = (f"every particle has robustness >= {level:.4g}: a plateau (the robustness "
                   "gives no lower level); the estimate is an upper bound")
            break
        share = 1 - dead.size / particles
        log_p += math.log(share)
        var += (dead.size / particles) / (share * particles)
        levels.append(float(level))
        acc = _resample(robustness, rng, z, r, dead, level, moves, rho)
        samples += dead.size * moves
        accepted += acc
        proposed += dead.size * moves
    final = float(np.mean(r < 0))
    if final == 0.0:
        est, rel = 0.0, math.inf
    else:
        est = math.exp(log_p) * final
        rel = math.sqrt(var + (1 - final) / (final * particles))
    zq = float(norm.ppf(0.5 + confidence / 2))
    interval = ((est * math.exp(-zq * rel), min(1.0, est * math.exp(zq * rel)))
                if est > 0 and math.isfinite(rel) else (0.0, math.exp(log_p)))
    return SplittingResult(est, rel, interval, confidence, levels, samples,
                           accepted / proposed if proposed else 0.0, final, reached, why,
                           [list(map(float, p)) for p in z[r < 0][:10]])
