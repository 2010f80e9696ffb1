"""Why a plain rclpy node's first message could be skipped as ``clock_backwards``, and that
it no longer is: the DDS client learns a new publication (the built-in ``DCPSPublication``
topic) a little before its reader is matched with the writer; a watermark computed over the
matched writers alone released the other topics' messages up to their newest, and the new
writer's first sample, written before the match completed and delivered once matched, was
older than what had gone. While a discovered publication is not matched yet the merge holds
by time alone (fretc.live.merge)."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                    "pip install 'fretc[watch]'")

from fretc.live.dds.client import DdsClient  # noqa: E402
from fretc.live.events import EventQueue  # noqa: E402
from fretc.live.merge import MergeBuffer  # noqa: E402

pytestmark = pytest.mark.watch


class _Reader:
    def __init__(self, handles: list[int]) -> None:
        self.handles = handles

    def get_matched_publications(self) -> list[int]:
        return list(self.handles)


def _client(readers: dict[str, list[int]], publications: dict[str, int]) -> DdsClient:
    c = DdsClient("dds://7", lambda t: True, topics=list(readers))
    c._readers = {t: (_Reader(h), "std_msgs/msg/Float64") for t, h in readers.items()}
    c._pubs = {t: {f"key-{t}-{i}" for i in range(n)} for t, n in publications.items()}
    return c


def test_a_discovered_writer_not_matched_yet_leaves_no_watermark():
    # /scan's writer is matched; /gwendolen_control's was discovered, its match not done yet
    c = _client({"/scan": [11], "/gwendolen_control": []},
                {"/scan": 1, "/gwendolen_control": 1})
    assert c._matched() is None
    c._readers["/gwendolen_control"][0].handles.append(22)  # matched now
    assert c._matched() == {"/scan": {11}, "/gwendolen_control": {22}}


def test_with_the_unmatched_writer_counted_its_first_sample_is_released_in_order():
    """The sequence of the skipped message, replayed through the merge: /scan's writer has
    delivered up to 3.05 s; /gwendolen_control's writer, discovered but not matched, wrote
    at 3.00 s and its sample comes once matched. Counted as matched only when it is, the
    watermark would have released /scan's 3.05 s first (the 3.00 s sample then went back in
    time); with no watermark until the match, the hold orders them."""
    events = EventQueue()
    merge = MergeBuffer(events, hold=60.0).start()  # (released by stop(), in order)
    c = _client({"/scan": [11], "/gwendolen_control": []},
                {"/scan": 1, "/gwendolen_control": 1})
    merge.put("/scan", 3_050_000_000, b"s", 0, 11)
    merge.sync(c._matched())  # None: the hold alone
    merge.put("/gwendolen_control", 3_000_000_000, b"g", 0, 22)  # delivered once matched
    merge.stop()
    got = []
    while True:
        try:
            got.append(events.get_nowait()[2])
        except Exception:  # noqa: BLE001 - queue.Empty: all taken
            break
    assert got == [3_000_000_000, 3_050_000_000]
    # what the matched set alone said: a watermark at 3.05 s, which releases /scan at once
    old = MergeBuffer(EventQueue(), hold=10.0)
    old.put("/scan", 3_050_000_000, b"s", 0, 11)
    old.sync({"/scan": {11}, "/gwendolen_control": set()})
    assert old._watermark == 3_050_000_000
