"""Foxglove's message path modifiers on bindings: ``@derivative``, ``@delta``,
``@timedelta`` (between the held message of the field's topic and the one before it, per
second of the time base), ``@abs``, ``@negative``, ``@sqrt``, ``@rad2deg``, ``@deg2rad``.
Both samplers give the same values, equal to numpy's differences of the log's own messages;
a tick waits (warm-up) until the topic has two messages."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import MS, S, audit_written, float64, write_mcap
from fretc.common.problems import BindingError
from fretc.logs import open_log
from fretc.signals.arrays import sample_arrays
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.spec import TickSpec, make_bindings
from fretc.signals.clock import sample

MODS = {"d": "/a.data@derivative", "dt": "/a.data@timedelta", "dl": "/a.data@delta",
        "mag": "/a.data@negative@abs", "root": "/a.data@abs@sqrt",
        "deg": "/a.data@rad2deg", "rad": "/a.data@deg2rad", "ok": "/a.data@derivative@abs < 50"}


def _same(g, w) -> bool:
    return (g != g and w != w) or g == pytest.approx(w, rel=1e-12, abs=1e-12)


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=st.lists(st.tuples(st.integers(0, 1000), st.floats(-100, 100)), min_size=1,
                  max_size=25, unique_by=lambda m: m[0]),
       period=st.integers(10, 200), per_topic=st.booleans())
def test_both_samplers_give_the_log_s_own_differences(tmp_path_factory, a, period, per_topic):
    a = sorted(a)
    msgs = [("/a", "std_msgs/msg/Float64", t * MS, float64(x)) for t, x in a]
    path = write_mcap(tmp_path_factory.mktemp("mod") / "m.mcap", msgs, chunk_size=256)
    tick = TickSpec(topic="/a") if per_topic else TickSpec(period_ns=period * MS)
    b = make_bindings(MODS, tick)
    src = open_log(path)
    ticks = list(sample(src, b))
    arr = sample_arrays(src, b)
    assert arr.times.tolist() == [t.time for t in ticks]
    for name in MODS:
        got, want = arr.columns[name].tolist(), [t.values[name] for t in ticks]
        assert all(_same(g, w) for g, w in zip(got, want)), (name, got, want)
    times = np.array([t * MS for t, _x in a])
    xs = np.array([x for _t, x in a])
    if len(a) < 2:
        assert ticks == []  # warm-up: @derivative needs two messages
        return
    for tk in ticks:  # independent: the held message and the one before it
        k = int(np.searchsorted(times, tk.time, side="right")) - 1
        assert k >= 1
        dt = (times[k] - times[k - 1]) / 1e9
        want = {"d": (xs[k] - xs[k - 1]) / dt, "dt": dt, "dl": xs[k] - xs[k - 1],
                "mag": abs(xs[k]), "root": math.sqrt(abs(xs[k])),
                "deg": math.degrees(xs[k]), "rad": math.radians(xs[k]),
                "ok": abs((xs[k] - xs[k - 1]) / dt) < 50}
        for name, w in want.items():
            assert _same(tk.values[name], w), (name, tk.time, tk.values[name], w)


def test_a_speed_limit_on_a_position_derivative_audits(tmp_path):
    # x moves 0.1 m per 100 ms (1 m/s), then jumps 0.5 m in 100 ms (5 m/s) once
    xs = [0.1 * i for i in range(10)] + [1.4, 1.5, 1.6]
    msgs = [("/x", "std_msgs/msg/Float64", S + i * S // 10, float64(x)) for i, x in enumerate(xs)]
    log = write_mcap(tmp_path / "x.mcap", msgs)
    la = audit_written(tmp_path, "s", "@tick_period 100 ms\nS1: robot shall always satisfy "
                                      "speed <= 2\n",
                                      '[tick]\nperiod = "100 ms"\n[variables]\n'
                                      'speed = "/x.data@derivative@abs"\n', str(log))
    (v,) = la.verdicts
    assert v.verdict == "violated" and v.warmup_ticks == 1
    assert v.first_violation.at.time_ns == S + 10 * S // 10
    assert v.robustness == pytest.approx(2 - 5.0)  # robustness carried through, in m/s


@pytest.mark.parametrize("expr, msg", [
    ("/a.x@speed", "unknown modifier @speed"),
    ("/a.x@abs@derivative", "right after the field"),
    ("/a@derivative", "takes a field of a message"),
])
def test_modifier_errors_are_positioned(expr, msg):
    with pytest.raises(BindingError, match=msg) as e:
        compile_expression("v", expr)
    assert "column" in str(e.value)


def test_a_wheel_speed_from_joint_positions(tmp_path):
    """JointState without velocities: the rate of change of one joint's position."""
    from _logs import ROS2, T, header

    def joint_state(names, positions, ns):
        return T(ROS2, "sensor_msgs/msg/JointState")(
            header=header(ns), name=list(names), position=np.array(positions, dtype=np.float64),
            velocity=np.array([], dtype=np.float64), effort=np.array([], dtype=np.float64))
    pos = [0.0, 0.5, 1.0, 1.5, 2.5]
    msgs = [("/joint_states", "sensor_msgs/msg/JointState", S + i * S // 10,
             joint_state(["left", "wheel"], [9.0, p], S + i * S // 10))
            for i, p in enumerate(pos)]
    log = write_mcap(tmp_path / "j.mcap", msgs)
    b = make_bindings({"w": 'derivative(joint(/joint_states.position, "wheel"))'},
                      TickSpec(topic="/joint_states"))
    got = [t.values["w"] for t in sample(open_log(log), b)]
    assert got == pytest.approx([5.0, 5.0, 5.0, 10.0])  # rad/s, from the second message on
