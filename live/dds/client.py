"""``fretc watch dds://DOMAIN``: a Cyclone DDS participant that reads the bound ROS 2 topics
of the robot's DDS domain and hands them to the watch engine as the Foxglove client does
(:mod:`fretc.live.protocol`'s events on an :class:`~fretc.live.events.EventQueue`).

Design notes: ARCHITECTURE.md, `live/dds/client.py`."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from fretc.live.protocol import WATCH_HINT, MissingDependency
from fretc.live.events import EventQueue
from fretc.live.merge import HOLD_SECONDS, MergeBuffer
from fretc.live.ros2_names import (CLOCK_TOPIC, advertisement, cdr_clock_ns, dds_topic,
                                   normal_type, parse_url, ros_topic_of_dds, ros_type,
                                   standard_store)

__all__ = ["DdsClient", "require_cyclonedds", "POLL_SECONDS"]

#: Seconds the reading thread waits at most for a sample or a publication (a DDS WaitSet
#: wakes it as soon as one of its readers has data): the pace of the checks that need no
#: data (silent publishers) and of the stop.
POLL_SECONDS = 0.05
#: an instance handle as one unsigned 64-bit number (Cyclone DDS's Python binding gives a
#: reader's matched publications signed and a sample's publication handle unsigned)
_HANDLE = 2**64 - 1
#: a publisher known this long (s) whose topic has sent nothing is reported once
#: (:meth:`DdsClient._check_silent`)
SILENT_SECONDS = 3.0
#: what to do when a discovered publisher's messages never arrive (Fast DDS may send to a
#: reader on the same host over shared memory only, a transport Cyclone DDS cannot read)
SILENT_HINT = ("if it is publishing, its middleware may be sending over a transport fretc "
               "cannot read (Fast DDS's shared memory, to a reader on the same host): on the "
               "robot, start the node with FASTDDS_BUILTIN_TRANSPORTS=UDPv4, or watch from "
               "another host (docs/guide/watch.md, 'ROS 2 on its defaults')")


def require_cyclonedds() -> None:
    """Raise :class:`~fretc.live.protocol.MissingDependency` naming the install hint when the
    ``cyclonedds`` package is not installed."""
    try:
        import cyclonedds.domain  # noqa: F401
    except ImportError:
        raise MissingDependency(f"the DDS transport needs cyclonedds: {WATCH_HINT}") from None


class DdsClient:
    """Watch ROS 2 topics on a DDS domain (module docstring).

    Args:
        url: ``dds://DOMAIN``.
        wanted: topic -> bool (the bound topics).
        topics: the bound topics (readers are created for these only).
        types: topic -> expected ROS type (the bindings' ``[types]``, ``--topic-type``).
        msg_path: folders of the robot's own ``.msg``/``.idl`` files.
        config_file: a Cyclone DDS XML configuration (``--dds-config``).
        events: the queue (a new bounded :class:`~fretc.live.events.EventQueue` by default).

    Raises:
        ValueError: a URL of the wrong form; MissingDependency: no cyclonedds.
    """

    leaving_ends_run = True
    #: the reader stays while a topic's publishers are away and reads a new publisher from
    #: its first message: a span without a publisher is a silence, nothing lost in it
    #: (:data:`fretc.logs.recorded_gaps.PUBLISHER_ABSENT`)
    hears_new_publishers = True

    def __init__(self, url: str, wanted: Callable[[str], bool], *, topics=(),
                 types: dict[str, str] | None = None, msg_path: tuple[str, ...] = (),
                 config_file: str | None = None, events: EventQueue | None = None,
                 merge_hold: float = HOLD_SECONDS, **_ignored) -> None:
        require_cyclonedds()
        self.url = parse_url(url)
        self.wanted = wanted
        self.topics = set(topics)
        self.types = dict(types or {})
        self.store = standard_store(tuple(msg_path))
        self.config_file = config_file
        self.events: EventQueue = events if events is not None else EventQueue()
        self._merge = MergeBuffer(self.events, merge_hold)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._pubs: dict[str, set] = {}  # topic -> publication keys alive
        self._readers: dict[str, tuple] = {}  # topic -> (reader, ROS type)
        self._advertised: set[str] = set()
        self._clock: int | None = None
        self._qos_reported: set[str] = set()
        #: topics read transient-local (latched): no watermark while one is read
        self._latched: set[str] = set()
        #: topic -> wall time (ns) its first publisher was discovered; topics heard from
        self._known_since: dict[str, int] = {}
        self._heard: set[str] = set()
        self._silent_reported: set[str] = set()
        self._conditions: list[Any] = []

    def start(self) -> DdsClient:
        """Join the domain and start reading in a background thread (returns at once)."""
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication

        from fretc.live.dds.idl_types import open_participant

        from cyclonedds.core import WaitSet

        self._dp = open_participant(self.url.domain, self.config_file)
        self._builtin = BuiltinDataReader(self._dp, BuiltinTopicDcpsPublication)
        # the reading thread sleeps until a reader has data (a sample, a publication): no
        # poll period between a sample's arrival and its reading
        self._waitset = WaitSet(self._dp)
        self._attach(self._builtin)
        self._merge.start()
        self.events.put(("connected", time.time_ns(), "dds", f"domain {self.url.domain}"))
        self._thread = threading.Thread(target=self._run, daemon=True, name="fretc-dds")
        self._thread.start()
        return self

    def _attach(self, reader) -> None:
        """Wake the reading thread when ``reader`` holds samples (a ReadCondition on any
        sample, view and instance state, as :func:`~fretc.live.dds.idl_types.take_raw`
        takes them)."""
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState

        cond = ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any)
        self._conditions.append(cond)  # (kept: a condition collected is detached)
        self._waitset.attach(cond)

    def stop(self) -> None:
        """Stop reading and leave the domain (idempotent)."""
        self._stop.set()
        waitset = getattr(self, "_waitset", None)
        if waitset is not None:
            waitset.set_trigger(True)  # (wakes the reading thread at once)
        if self._thread is not None:
            self._thread.join(5)
        self._merge.stop()
        self._readers.clear()
        self._builtin = self._dp = None  # type: ignore[assignment]  # (closed)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self._discover()
                busy = self._read()
                self._check_silent(time.time_ns())
            except Exception as exc:  # one bad sample or entity costs that poll only
                self.events.put(("protocol", time.time_ns(),
                                 f"DDS: {type(exc).__name__}: {str(exc)[:200]}"))
                busy = False
            if not busy and not self._stop.is_set():
                self._waitset.wait(int(POLL_SECONDS * 1e9))

    def _discover(self) -> None:
        """Read the built-in publications: new ones of bound topics (and ``/clock``)
        advertise and get a reader; gone ones unadvertise their topic when it was the last."""
        from cyclonedds.core import InstanceState

        def alive_of(p) -> bool:
            info = getattr(p, "sample_info", None)
            return info is None or info.instance_state == InstanceState.Alive

        gone: list[str] = []

        def flush() -> None:
            # what any writer sent before these left is still in the readers: taken first,
            # so each unadvertisement comes after it (and after the others' data of then)
            if gone:
                for t in list(self._readers):
                    self._take(t, until_empty=True)
                for t in gone:
                    self._merge.forget(t)  # its writers' last messages are put
                    self._merge.put_event(("unadvertise", time.time_ns(), [t]))
                gone.clear()

        # publications gone before new ones in one batch: a writer replaced by another
        # (a node restart) is seen as its topic leaving and coming back, never as nothing
        for p in sorted(self._builtin.take(64), key=alive_of):
            topic = ros_topic_of_dds(getattr(p, "topic_name", "") or "")
            alive = alive_of(p)
            key, now = p.key, time.time_ns()
            if alive:
                flush()
                if topic is None or not (self.wanted(topic) or topic == CLOCK_TOPIC):
                    continue
                self._pubs.setdefault(topic, set()).add(key)
                self._known_since.setdefault(topic, now)
                self._add(topic, ros_type(p.type_name), p.qos, now)
                continue
            for t, keys in self._pubs.items():
                if key in keys:
                    keys.discard(key)
                    if not keys and t in self._advertised:
                        self._advertised.discard(t)
                        gone.append(t)
        flush()

    def _add(self, topic: str, ros: str, qos, now: int) -> None:
        """Advertise ``topic`` and create its reader (once)."""
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from fretc.live.dds.idl_types import idl_struct, reader_qos, transient_local

        if topic == CLOCK_TOPIC and self._clock is None:
            self._clock = 0
        if topic in self._readers:
            if self.wanted(topic) and topic not in self._advertised:
                self._advertised.add(topic)  # a publisher came back (a restart): behind
                # its unadvertisement, which waits with the messages merged
                self._merge.put_event(("advertise", now, [advertisement(
                    0, topic, ros, self.store, self.types.get(topic))]))
            return
        adv = advertisement(len(self._readers) + 1, topic, ros, self.store,
                            self.types.get(topic))
        if adv.unreadable:
            self.events.put(("protocol", now, f"{adv.unreadable}: the topic is not read"))
        if self.wanted(topic):
            self._advertised.add(topic)
            self.events.put(("advertise", now, [adv]))
        try:
            cls = None if adv.unreadable else idl_struct(self.store, normal_type(ros))
        except Exception:  # a definition Cyclone DDS's IDL cannot take
            cls = None
        if cls is None:
            self._readers[topic] = (None, ros)
            return
        tp: Topic[Any] = Topic(self._dp, dds_topic(topic), cls)
        self._readers[topic] = (DataReader(self._dp, tp, qos=reader_qos(qos, topic)), ros)
        self._attach(self._readers[topic][0])
        if transient_local(qos, topic):
            self._latched.add(topic)

    def _read(self) -> bool:
        """Take every reader's samples, then set the merge's watermark from the writers each
        reader is matched with now (read after the takes: a writer matched later has
        written nothing taken yet); True when some came."""
        got = False
        for topic in list(self._readers):
            got |= self._take(topic)
        self._merge.sync(self._matched())
        return got

    def _matched(self) -> dict[str, set[int]] | None:
        """Topic -> the writers each bound topic's reader is matched with now, for the
        merge's watermark; None (the hold alone) while a topic is read latched (a writer
        matched later sends stored samples of any age) or while a publication discovered
        is not matched yet: DDS matches a discovered writer with the reader a little later,
        and a writer already writing (a node that started while the watch runs) can have
        its first samples delivered once matched, older than what a watermark over the
        other writers alone would have released (the ``clock_backwards`` of a plain rclpy
        node, tests/live/test_dds_watermark.py)."""
        matched: dict[str, set[int]] = {}
        for topic, (reader, _ros) in list(self._readers.items()):
            if reader is None or not self.wanted(topic):
                continue
            if topic in self._latched:
                return None
            matched[topic] = {h & _HANDLE for h in reader.get_matched_publications()}
            if len(matched[topic]) < len(self._pubs.get(topic, ())):
                return None
        return matched

    def _take(self, topic: str, until_empty: bool = False) -> bool:
        """Take ``topic``'s samples into the merge (one batch, or every sample the reader
        holds when ``until_empty``); True when some came."""
        from fretc.live.dds.idl_types import take_raw

        reader = self._readers[topic][0]
        if reader is None:
            return False
        self._check_qos(topic, reader)
        got = False
        while True:
            batch = take_raw(reader)
            for data, info in batch:
                got = True
                self._heard.add(topic)
                now = time.time_ns()
                if topic == CLOCK_TOPIC:
                    self._clock = cdr_clock_ns(data)
                    if not self.wanted(topic):
                        continue
                stamp = info.source_timestamp
                log_time = self._clock if self._clock else (stamp if stamp > 0 else now)
                self._merge.put(topic, log_time, data, now, info.publication_handle & _HANDLE)
            if not (until_empty and batch):
                return got

    def _check_silent(self, now: int) -> None:
        """A ``protocol`` event (once per topic) for a bound topic whose publisher has been
        known for :data:`SILENT_SECONDS`, whose messages are known to have been sent (DDS
        tells the reader it lost samples: ``SampleLostStatus``) and none of which arrived:
        the transport hint (:data:`SILENT_HINT`). A publisher that is only silent (a node
        that starts publishing later) gets no hint: its topic waits, and a topic that gave
        no message in the whole run is its requirements' error at the end."""
        for topic, since in self._known_since.items():
            if (topic in self._heard or topic in self._silent_reported
                    or not self._pubs.get(topic) or not self.wanted(topic)
                    or now - since < SILENT_SECONDS * 1e9 or not self._lost(topic)):
                continue
            self._silent_reported.add(topic)
            self.events.put(("protocol", now, f"{topic}: a publisher is known since "
                             f"{(now - since) / 1e9:.0f} s and DDS reports "
                             f"{self._lost(topic)} of its samples lost, none arrived; "
                             + SILENT_HINT))

    def _lost(self, topic: str) -> int:
        """Samples of ``topic`` its reader knows were sent but did not get (DDS's
        ``SampleLostStatus``); 0 without a reader."""
        reader = self._readers.get(topic, (None, ""))[0]
        if reader is None:
            return 0
        try:
            return int(getattr(reader.get_sample_lost_status(), "total_count", 0) or 0)
        except Exception:  # noqa: BLE001 - a status the binding cannot read: nothing known
            return 0

    def _check_qos(self, topic: str, reader) -> None:
        """A reader whose QoS cannot match a publisher's is a ``protocol`` event (once)."""
        if topic in self._qos_reported:
            return
        status = reader.get_requested_incompatible_qos_status()
        if getattr(status, "total_count", 0):
            self._qos_reported.add(topic)
            self.events.put(("protocol", time.time_ns(), f"{topic}: a publisher's QoS is "
                             "incompatible with the subscription's (policy id "
                             f"{getattr(status, 'last_policy_id', '?')}); its messages are not "
                             "received"))
