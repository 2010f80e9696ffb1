"""Binding files, the expression language, REP 117 handling, errors with file:line:col."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from fretc.signals.columns import HeldColumns, MessageColumns
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.common.units import parse_duration
from fretc.signals.bindings.binding import compile_expression, parse_inline
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.files import load_bindings, parse_bindings
from fretc.signals.bindings.spec import Bindings, TickSpec, make_bindings
from fretc.common.problems import BindingError, SignalError

from _logs import ROS1, ROS2, scan, twist

NS = SimpleNamespace


def ev(expr, msgs, now=0, times=None):
    b = compile_expression("v", expr)
    st_ = EvalState()
    st_.msgs = msgs
    st_.times = times or {t: 0 for t in msgs}
    st_.now = now
    with np.errstate(all="ignore"):
        return b.evaluate(st_)


# ------------------------------------------------------------------------------------------------
# Binding files
# ------------------------------------------------------------------------------------------------

GOOD = """\
# Safe-ROS R1 on the Scout Mini
[tick]
period = "100 ms"
time = "log"

[variables]
too_close = "min(/scan.ranges) < 0.9"
stopped = "abs(/cmd_vel_filtered.linear.x) < 1e-3 & abs(/cmd_vel_filtered.angular.z) < 1e-3"
stop_requested = "/gwendolen_control.data"
linear_speed = "abs(/cmd_vel_filtered.linear.x)"
scan_stale = "age(/scan) > 0.3"
"""


def test_load_bindings_file(tmp_path):
    p = tmp_path / "scout.toml"
    p.write_text(GOOD)
    b = load_bindings(p)
    assert list(b.variables) == ["too_close", "stopped", "stop_requested", "linear_speed", "scan_stale"]
    assert b.tick == TickSpec(period_ns=100_000_000)
    assert b.time_base == "log" and b.source == str(p)
    assert b.topics == {"/scan", "/cmd_vel_filtered", "/gwendolen_control"}
    assert b.variables["scan_stale"].topics == {"/scan"}
    too_close = b.variables["too_close"]
    assert (too_close.line, too_close.col) == (7, 14)  # first char inside the quotes


@pytest.mark.tor("TOR-TCK-005", "TOR-TCK-008")
def test_tick_topic_header_time_and_lag():
    b = parse_bindings('[tick]\ntopic = "/scan"\ntime = "header"\nheader_lag = "250 ms"\n[variables]\nx = "/scan.range_max > 1"\n')
    assert b.tick == TickSpec(topic="/scan") and b.time_base == "header"
    assert b.header_lag_ns == 250_000_000


@pytest.mark.parametrize("value, ns", [
    ("100 ms", 100_000_000), ("0.1 s", 100_000_000), ("10 Hz", 100_000_000), ("1 min", 60 * 10**9),
    ("250us", 250_000), ("7 ns", 7), (0.05, 50_000_000), (2, 2 * 10**9), ("3 Hz", 333_333_333),
])
def test_parse_duration(value, ns):
    assert parse_duration(value) == ns


@pytest.mark.parametrize("value", ["100", "fast", "0 ms", "-1 s", "10 parsecs", True, "0 Hz"])
def test_parse_duration_rejects(value):
    with pytest.raises(ValueError):
        parse_duration(value)


@pytest.mark.parametrize("text, line, col, what", [
    ('[tick]\nperiod = "100 ms"\n[variables]\nok = "/a.x > 1"\nbad = "min(/scan.ranges) <"\n', 5, 27,
     "expression ends too early"),
    ('[tick]\nperiod = "100 ms"\n[variables]\nbad = "abs(/a.x) $ 3"\n', 4, 18, "unexpected character '$'"),
    ('[tick]\nperiod = "100 ms"\n[variables]\n  bad = "1 + hypot(/a.x)"\n', 4, 14, "unknown function 'hypot'"),
    ('[tick]\nperiod = "100 ms"\n[variables]\nbad = "age(/a.x) > 1"\n', 4, 12, "age() takes a topic"),
    ('[tick]\nperiod = "100 ms"\n[variables]\nbad = "/scan < 3"\n', 4, 8, "is a topic, not a value"),
    ('[tick]\nperiod = "100 ms"\n[variables]\nbad = 3\n', 4, 7, "must be a string"),
    ('[tick]\nperiod = "100 ms"\n[variables]\n" bad" = "/a.x"\n', 4, 1, "not an identifier"),
    ('[tick]\nperiod = "fast"\n[variables]\n', 2, 10, "[tick] period"),
    ('[tick]\nperiod = "1 s"\ntopic = "/a"\n[variables]\n', 1, 1, "exactly one of"),
    ('[tick]\nperiod = "1 s"\ntime = "wall"\n[variables]\n', 3, 8, "time must be"),
    ('[tick]\nperiod = "1 s"\nsped = 2\n[variables]\n', 3, 8, "unknown key 'sped'"),
    ('[tick]\ntopic = " "\n[variables]\n', 2, 9, "not a topic name"),
    ('[tick]\nperiod = "1 s"\n[variabels]\nx = "/a.b"\n', 3, 1, "unknown table [variabels]"),
    ('[variables]\nx = "/a.b"\n', 1, None, "missing [tick]"),
    ('[tick]\nperiod = "1 s"\n[variables]\nx = "/a.b\n', 4, None, "TOML syntax error"),
])
def test_binding_file_errors_name_file_line_col(tmp_path, text, line, col, what):
    p = tmp_path / "b.toml"
    p.write_text(text)
    with pytest.raises(BindingError) as err:
        load_bindings(p)
    e = err.value
    assert e.source == str(p) and e.line == line
    if col is not None:
        assert e.col == col
    assert what in str(e)
    assert str(e).startswith(f"{p}:{line}")


def test_error_names_the_variable(tmp_path):
    p = tmp_path / "b.toml"
    p.write_text('[tick]\nperiod = "1 s"\n[variables]\nstopped = "abs(/v.x) <"\n')
    with pytest.raises(BindingError, match=r"b\.toml:4:\d+: variable 'stopped': syntax error"):
        load_bindings(p)


def test_inline_bindings_override_and_errors(tmp_path):
    p = tmp_path / "b.toml"
    p.write_text(GOOD)
    b = load_bindings(p, inline=["too_close=min(/scan.ranges) < 0.5", "extra = /odom.pose.pose.position.x > 1"])
    assert b.variables["too_close"].expr == "min(/scan.ranges) < 0.5"
    assert b.variables["too_close"].source == "<--bind too_close>"
    assert "/odom" in b.topics and list(b.variables)[-1] == "extra"
    with pytest.raises(BindingError, match=r"<--bind x>:1:10: variable 'x': syntax error"):
        parse_inline("x=/a.b < ")
    with pytest.raises(BindingError, match="NAME=EXPRESSION"):
        parse_inline("just an expression")


# ------------------------------------------------------------------------------------------------
# Expression semantics
# ------------------------------------------------------------------------------------------------


def test_precedence_and_fret_spellings():
    m = {"/a": NS(x=2.0, y=-3.0, f=True, g=False)}
    assert ev("/a.x + /a.y * 2", m) == -4.0
    assert ev("-/a.y - -1", m) == 4.0
    assert ev("(/a.x + /a.y) * 2", m) == -2.0
    assert ev("/a.x/2", m) == 1.0  # "/" after an operand divides
    assert ev("!/a.x < 1", m) is True  # ! is looser than comparison
    assert ev("/a.f & /a.g | true", m) is True
    assert ev("/a.f & (/a.g | false)", m) is False
    assert ev("/a.g -> /a.x > 100", m) is True
    assert ev("/a.f -> /a.g -> /a.f", m) is True  # right-assoc: f -> (g -> f)
    assert ev("/a.f <-> /a.g", m) is False
    assert ev("/a.x = 2 & /a.x == 2 & /a.y != 2", m) is True
    assert ev("/a.x >= 2 & /a.x <= 2 & !(/a.x > 2)", m) is True


def test_integer_fields_become_floats_and_results_are_python_types():
    m = {"/s": NS(level=np.int32(3), n=7, ok=np.bool_(True))}
    assert ev("/s.level", m) == 3.0 and type(ev("/s.level", m)) is float
    assert type(ev("/s.n", m)) is float
    assert ev("/s.ok", m) is True
    assert ev("/s.n / 2", m) == 3.5


def test_division_by_zero_is_ieee():
    m = {"/a": NS(x=1.0, z=0.0)}
    assert ev("/a.x / /a.z", m) == math.inf
    assert ev("-/a.x / /a.z", m) == -math.inf
    assert math.isnan(ev("/a.z / /a.z", m))


@pytest.mark.tor("TOR-DMG-004", "TOR-VER-004")
def test_nan_compares_unknown_and_logic_is_three_valued():
    """[tick] nan = "unread" (the default): a comparison with NaN is NaN, Kleene logic."""
    m = {"/a": NS(x=math.nan, y=1.0, arr=np.array([1.0, math.nan, 7.0]))}
    for e in ("/a.x < 1", "/a.x >= 1", "!(/a.x >= 1)", "/a.x != /a.x", "/a.x = /a.x"):
        assert math.isnan(ev(e, m)), e
    assert ev("/a.x < 1 & /a.y > 5", m) is False       # false & unknown = false
    assert ev("/a.x < 1 | /a.y < 5", m) is True        # true | unknown = true
    assert ev("/a.y > 5 -> /a.x < 1", m) is True       # false -> unknown = true
    for e in ("/a.x < 1 & /a.y < 5", "/a.x < 1 | /a.y > 5", "/a.x < 1 <-> /a.y < 5",
              "/a.y < 5 -> /a.x < 1"):
        assert math.isnan(ev(e, m)), e
    assert ev("any(/a.arr > 5)", m) is True            # one item true decides any
    assert math.isnan(ev("any(/a.arr > 9)", m))        # none true, one unknown
    assert ev("all(/a.arr < 5)", m) is False           # one item false decides all
    assert math.isnan(ev("all(/a.arr < 9)", m))
    assert math.isnan(ev("count(/a.arr > 0)", m))
    assert math.isnan(ev("min(/a.x, 1)", m)) and math.isnan(ev("max(1, /a.x)", m))


def test_nan_policy_false_is_ieee():
    m = {"/a": NS(x=math.nan)}

    def ev_false(expr):
        b = compile_expression("v", expr, nan="false")
        st_ = EvalState()
        st_.msgs, st_.times, st_.now = m, {"/a": 0}, 0
        return b.evaluate(st_)
    assert ev_false("/a.x < 1") is False and ev_false("/a.x >= 1") is False
    assert ev_false("/a.x != /a.x") is True
    assert ev_false("/a.x & true") is True  # a number read as a boolean: != 0


@pytest.mark.tor("TOR-DMG-004", "TOR-VER-004")
@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from([0.0, 1.0, 6.0, math.nan]), min_size=1, max_size=8),
       st.lists(st.sampled_from([0.0, 3.0, math.nan]), min_size=1, max_size=8),
       st.sampled_from(["/a.x > 5 & /a.y < 1", "/a.x > 5 | !(/a.y < 1)",
                        "/a.x < 2 -> /a.y = 0", "(/a.x > 0) <-> (/a.y > 0)",
                        "!(/a.x >= 1)"]))
def test_three_valued_is_the_same_per_tick_and_vectorized(xs, ys, expr):
    """The vectorized evaluator gives the per-tick one's values, NaN included."""
    n = min(len(xs), len(ys))
    b = compile_expression("v", expr)
    per_tick = []
    for i in range(n):
        per_tick.append(ev(expr, {"/a": NS(x=xs[i], y=ys[i])}))

    class Cols:
        def field(self, topic, path, node):
            return np.array((xs if path == ("x",) else ys)[:n])
    with np.errstate(all="ignore"):
        vec = np.asarray(b._vector(Cols()), dtype=np.float64)
    want = np.array(per_tick, dtype=np.float64)
    assert np.array_equal(vec, want, equal_nan=True), (expr, xs, ys)


