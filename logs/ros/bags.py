"""ROS 1 bags (``*.bag``) and rosbag2 folders as a :class:`~fretc.logs.base.LogSource`,
read with the rosbags readers (:mod:`rosbags.rosbag1`, :mod:`rosbags.rosbag2`: sqlite3 or
mcap storage). A ROS 1 bag whose index is damaged or missing is read without it
(:mod:`fretc.logs.ros.ros1_linear`).
"""

from __future__ import annotations

import os
import struct
import zlib
import shutil
import weakref
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from rosbags.interfaces import MessageDefinitionFormat
from rosbags.typesys.msg import normalize_msgtype
from rosbags.rosbag1 import Reader as Ros1Reader, ReaderError as Ros1ReaderError
from rosbags.rosbag2 import Reader as Ros2Reader, ReaderError as Ros2ReaderError
from rosbags.typesys.store import Typestore

from fretc.common import problems as P
from fretc.common.problems import LogError
from fretc.logs.base import LogSource, Message, header_stamp
from fretc.logs.decoding import (DECODE_ERRORS, SCHEMA_FOR_ENCODING, UnsupportedSchema,
                                 build_typestore, service_event_text)
from fretc.logs.decoding import decoder_for
from fretc.logs.ros.msg_path import MSG_PATH_HINT
from fretc.logs.ros.ros1_linear import Ros1Linear, is_ros1_bag
from fretc.logs.ros.rosbag2_storage import lone_storage, storage_folder, stored_definitions

__all__ = ["BagSource", "connection_typestore"]

#: Errors of a bag whose data is damaged part-way.
_BAG_ERRORS = (Ros1ReaderError, Ros2ReaderError, OSError, struct.error, EOFError, ValueError,
               KeyError, IndexError, zlib.error, AssertionError)  # rosbags asserts on some corrupt bags


def connection_typestore(kind: str, conn: Any, fallback: Typestore | None,
                         stored: Mapping[str, tuple[str, str]] | None = None
                         ) -> tuple[Typestore, str]:
    """The typestore and type name of one bag connection, built from the definition the bag
    stores (ROS 1 connection header ``message_definition``: ``ros1msg``; rosbag2
    ``message_definition``: ``ros2msg`` or ``ros2idl``), else taken from ``fallback``.

    Args:
        kind: ``"bag"`` (ROS 1) or ``"rosbag2"``.
        conn: a rosbags ``Connection``.
        fallback: types for connections that carry no definition, or None.
        stored: the definitions the bag's storage keeps by type name
            (:func:`fretc.logs.ros.rosbag2_storage.stored_definitions`): a service event topic
            (``pkg/srv/Name_Event``) whose own definition is not stored is built from the
            service's (``pkg/srv/Name``, as rosbag2 stores it).

    Raises:
        UnsupportedSchema: no definition and no fallback type, or a definition rosbags cannot
            parse.
    """
    fmt, text = conn.msgdef.format, conn.msgdef.data
    service = conn.msgtype[:-len("_Event")] if conn.msgtype.endswith("_Event") else None
    if (fmt == MessageDefinitionFormat.NONE or not text.strip()) and stored and service \
            and "/srv/" in conn.msgtype and stored.get(service, ("", ""))[0] == "ros2msg":
        return build_typestore("ros2msg", conn.msgtype,
                               service_event_text(conn.msgtype, stored[service][1]))
    if fmt == MessageDefinitionFormat.NONE or not text.strip():
        name = conn.msgtype
        if fallback is not None and name not in fallback.fielddefs:
            name = normalize_msgtype(name)  # pkg/srv/T as rosbags stores it: pkg/srv/msg/T
        if fallback is None or name not in fallback.fielddefs:
            raise UnsupportedSchema(f"the bag stores no definition of {conn.msgtype!r} and no "
                                    f"folder given defines it: give its .msg with {MSG_PATH_HINT}")
        return fallback, name
    schema_encoding = ("ros1msg" if kind == "bag" else
                       "ros2idl" if fmt == MessageDefinitionFormat.IDL else "ros2msg")
    return build_typestore(schema_encoding, conn.msgtype, text)


