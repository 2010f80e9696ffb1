"""FoxQL filters right after the topic (docs/bindings.md, "FoxQL"): ``/r{radiation_type==1}.range``
reads the newest message of ``/r`` that passes the filter; messages that fail it are, for that
binding, as if not published (before the first passing one the binding waits, as before a
topic's first message), and a window over it counts passing messages only. Both clocks (the
watch's tick-by-tick one and the audit's block sampler) are checked against a recomputation
in plain Python over the generated messages."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import MS, both_clocks, ROS2, T, header, write_mcap
from fretc.common.problems import BindingError, SignalError
from fretc.logs import open_log
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.files import parse_bindings
from fretc.signals.bindings.spec import TickSpec, make_bindings
from fretc.signals.bindings.typecheck import check_types
from fretc.logs.schema import log_schemas
from fretc.signals.streams import Streams


def _range(ns: int, kind: int, r: float, frame: str) -> object:
    return T(ROS2, "sensor_msgs/msg/Range")(
        header=header(ns, ROS2, frame), radiation_type=kind, field_of_view=0.1,
        min_range=0.0, max_range=100.0, range=r)


def _log(tmp_path_factory, msgs):
    rows = [("/r", "sensor_msgs/msg/Range", t * MS, _range(t * MS, k, x, f))
            for t, k, x, f in sorted(msgs, key=lambda m: m[0])]
    return write_mcap(tmp_path_factory.mktemp("flt") / "f.mcap", rows, chunk_size=256)


_both_clocks = both_clocks


MSGS = st.lists(st.tuples(st.integers(0, 2000), st.integers(0, 2),
                          st.integers(-50, 50).map(float), st.sampled_from(["a", "b"])),
                min_size=1, max_size=50)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(msgs=MSGS, kind=st.integers(0, 2), period=st.integers(20, 300),
       span=st.integers(1, 800))
def test_a_filter_after_the_topic_holds_the_newest_passing_message(tmp_path_factory, msgs, kind,
                                                                   period, span):
    path = _log(tmp_path_factory, msgs)
    b = make_bindings({"x": f"/r{{radiation_type=={kind}}}.range",
                       "y": f'/r{{radiation_type>={kind}}}{{header.frame_id=="a"}}.range',
                       "n": f"count(/r{{radiation_type=={kind}}}.range > 0, {span} ms)"},
                      TickSpec(period_ns=period * MS))
    ticks = _both_clocks(path, b)
    order = sorted(msgs, key=lambda m: m[0])  # log order: stable for equal times
    px = [(t, x) for t, k, x, _f in order if k == kind]
    py = [(t, x) for t, k, x, f in order if k >= kind and f == "a"]
    if not px or not py:
        assert ticks == []  # before any passing message the bindings wait (warm-up)
        return
    # messages that fail the filters are as if not published: the grid runs from the first
    # passing message to the last (the first multiples at or after them); warm-up until
    # every stream has passed one and the window lies after the first
    first, last = min(px[0][0], py[0][0]), max(px[-1][0], py[-1][0])
    ready = max(px[0][0], py[0][0], px[0][0] + span)
    start = -(-first // period) * period  # the first multiple of the period from the first
    end = -(-last // period) * period  # and from the last
    grid = list(range(start, end + 1, period))
    assert [t.time / MS for t in ticks] == [g for g in grid if g >= ready]
    for tk in ticks:
        now = tk.time / MS
        assert tk.values["x"] == [x for t, x in px if t <= now][-1]
        assert tk.values["y"] == [x for t, x in py if t <= now][-1]
        assert tk.values["n"] == sum(1 for t, x in px if now - span < t <= now and x > 0)


def test_a_filter_after_the_topic_in_a_binding_file_and_its_text(tmp_path_factory):
    b = parse_bindings('[tick]\nperiod = "100 ms"\n[path_variables]\nk = 1\n'
                       "[variables]\nv = '/r{radiation_type==$k}.range'\n", "b.toml")
    node = b.variables["v"].ast
    assert node.topic == "/r{radiation_type==1.0}" and node.path == ("range",)
    assert node.text() == "/r{radiation_type==1.0}.range"
    assert b.variables["v"].topics == frozenset({"/r{radiation_type==1.0}"})


@pytest.mark.parametrize("expr, message", [
    ("/r{radiation_typo==1}.range", "has no field 'radiation_typo'.*topic /r"),
    ('/r{radiation_type=="x"}.range', "compares a uint8 field with a string"),
    ("/r{header==1}.range", "not a boolean, a number or a string"),
])
def test_a_bad_filter_after_the_topic_names_where_it_is(tmp_path_factory, expr, message):
    path = _log(tmp_path_factory, [(0, 1, 1.0, "a")])
    b = compile_expression("v", expr, source="b.toml", line=3, col=5)
    with pytest.raises(BindingError, match=message) as info:
        check_types(b, log_schemas(open_log(path)))
    assert str(info.value).startswith("b.toml:3:")


def test_a_message_without_the_filtered_field_names_the_binding_topic_and_log_time():
    b = compile_expression("v", "/j{id==3}.x", source="b.toml", line=4, col=5)
    streams = Streams([b])
    assert streams.fan_out("/j", 7, SimpleNamespace(id=3, x=1.0)) == ["/j{id==3.0}"]
    assert streams.fan_out("/j", 8, SimpleNamespace(id=2, x=1.0)) == []
    with pytest.raises(SignalError, match=r"b.toml:4:\d+: .*has no field 'id' "
                       r"\(topic /j, message at log time 9 ns\)"):
        streams.fan_out("/j", 9, SimpleNamespace(x=1.0))
    seen = []
    assert streams.fan_out("/j", 9, SimpleNamespace(x=1.0),
                           on_error=lambda s, e: seen.append(s)) == []
    assert seen == ["/j{id==3.0}"]
    assert streams.fan_out("/j", 10, SimpleNamespace(id=3, x=1.0)) == []  # read no more
