"""A live message whose log time goes back before one already used is one ``clock_backwards``
data problem, counted once (it was counted twice, once as the problem reported
and once as the message lost that makes its gap), and its gap is still made."""

from __future__ import annotations

import struct

from fretc.live.events import EventQueue
from fretc.live.source import CLOCK_BACKWARDS, WatchSource

T0 = 1_700_000_000_000_000_000
MS = 1_000_000


class _Client:
    def __init__(self, events):
        self.events = events


def _source() -> WatchSource:
    src = WatchSource("ws://test", _Client(EventQueue(max_messages=100)), restart_grace=0)
    src.advertised["/a"] = None
    src.decoders["/a"] = lambda payload: struct.unpack("<d", payload)[0]
    return src


def test_each_message_back_in_time_is_counted_once():
    src = _source()
    assert src._deliver("/a", T0 + 500 * MS, struct.pack("<d", 1.0)) is not None
    for k in range(3):  # three messages before the one used
        assert src._deliver("/a", T0 + k * MS, struct.pack("<d", 1.0)) is None
    assert src._deliver("/a", T0 + 600 * MS, struct.pack("<d", 1.0)) is not None
    counts = {k: n for k, n in src.problem_counts.items() if k[0] == CLOCK_BACKWARDS}
    assert counts == {(CLOCK_BACKWARDS, "/a"): 3}
    listed = [p for p in src.problems if p.kind == CLOCK_BACKWARDS]
    assert len(listed) == 1 and "3 messages" in listed[0].detail, listed
    # each skipped message is still a loss at its log time: the ticks it would have held
    # at are not judged
    assert [(g.start, g.end) for g in src.lost_gaps()] == [(T0 + k * MS, T0 + k * MS)
                                                          for k in range(3)]
