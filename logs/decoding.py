"""The decoder layer: rosbags types built from the schema text a log embeds, and a
``bytes -> message`` function per channel.

Schema encodings ``ros2msg``, ``ros2idl`` and ``ros1msg``, message encodings ``cdr`` (ROS 2)
and ``ros1`` (MCAP spec, "Well-known encodings"). Decoders read every field, or only the fields the
signal bindings read (:mod:`fretc.logs.ros.selective`). The self-describing encodings (``json``,
``protobuf``, ``cbor``) are :mod:`fretc.logs.mcap.encodings`'; :func:`schema_decoder` serves both.
"""

from __future__ import annotations

import functools
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rosbags.serde import SerdeError

from fretc.logs.ros.columnar import ColumnarDecoder, columnar_decoder
from fretc.logs.mcap.encodings import (SELF_DESCRIBING, UNSUPPORTED_ENCODINGS, EncodingError,
                                       other_decoder)
from fretc.logs.ros.known_types import layout_mismatch
from fretc.logs.ros.selective import selective_decoder

if TYPE_CHECKING:  # rosbags' type system is imported when a schema is built (start-up of
    # the logs that need none: json, protobuf, cbor, ULog, CSV)
    from rosbags.typesys.store import Typestore

__all__ = ["UnsupportedSchema", "build_typestore", "decoder_for", "schema_decoder",
           "schema_columnar",
           "DECODE_ERRORS", "SCHEMA_FOR_ENCODING", "event_encoding"]

_IDL_SEP = "=" * 80 + "\n"


class UnsupportedSchema(Exception):
    """A channel whose messages cannot be decoded: an unsupported schema or message encoding,
    a missing schema, or a definition rosbags cannot parse (the message says which). The
    readers report it as an ``unknown_schema`` / ``unknown_encoding`` problem and skip the
    channel's messages."""


def build_typestore(schema_encoding: str, name: str, text: str) -> tuple[Typestore, str]:
    """A rosbags Typestore holding the types of one embedded schema. Building one compiles
    rosbags' (de)serializers of its types (tens of ms); the stores of the latest
    :data:`_STORES_KEPT` distinct schemas are kept and shared (read only: nothing registers
    types in a store after it is built), so a log's channels, its binding type check and the
    logs of one fleet audit with the same schema build it once.

    Args:
        schema_encoding: ``"ros2msg"``, ``"ros1msg"`` (concatenated .msg text with
            ``MSG: pkg/Type`` sections) or ``"ros2idl"`` (``IDL: pkg/msg/Type`` sections),
            per the MCAP spec's well-known schema encodings.
        name: the schema (message type) name, ROS 1 or ROS 2 spelling.
        text: the schema data as text.

    Returns:
        (typestore, normalized type name).

    Raises:
        UnsupportedSchema: unknown schema encoding, or a definition rosbags cannot parse.
    """
    return _build_typestore(schema_encoding, name, text)


#: Distinct schemas whose Typestore :func:`build_typestore` keeps.
_STORES_KEPT = 64


def _roslib_header(schema_encoding: str, text: str) -> str:
    """ROS 1 definitions recorded before ROS Diamondback (2010) name the header type
    ``roslib/Header``, which became ``std_msgs/Header`` with the same fields; a field of type
    ``Header`` means ``std_msgs/Header`` to rosbags, so such a definition is read with the
    section renamed."""
    if (schema_encoding == "ros1msg" and "MSG: roslib/Header" in text
            and "MSG: std_msgs/Header" not in text):
        return text.replace("MSG: roslib/Header", "MSG: std_msgs/Header")
    return text


