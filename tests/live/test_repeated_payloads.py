"""A live source decodes a payload repeated from its topic's last message once (a robot's
flags and commands repeat at tens of kHz): the same message object is held again, and the
changes a tick skipped are counted from it as from a fresh decode (metamorphic: the same
counts and values whether the messages come as shared objects or as copies)."""

from __future__ import annotations

import copy

from fretc.live.protocol import Advertised
from fretc.live.source import WatchSource
from fretc.signals.bindings.files import parse_bindings
from fretc.signals.clock import Clock, Sampling

BOOL_SCHEMA = "bool data"


class _Client:
    events = None


def _bool(x: bool) -> bytes:
    return b"\x00\x01\x00\x00" + bytes([x])


def test_a_repeated_payload_is_the_same_message_a_new_one_is_decoded():
    src = WatchSource("dds://0", _Client())
    ch = Advertised(1, "/a", "cdr", "std_msgs/msg/Bool", BOOL_SCHEMA, "ros2msg")
    src._handle(("advertise", 0, [ch]))
    m1 = src._deliver("/a", 1_000, _bool(True))
    m2 = src._deliver("/a", 2_000, _bool(True))
    m3 = src._deliver("/a", 3_000, _bool(False))
    assert m1 is not None and m2 is not None and m3 is not None
    assert m2.data is m1.data and m3.data is not m1.data
    assert (m1.data.data, m3.data.data) == (True, False)
    assert [m.log_time for m in (m1, m2, m3)] == [1_000, 2_000, 3_000]


def _ticks(messages, share: bool):
    b = parse_bindings('[tick]\nperiod = "100 ms"\n[variables]\nok = "!(/a.data == false)"\n', "t.toml")
    s = Sampling(src := WatchSource("dds://0", _Client()), b)
    del src
    c = Clock(s, list(b.variables.values()), {"/a"}, b.tick)
    out, last = [], None
    for t, x in messages:
        data = type("Bool", (), {"data": x})()
        if share and last is not None and last[0] == x:
            data = last[1]  # (as the live source gives a repeated payload)
        last = (x, data)
        out += [(k.index, k.time, dict(k.values)) for k in c.push("/a", t, t, copy.copy(data)
                                                                   if not share else data)]
    out += [(k.index, k.time, dict(k.values)) for k in c.finish()]
    return out, dict(s.missed_changes)


def test_changes_a_tick_skipped_are_counted_alike_from_shared_messages():
    # a pulse of false between two ticks, twice; true repeated around them
    msgs = [(k * 10_000_000, not (k in (13, 14, 15, 52))) for k in range(80)]
    assert _ticks(msgs, share=True) == _ticks(msgs, share=False)
    assert _ticks(msgs, share=True)[1] == {"ok": 4}  # (three skipped falses, then one)
