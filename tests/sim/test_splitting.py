"""Adaptive multilevel splitting (sim/splitting.py) against closed forms: a synthetic model
whose violation probability is known exactly (a half-space of a standard normal), at 1e-5
and near 1e-2 (there also against crude Monte Carlo)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binomtest, norm

from fretc.sim.splitting import SplittingError, adaptive_multilevel_splitting


def _halfspace(p: float):
    """Robustness ``c - (z1 + z2) / sqrt(2)``: violated (negative) with probability p."""
    c = float(norm.isf(p))
    return lambda zs: [c - (z[0] + z[1]) / math.sqrt(2) for z in zs]


def test_1e_minus_5_within_a_factor_2_with_100x_fewer_samples_than_crude():
    p = 1e-5
    res = adaptive_multilevel_splitting(_halfspace(p), 2, seed=3, particles=200, kill=20,
                                        moves=5)
    assert p / 2 <= res.estimate <= 2 * p
    assert res.interval[0] <= p <= res.interval[1]
    # crude Monte Carlo needs (1 - p) / (p r^2) samples for the same relative error r
    crude = (1 - p) / (p * res.relative_error ** 2)
    assert res.samples * 100 <= crude, (res.samples, crude)
    assert res.reached and res.levels == sorted(res.levels, reverse=True)


def test_near_1e_minus_2_agrees_with_crude_monte_carlo_within_both_intervals():
    p = 0.012
    f = _halfspace(p)
    res = adaptive_multilevel_splitting(f, 2, seed=5, particles=100, kill=10, moves=5)
    z = np.random.default_rng(9).standard_normal((20000, 2))
    k = sum(r < 0 for r in f(z.tolist()))
    ci = binomtest(int(k), 20000).proportion_ci(method="exact")
    assert res.interval[0] <= ci.high and ci.low <= res.interval[1]
    assert res.interval[0] <= p <= res.interval[1] and ci.low <= p <= ci.high


def test_same_seed_same_result():
    a = adaptive_multilevel_splitting(_halfspace(1e-3), 2, seed=1, particles=50, kill=5)
    b = adaptive_multilevel_splitting(_halfspace(1e-3), 2, seed=1, particles=50, kill=5)
    assert a.to_json() == b.to_json()


def test_boolean_robustness_has_no_levels():
    with pytest.raises(SplittingError, match="boolean"):
        adaptive_multilevel_splitting(lambda zs: [math.inf] * len(zs), 2, seed=1,
                                      particles=20, kill=2)


def test_unknown_runs_count_as_violations():
    # robustness z1 where z1 > 0, unknown (None) elsewhere: every unknown is a violation
    f = lambda zs: [z[0] if z[0] > 0 else None for z in zs]  # noqa: E731
    res = adaptive_multilevel_splitting(f, 1, seed=1, particles=200, kill=20)
    assert 0.4 <= res.estimate <= 0.6


def test_a_budget_too_small_says_so():
    res = adaptive_multilevel_splitting(_halfspace(1e-6), 2, seed=1, particles=50, kill=5,
                                        budget=300)
    assert not res.reached and "budget" in res.why
