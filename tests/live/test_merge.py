"""The log-time merge's watermark (live/merge.py): a held message goes as soon as every matched
writer has delivered one at or after it; never out of log-time order while each writer's
messages come in order. No middleware needed; the releasing step is driven by hand (hold of
an hour: only the watermark or the stop releases) except in the threaded test."""

import threading

from hypothesis import given
from hypothesis import strategies as st

from fretc.live.events import EventQueue
from fretc.live.merge import MergeBuffer

from _dds import fresh_domain

HOUR = 3600.0


def _released(q: EventQueue) -> list[tuple]:
    out = []
    while q.qsize():
        out.append(q.get_nowait())
    return out


def _times(events) -> list[int]:
    return [e[2] for e in events if e[0] == "message"]


@st.composite
def _runs(draw):
    """Writers (topic, id) each with non-decreasing log times, one interleaving of their puts,
    and the syncs between them (every writer matched from the start: a static graph)."""
    n_topics = draw(st.integers(1, 3))
    writers = [(f"/t{t}", w) for t in range(n_topics) for w in range(draw(st.integers(1, 2)))]
    seqs = {}
    for wr in writers:
        steps = draw(st.lists(st.integers(0, 5), max_size=8))
        start = draw(st.integers(0, 20))
        seqs[wr] = [start + sum(steps[:i + 1]) for i in range(len(steps))]
    order = [wr for wr in writers for _ in seqs[wr]]
    order = draw(st.permutations(order))
    syncs = draw(st.lists(st.booleans(), min_size=len(order), max_size=len(order)))
    return writers, seqs, order, syncs


@given(_runs())
def test_watermark_releases_in_log_time_order_and_at_once(run):
    writers, seqs, order, syncs = run
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR)
    matched: dict[str, set] = {}
    for topic, w in writers:
        matched.setdefault(topic, set()).add(w)
    pos = dict.fromkeys(writers, 0)
    latest: dict = {}
    out: list[tuple] = []
    for wr, sync in zip(order, syncs, strict=True):
        t = seqs[wr][pos[wr]]
        pos[wr] += 1
        latest[wr] = t
        m.put(wr[0], t, b"", 0, wr[1])
        if sync:
            m.sync(matched)
            m._release()
            out += _released(q)
            held = [e[0] for e in m._heap]
            if len(latest) == len(writers):  # every writer delivered: nothing at or
                mark = min(latest.values())  # before the oldest latest stays held
                assert all(h > mark for h in held)
            else:  # a matched writer silent so far: the hold alone (an hour) releases
                assert out == []
    m.stop()
    out += _released(q)
    assert _times(out) == sorted(t for s in seqs.values() for t in s)


def test_a_silent_matched_writer_holds_everything_back_until_forgotten():
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR)
    for t in (10, 20, 30):
        m.put("/a", t, b"", 0, "a1")
    m.sync({"/a": {"a1"}, "/b": {"b1"}})  # /b's writer matched, nothing from it yet
    m._release()
    assert _released(q) == []
    m.put("/b", 25, b"", 0, "b1")
    m.sync({"/a": {"a1"}, "/b": {"b1"}})
    m._release()
    assert _times(_released(q)) == [10, 20, 25]  # 30: /b's next may be older
    m.forget("/b")  # /b's publishers all left (after their messages were put)
    m.sync({"/a": {"a1"}})
    m._release()
    assert _times(_released(q)) == [30]


def test_a_second_writer_of_a_topic_holds_it_back():
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR)
    m.put("/a", 50, b"", 0, "a1")
    m.put("/b", 40, b"", 0, "b1")
    m.sync({"/a": {"a1", "a2"}, "/b": {"b1"}})  # a2 matched, silent: it may send 41
    m._release()
    assert _released(q) == []
    m.put("/a", 41, b"", 0, "a2")
    m.sync({"/a": {"a1", "a2"}, "/b": {"b1"}})
    m._release()
    assert _times(_released(q)) == [40]  # b1 may still send 40 or later
    m.put("/b", 45, b"", 0, "b1")
    m.sync({"/a": {"a1", "a2"}, "/b": {"b1"}})
    m._release()
    assert _times(_released(q)) == [41]  # a1's 50 waits for a2 and b1


def test_no_writer_id_or_no_sync_is_the_hold_alone():
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR)
    m.put("/a", 10, b"", 0)  # the transport names no writer
    m.put("/b", 20, b"", 0, "b1")
    m.sync({"/b": {"b1"}})
    m._release()
    assert _released(q) == []
    m2 = MergeBuffer(q, hold=HOUR)
    m2.put("/a", 10, b"", 0, "a1")  # writers named, never synced
    m2._release()
    assert _released(q) == []


def test_events_put_behind_held_messages_go_with_them():
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR)
    m.put("/a", 10, b"", 0, "a1")
    m.put_event(("unadvertise", 0, ["/a"]))
    m.put("/b", 5, b"", 0, "b1")
    m.sync({"/a": {"a1"}, "/b": {"b1"}})
    m._release()
    assert [e[0] for e in _released(q)] == ["message"]  # /b's 5; /a's 10 waits for /b
    m.put("/b", 12, b"", 0, "b1")
    m.sync({"/a": {"a1"}, "/b": {"b1"}})
    m._release()
    assert [(e[0], e[2] if e[0] == "message" else None) for e in _released(q)] == [
        ("message", 10), ("unadvertise", None)]


