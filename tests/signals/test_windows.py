"""Windows over time (docs/bindings.md, "Windows over time"): ``mean(/a.data, 2s)`` and the
other window functions over a sliding window of a topic's messages. Both clocks (the
tick-by-tick one of the watch and the block sampler of the audit) are checked against
pandas' rolling functions on generated logs: time-based windows (``rolling("2s")``, closed
on the right) and counts of messages (``rolling(50)``)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import MS, both_clocks, float64, write_mcap
from fretc.common.problems import BindingError
from fretc.logs import open_log
from fretc.signals.arrays import sample_arrays
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.spec import TickSpec, make_bindings
from fretc.signals.bindings.windowing import WindowSpec
from fretc.signals.clock import sample
from fretc.signals.windows import SlidingWindow

FUNCS = {
    "w_mean": ("mean(/a.data, {w})", lambda r: r.mean()),
    "w_sum": ("sum(/a.data, {w})", lambda r: r.sum()),
    "w_min": ("min(/a.data, {w})", lambda r: r.min()),
    "w_max": ("max(/a.data * 2, {w})", lambda r: r.max() * 2),
    "w_median": ("median(/a.data, {w})", lambda r: r.median()),
    "w_p90": ("percentile(/a.data, 90, {w})", lambda r: r.quantile(0.9)),
    "w_var": ("variance(/a.data, {w})", lambda r: r.var()),
}


def _log(tmp_path_factory, a, t_times):
    msgs = [("/a", "std_msgs/msg/Float64", t * MS, float64(x)) for t, x in a]
    msgs += [("/t", "std_msgs/msg/Float64", t * MS, float64(0.0)) for t in t_times]
    return write_mcap(tmp_path_factory.mktemp("win") / "w.mcap",
                      sorted(msgs, key=lambda m: (m[2], m[0])), chunk_size=256)


_both_clocks = both_clocks


def _reference(a, times, span_ms, frame_fn, **kw):
    """pandas' time-based rolling window at each tick: the ticks are rows with no value,
    after the messages of their time, so each tick's window is its (t - span, t]."""
    rows = [(t, 0, x) for t, x in a] + [(t, 1, math.nan) for t in times]
    rows.sort(key=lambda r: (r[0], r[1]))
    df = pd.DataFrame(rows, columns=["t", "tick", "x"])
    df.index = pd.to_datetime(df["t"], unit="ms")
    r = df["x"].rolling(f"{span_ms}ms", closed="right", **kw)
    out = frame_fn(r)
    return out[df["tick"].to_numpy() == 1].to_numpy()


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=st.lists(st.tuples(st.integers(0, 3000), st.floats(-50, 50, allow_nan=False)),
                  min_size=1, max_size=60),
       t_times=st.lists(st.integers(0, 3000), min_size=1, max_size=20),
       span=st.integers(1, 1500), period=st.integers(20, 300), per_topic=st.booleans())
@pytest.mark.tor("TOR-BND-004")
def test_time_windows_equal_pandas_rolling(tmp_path_factory, a, t_times, span, period,
                                           per_topic):
    a = [(t, round(x, 3)) for t, x in a]
    path = _log(tmp_path_factory, a, t_times)
    tick = TickSpec(topic="/t") if per_topic else TickSpec(period_ns=period * MS)
    b = make_bindings({k: e.format(w=f"{span} ms") for k, (e, _f) in FUNCS.items()}
                      | {"w_count": f"count(/a.data > 0, {span}ms)",
                         "w_rate": f"rate(/a, {span} ms)"}, tick)
    ticks = _both_clocks(path, b)
    a_sorted = sorted(a, key=lambda m: m[0])
    first = a_sorted[0][0]
    times_ms = [t.time / MS for t in ticks]
    assert all(t - span >= first for t in times_ms)  # warm-up: only complete windows
    if not ticks:
        return
    for name, (_e, f) in FUNCS.items():
        want = _reference(a_sorted, times_ms, span, f, min_periods=0 if name == "w_sum" else 1)
        got = np.array([t.values[name] for t in ticks])
        assert np.allclose(got, want, rtol=1e-9, atol=1e-9, equal_nan=True), (name, got, want)
    pos = [(t, 1.0 if x > 0 else 0.0) for t, x in a_sorted]
    want = _reference(pos, times_ms, span, lambda r: r.sum(), min_periods=0)
    assert [t.values["w_count"] for t in ticks] == want.tolist()
    n = _reference(a_sorted, times_ms, span, lambda r: r.count(), min_periods=0)
    assert np.allclose([t.values["w_rate"] for t in ticks], n / (span / 1000))


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=st.lists(st.tuples(st.integers(0, 3000), st.floats(-50, 50, allow_nan=False)),
                  min_size=1, max_size=60),
       t_times=st.lists(st.integers(0, 3000), min_size=1, max_size=20),
       n=st.integers(1, 12), period=st.integers(20, 300))