@pytest.mark.tor("TOR-DMG-004", "TOR-VER-004")
def test_any_and_all_over_arrays_of_many_ticks_are_unknown_only_where_an_item_is():
    """``any``/``all`` of an array field read over many ticks at once (the vectorized
    evaluator): a tick is unknown only when its own items leave it undecided, whatever an
    item of another tick; the values are the per-tick evaluator's."""
    arrays = [[1.0, math.nan], [1.0, 2.0], [0.1, math.nan], [3.0, 4.0]]
    messages = [NS(arr=np.array(a)) for a in arrays]
    idx = np.arange(len(messages), dtype=np.int64)
    cols = HeldColumns(MessageColumns({"/a": messages}), idx, {"/a": idx}, {"/a": idx})
    for expr, want in [("any(/a.arr < 0.5)", [math.nan, 0.0, 1.0, 0.0]),
                       ("all(/a.arr < 5)", [math.nan, 1.0, math.nan, 1.0])]:
        b = compile_expression("v", expr)
        with np.errstate(all="ignore"):
            vec = np.asarray(b.evaluate_columns(cols), dtype=np.float64)
        per_tick = [ev(expr, {"/a": m}) for m in messages]
        assert np.array_equal(vec, np.array(want), equal_nan=True), (expr, vec)
        assert np.array_equal(np.array(per_tick, dtype=np.float64), vec, equal_nan=True), expr