def test_threads_putting_in_any_interleaving_reach_the_queue_in_log_time_order():
    """Four writers on three threads put their own increasing times while a fourth thread
    syncs; the releasing thread runs (hold of an hour): whatever the interleaving, the queue
    gets every message in log-time order."""
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR).start()
    matched = {"/a": {1, 2}, "/b": {3}, "/c": {4}}
    plan = {1: range(0, 3000, 3), 2: range(1, 3000, 3), 3: range(2, 3000, 2), 4: range(0, 3000, 5)}
    topic = {1: "/a", 2: "/a", 3: "/b", 4: "/c"}
    done = threading.Event()

    def produce(ws):
        for i in range(max(len(plan[w]) for w in ws)):
            for w in ws:
                if i < len(plan[w]):
                    m.put(topic[w], plan[w][i], b"", 0, w)

    def syncer():
        while not done.is_set():
            m.sync(matched)

    threads = [threading.Thread(target=produce, args=(ws,)) for ws in ([1, 2], [3], [4])]
    s = threading.Thread(target=syncer)
    s.start()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    done.set()
    s.join()
    m.sync(matched)
    m.stop()
    got = _times(_released(q))
    assert got == sorted(t for r in plan.values() for t in r)


def _dds_server(tmp_path):
    """(the DDS client class, fretc's DDS replay server on a fresh loopback domain, its URL,
    the Cyclone DDS configuration file); a skip without cyclonedds."""
    import pytest

    pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                        "pip install 'fretc[watch]'")
    from fretc.live.dds.client import DdsClient
    from fretc.live.dds.serve import DdsServer
    from fretc.live.dds.idl_types import LOOPBACK_XML

    xml = tmp_path / "loopback.xml"
    xml.write_text(LOOPBACK_XML, encoding="utf-8")
    url = f"dds://{fresh_domain()}"
    return DdsClient, DdsServer(url, str(xml)), url, xml


def test_the_dds_client_releases_at_the_watermark(tmp_path):
    """Two Cyclone DDS writers (fretc's replay server, in this process) of two topics, read by
    the DDS client with a hold of an hour: the messages reach the queue in log-time order by
    the watermark alone (each sample's publication handle names one of the readers' matched
    writers); once one topic's publisher left, the other's last message goes too."""
    import queue
    import struct

    import pytest

    DdsClient, server, url, xml = _dds_server(tmp_path)
    for t in ("/a", "/b"):
        server.channel(t, "cdr", "std_msgs/msg/Float64", "ros2msg", b"float64 data")
    q = EventQueue()
    client = DdsClient(url, lambda t: t in ("/a", "/b"), topics=("/a", "/b"),
                       config_file=str(xml), events=q, merge_hold=HOUR).start()
    try:
        assert server.wait_subscribed(["/a", "/b"], timeout=30)
        payload = bytes([0, 1, 0, 0]) + struct.pack("<d", 1.0)  # CDR little endian
        t0 = 1_700_000_000 * 10**9
        for k in range(20):  # /b written before /a at each step, /a's time the earlier
            server.log("/b", payload, t0 + 10 * k + 5)
            server.log("/a", payload, t0 + 10 * k)
        got: list[int] = []
        while len(got) < 39:  # every message but /b's last: /a may still send before it
            ev = q.get(timeout=30)
            if ev[0] == "message":
                got.append(ev[2] - t0)
        server.unpublish("/a")  # /a's publisher left: /b's last message goes
        while len(got) < 40:
            ev = q.get(timeout=30)
            if ev[0] == "message":
                got.append(ev[2] - t0)
        assert got == sorted(10 * k + d for k in range(20) for d in (0, 5))
        with pytest.raises(queue.Empty):
            while True:
                assert q.get_nowait()[0] != "message"
    finally:
        client.stop()
        server.stop()


def test_a_transport_that_cannot_tell_its_writers_leaves_the_hold_alone():
    q = EventQueue()
    m = MergeBuffer(q, hold=HOUR)
    m.put("/a", 10, b"", 0, "a1")
    m.put("/a", 20, b"", 0, "a1")
    m.sync({"/a": {"a1"}})
    m._release()
    assert _times(_released(q)) == [10, 20]
    m.put("/a", 30, b"", 0, "a1")
    m.sync(None)  # e.g. a latched topic read: a writer matched later sends old samples
    m._release()
    assert _released(q) == []


def test_the_dds_client_reading_a_latched_topic_has_no_watermark(tmp_path):
    """/tf_static is read transient-local (a writer that appears sends its stored samples, of
    any age): while it is read, the hold alone releases, even with every writer heard."""
    import struct
    import time

    DdsClient, server, url, xml = _dds_server(tmp_path)
    topics = ("/a", "/tf_static")
    for t in topics:
        server.channel(t, "cdr", "std_msgs/msg/Float64", "ros2msg", b"float64 data")
    q = EventQueue()
    client = DdsClient(url, lambda t: t in topics, topics=topics, config_file=str(xml),
                       events=q, merge_hold=HOUR).start()
    try:
        assert server.wait_subscribed(list(topics), timeout=30)
        payload = bytes([0, 1, 0, 0]) + struct.pack("<d", 1.0)
        for k in range(5):
            for t in topics:
                server.log(t, payload, 1_700_000_000 * 10**9 + k)
        deadline = time.monotonic() + 30
        while len(client._merge._latest) < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.2)  # a few polls (each syncs)
        assert client._latched == {"/tf_static"}
        assert len(client._merge._latest) == 2 and client._merge._watermark is None
        assert all(ev[0] != "message" for ev in _released(q))
    finally:
        client.stop()
        server.stop()
