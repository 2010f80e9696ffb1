"""Events between ticks: a binding may fold the messages of its topic since the previous
tick (``any_of_messages``, ``all_of_messages``, ``count_of_messages``, ``min_of_messages``,
``max_of_messages``), so an ERROR superseded within milliseconds is still seen at the next
tick. The tick-by-tick clock (the watch) and the block sampler (the audit) fold the same
windows, checked against an independent fold of the log's own messages."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import MS, S, float64, write_mcap
from _shared import SHARED, params
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.common.problems import BindingError
from fretc.logs import open_log
from fretc.signals.arrays import sample_arrays
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.spec import TickSpec, make_bindings
from fretc.signals.clock import sample

BASIS = SHARED / "data" / "foreign_logs" / "basis_pb" / "demo_81739.567984327.mcap"

FOLDS = {
    "any_hi": ("any_of_messages(/a.data > 0.5)", lambda xs: _kleene_any([x > 0.5 for x in xs], xs)),
    "all_lo": ("all_of_messages(/a.data > -0.5)", lambda xs: _kleene_all([x > -0.5 for x in xs], xs)),
    "n_pos": ("count_of_messages(/a.data > 0)",
              lambda xs: math.nan if any(x != x for x in xs) else float(sum(x > 0 for x in xs))),
    "lo": ("min_of_messages(/a.data)", lambda xs: math.nan if any(x != x for x in xs) else min(xs)),
    "hi": ("max_of_messages(/a.data * 2)",
           lambda xs: math.nan if any(x != x for x in xs) else 2 * max(xs)),
}
EMPTY = {"any_hi": False, "all_lo": True, "n_pos": 0.0}


def _kleene_any(truth, xs):
    if any(t and x == x for t, x in zip(truth, xs)):
        return True
    return math.nan if any(x != x for x in xs) else False


def _kleene_all(truth, xs):
    if any((not t) and x == x for t, x in zip(truth, xs)):
        return False
    return math.nan if any(x != x for x in xs) else True


def _same(g, w) -> bool:
    return (g != g and w != w) or g == w


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=st.lists(st.tuples(st.integers(0, 1500), st.sampled_from([-1.0, 0.0, 0.7, 2.0, math.nan])),
                  min_size=1, max_size=30),
       t_times=st.lists(st.integers(0, 1500), min_size=1, max_size=12),
       period=st.integers(20, 300), per_topic=st.booleans())
@pytest.mark.tor("TOR-BND-005")
def test_both_clocks_fold_the_messages_since_the_previous_tick(tmp_path_factory, a, t_times,
                                                               period, per_topic):
    msgs = [("/a", "std_msgs/msg/Float64", t * MS, float64(x)) for t, x in a]
    msgs += [("/t", "std_msgs/msg/Float64", t * MS, float64(0.0)) for t in t_times]
    path = write_mcap(tmp_path_factory.mktemp("agg") / "a.mcap",
                      sorted(msgs, key=lambda m: (m[2], m[0])), chunk_size=256)
    tick = TickSpec(topic="/t") if per_topic else TickSpec(period_ns=period * MS)
    b = make_bindings({**{k: e for k, (e, _f) in FOLDS.items()}, "held": "/a.data + 0"}, tick)
    src = open_log(path)
    ticks = list(sample(src, b))
    arr = sample_arrays(src, b)
    assert arr.times.tolist() == [t.time for t in ticks]
    for name in b.variables:  # the two clocks agree, value by value and type by type
        got = arr.columns[name].tolist() if hasattr(arr, "columns") else arr[1][name].tolist()
        want = [t.values[name] for t in ticks]
        assert all(_same(g, w) for g, w in zip(got, want)), (name, got, want)
    # and both fold what the log holds between two ticks (independent of fretc's clocks)
    a_sorted = sorted(a, key=lambda m: m[0])  # stable: the order the log was written in
    times = [t.time for t in ticks]
    for i in range(1, len(ticks)):
        window = [x for t, x in a_sorted if times[i - 1] < t * MS <= times[i]]
        for name, (_e, f) in FOLDS.items():
            if window:
                want = f(window)
            elif name in EMPTY:
                want = EMPTY[name]
            else:  # min/max of no new message: the held message's value, as without a fold
                held = ticks[i].values["held"]
                want = held * (2 if name == "hi" else 1)
            assert _same(ticks[i].values[name], want), (name, i, window, ticks[i].values[name])


def _audit(tmp_path: Path, fret: str, bindings: str, log: Path):
    (tmp_path / "g.fret").write_text(fret)
    (tmp_path / "g.bindings.toml").write_text(bindings)
    return audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / "g.fret"),))), str(log))


def _spike(path, extra=()):
    """/v at 1.0 every 100 ms for 2 s, and a 9.0 then a 1.0 between the ticks at 0.5 and
    0.6 s; ``extra`` (log time, value) messages too."""
    msgs = [("/v", "std_msgs/msg/Float64", S + i * S // 10, float64(1.0)) for i in range(20)]
    msgs += [("/v", "std_msgs/msg/Float64", t, float64(x))
             for t, x in [(S + 5 * S // 10 + 1000, 9.0), (S + 5 * S // 10 + 2000, 1.0), *extra]]
    return write_mcap(path, sorted(msgs, key=lambda m: m[2]))


def test_an_error_superseded_within_a_tick_is_violated_at_the_next_tick(tmp_path):
    log = _spike(tmp_path / "e.mcap")
    la = _audit(tmp_path, "@tick_period 100 ms\nE1: agent shall always satisfy !err\n"
                "E2: agent shall always satisfy !err_held\n",
                '[tick]\nperiod = "100 ms"\n[variables]\n'
                'err = "any_of_messages(/v.data >= 8)"\nerr_held = "/v.data >= 8"\n', log)
    got = {v.requirement: v for v in la.verdicts}
    assert got["E1"].verdict == "violated"
    assert got["E1"].first_violation.at.time_ns == S + 6 * S // 10  # the tick after it
    assert got["E1"].unsampled_messages == {}  # every /v message was folded
    assert got["E2"].verdict == "satisfied"  # sample-and-hold never sees it ...
    assert got["E2"].unsampled_messages == {"/v": 2}  # ... and says how many it skipped


@pytest.mark.parametrize("log", params(lambda: [BASIS]))
def test_the_basis_error_log_is_seen_with_an_aggregation(tmp_path, log):
    """On the protobuf basis log the one ERROR is superseded within milliseconds;
    folded with any_of_messages it is violated at the first tick at or after it."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    with open(log, "rb") as f:  # an independent read: mcap + its protobuf decoder
        errors = [m.log_time for _s, _c, m, d in make_reader(
            f, decoder_factories=[DecoderFactory()]).iter_decoded_messages(topics=["/log"])
            if d.level >= 4]  # foxglove.Log.Level.ERROR = 4
    assert errors
    la = _audit(tmp_path, "@tick_period 100 ms\nE: the robot shall never satisfy error_logged\n",
                '[tick]\nperiod = "100 ms"\n[variables]\n'
                'error_logged = "any_of_messages(/log.level >= ERROR)"\n', log)
    v = la.verdicts[0]
    assert v.verdict == "violated", (v.verdict, v.error)
    at = v.first_violation.at.log_time_ns
    assert min(errors) <= v.first_violation.at.time_ns < min(errors) + 100 * MS, (at, errors)