def test_indexing_norm_len_and_arrays():
    m = {"/v": NS(items=[NS(p=1.0), NS(p=2.0), NS(p=5.0)], arr=np.array([3.0, -4.0, 12.0]))}
    assert ev("/v.items[0].p + /v.items[-1].p", m) == 6.0
    assert ev("/v.arr[1]", m) == -4.0
    assert ev("norm(/v.arr[0], /v.arr[1])", m) == 5.0
    assert ev("norm(/v.arr)", m) == 13.0
    assert ev("len(/v.arr)", m) == 3.0
    assert ev("count(/v.arr > 0)", m) == 2.0
    assert ev("any(/v.arr < -3) & !all(/v.arr > 0)", m) is True
    assert ev("max(abs(/v.arr))", m) == 12.0
    assert ev("mean(/v.arr * 2 + 1)", m) == pytest.approx(np.mean(np.array([3.0, -4.0, 12.0]) * 2 + 1))
    assert ev("min(/v.arr[0], /v.arr[1], 7)", m) == -4.0
    assert ev("len(/v.items)", m) == 3.0  # a sequence of messages
    with pytest.raises(SignalError, match=r"variable 'v': any\(\) takes an array"):
        ev("any(/v.items[0].p)", m)


def test_array_valued_variable_is_an_error():
    m = {"/v": NS(arr=np.array([1.0, 2.0]))}
    with pytest.raises(SignalError, match=r"variable 'v': value is an array of 2 items"):
        ev("/v.arr * 2", m)


