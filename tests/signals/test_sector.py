"""Sectors by angle in the LiDAR's own frame (``sector(/scan.ranges, lo, hi)``, REP 103):
the same binding selects the same directions on a LiDAR of any beam count and field of view.
A slice by beam index (``[270:451]``, the simulator's 720 beams) read an empty slice on a
LiDAR of fewer beams: no valid return, ``min`` +inf, a clear path ahead of an obstacle at
0.5 m."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.files import parse_bindings

from _logs import scan

REPO = Path(__file__).resolve().parents[2]
TRACES = sorted((REPO / "traces").glob("*.mcap"))


def _value(expr: str, msg) -> float:
    b = parse_bindings(f'[tick]\nperiod = "100 ms"\n[variables]\nv = "{expr}"\n')
    s = EvalState()
    s.msgs["/scan"], s.times["/scan"] = msg, 0
    return b.variables["v"].evaluate(s)


def _lidar(n: int, start: float, step: float, ranges) -> object:
    m = scan(np.asarray(ranges, dtype=float))
    m.angle_min, m.angle_increment = start, step
    m.angle_max = start + step * (n - 1)
    return m


@settings(max_examples=80, deadline=None)
@given(n=st.integers(8, 2000), fov=st.sampled_from([math.pi / 2, math.pi, 1.5 * math.pi,
                                                     2 * math.pi]),
       bearing=st.floats(-math.pi, math.pi, allow_nan=False), ccw=st.booleans())
def test_an_obstacle_ahead_is_ahead_on_any_lidar(n, fov, bearing, ccw):
    """One obstacle at 0.5 m on the beam nearest ``bearing`` (everything else at 5 m), any
    beam count, field of view and direction of scanning: ``min(sector(..., -pi/4, pi/4))`` is
    0.5 exactly when that beam's angle is within 45 degrees of ahead."""
    step = fov / n * (1 if ccw else -1)
    start = -fov / 2 if ccw else fov / 2
    angles = np.remainder(start + np.arange(n) * step + math.pi, 2 * math.pi) - math.pi
    k = int(np.argmin(np.abs(np.remainder(angles - bearing + math.pi, 2 * math.pi) - math.pi)))
    ranges = np.full(n, 5.0)
    ranges[k] = 0.5
    got = _value("min(sector(/scan.ranges, -0.7854, 0.7854))", _lidar(n, start, step, ranges))
    ahead = abs(angles[k]) <= 0.7854
    inside = (np.abs(angles) <= 0.7854).any()
    assert got == (0.5 if ahead else 5.0 if inside else math.inf), (got, angles[k])


def test_a_covered_sector_is_unknown_and_a_sector_the_lidar_does_not_see_is_empty():
    """Every beam of the sector NaN: unknown (NaN), never the clear +inf; a LiDAR whose field
    of view misses the sector (a rear-facing one): no beam, +inf, and ``len`` 0."""
    n, step = 360, math.pi / 180
    ranges = np.full(n, 5.0)
    ranges[135:226] = np.nan  # (-45..+45 degrees of a LiDAR from -180)
    m = _lidar(n, -math.pi, step, ranges)
    assert math.isnan(_value("min(sector(/scan.ranges, -0.7854, 0.7854))", m))
    assert _value("invalid(sector(/scan.ranges, -0.7854, 0.7854))", m) == 91.0
    assert _value("min(sector(/scan.ranges, 2.3561, -2.3561))", m) == 5.0
    rear = _lidar(90, 2.36, math.pi / 180, np.full(90, 5.0))  # (135..224 degrees)
    assert _value("len(sector(/scan.ranges, -0.7854, 0.7854))", rear) == 0.0
    assert _value("min(sector(/scan.ranges, -0.7854, 0.7854))", rear) == math.inf


@pytest.mark.parametrize("trace", TRACES, ids=[t.stem for t in TRACES])
def test_the_shipped_sectors_by_angle_equal_the_beam_slices_on_the_simulators_lidar(trace):
    """On every shipped trace (720 beams from -180 degrees), the shipped bindings' sectors by
    angle give the beam slices' values at every tick (metamorphic: the same sector written
    two ways)."""
    from fretc.logs import open_log
    from fretc.signals.arrays import sample_arrays

    b = parse_bindings(
        '[tick]\nperiod = "100 ms"\n[variables]\n'
        'ahead = "min(sector(/scan.ranges, -0.7854, 0.7854))"\n'
        'ahead_i = "min(/scan.ranges[270:451])"\n'
        'behind = "min(sector(/scan.ranges, 2.3561, -2.3561))"\n'
        'behind_i = "min(min(/scan.ranges[:91]), min(/scan.ranges[630:]))"\n')
    _times, cols = sample_arrays(open_log(trace), b)
    for a, i in (("ahead", "ahead_i"), ("behind", "behind_i")):
        x, y = np.asarray(cols[a], dtype=float), np.asarray(cols[i], dtype=float)
        assert len(x) > 0 and np.array_equal(x, y, equal_nan=True), (trace.name, a)