def _service_type(name: str) -> str:
    """The name a ros2msg definition of a service's or an action's message is parsed under:
    rosbag2 records a service's events as ``pkg/srv/Name_Event`` (ROS 2 Jazzy's service
    introspection) and an action's as ``pkg/action/Name_FeedbackMessage``, their definitions
    naming the request and response types relative to the package (``Name_Request``,
    ``MSG: pkg/Name_Request``), which rosbags resolves under ``pkg/msg/``; the type is read as
    ``pkg/msg/Name_Event`` (its CDR is the same)."""
    parts = name.split("/")
    if len(parts) == 3 and parts[1] in ("srv", "action"):
        return f"{parts[0]}/msg/{parts[2]}"
    return name


#: service_msgs/msg/ServiceEventInfo and builtin_interfaces/msg/Time (ROS 2 Jazzy), the
#: dependencies of every service event a bare ``.srv`` schema leaves out
_EVENT_INFO = ("MSG: service_msgs/ServiceEventInfo\nuint8 REQUEST_SENT = 0\n"
               "uint8 REQUEST_RECEIVED = 1\nuint8 RESPONSE_SENT = 2\nuint8 RESPONSE_RECEIVED = 3\n"
               "uint8 event_type\nbuiltin_interfaces/Time stamp\nchar[16] client_gid\n"
               "int64 sequence_number\n" + _IDL_SEP
               + "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")


def service_event_text(name: str, text: str) -> str:
    """The full ros2msg definition of a service's event type ``pkg/srv/Name_Event`` when a
    log stores the service's ``.srv`` text instead (rosbag2_cpp's writer looks up the
    service's own definition: the bare ``request --- response`` text in its test bags, an
    ``SRV: pkg/srv/Name`` section in Jazzy's); ``text`` unchanged for anything else. The event
    is ``service_msgs/ServiceEventInfo info``, ``Name_Request[<=1] request``,
    ``Name_Response[<=1] response`` (ROS 2 service introspection, REP 2012 era Iron/Jazzy);
    the ``.srv``'s own ``MSG:`` sections are kept for the types its fields name."""
    parts = name.split("/")
    if len(parts) != 3 or parts[1] != "srv" or not parts[2].endswith("_Event"):
        return text
    sections = text.split(_IDL_SEP)
    body, rest = None, []
    for k, sec in enumerate(sections):
        head = sec.split("\n", 1)[0].strip()
        if head.startswith("SRV:"):
            body = sec.split("\n", 1)[1] if "\n" in sec else ""
        elif k == 0 and not head.startswith("MSG:") and _has_separator(sec):
            body = sec
        else:
            rest.append(sec)
    if body is None:
        return text
    lines = body.splitlines()
    cut = next(i for i, ln in enumerate(lines) if ln.strip() == "---") if _has_separator(
        body) else len(lines)
    pkg, svc = parts[0], parts[2][:-len("_Event")]
    request, response = "\n".join(lines[:cut]), "\n".join(lines[cut + 1:])
    # the request and response named in full (pkg/srv/Name_Request): rosbags resolves a
    # relative name against the event's own package path, which differs between a type
    # store (pkg/srv/msg/...) and a log's schema read under pkg/msg/ (_service_type)
    out = (f"service_msgs/ServiceEventInfo info\n{pkg}/srv/{svc}_Request[<=1] request\n"
           f"{pkg}/srv/{svc}_Response[<=1] response\n" + _IDL_SEP + _EVENT_INFO + _IDL_SEP
           + f"MSG: {pkg}/srv/{svc}_Request\n{request}\n" + _IDL_SEP
           + f"MSG: {pkg}/srv/{svc}_Response\n{response}\n")
    kept = [sec for sec in rest if sec.strip()]
    return out + "".join(_IDL_SEP + sec for sec in kept)


def _has_separator(text: str) -> bool:
    return any(ln.strip() == "---" for ln in text.splitlines())