def test_missing_field_and_index_errors_name_the_column():
    b = compile_expression("speed", "abs(/cmd.linear.q) > 1", source="b.toml", line=9, col=10)
    st_ = EvalState()
    st_.msgs = {"/cmd": twist(1.0)}
    with pytest.raises(SignalError, match=r"b\.toml:9:14: variable 'speed': /cmd\.linear\.q: a "
                                          r"geometry_msgs/msg/Vector3 message has no field 'q'"):
        b.evaluate(st_, " at log time 5")
    b = compile_expression("r", "/scan.ranges[5] > 1", source="b.toml", line=2, col=5)
    st_.msgs = {"/scan": scan([1.0, 2.0])}
    with pytest.raises(SignalError, match=r"b\.toml:2:5: variable 'r': /scan\.ranges\[5\]: index out of range"):
        b.evaluate(st_)


def test_age_is_seconds_since_the_held_message():
    assert ev("age(/a)", {"/a": NS(x=1)}, now=1_250_000_000, times={"/a": 1_000_000_000}) == 0.25
    assert ev("age(/a) > 0.3", {"/a": NS(x=1)}, now=1_250_000_000, times={"/a": 1_000_000_000}) is False


# -- REP 117 ------------------------------------------------------------------------------------


def test_laserscan_rep117_ignores_nan_inf_and_out_of_range():
    ranges = [0.05, 0.95, np.nan, np.inf, 2.5, 10.0, 10.5, 0.1]
    m = {"/scan": scan(ranges, range_min=0.1, range_max=10.0)}
    r = np.asarray(ranges, dtype=np.float32).astype(np.float64)
    valid = r[(r >= np.float32(0.1)) & (r <= np.float32(10.0))]
    assert sorted(valid) == pytest.approx([0.1, 0.95, 2.5, 10.0])
    assert ev("min(/scan.ranges)", m) == valid.min()
    assert ev("max(/scan.ranges)", m) == valid.max()
    assert ev("mean(/scan.ranges)", m) == pytest.approx(valid.mean())
    assert ev("len(/scan.ranges)", m) == 4.0
    assert ev("count(/scan.ranges < 0.9)", m) == 1.0  # 0.1 only; 0.05 is below range_min
    assert ev("any(/scan.ranges > 10.2)", m) is False  # 10.5 is beyond range_max
    assert ev("all(/scan.ranges >= 0.1)", m) is True
    assert ev("norm(/scan.ranges)", m) == pytest.approx(np.sqrt((valid ** 2).sum()))
    # Indexing reads the raw beam.
    assert math.isnan(ev("/scan.ranges[2]", m))
    assert ev("/scan.ranges[0]", m) == pytest.approx(0.05)
    # Intensities are not filtered.
    assert ev("len(/scan.intensities)", m) == 8.0