@pytest.mark.tor("TOR-BND-004")
def test_windows_of_a_count_of_messages_equal_pandas_rolling(tmp_path_factory, a, t_times, n,
                                                             period):
    a = [(t, round(x, 3)) for t, x in a]
    path = _log(tmp_path_factory, a, t_times)
    b = make_bindings({"m": f"mean(/a.data, {n} messages)", "lo": f"min(/a.data, {n} messages)",
                       "p": f"percentile(/a.data, 25, {n} messages)"},
                      TickSpec(period_ns=period * MS))
    ticks = _both_clocks(path, b)
    s = pd.Series([x for _t, x in sorted(a, key=lambda m: m[0])])
    mt = np.array(sorted(t for t, _x in a)) * MS
    ref = {"m": s.rolling(n).mean(), "lo": s.rolling(n).min(), "p": s.rolling(n).quantile(0.25)}
    for t in ticks:
        held = int(np.searchsorted(mt, t.time, side="right")) - 1
        assert held >= n - 1  # warm-up until the window holds n messages
        for name, r in ref.items():
            assert math.isclose(t.values[name], r.iloc[held], rel_tol=1e-9, abs_tol=1e-9)


def test_a_nan_in_the_window_is_unread_and_an_empty_window_is_zero_or_nan():
    w = SlidingWindow(WindowSpec("mean", "/a", 1000, None, None, "1 us"))
    w.push(0, 1.0)
    w.push(500, math.nan)
    assert math.isnan(w.value(900))
    assert w.value(1499) != w.value(1499)  # the NaN still in (499, 1499]
    w.push(1600, 3.0)
    assert w.value(1600) == 3.0  # the NaN left the window
    assert math.isnan(w.value(5000))  # no message: no mean
    c = SlidingWindow(WindowSpec("count", "/a", 1000, None, None, "1 us"))
    c.push(0, True)
    assert c.value(0) == 1.0 and c.value(5000) == 0.0


@pytest.mark.parametrize("expr, message", [
    ("mean(/a.data, 2s) < 3", "the whole binding"),
    ("sum(/a.data)", "window function"),
    ("rate(/a.data, 1s)", "counts every message"),
    ("rate(/a, 10 messages)", "over a duration"),
    ("percentile(/a.data, 101, 2s)", "from 0 to 100"),
    ("mean(/a.data + /b.data, 2s)", "one topic"),
    ("mean(/a.data, 0 messages)", "at least 1"),
    ("mean(age(/a), 2s)", "not a field"),
    ("len(/a.data, 2s)", "no window"),
])
def test_bad_windows_are_errors_naming_the_column(expr, message):
    with pytest.raises(BindingError, match=message) as info:
        compile_expression("v", expr, source="b.toml", line=3, col=5)
    assert "b.toml:3:" in str(info.value)


def test_an_error_on_a_message_of_a_window_is_raised_by_both_clocks(tmp_path):
    """A message its window cannot read is an error at the first evaluated tick, also when
    that tick waits for another topic (warm-up): never lost."""
    from _logs import scan

    from fretc.common.problems import SignalError

    msgs = [("/scan", "sensor_msgs/msg/LaserScan", k * 100 * MS, scan([1.0] * 10, k * 100 * MS))
            for k in range(30)]
    msgs += [("/b", "std_msgs/msg/Float64", 2000 * MS, float64(1.0))]
    path = write_mcap(tmp_path / "e.mcap", sorted(msgs, key=lambda m: m[2]))
    b = make_bindings({"w": "mean(/scan.ranges[800], 1s)", "late": "/b.data"},
                      TickSpec(period_ns=100 * MS))
    with pytest.raises(SignalError, match="800") as one:
        list(sample(open_log(path), b))
    with pytest.raises(SignalError, match="800") as two:
        sample_arrays(open_log(path), b)
    assert "variable 'w'" in str(one.value) and "variable 'w'" in str(two.value)