class BagSource(LogSource):
    """A ROS 1 ``.bag`` file (kind ``"bag"``) or a rosbag2 folder (kind ``"rosbag2"``).

    Read with rosbags.rosbag1.Reader / rosbags.rosbag2.Reader.  Each connection's type is built
    from the definition stored in the bag (ROS 1 connection header ``message_definition``;
    rosbag2 ``message_definition`` / mcap schema).  A connection without one uses
    ``fallback_typestore`` if given, else its topic gets an ``unknown_schema`` problem.
    Bags do not record a publish time: ``Message.publish_time == log_time``.

    A ROS 1 bag whose index is damaged or missing (a crashed recording) is read record by
    record from the start (:class:`~fretc.logs.ros.ros1_linear.Ros1Linear`), as far as
    it goes; the log is then ``partial``. A rosbag2 sqlite3 storage file given alone (a
    ``.db3``, or a folder holding one without ``metadata.yaml``) is read as rosbag2 opens it
    (:mod:`fretc.logs.ros.rosbag2_storage`).

    Raises:
        LogError: the bag cannot be opened (a rosbag2 folder rosbags cannot read, a ``.bag``
            file that is not a ROS 1 bag).
    """

    def __init__(self, path: str | os.PathLike, *, fallback_typestore: Typestore | None = None) -> None:
        super().__init__(path)
        p = Path(path)
        self.kind = "rosbag2" if p.is_dir() or p.suffix.lower() == ".db3" else "bag"
        self._read_path = p
        alone = lone_storage(p) if self.kind == "rosbag2" else None
        if alone is not None:  # the folder made for it goes with the source
            self._read_path = storage_folder(alone)
            weakref.finalize(self, shutil.rmtree, self._read_path, True)
        self._stored = stored_definitions(self._read_path) if self.kind == "rosbag2" else {}
        self._fallback = fallback_typestore
        self._topics: dict[str, str] = {}
        self._linear_bag: Ros1Linear | None = None
        try:
            with self._reader() as reader:
                for c in reader.connections:
                    self._topics.setdefault(c.topic, c.msgtype)
                if reader.message_count:
                    self._start_time = reader.start_time
                    self._end_time = reader.end_time - 1  # rosbags' end_time is one past the last
        except LogError:
            raise
        except Exception as exc:  # rosbags ReaderError and friends
            if self.kind != "bag" or not is_ros1_bag(p):
                raise LogError(path, _bag_open_error(p, self.kind, exc)) from None
            # a ROS 1 bag whose index (at its end) is damaged or missing, as a crashed
            # recording leaves it: read its records from the start, as far as they go
            why = f"{type(exc).__name__}: {exc}" if str(exc) else \
                f"{type(exc).__name__}, without a message"
            self._linear_bag = Ros1Linear(self, f"rosbags' reader: {why}")
            self._open_damage = True
            self.partial = True
            self._topics = self._linear_bag.scan()

    def _reader(self) -> Any:
        return (Ros1Reader if self.kind == "bag" else Ros2Reader)(self._read_path)

    @property
    def linear(self) -> Ros1Linear | None:
        """The record-by-record reader of a ROS 1 bag whose index is damaged or missing
        (class docstring), or None when rosbags reads the bag."""
        return self._linear_bag

    def raw_messages(self) -> Iterator[Message]:
        """A pass over a ROS 1 bag read record by record (:attr:`linear` not None): every
        message undecoded (:meth:`~fretc.logs.ros.ros1_linear.Ros1Linear.raw_messages`),
        the damage recorded as by :meth:`messages`.

        Raises:
            ValueError: rosbags reads this bag (its own reader gives the bytes)."""
        if self._linear_bag is None:
            raise ValueError(f"{self.path}: read by rosbags, not record by record")
        self._begin_pass()
        yield from self._linear_bag.raw_messages()

    def topics(self) -> dict[str, str]:
        """Topic → type name (normalized ``pkg/msg/Type``)."""
        return dict(sorted(self._topics.items()))

    def _decoder(self, conn: Any, log_time: int) -> Callable[[bytes], Any] | None:
        if conn.id in self._decoders:
            return self._decoders[conn.id]
        dec = None
        encoding = "ros1" if self.kind == "bag" else getattr(conn.ext, "serialization_format", "cdr")
        try:
            store, typename = connection_typestore(self.kind, conn, self._fallback, self._stored)
            dec = decoder_for(store, typename, encoding, self._fields_for(conn.topic))
        except UnsupportedSchema as exc:
            kind = P.UNKNOWN_ENCODING if encoding not in SCHEMA_FOR_ENCODING else P.UNKNOWN_SCHEMA
            self._no_decoder[conn.id] = (kind, str(exc))
        self._decoders[conn.id] = dec
        return dec

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """Decoded messages of ``topics`` (all when None) in non-decreasing log time.

        A read error part-way (damaged bag) ends the pass with ``partial`` set.
        """
        self._begin_pass()
        if self._linear_bag is not None:
            yield from self._linear_bag.messages(topics)
            return
        last: int | None = None
        try:
            with self._reader() as reader:
                conns = [c for c in reader.connections if topics is None or c.topic in topics]
                if not conns:
                    return
                for conn, log_time, raw in reader.messages(connections=conns):
                    if last is not None and log_time < last:
                        self._problem(P.OUT_OF_ORDER, conn.topic, log_time,
                                      f"message is {last - log_time} ns older than the previous "
                                      "one; skipped")
                        continue
                    dec = self._decoder(conn, log_time)
                    if dec is None:
                        kind, why = self._no_decoder[conn.id]
                        self._lose(kind, conn.topic, conn.id, log_time, why)
                        continue
                    try:
                        data = dec(raw)
                    except DECODE_ERRORS as exc:
                        self._lose(P.UNDECODABLE, conn.topic, conn.id, log_time,
                                   f"a payload of {len(raw)} bytes does not deserialize: "
                                   f"{type(exc).__name__}: {exc}")
                        continue
                    last = log_time
                    self.counts[conn.topic] = self.counts.get(conn.topic, 0) + 1
                    yield Message(conn.topic, log_time, log_time, header_stamp(data), data)
        except _BAG_ERRORS as exc:  # data corrupt part-way
            self._gap(last, cause=P.CORRUPT_RECORD)
            self._problem(P.CORRUPT_RECORD, None, last,
                          f"reading stopped: {type(exc).__name__}: {exc}")


def _bag_open_error(path: Path, kind: str, exc: Exception) -> str:
    """Why a bag cannot be opened, naming the format of a ROS 1 bag older than 2.0 (the
    first line of a bag is ``#ROSBAG V<major>.<minor>``)."""
    if kind == "bag":
        try:
            with open(path, "rb") as f:
                head = f.read(16)
        except OSError:
            head = b""
        if head.startswith(b"#ROSBAG V") and not head.startswith(b"#ROSBAG V2.0"):
            version = head[9:].split(b"\n", 1)[0].decode("ascii", "replace")
            return (f"ROS bag format {version} is not supported: only format 2.0 (every ROS 1 "
                    "distribution since 2010) is read")
    return f"cannot open {kind}: {exc}"