@functools.lru_cache(maxsize=_STORES_KEPT)
def _build_typestore(schema_encoding: str, name: str, text: str) -> tuple[Typestore, str]:
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
    from rosbags.typesys.msg import normalize_msgtype

    typename = normalize_msgtype(_service_type(name) if schema_encoding == "ros2msg" else name)
    if schema_encoding in ("ros2msg", "unknown"):
        text = service_event_text(name, text)
        if schema_encoding == "unknown" and text.startswith("service_msgs/ServiceEventInfo info"):
            schema_encoding = "ros2msg"
            typename = normalize_msgtype(_service_type(name))
    if not text.strip():
        raise UnsupportedSchema(f"schema {name!r} is empty")
    if schema_encoding not in ("ros2msg", "ros1msg", "ros2idl"):
        raise UnsupportedSchema(f"schema encoding {schema_encoding!r} is not supported "
                                "(supported: ros2msg, ros2idl, ros1msg)")
    try:
        if schema_encoding == "ros2idl":
            typs = {}
            if text.startswith(_IDL_SEP + "IDL: "):
                for part in text.split(_IDL_SEP)[1:]:
                    _hdr, idl = part.split("\n", 1)
                    typs.update(get_types_from_idl(idl))
            else:
                typs.update(get_types_from_idl(text))
        else:
            typs = get_types_from_msg(_roslib_header(schema_encoding, text), typename)
        store = get_typestore(Stores.EMPTY)
        store.register(typs)
        store.get_msgdef(typename)  # fails now, not on the first message, if incomplete
    except Exception as exc:  # rosbags' PEG parser raises plain exceptions on bad text
        raise UnsupportedSchema(f"schema {name!r} ({schema_encoding}) cannot be parsed: {exc}") from None
    return store, typename


def decoder_for(store: Typestore, typename: str, message_encoding: str,
                fields: Any = None) -> Callable[[bytes], Any]:
    """A function ``bytes -> message`` of ``typename`` held in ``store``.

    Args:
        store: a rosbags Typestore holding ``typename``.
        typename: the normalized type name (``pkg/msg/Type``).
        message_encoding: ``"cdr"`` or ``"ros1"``.
        fields: field paths to decode (:mod:`fretc.logs.ros.selective`); None: every field.

    Raises:
        UnsupportedSchema: another message encoding.
    """
    if message_encoding == "cdr":
        deser = store.deserialize_cdr
    elif message_encoding == "ros1":
        deser = store.deserialize_ros1
    else:
        raise UnsupportedSchema(f"message encoding {message_encoding!r} is not supported (cdr, ros1)")

    def decode(raw: bytes) -> Any:
        return deser(raw, typename)

    if fields is not None:  # only the fields the bindings read (logs.selective)
        return selective_decoder(store, typename, message_encoding, fields, decode) or decode
    return decode


SCHEMA_FOR_ENCODING = {"cdr": ("ros2msg", "ros2idl"), "ros1": ("ros1msg",)}


def event_encoding(message_encoding: str, schema_encoding: str | None,
                   schema_name: str | None) -> str | None:
    """``ros2msg`` for a service event channel whose schema encoding rosbag2 wrote as
    ``unknown`` (Jazzy, a service of primitive fields only: the schema is the ``.srv``
    text, :func:`service_event_text`); ``schema_encoding`` unchanged for any other."""
    parts = (schema_name or "").split("/")
    if (schema_encoding == "unknown" and message_encoding == "cdr" and len(parts) == 3
            and parts[1] == "srv" and parts[2].endswith("_Event")):
        return "ros2msg"
    return schema_encoding