@pytest.mark.parametrize("expr, where", [
    ("any_of_messages(/a.x > 0) & /b.y > 0", "the whole binding"),
    ("!any_of_messages(/a.x > 0)", "the whole binding"),
    ("any_of_messages(/a.x > /b.y)", "one topic"),
    ("any_of_messages(age(/a) > 1)", "not a field"),
    ("max_of_messages(max_of_messages(/a.x))", "do not nest"),
])
def test_aggregations_are_whole_bindings_of_one_topic(expr, where):
    with pytest.raises(BindingError, match=where):
        compile_expression("v", expr)


@pytest.mark.tor("TOR-BND-005")
def test_a_boolean_that_skipped_a_change_says_so(tmp_path):
    log = _spike(tmp_path / "m.mcap", [(S + 8 * S // 10 + 2000, 2.0)])
    la = _audit(tmp_path, "@tick_period 100 ms\nE2: agent shall always satisfy !err_held\n"
                "E3: agent shall always satisfy x < 5\n",
                '[tick]\nperiod = "100 ms"\n[variables]\n'
                'err_held = "/v.data >= 8"\nx = "/v.data"\n', log)
    got = {v.requirement: v for v in la.verdicts}
    # three messages no tick sampled; one of them (9.0) flips err_held, and it says so
    assert got["E2"].unsampled_messages == {"/v": 3}
    assert got["E2"].missed_changes == {"err_held": 1}
    assert any("any_of_messages(/v.data >= 8)" in n for n in got["E2"].notes)
    assert got["E3"].missed_changes == {}  # numbers change with every message: not counted
    # the watch's tick-by-tick clock counts the same
    from fretc.signals.bindings.files import load_bindings
    b = load_bindings(str(tmp_path / "g.bindings.toml"))
    s = sample(open_log(log), b)
    for _ in s:
        pass
    assert s.missed_changes == {"err_held": 1} and s.unsampled == {"/v": 3}
