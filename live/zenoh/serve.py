"""``fretc replay LOG --serve zenoh://HOST:PORT``: a recorded log's messages published as a
ROS 2 node on rmw_zenoh would publish them (naming rules: :mod:`fretc.live.ros2_names`).

Design notes: ARCHITECTURE.md, `live/zenoh/serve.py`."""

from __future__ import annotations

import os
import time
from collections.abc import Iterable
from typing import Any

from fretc.logs.decoding import build_typestore

from fretc.live.ros2_names import (attachment, bridge_key, bridge_liveliness, liveliness_token,
                                   parse_url, zenoh_key)
from fretc.live.zenoh.client import require_zenoh, zenoh_config

__all__ = ["ZenohServer"]


class ZenohServer:
    """A Zenoh peer publishing ROS 2 topics (module docstring).

    Args:
        url: ``zenoh://HOST:PORT[?domain=D]`` (the endpoint listened on).
        name: the node name in the liveliness tokens.
        config_file: a Zenoh JSON5 configuration read first.
        session: publish on this open session (the watch's, for ``--publish-diagnostics``)
            instead of a new one listening on the URL's endpoint; not closed by :meth:`stop`.

    Raises:
        ValueError: a URL of the wrong form; MissingDependency: no eclipse-zenoh;
        zenoh.ZError: the endpoint cannot be listened on (port in use).
    """

    def __init__(self, url: str, name: str = "fretc_replay",
                 config_file: str | None = None, session=None) -> None:
        require_zenoh()
        self.address = parse_url(url)
        self.url = url
        self.node = "".join(c if c.isalnum() else "_" for c in name)[:60] or "fretc_replay"
        self._own = session is None
        self.session = session if session is not None else __import__("zenoh").open(
            zenoh_config(listen=self.address.endpoint, config_file=config_file, mode="router"))
        self.channels: dict[str, Any] = {}  # topic -> the library's channel or writer
        self.skipped: dict[str, str] = {}
        self._tokens: dict[str, Any] = {}  # topic -> its liveliness token
        self._seq = 0
        self._gid = os.urandom(16)

    def channel(self, topic: str, message_encoding: str, schema_name: str,
                schema_encoding: str, schema_data: bytes) -> Any:  # the writer, or None
        """Declare the publisher and liveliness token of ``topic`` (once); None for a
        channel that cannot be published (not CDR, or a schema rosbags cannot read)."""
        if topic in self.channels or topic in self.skipped:
            return self.channels.get(topic)
        if message_encoding != "cdr":
            self.skipped[topic] = f"message encoding {message_encoding!r} is not CDR"
            return None
        try:
            store, typename = build_typestore(schema_encoding, schema_name,
                                              schema_data.decode("utf-8"))
            type_hash = store.hash_rihs01(typename)
        except Exception as exc:  # a schema rosbags cannot read
            self.skipped[topic] = f"schema {schema_name!r} cannot be read ({exc})"
            return None
        d, zid = self.address.domain, str(self.session.zid())
        if self.address.layout == "bridge":  # zenoh-bridge-ros2dds's keys (ros2_names)
            key = bridge_key(self.address.namespace, topic)
            pub = self.session.declare_publisher(key)
            token = bridge_liveliness(zid, key, typename)
        else:
            pub = self.session.declare_publisher(zenoh_key(d, topic, typename, type_hash))
            token = liveliness_token(d, zid, len(self.channels) + 10, "MP", self.node, topic,
                                     typename, type_hash)
        self._tokens[topic] = self.session.liveliness().declare_token(token)
        self.channels[topic] = pub
        return pub

    def log(self, topic: str, data: bytes, log_time: int) -> None:
        """Publish one message of ``topic`` with ``log_time`` (ns) as its source timestamp
        (the bridge layout carries none); a skipped channel's messages are dropped."""
        pub = self.channels.get(topic)
        if pub is None:
            return
        self._seq += 1
        if self.address.layout == "bridge":  # the bridge forwards the DDS payload alone
            pub.put(bytes(data))
        else:
            pub.put(bytes(data), attachment=attachment(self._seq, int(log_time), self._gid))

    def wait_subscribed(self, topics: Iterable[str] | None = None, timeout: float = 30.0,
                        settle: float = 0.2) -> bool:
        """Block until a subscriber matches every publisher of ``topics`` (None: any
        publisher), then ``settle`` seconds more; False on timeout."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            pubs = [p for t, p in self.channels.items() if topics is None or t in topics]
            matched = [p.matching_status.matching for p in pubs]
            if matched and (all(matched) if topics is not None else any(matched)):
                time.sleep(settle)
                return True
            time.sleep(0.05)
        return False

    def unpublish(self, topic: str) -> None:
        """Undeclare the publisher of ``topic`` and its liveliness token (that publisher
        left; the others go on)."""
        tok = self._tokens.pop(topic, None)
        if tok is not None:
            tok.undeclare()
        pub = self.channels.pop(topic, None)
        if pub is not None:
            pub.undeclare()

    def stop(self) -> None:
        """Undeclare the tokens and publishers (the node left) and close the session."""
        for tok in self._tokens.values():
            tok.undeclare()
        for pub in self.channels.values():
            pub.undeclare()
        self._tokens.clear()
        self.channels.clear()
        if self._own:
            self.session.close()