def test_laserscan_negative_infinity_is_a_too_close_return():
    # REP 117: -inf = detected but closer than range_min; it must not hide an obstacle
    m = {"/scan": scan([2.0, -np.inf, 5.0], range_min=0.1, range_max=10.0)}
    assert ev("min(/scan.ranges)", m) == pytest.approx(0.1)
    assert ev("min(/scan.ranges) < 0.9", m) is True
    assert ev("len(/scan.ranges)", m) == 3.0
    assert ev("/scan.ranges[1]", m) == -math.inf  # indexing stays raw


@pytest.mark.tor("TOR-BND-002")
def test_laserscan_with_no_valid_return():
    """No valid return and invalid measurements (REP 117: NaN, 0.01 and 50.0 outside the
    limits): ``min`` is unknown (NaN), and ``min(...) < 0.9`` neither true nor false; it was
    +inf and false, a blind LiDAR read as a clear path. Only +inf beams: the clear view."""
    m = {"/scan": scan([np.nan, np.inf, 0.01, 50.0], range_min=0.1, range_max=10.0)}
    assert math.isnan(ev("min(/scan.ranges)", m))
    assert math.isnan(ev("max(/scan.ranges)", m))
    assert math.isnan(ev("mean(/scan.ranges)", m))
    assert math.isnan(ev("min(/scan.ranges) < 0.9", m))
    assert ev("invalid(/scan.ranges)", m) == 3.0
    clear = {"/scan": scan([np.inf, np.inf], range_min=0.1, range_max=10.0)}
    assert ev("min(/scan.ranges)", clear) == math.inf
    assert ev("min(/scan.ranges) < 0.9", clear) is False
    assert ev("invalid(/scan.ranges)", clear) == 0.0
    assert ev("len(/scan.ranges)", m) == 0.0
    assert ev("count(/scan.ranges < 100)", m) == 0.0
    assert ev("any(/scan.ranges < 100)", m) is False
    assert ev("all(/scan.ranges < 0)", m) is True


def test_laserscan_ros1_type_is_recognized():
    m = {"/scan": scan([0.01, 1.0], range_min=0.1, range_max=5.0, store=ROS1)}
    assert ev("min(/scan.ranges)", m) == 1.0


