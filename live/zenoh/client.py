"""``fretc watch zenoh://HOST:PORT``: a Zenoh session (a peer of the robot's rmw_zenoh router or
sessions) that hands the bound topics' messages to the watch engine as the Foxglove client does
(:mod:`fretc.live.protocol`'s events on an :class:`~fretc.live.events.EventQueue`).

Design notes: ARCHITECTURE.md, `live/zenoh/client.py`."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from fretc.live.protocol import WATCH_HINT, MissingDependency
from fretc.live.events import EventQueue
from fretc.live.merge import HOLD_SECONDS, MergeBuffer
from fretc.live.ros2_names import (CLOCK_TOPIC, LIVELINESS_PREFIX, advertisement, attachment_time,
                                   bridge_key, cdr_clock_ns, normal_type, parse_bridge_liveliness,
                                   parse_liveliness, parse_url, parse_zenoh_key, standard_store,
                                   zenoh_topic_key)

__all__ = ["ZenohClient", "zenoh_config", "require_zenoh"]



def require_zenoh() -> Any:  # the zenoh module
    """The ``zenoh`` module; raises :class:`~fretc.live.protocol.MissingDependency` naming the
    install hint when ``eclipse-zenoh`` is not installed."""
    try:
        import zenoh
    except ImportError:
        raise MissingDependency(f"the Zenoh transport needs eclipse-zenoh: {WATCH_HINT}") \
            from None
    return zenoh


def zenoh_config(*, listen: str | None = None, connect: str | None = None,
                 config_file: str | None = None, mode: str = "peer") -> Any:  # a zenoh.Config
    """A Zenoh session's configuration (``mode`` ``peer`` or ``router``): multicast scouting
    off, listening on and/or connecting to the given ``tcp/host:port`` endpoints
    (``config_file``: a Zenoh JSON5 configuration read first, e.g. TLS or access control)."""
    zenoh = require_zenoh()
    cfg = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
    cfg.insert_json5("mode", f'"{mode}"')
    cfg.insert_json5("scouting/multicast/enabled", "false")
    cfg.insert_json5("listen/endpoints", f'["{listen}"]' if listen else "[]")
    cfg.insert_json5("connect/endpoints", f'["{connect}"]' if connect else "[]")
    return cfg


class ZenohClient:
    """Watch the ROS 2 topics ``topics`` over Zenoh (module docstring); the events of
    :mod:`fretc.live.websocket.foxglove` on :attr:`events`.

    Args:
        url: ``zenoh://HOST:PORT[?domain=D]``.
        wanted: topic -> bool (the bound topics).
        topics: the bound topics (subscribed to; nothing else is).
        types: topic -> expected ROS type (the bindings' ``[types]``, ``--topic-type``).
        msg_path: folders of the robot's own ``.msg``/``.idl`` files.
        events: the queue (a new bounded :class:`~fretc.live.events.EventQueue` by default).

    Raises:
        ValueError: a URL of the wrong form; MissingDependency: no eclipse-zenoh.
    """

    #: every publisher of the bound topics leaving is the end of the run (no close frame on
    #: this transport)
    leaving_ends_run = True
    #: the reader stays while a topic's publishers are away and reads a new publisher from
    #: its first message: a span without a publisher is a silence, nothing lost in it
    #: (:data:`fretc.logs.recorded_gaps.PUBLISHER_ABSENT`)
    hears_new_publishers = True
    #: :meth:`stop` leaves the session open (closed by :meth:`close`)
    keep_session = False

    def __init__(self, url: str, wanted: Callable[[str], bool], *, topics=(),
                 types: dict[str, str] | None = None, msg_path: tuple[str, ...] = (),
                 events: EventQueue | None = None, config_file: str | None = None,
                 merge_hold: float = HOLD_SECONDS, **_ignored) -> None:
        require_zenoh()
        self.url = parse_url(url)
        self.wanted = wanted
        self.topics = sorted(set(topics))
        self.types = dict(types or {})
        self.store = standard_store(tuple(msg_path))
        self.config_file = config_file
        self.events: EventQueue = events if events is not None else EventQueue()
        self._lock = threading.Lock()
        self._publishers: dict[str, set[str]] = {}  # topic -> live publisher token keys
        self._advertised: dict[str, str] = {}  # topic -> ROS type
        self._seen: set[str] = set()  # topics advertised once (a second time: a restart)
        self._clock: int | None = None
        self._session: Any = None  # the open zenoh Session
        self._decls: list = []
        self._stop = threading.Event()
        self._watcher: threading.Thread | None = None
        self._merge = MergeBuffer(self.events, merge_hold)

    # -- thread control ----------------------------------------------------------------------
    def start(self) -> ZenohClient:
        """Open the session and declare the subscribers (returns at once)."""
        zenoh = require_zenoh()
        self._merge.start()
        self._session = zenoh.open(zenoh_config(connect=self.url.endpoint,
                                                config_file=self.config_file))
        bridge = self.url.layout == "bridge"
        lv = f"{LIVELINESS_PREFIX}/{'*/MP' if bridge else self.url.domain}/**"
        self._decls.append(self._session.liveliness().declare_subscriber(
            lv, self._on_token, history=True))
        for t in sorted(set(self.topics) | {CLOCK_TOPIC}):
            key = (bridge_key(self.url.namespace, t) if bridge
                   else zenoh_topic_key(self.url.domain, t))
            self._decls.append(self._session.declare_subscriber(
                key, lambda sample, t=t: self._on_sample(sample, t)))
        self._watcher = threading.Thread(target=self._watch_peers, daemon=True,
                                         name="fretc-zenoh-peers")
        self._watcher.start()
        return self

    def stop(self) -> None:
        """Undeclare the subscribers and close the session (idempotent); with
        :attr:`keep_session` the session stays open until :meth:`close` (the final
        ``/diagnostics`` of ``--publish-diagnostics`` goes out on it)."""
        self._stop.set()
        if self._watcher is not None:
            self._watcher.join(2)
        for d in self._decls:
            try:
                d.undeclare()
            except Exception:  # already gone with the session
                pass
        self._decls.clear()
        self._merge.stop()
        if not self.keep_session:
            self.close()

    def close(self) -> None:
        """Close the session (idempotent)."""
        session, self._session = self._session, None
        if session is not None:
            session.close()

    def _watch_peers(self) -> None:
        """``connected`` when the first peer or router is reached, ``disconnected`` when none
        is left (Zenoh reconnects by itself)."""
        up = False
        while not self._stop.wait(0.05):
            session = self._session
            if session is None:
                return
            try:
                info = session.info
                now = bool(list(info.peers_zid()) or list(info.routers_zid()))
            except Exception:  # the session is closing
                return
            if now and not up:
                self.events.put(("connected", time.time_ns(), "zenoh", ""))
            elif up and not now and self._advertised:  # not after every publisher left
                self.events.put(("disconnected", time.time_ns(),
                                 f"no Zenoh peer or router reachable at {self.url.endpoint}"))
            up = now

    # -- the graph -------------------------------------------------------------------------------
    def _on_token(self, sample) -> None:
        """A liveliness token appeared (PUT) or went (DELETE)."""
        if self.url.layout == "bridge":
            tok = parse_bridge_liveliness(str(sample.key_expr), self.url.namespace)
        else:
            tok = parse_liveliness(str(sample.key_expr))
        if tok is None or tok.kind != "MP" or tok.domain != self.url.domain:
            return
        key, now = str(sample.key_expr), time.time_ns()
        with self._lock:
            pubs = self._publishers.setdefault(tok.topic, set())
            if str(sample.kind).endswith("PUT"):
                pubs.add(key)
                if tok.topic == CLOCK_TOPIC and self._clock is None:
                    self._clock = 0  # simulated time from now on
                if self.wanted(tok.topic):
                    self._advertise(tok.topic, tok.type, now)
            elif key in pubs:
                pubs.discard(key)
                if not pubs and tok.topic in self._advertised:
                    del self._advertised[tok.topic]
                    self._merge.put_event(("unadvertise", now, [tok.topic]))

    def _advertise(self, topic: str, ros: str, now: int) -> None:
        """Advertise ``topic`` once with type ``ros`` (lock held); a type other than the
        bindings' expectation advertises no schema (its requirements are ``error``) and is a
        ``protocol`` event."""
        if topic in self._advertised:
            return
        self._advertised[topic] = ros
        expected = self.types.get(topic)
        adv = advertisement(len(self._advertised), topic, ros, self.store, expected)
        if adv.unreadable:
            self.events.put(("protocol", now, f"{adv.unreadable}: the topic is not read"))
        if topic in self._seen:  # a publisher came back (a restart): behind its
            self._merge.put_event(("advertise", now, [adv]))  # unadvertisement, merged
        else:
            self._seen.add(topic)
            self.events.put(("advertise", now, [adv]))

    # -- the data ----------------------------------------------------------------------------------
    def _on_sample(self, sample, topic: str) -> None:
        """One message of a bound topic (or of ``/clock``), from the subscriber of
        ``topic``; whatever it holds, it costs that message only (a ``protocol`` event)."""
        try:
            self._sample(sample, topic)
        except Exception as exc:
            self.events.put(("protocol", time.time_ns(), f"a Zenoh sample on "
                             f"{str(sample.key_expr)[:200]} could not be read "
                             f"({type(exc).__name__}: {str(exc)[:200]})"))

    def _sample(self, sample, topic: str) -> None:
        now = time.time_ns()
        if self.url.layout == "bridge":  # the key names no type: the token's, or [types]
            ros = self._advertised.get(topic) or self.types.get(topic) or ""
            if not ros and topic == CLOCK_TOPIC \
                    and str(sample.key_expr) == bridge_key(self.url.namespace, topic):
                ros = "rosgraph_msgs/msg/Clock"  # the bridge's /clock key (not a wildcard)
            if not ros:
                self.events.put(("protocol", now, f"a message of {topic} before its "
                                 "publisher's liveliness token (its type is not known): "
                                 "not read"))
                return
        else:
            ros = self._key_type(str(sample.key_expr), topic)  # type: ignore[assignment]  # (None: returned below)
            if ros is None and topic == CLOCK_TOPIC and not self.wanted(topic):
                return  # a put on a wildcard (``**``) that reached the time source's
                # subscriber too: not a clock message, and the topics it is for read it
            if ros is None:
                self.events.put(("protocol", now, f"a message of {topic} on the key "
                                 f"expression {str(sample.key_expr)[:200]} names no type "
                                 "and its publisher's liveliness token none either (give "
                                 "[types] in the bindings or --topic-type): not read"))
                return
        payload = sample.payload.to_bytes()
        att = sample.attachment
        stamp = attachment_time(att.to_bytes() if att is not None else None)
        if stamp is None and sample.timestamp is not None:
            stamp = _ntp64_ns(sample.timestamp)
        with self._lock:
            if topic == CLOCK_TOPIC and normal_type(ros) == "rosgraph_msgs/msg/Clock":
                self._clock = cdr_clock_ns(payload)
                if not self.wanted(topic):
                    return
            if not self.wanted(topic):
                return
            if topic not in self._advertised:  # data before its publisher's token
                self._advertise(topic, ros, now)
            elif normal_type(self._advertised[topic]) != normal_type(ros):
                self.events.put(("protocol", now, f"a message of {topic} of type {ros}, "
                                 f"advertised as {self._advertised[topic]}: not decoded"))
                payload = b""
            log_time = self._clock if self._clock else (stamp if stamp is not None else now)
        self._merge.put(topic, log_time, payload, now)


    def _key_type(self, key: str, topic: str) -> str | None:
        """The ROS type of a sample that the subscriber of ``topic`` received on ``key``.

        Zenoh delivers a sample to every subscriber whose key expression intersects the
        sample's, wildcards included (Zenoh's key expression language: ``*`` one chunk,
        ``**`` any chunks): a put on ``0/v/**`` or ``**`` reaches the subscriber of ``/v``
        and is a message of ``/v``, as a ROS subscriber on rmw_zenoh would take it. The
        type is the key's when its type chunk is concrete (rmw_zenoh's ``D/topic/type/hash``
        of this topic), else the one the topic was advertised with (its publisher's
        liveliness token) or given in the bindings' ``[types]``; None when none is
        known (``/clock`` included: a wildcard put that no clock publisher advertised is
        not read as the clock)."""
        parsed = parse_zenoh_key(key)
        if parsed is not None and parsed[1] == topic and "*" not in parsed[2] \
                and "$" not in parsed[2]:
            return parsed[2]
        return self._advertised.get(topic) or self.types.get(topic) or None



def _ntp64_ns(ts) -> int | None:
    """A Zenoh timestamp (NTP64 since the epoch) in ns; None when it cannot be read."""
    try:
        return int(ts.get_time().timestamp() * 1e9)
    except Exception:  # another binding's timestamp object
        return None