def test_rate_takes_a_quoted_topic_as_age_does():
    """``rate("vehicle_status", 1 s)``: a topic without a leading / (a flight log's) is
    written quoted, as in ``age("vehicle_status")`` (found by the metamorphic sweep)."""
    from fretc.signals.bindings.expression import ExprLocation, Field, Span
    from fretc.signals.bindings.parse import parse_expression

    node, topics = parse_expression('rate("vehicle_status", 1 s)', ExprLocation("f", "v", 1, 1))
    assert isinstance(node.args[0], Field) and node.args[0].topic == "vehicle_status"
    assert isinstance(node.args[1], Span) and node.args[1].ns == 1_000_000_000
    assert topics == frozenset({"vehicle_status"})


@pytest.mark.parametrize("func", ["median(/v.data, 2s)", "percentile(/v.data, 90, 2s)"])
def test_median_and_percentile_keep_an_order_statistics_structure(func):
    """The window's values sorted in a list cost a memory move of the window per message
    (10^6 messages at 1 kHz in a 900 s window: about 100 s, against 10 s for ``max``); an
    order-statistics structure inserts and removes in logarithmic time
    (``bench/fuzz_hostile.py --classes windows``: the ratio measured in one run). Its values
    stay those of a sorted list: checked here message by message on a window that fills,
    slides and holds ties and signed zeros."""
    import random

    from sortedcontainers import SortedList

    from fretc.signals.bindings.binding import compile_expression
    from fretc.signals.windows import sliding_windows

    b = compile_expression("w", func, source="b.toml", line=1, col=1)
    (w,) = sliding_windows([b]).values()
    assert isinstance(w.ordered, SortedList)
    rng = random.Random(7)
    ref: list[tuple[int, float]] = []
    for k in range(3000):
        t = k * 10**7  # 100 Hz in a 2 s window: 200 values
        x = rng.choice([0.0, -0.0, 1.5, rng.uniform(-5, 5)])
        w.push(t, x)
        ref = [(u, y) for u, y in ref + [(t, x)] if u > t - 2 * 10**9]
        got = w.value(t)
        want = sorted(y for _u, y in ref)
        q = 0.5 if func.startswith("median") else 0.9
        pos = q * (len(want) - 1)
        i = int(pos)
        j = min(i + 1, len(want) - 1)
        assert got == pytest.approx(want[i] + (want[j] - want[i]) * (pos - i), abs=1e-12)


@pytest.mark.tor("TOR-TCK-004")
def test_a_window_extends_the_warm_up_until_it_is_complete(tmp_path_factory):
    """A window over 500 ms of /a, sent every 100 ms from 0: the ticks before the window is
    complete are warm-up (0 to 400 ms), the first evaluated is at 500 ms, and every later
    tick is evaluated; the same variable without a window is evaluated from the first
    message on."""
    path = _log(tmp_path_factory, [(t, float(t)) for t in range(0, 2001, 100)], [])
    tick = TickSpec(period_ns=100 * MS)
    s = sample(open_log(path), make_bindings({"m": "mean(/a.data, 500 ms)"}, tick))
    ticks = list(s)
    assert s.warmup_ticks == 5 and s.first_time == 500 * MS
    assert [t.time for t in ticks] == [t * MS for t in range(500, 2001, 100)]
    assert ticks[0].values["m"] == pytest.approx(300.0)  # (100 + ... + 500) / 5
    assert _both_clocks(path, make_bindings({"m": "mean(/a.data, 500 ms)"}, tick)) == ticks
    s = sample(open_log(path), make_bindings({"x": "/a.data"}, tick))
    assert len(list(s)) == 21 and s.warmup_ticks == 0 and s.first_time == 0