def test_plain_arrays_propagate_nan_and_empty_reductions():
    m = {"/a": NS(v=np.array([1.0, np.nan]), e=np.array([], dtype=np.float64))}
    assert math.isnan(ev("min(/a.v)", m))
    assert ev("min(/a.e)", m) == math.inf and ev("max(/a.e)", m) == -math.inf
    assert ev("count(/a.e)", m) == 0.0 and ev("len(/a.e)", m) == 0.0


finite = st.floats(min_value=-5, max_value=20, allow_nan=False, width=32)
cell = st.one_of(finite, st.just(float("nan")), st.just(float("inf")), st.just(float("-inf")))


@settings(max_examples=60, deadline=None)
@given(st.lists(cell, min_size=0, max_size=40), st.floats(0, 1, width=32), st.floats(2, 15, width=32))
def test_rep117_reductions_match_numpy(ranges, rmin, rmax):
    m = {"/scan": scan(ranges, range_min=rmin, range_max=rmax)}
    msg = m["/scan"]
    r = np.asarray(msg.ranges, dtype=np.float64)
    r = np.where(np.isneginf(r), msg.range_min, r)  # REP 117 -inf: closer than range_min
    ok = (r >= msg.range_min) & (r <= msg.range_max)
    v = r[ok]
    # (no valid return: +inf / -inf when every beam is +inf, "no return", a clear view; NaN,
    # unknown, when one is an invalid measurement: a blind LiDAR is no clear path)
    invalid = ~ok & ~np.isposinf(r)
    blind = not v.size and invalid.any()
    lo, hi = ev("min(/scan.ranges)", m), ev("max(/scan.ranges)", m)
    if blind:
        assert math.isnan(lo) and math.isnan(hi)
    else:
        assert lo == (v.min() if v.size else math.inf)
        assert hi == (v.max() if v.size else -math.inf)
    assert ev("invalid(/scan.ranges)", m) == float(invalid.sum())
    assert ev("count(/scan.ranges < 3)", m) == float((v < 3).sum())
    assert ev("len(/scan.ranges)", m) == float(v.size)
    mean = ev("mean(/scan.ranges)", m)
    if v.size:
        assert mean == pytest.approx(v.mean(), rel=1e-12)
    else:
        assert math.isnan(mean)


def test_make_bindings_and_tickspec_validation():
    b = make_bindings({"fast": "abs(/cmd.linear.x) > 0.5"}, TickSpec(topic="/cmd"))
    assert isinstance(b, Bindings) and b.topics == {"/cmd"}
    with pytest.raises(ValueError):
        TickSpec(period_ns=10, topic="/a")
    with pytest.raises(ValueError):
        TickSpec()
    with pytest.raises(ValueError):
        Bindings({}, TickSpec(period_ns=1), time_base="wall")


def test_ros2_laserscan_type_name_and_vectorized_agree():
    """The per-tick and vectorized closures of one binding give identical values."""
    b = compile_expression("v", "mean(/scan.ranges * 2) + count(/scan.ranges > 1) - min(/scan.ranges)")
    scans = [scan(np.random.default_rng(i).uniform(-1, 12, 50)) for i in range(20)]
    per_tick = []
    for s in scans:
        st_ = EvalState()
        st_.msgs = {"/scan": s}
        per_tick.append(b.evaluate(st_))
    msgs = MessageColumns({"/scan": scans})
    idx = np.arange(len(scans))
    cols = HeldColumns(msgs, idx.astype(np.int64), {"/scan": idx.astype(np.int64)},
                       {"/scan": idx})
    assert b.evaluate_columns(cols).tolist() == per_tick
    assert ROS2.types["sensor_msgs/msg/LaserScan"].__msgtype__ == "sensor_msgs/msg/LaserScan"


def test_a_tick_topic_is_named_as_inspect_lists_it():
    """A flight log's topics have no leading ``/`` (``vehicle_local_position``, ``GPS/1``):
    a tick topic is any name inspect lists, quoted as a binding quotes it or not."""
    import json as _json

    from fretc.signals.bindings.paths import topic_name

    for text, name in [("/scan", "/scan"), ("vehicle_local_position", "vehicle_local_position"),
                       ('"vehicle_local_position"', "vehicle_local_position"),
                       ("GPS/1", "GPS/1"), ('"ORB-SLAM"', "ORB-SLAM")]:
        assert topic_name(text) == name
        b = parse_bindings(f"[tick]\ntopic = {_json.dumps(text)}\n[variables]\n", "b.toml")
        assert b.tick.topic == name
    for bad in ("", " ", "a\x00b", '"unbalanced', '""'):
        assert topic_name(bad) is None, bad


