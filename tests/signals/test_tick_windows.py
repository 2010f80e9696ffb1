"""Counts of ticks where a condition held (docs/bindings.md, "Windows over time"):
``count_ticks(COND, span)`` at tick t counts the ticks of the clock in ``(t - span, t]`` whose
COND held, COND over several topics. Both clocks (the watch's tick by tick, the audit's
blocks) are checked against pandas' rolling sum over an independent sample-and-hold of the
generated messages in plain Python: its values, its warm-up (the first span after the
clock's first evaluated tick) and its unknown (a NaN operand in the window: NaN, never 0)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import MS, float64, write_mcap
from fretc.common.problems import BindingError
from fretc.logs import open_log
from fretc.signals.arrays import sample_arrays
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.spec import TickSpec, make_bindings
from fretc.signals.clock import sample


def _both_clocks(path, bindings):
    src = open_log(path)
    s = sample(src, bindings)
    ticks = list(s)
    arr = sample_arrays(src, bindings)
    assert arr.times.tolist() == [t.time for t in ticks]
    assert [t.index for t in ticks] == list(range(len(ticks)))
    for name in bindings.variables:
        got, want = arr.columns[name].tolist(), [t.values[name] for t in ticks]
        assert all((g != g and w != w) or g == w for g, w in zip(got, want)), (name, got, want)
    return ticks, s


def _held(msgs, t):
    """The newest value at or before ``t`` (log order among equal times), or None."""
    vals = [x for u, x in msgs if u <= t]
    return vals[-1] if vals else None


def _and(a, b):
    """Kleene's and of two comparisons (None: unknown, a NaN operand)."""
    if a is False or b is False:
        return False
    return None if a is None or b is None else True


VALUES = st.one_of(st.integers(-2, 2).map(float), st.just(math.nan))


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=st.lists(st.tuples(st.integers(0, 3000), VALUES), min_size=1, max_size=40),
       b=st.lists(st.tuples(st.integers(0, 3000), st.integers(-2, 2).map(float)),
                  min_size=1, max_size=40),
       span=st.integers(1, 1200), period=st.integers(20, 300), k=st.integers(0, 5))
def test_count_ticks_equals_pandas_rolling_over_the_ticks(tmp_path_factory, a, b, span, period,
                                                          k):
    span = k * period if k else span  # a whole number of periods: ticks on the window's edge
    rows = [("/a", "std_msgs/msg/Float64", t * MS, float64(x)) for t, x in a]
    rows += [("/b", "std_msgs/msg/Float64", t * MS, float64(x)) for t, x in b]
    rows.sort(key=lambda m: (m[2], m[0]))
    path = write_mcap(tmp_path_factory.mktemp("tw") / "w.mcap", rows, chunk_size=256)
    bindings = make_bindings({"n": f"count_ticks(/a.data > 0 & /b.data > 0, {span} ms)"},
                             TickSpec(period_ns=period * MS))
    ticks, s = _both_clocks(path, bindings)
    # the clock by hand: the grid from the first multiple at or after the first message to
    # the first at or after the last, evaluated once both topics have a message
    a_s, b_s = sorted(a, key=lambda m: m[0]), sorted(b, key=lambda m: m[0])
    first, last = min(a_s[0][0], b_s[0][0]), max(a_s[-1][0], b_s[-1][0])
    start, end = -(-first // period) * period, -(-last // period) * period
    grid = [t for t in range(start, end + 1, period)
            if _held(a_s, t) is not None and _held(b_s, t) is not None]
    if not grid:
        assert ticks == []
        return
    cond = []
    for t in grid:
        x, y = _held(a_s, t), _held(b_s, t)
        cond.append(_and(None if x != x else x > 0, y > 0))
    df = pd.DataFrame({"held": [1.0 if c else 0.0 for c in cond],
                       "unknown": [1.0 if c is None else 0.0 for c in cond]},
                      index=pd.to_datetime(grid, unit="ms"))
    roll = df.rolling(f"{span}ms", closed="right").sum()
    want = np.where(roll["unknown"].to_numpy() > 0, np.nan, roll["held"].to_numpy())
    kept = [i for i, t in enumerate(grid) if t - span >= grid[0]]  # the window's warm-up
    assert [t.time / MS for t in ticks] == [grid[i] for i in kept]
    got = np.array([t.values["n"] for t in ticks])
    assert np.array_equal(got, want[kept], equal_nan=True), (got, want[kept])
    assert s.warmup_ticks == len(range(start, end + 1, period)) - len(kept)
    assert s.ticks == len(kept)
    if kept:
        assert s.first_time == grid[kept[0]] * MS


@pytest.mark.parametrize("expr, message", [
    ("count_ticks(/a.data > 0, 10 messages)", "counts the ticks of a duration"),
    ("count_ticks(/a.data > 0, /b.data > 0, 1s)", "takes a condition and a duration"),
    ("count_ticks(/a.data > 0, 1s) > 3", "is the whole binding"),
    ("count_ticks(mean(/a.data, 1s) > 0, 1s)", "windows do not nest"),
    ("count_ticks(/a.data > 0)", "takes a condition and a duration"),
    ("count_ticks(/a.data > 0, -2 min)", "span must be positive, not -2 min"),
    ("mean(/a.data, -1s)", "span must be positive, not -1s"),
])
def test_bad_count_ticks_name_where(expr, message):
    with pytest.raises(BindingError, match=message) as info:
        compile_expression("n", expr, source="b.toml", line=2, col=5)
    assert str(info.value).startswith("b.toml:2:")


def test_a_gap_makes_the_count_unknown_while_its_ticks_are_in_the_window():
    """A gap of a topic the condition reads leaves its ticks unknown (the plain rule), and
    the count unknown for a span after the last of them."""
    from fretc.audit.gaps import unknown_masks
    from fretc.logs.base import Gap

    bindings = make_bindings({"n": "count_ticks(/a.data > 0 & /b.data > 0, 300 ms)",
                              "c": "/a.data > 0 & /b.data > 0"}, TickSpec(period_ns=100 * MS))
    times = np.arange(10, dtype=np.int64) * 100 * MS
    held = {"/a": times.copy(), "/b": times.copy()}  # a message of each at every tick
    masks = unknown_masks(times, held, ["n", "c"], bindings,
                          [Gap(350 * MS, 420 * MS, frozenset({"/a"}), "chunk_crc")])
    assert np.flatnonzero(masks["c"]).tolist() == [4]  # it holds the message before the gap
    assert np.flatnonzero(masks["n"]).tolist() == [4, 5, 6]  # (t - 300 ms, t] holds tick 4


def test_count_ticks_on_a_csv_trace_in_the_audit(tmp_path):
    """A CSV trace's one clock counts once (a row per tick): violated at the first complete
    window with more than 3 true rows."""
    from fretc.audit import AuditConfig, audit_log, load_plan

    rows = [1 if i % 3 else 0 for i in range(40)]
    (tmp_path / "t.csv").write_text("time,a\n" + "".join(f"{i / 10:.1f},{a}\n"
                                                          for i, a in enumerate(rows)))
    (tmp_path / "r.fret").write_text("R: the robot shall always satisfy n <= 3\n")
    (tmp_path / "r.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nn = "count_ticks(/csv.a, 500 ms)"\n')
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),))),
                   str(tmp_path / "t.csv"))
    v = la.verdicts[0]
    first = next(i for i in range(5, 40) if sum(rows[i - 4:i + 1]) > 3)
    assert (v.verdict, v.warmup_ticks, v.ticks_evaluated) == ("violated", 5, 35)
    assert v.first_violation.at.time_ns == first * 100 * MS
