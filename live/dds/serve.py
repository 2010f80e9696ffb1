"""``fretc replay LOG --serve dds://DOMAIN``: a recorded log's messages published on a DDS domain
(Cyclone DDS) as a ROS 2 node would publish them: topic ``rt/<name>``, type
``pkg::msg::dds_::Type_`` (:mod:`fretc.live.ros2_names`, :mod:`fretc.live.dds.idl_types`), each
message's CDR bytes as recorded, its log time as the sample's source timestamp. Writers are
reliable, keep-all (transient-local for ``/tf_static``). At the end the writers are deleted (their
publications disposed: a watch sees the publishers leave). Channels of other encodings are not
published (:attr:`DdsServer.skipped`).

The object has the interface of :class:`fretc.live.websocket.serve.FoxgloveServer` that
:func:`fretc.live.websocket.serve.replay_mcap` drives (``channel``, ``log``, ``wait_subscribed``,
``stop``).
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from typing import Any

from fretc.logs.decoding import build_typestore

from fretc.live.dds.client import require_cyclonedds
from fretc.live.ros2_names import dds_topic, parse_url

__all__ = ["DdsServer"]


class DdsServer:
    """DDS writers of a log's topics (module docstring).

    Args:
        url: ``dds://DOMAIN``.
        config_file: a Cyclone DDS XML configuration (``--dds-config``).

    Raises:
        ValueError: a URL of the wrong form; MissingDependency: no cyclonedds.
    """

    def __init__(self, url: str, config_file: str | None = None) -> None:
        require_cyclonedds()
        from fretc.live.dds.idl_types import open_participant

        self.url = url
        self.domain = parse_url(url).domain
        self.participant = open_participant(self.domain, config_file)
        self.channels: dict[str, Any] = {}  # topic -> the library's channel or writer
        self.skipped: dict[str, str] = {}

    def channel(self, topic: str, message_encoding: str, schema_name: str,
                schema_encoding: str, schema_data: bytes) -> Any:  # the writer, or None
        """Create the writer of ``topic`` (once); None for a channel that cannot be
        published (not CDR, or a schema rosbags cannot read)."""
        from cyclonedds.pub import DataWriter
        from cyclonedds.topic import Topic

        from fretc.live.dds.idl_types import idl_struct, writer_qos

        if topic in self.channels or topic in self.skipped:
            return self.channels.get(topic)
        if message_encoding != "cdr":
            self.skipped[topic] = f"message encoding {message_encoding!r} is not CDR"
            return None
        try:
            store, typename = build_typestore(schema_encoding, schema_name,
                                              schema_data.decode("utf-8"))
            cls = idl_struct(store, typename)
        except Exception as exc:  # a schema rosbags cannot read
            self.skipped[topic] = f"schema {schema_name!r} cannot be read ({exc})"
            return None
        tp: Topic[Any] = Topic(self.participant, dds_topic(topic), cls)
        w = DataWriter(self.participant, tp, qos=writer_qos(topic))
        self.channels[topic] = w
        return w

    def log(self, topic: str, data: bytes, log_time: int) -> None:
        """Write one message of ``topic`` with ``log_time`` (ns) as its source timestamp;
        a skipped channel's messages are dropped."""
        from fretc.live.dds.idl_types import write_raw

        w = self.channels.get(topic)
        if w is not None:
            write_raw(w, data, log_time)

    def wait_subscribed(self, topics: Iterable[str] | None = None, timeout: float = 30.0,
                        settle: float = 0.2) -> bool:
        """Block until a reader matches every writer of ``topics`` (None: any writer), then
        ``settle`` seconds more; False on timeout."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            ws = [w for t, w in self.channels.items() if topics is None or t in topics]
            matched = [w.get_publication_matched_status().current_count > 0 for w in ws]
            if matched and (all(matched) if topics is not None else any(matched)):
                time.sleep(settle)
                return True
            time.sleep(0.05)
        return False

    def unpublish(self, topic: str) -> None:
        """Delete the writer of ``topic`` once its samples are acknowledged (up to 5 s):
        that publisher left (its publication disposed), the others go on."""
        w = self.channels.pop(topic, None)
        if w is None:
            return
        try:
            w.wait_for_acks(5_000_000_000)
        except Exception:  # a reader gone: nothing to wait for
            pass
        import gc

        del w
        gc.collect()  # cyclonedds deletes an entity when its Python object goes

    def stop(self) -> None:
        """Wait (up to 5 s) for the readers to acknowledge every sample, then delete the
        writers and leave the domain."""
        for w in self.channels.values():
            try:
                w.wait_for_acks(5_000_000_000)
            except Exception:  # a reader gone: nothing to wait for
                pass
        self.channels.clear()
        self.participant = None