def _count_parses(monkeypatch) -> list[str]:
    """Count the expressions parsed (``parse_expression``, imported where it is called)."""
    from fretc.signals.bindings import parse

    calls: list[str] = []
    real = parse.parse_expression

    def counted(expr, where, path_vars=None):
        calls.append(expr)
        return real(expr, where, path_vars)

    monkeypatch.setattr(parse, "parse_expression", counted)
    return calls


_THREE = ('[tick]\nperiod = "100 ms"\n[variables]\nnear = "min(/scan.ranges) < 0.9"\n'
          'fast = "abs(/cmd_vel.linear.x) > 0.4"\nboth = "near & fast"\n')


def _trees(b) -> dict:
    return {n: (repr(v.ast), v.topics) for n, v in b.variables.items()}


def test_a_binding_file_parses_each_expression_once(monkeypatch):
    """Each variable's text is parsed once, references included (the parse that orders the
    variables is the one compiled), and the compiled bindings are those of a parse each."""
    monkeypatch.setenv("FRETC_CACHE_DIR", "")
    once = parse_bindings(_THREE, "b.toml")
    calls = _count_parses(monkeypatch)
    again = parse_bindings(_THREE, "b.toml")
    assert sorted(calls) == sorted(["min(/scan.ranges) < 0.9", "abs(/cmd_vel.linear.x) > 0.4",
                                    "near & fast"])
    assert _trees(again) == _trees(once)


def _binding_files() -> list:
    root = Path(__file__).resolve().parents[2]
    return sorted(p for d in ("requirements", "examples", "traces") if (root / d).is_dir()
                  for p in (root / d).rglob("*.bindings.toml"))