def schema_decoder(message_encoding: str, schema_encoding: str | None, schema_name: str | None,
                   schema_text: str | bytes | None, fields: Any = None) -> Callable[[bytes], Any]:
    """A function ``bytes -> rosbags message`` for one channel, with its types built from the
    schema text the channel carries (an MCAP Schema record, or a Foxglove WebSocket
    ``advertise``): shared by the log readers and ``fretc watch``.

    Args:
        message_encoding: ``"cdr"`` (ROS 2), ``"ros1"``, or a self-describing encoding of
            :data:`fretc.logs.mcap.encodings.SELF_DESCRIBING` (MCAP well-known message encodings).
        schema_encoding: ``"ros2msg"``, ``"ros2idl"`` or ``"ros1msg"`` (well-known schema
            encodings), matching the message encoding; None or ``""`` when the channel has none.
        schema_name: the message type (``pkg/msg/Type`` or ``pkg/Type``).
        schema_text: the definition text (see :func:`build_typestore`), or the schema's bytes
            (MCAP Schema ``data``; binary for ``protobuf``).
        fields: field paths to decode (:mod:`fretc.logs.ros.selective`); None: every field.

    Raises:
        UnsupportedSchema: an unsupported message encoding, a channel without schema, a schema
            encoding that does not go with the message encoding, a schema rosbags cannot
            parse, or a definition of a standard ROS type whose layout is not ROS's
            (:func:`fretc.logs.ros.known_types.layout_mismatch`; the message says which).
    """
    if message_encoding in SELF_DESCRIBING:
        try:
            return other_decoder(message_encoding, schema_encoding or "", schema_name or "",
                                 schema_text, fields)
        except EncodingError as exc:
            raise UnsupportedSchema(str(exc)) from None
    if message_encoding not in SCHEMA_FOR_ENCODING:
        why = UNSUPPORTED_ENCODINGS.get(message_encoding)
        raise UnsupportedSchema(f"message encoding {message_encoding!r} is not supported"
                                + (f": {why}" if why else "")
                                + " (read: cdr, ros1, " + ", ".join(SELF_DESCRIBING) + ")")
    if isinstance(schema_text, bytes):
        schema_text = schema_text.decode("utf-8", errors="replace")
    schema_encoding = event_encoding(message_encoding, schema_encoding, schema_name)
    if not schema_encoding or not schema_name or schema_text is None:
        raise UnsupportedSchema("the channel has no schema")
    if schema_encoding not in SCHEMA_FOR_ENCODING[message_encoding]:
        raise UnsupportedSchema(f"schema encoding {schema_encoding!r} does not go with message "
                                f"encoding {message_encoding!r}")
    store, typename = build_typestore(schema_encoding, schema_name, schema_text)
    lie = layout_mismatch(schema_encoding, store, typename)
    if lie is not None:
        raise UnsupportedSchema(lie)
    return decoder_for(store, typename, message_encoding, fields)



#: Exceptions a decoder from :func:`schema_decoder` raises on a payload that does not match.
DECODE_ERRORS = (SerdeError, struct.error, IndexError, ValueError, AssertionError,
                 UnicodeDecodeError, KeyError, TypeError, OverflowError)


def schema_columnar(message_encoding: str, schema_encoding: str | None, schema_name: str | None,
                    schema_text: str | bytes | None, fields: Any) -> ColumnarDecoder | None:
    """A :class:`~fretc.logs.ros.columnar.ColumnarDecoder` of one channel's ``fields``, or
    None wherever :func:`schema_decoder` would raise or the columnar walk does not cover the
    type (the channel is then decoded message by message, which reports the problem). Never
    raises; the arguments are :func:`schema_decoder`'s."""
    if message_encoding != "cdr" or fields is None:
        return None
    schema_encoding = event_encoding(message_encoding, schema_encoding, schema_name)
    try:
        if (not schema_name or schema_text is None
                or schema_encoding not in SCHEMA_FOR_ENCODING[message_encoding]):
            return None
        if isinstance(schema_text, bytes):
            schema_text = schema_text.decode("utf-8", errors="replace")
        store, typename = build_typestore(schema_encoding, schema_name, schema_text)
        if layout_mismatch(schema_encoding, store, typename) is not None:
            return None
        return columnar_decoder(store, typename, message_encoding, fields)
    except Exception:  # noqa: BLE001 - whatever fails here fails again, reported, one by one
        return None
