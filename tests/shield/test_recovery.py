"""A shield that lost its state knows it again by itself when its requirements look back a
bounded number of ticks (shield/lookback.py, the runtime's "a lost state recovers"), else
only through a reset; the message shield's proposal timeout and its answer between ticks.

Each test fails on the behaviour before: a lost machine stayed lost until a reset (the
ROS 2 node stayed stopped for good), a silent controller's last proposal was used at every
tick, and no proposal could be decided between ticks.
"""

from __future__ import annotations

from rosbags.typesys import Stores, get_typestore

from fretc.shield.build import build_shield
from fretc.shield.emit_python import tables
from fretc.shield.lookback import lookback
from fretc.shield.messages import MessageShield, default_message
from fretc.shield.runtime import ShieldRuntime
from fretc.signals.bindings.files import load_bindings

from _gen import compile_text

STORE = get_typestore(Stores.ROS2_JAZZY)


def _bool(value: bool):
    msg = default_message(STORE, "std_msgs/msg/Bool")
    msg.data = value
    return msg


HOLD = ("R1: upon a & x sw shall for 3 ticks satisfy x\n"
        "R2: whenever a sw shall within 2 ticks satisfy x\n")


def _shield(text: str, tmp_path, inputs=("a",), outputs=("x",), bindings=None):
    tmp_path.mkdir(parents=True, exist_ok=True)
    compiled = compile_text(text, tmp_path)
    return build_shield(compiled, list(inputs), list(outputs), fork=False,
                        fallback={"x": True}, bindings=bindings)


def test_a_bounded_past_is_read_through_fret_for_timing(tmp_path):
    shield = _shield(HOLD, tmp_path)
    (m,) = shield.machines
    # R1's ``O[0,3] t -> (H !t | x)``: its H never decides; R2's deadline 2 ticks
    assert m.stats["lookback"] is not None and 2 <= m.stats["lookback"] <= 6, m.stats
    once = _shield("R3: after a sw shall always satisfy x\n", tmp_path / "u")
    assert once.machines[0].stats["lookback"] is None
    assert lookback([]) == 0


def test_a_lost_machine_recovers_after_its_lookback_of_readable_ticks(tmp_path):
    shield = _shield(HOLD, tmp_path)
    rt = ShieldRuntime(tables(shield))
    (m,) = rt.machines
    rt.restore((("lost",),))
    ticks = []
    for _ in range(m.lookback + 3):
        d = rt.step({"a": False}, {"x": False})
        ticks.append((bool(d.lost), d.recovered))
        if not d.lost:
            break
    first = [k for k, (_lost, back) in enumerate(ticks) if back]
    assert first == [m.lookback], ticks
    assert ticks[-1] == (False, ()) and d.outputs == {"x": False}, (ticks, d)
    # an unreadable input starts the count again
    rt.restore((("lost",),))
    for _ in range(m.lookback):
        rt.step({"a": False}, {"x": False})
    d = rt.step({"a": float("nan")}, {"x": False})
    assert d.lost and "0 so far" in d.fault, d.fault
    # the state the runtime reports holds the copy (a host puts it back as it was)
    assert rt.state[0][0] == "lost" and len(rt.state[0]) == 3


def test_an_unbounded_past_needs_a_reset_and_says_so(tmp_path):
    shield = _shield("R3: after a sw shall always satisfy x\n", tmp_path)
    rt = ShieldRuntime(tables(shield))
    rt.restore((("lost",),))
    for _ in range(20):
        d = rt.step({"a": False}, {"x": False})
    assert d.lost and "reset the shield" in d.fault and d.outputs == {"x": True}, d
    rt.reset()
    assert not rt.step({"a": False}, {"x": False}).lost


BINDINGS = ('[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\n'
            'a = "/near.data"\nx = "/stop_out.data"\n'
            '[types]\n"/near" = "std_msgs/msg/Bool"\n"/stop_out" = "std_msgs/msg/Bool"\n'
            '"/stop_in" = "std_msgs/msg/Bool"\n')


def _message_shield(tmp_path, timeout_ns):
    tmp_path.mkdir(parents=True, exist_ok=True)
    b = tmp_path / "b.toml"
    b.write_text(BINDINGS, encoding="utf-8")
    bindings = load_bindings(b)
    shield = _shield("R1: whenever a sw shall immediately satisfy x\n", tmp_path,
                     bindings=bindings)

    return MessageShield(ShieldRuntime(tables(shield)), bindings, {"/stop_out": "/stop_in"},
                         lambda _topic: _bool(False), timeout_ns)


def test_a_proposal_older_than_the_timeout_is_absent_and_the_fallback_given(tmp_path):
    ms = _message_shield(tmp_path, 300_000_000)
    ms.hear("/near", _bool(False), 0)
    ms.hear("/stop_in", _bool(False), 0)
    d, msgs = ms.tick(100_000_000)
    assert not d.fault and msgs[0][1].data is False, d
    d, msgs = ms.tick(400_000_001)  # the controller silent for more than 300 ms
    assert "no proposal on /stop_in for 400 ms" in d.fault and "proposal timeout" in d.fault
    assert msgs[0][1].data is True, (d, msgs)  # the fallback's x, not the last proposal
    ms.hear("/stop_in", _bool(False), 450_000_000)
    d, msgs = ms.tick(500_000_000)
    assert not d.fault and msgs[0][1].data is False, d
    # without a timeout (a recording replayed) the last proposal is the proposal
    ms = _message_shield(tmp_path / "n", None)
    ms.hear("/near", _bool(False), 0)
    ms.hear("/stop_in", _bool(False), 0)
    assert not ms.tick(10_000_000_000)[0].fault


def test_a_proposal_is_answered_between_ticks_without_moving_the_state(tmp_path):
    b = tmp_path / "b.toml"
    b.write_text(BINDINGS, encoding="utf-8")
    shield = _shield(HOLD, tmp_path / "s", bindings=load_bindings(b))
    ms = MessageShield(ShieldRuntime(tables(shield)), load_bindings(b),
                       {"/stop_out": "/stop_in"}, lambda _t: _bool(False),
                       300_000_000)
    ms.hear("/near", _bool(True), 0)
    ms.hear("/stop_in", _bool(True), 0)
    ms.tick(0)  # a & x: R1's hold starts
    before = ms.runtime.state
    ms.hear("/stop_in", _bool(False), 50_000_000)
    d, msgs = ms.answer(50_000_000)
    assert d.overridden and msgs[0][1].data is True, d  # held: the hold's correction
    assert ms.runtime.state == before  # the state advances on ticks only