@pytest.mark.parametrize("path", _binding_files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_parsed_expressions_from_the_cache_are_the_parsed_ones(path, tmp_path, monkeypatch):
    """Cold, warm (read from disk: nothing parsed) and cache off give the same trees and
    topics for every binding file of the repository."""
    calls = _count_parses(monkeypatch)
    got = []
    for cache_dir in (tmp_path / "c", tmp_path / "c", ""):
        monkeypatch.setenv("FRETC_CACHE_DIR", str(cache_dir))
        calls.clear()
        got.append((_trees(load_bindings(path)), len(calls)))
    assert got[0][0] == got[1][0] == got[2][0]
    n = got[0][1]
    assert [c for _t, c in got] == [n, 0, n] and n >= 1


def test_binding_parse_cache_misses_on_other_text_code_damage_and_keeps_no_error(
        tmp_path, monkeypatch):
    from fretc.signals.bindings import parse_cache

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    calls = _count_parses(monkeypatch)
    first = _trees(parse_bindings(_THREE, "b.toml"))
    other = _THREE.replace("0.9", "0.8")
    assert _trees(parse_bindings(other, "b.toml")) != first  # same file, other text
    calls.clear()
    assert _trees(parse_bindings(_THREE, "b.toml")) == first and len(calls) == 3
    calls.clear()
    assert _trees(parse_bindings(_THREE, "b.toml")) == first and not calls  # a hit
    monkeypatch.setattr(parse_cache, "_CODE_KEY", "other code")
    assert _trees(parse_bindings(_THREE, "b.toml")) == first and len(calls) == 3
    (f,) = (tmp_path / "binding-parses").iterdir()
    for damage in (lambda b: b[:len(b) // 2], lambda b: b[:-10] + bytes(10),
                   lambda b: b"x" + b[1:]):
        f.write_bytes(damage(f.read_bytes()))
        calls.clear()
        assert _trees(parse_bindings(_THREE, "b.toml")) == first and len(calls) == 3
    bad = _THREE.replace('"near & fast"', '"near & (fast"')
    for _ in range(2):  # an expression that does not parse: never kept, its error each time
        with pytest.raises(BindingError, match="syntax error"):
            parse_bindings(bad, "bad.toml")


def _holds(obj, target) -> bool:
    """Whether the tree ``obj`` holds the very object ``target`` (an entity key)."""
    import dataclasses

    from fretc.signals.bindings.expression import EntityParam

    if obj is target:
        return True
    if isinstance(obj, EntityParam):
        return False
    if dataclasses.is_dataclass(obj):
        return any(_holds(getattr(obj, f.name), target) for f in dataclasses.fields(obj))
    return isinstance(obj, (tuple, list)) and any(_holds(x, target) for x in obj)


def test_entity_keys_are_read_back_from_the_cache_as_the_live_key(tmp_path, monkeypatch):
    """A tree over an entity's key holds the very object the audit sets each entity's value
    on: read back from the cache, it holds the key object of the load it is read for (never
    a copy, nor an earlier load's key)."""
    from fretc.signals.bindings.expression import EntityParam
    from fretc.signals.bindings.files import _compile_in_order

    holds = _holds
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    calls = _count_parses(monkeypatch)
    keys = []
    for _ in range(3):
        key = EntityParam("track")
        keys.append(key)
        pending = {"near": ('max(/tracks.tracks[:]{id == $track}.x) < 2', None, None, True)}
        compiled = _compile_in_order(pending, "e.toml", path_vars={"track": key})
        assert holds(compiled["near"].ast, key)
        assert not any(holds(compiled["near"].ast, k) for k in keys[:-1])
    assert len(calls) == 1  # (the first load parsed; the others read the cache)
    assert list((tmp_path / "binding-parses").iterdir())
    other = {"near": ('max(/tracks.tracks[:]{id == $ship}.x) < 2', None, None, True)}
    ship = EntityParam("ship")
    assert holds(_compile_in_order(other, "e.toml", path_vars={"ship": ship})["near"].ast, ship)


def test_per_entity_variables_and_keys_are_parsed_once_across_loads(tmp_path, monkeypatch):
    """A per-entity binding file: its per-entity variables (compiled per entity key object,
    :meth:`Bindings.for_entity`) and its ``[entities]`` key are parsed once; later loads
    read the cache and their trees hold that load's own key object. Compiled for an
    entity's own value they are parsed each time and never written to the cache. An
    expression that does not parse still gives its error, with its place."""
    from fretc.audit.entities.kinds import entity_kind
    from fretc.common.problems import BindingError
    from fretc.signals.bindings.expression import EntityParam

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    calls = _count_parses(monkeypatch)
    text = ('[tick]\nperiod = "100 ms"\n[entities]\ntrack = "/tracks.tracks[:].id"\n'
            '[variables]\ndist = "min(/tracks.tracks[:]{id==$track}.distance)"\n'
            'near = "dist < 1"\n')
    for k in range(3):
        b = parse_bindings(text, "e.toml")
        key = EntityParam("track")
        own = b.for_entity({"track": key}).variables
        assert _holds(own["dist"].ast, key) and _holds(own["near"].ast, key)
        assert entity_kind(b, "track").topic == "/tracks"
        if k == 0:
            first = len(calls)
    assert first >= 3 and len(calls) == first
    entries = sorted((f.name, f.stat().st_mtime_ns) for f in (tmp_path / "binding-parses").iterdir())
    for value in (7, 8):  # (an entity's own value, as fretc watch compiles one: not kept)
        assert b.for_entity({"track": value}).variables["dist"].topics == {"/tracks"}
    assert len(calls) == first + 4
    assert sorted((f.name, f.stat().st_mtime_ns)
                  for f in (tmp_path / "binding-parses").iterdir()) == entries
    bad = text.replace("{id==$track}.distance)", "{id==$track}.distance")
    with pytest.raises(BindingError, match=r"e\.toml:\d+:\d+"):
        parse_bindings(bad, "e.toml").for_entity({"track": EntityParam("track")})
