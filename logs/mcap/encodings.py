"""MCAP's message encodings beside ROS's (MCAP specification, "Well-known encodings"):
``json`` (schema encoding ``jsonschema``, or none), ``protobuf`` (schema encoding
``protobuf``: a binary ``FileDescriptorSet``) and ``cbor`` (no schema). ``flatbuffer`` is
refused by name: no maintained Python library reads FlatBuffers by reflection from a
``.bfbs`` schema.

Design notes: ARCHITECTURE.md, `logs/mcap/encodings.py`."""

from __future__ import annotations

import re

import base64
import json
from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import numpy as np

from fretc.logs.field_select import field_tree, json_picker, protobuf_picker
from fretc.logs.mcap.json_values import as_message, checked_picker, type_check

__all__ = ["SELF_DESCRIBING", "UNSUPPORTED_ENCODINGS", "other_decoder", "definition",
           "type_name"]

#: message encodings read here, with the schema encodings each takes ("" none)
SELF_DESCRIBING = {"json": ("jsonschema", ""), "protobuf": ("protobuf",), "cbor": ("",)}
#: message encodings named in MCAP's registry that are refused, with the reason
UNSUPPORTED_ENCODINGS = {
    "flatbuffer": "no maintained Python library reads FlatBuffers by reflection from a "
                  ".bfbs schema"}


class EncodingError(ValueError):
    """A schema of a self-describing encoding that cannot be used (the message says why)."""


def _as_bytes(data: bytes | str) -> bytes:
    """Schema data as bytes: MCAP gives bytes; the Foxglove WebSocket protocol base64-encodes
    binary schemas (``protobuf``) in its JSON ``advertise``."""
    if isinstance(data, bytes):
        return data
    try:
        return base64.b64decode(data, validate=True)
    except ValueError:
        return data.encode("utf-8", "surrogatepass")


def other_decoder(message_encoding: str, schema_encoding: str, schema_name: str,
                  schema_data: bytes | str | None, fields: Any = None
                  ) -> Callable[[bytes], Any]:
    """A function ``bytes -> message object`` for a channel of a self-describing encoding.
    With ``fields`` (the field paths the bindings read, :mod:`fretc.logs.ros.selective`), a
    ``json`` or ``protobuf`` message object holds only those fields, and only their types
    are checked (:mod:`fretc.logs.field_select`); None: every field.

    Raises:
        EncodingError: a protobuf channel whose schema is missing, is no FileDescriptorSet
            or does not define ``schema_name``; a schema encoding that does not go with the
            message encoding.
    """
    if (schema_encoding or "") not in SELF_DESCRIBING[message_encoding]:
        raise EncodingError(f"schema encoding {schema_encoding!r} does not go with message "
                            f"encoding {message_encoding!r}")
    typ = type_name(schema_name) if schema_name else None
    tree = field_tree(fields) if message_encoding != "cbor" else None
    loads: Callable[[bytes], Any]
    if message_encoding == "json":
        loads = json.loads
    elif message_encoding == "cbor":
        import cbor2  # lazy: only for cbor channels

        loads = cbor2.loads
    else:
        if tree is not None:  # (the fields read: one function a message, no wrapper each)
            return _protobuf_selected(schema_name, _as_bytes(schema_data or b""), tree, typ,
                                      message_encoding)
        pb = _protobuf_decoder(schema_name, _as_bytes(schema_data or b""), tree)
        return _checked(lambda raw: _typed(pb(raw), typ), message_encoding)
    doc = (_json_schema(schema_data) if message_encoding == "json"
           and schema_encoding == "jsonschema" and schema_data else None)
    if tree is not None:  # the fields read, checked and converted in one walk
        pick = checked_picker(doc, tree) if doc is not None else json_picker(tree, as_message)
        return _checked(lambda raw: _typed(pick(loads(raw)), typ), message_encoding)
    check = type_check(doc) if doc is not None else None
    if check is not None:
        return _checked(lambda raw: _typed(as_message(check(loads(raw))), typ),
                        message_encoding)
    return _checked(lambda raw: _typed(as_message(loads(raw)), typ), message_encoding)


def json_type_check(schema_data: bytes | str) -> Callable[[Any], Any] | None:
    """:func:`fretc.logs.mcap.json_values.type_check` of a channel's JSON Schema (bytes or text);
    None when the schema cannot be read or declares nothing to check."""
    doc = _json_schema(schema_data)
    return None if doc is None else type_check(doc)


def _json_schema(schema_data: bytes | str) -> dict | None:
    """A channel's JSON Schema document, or None when it is no JSON object."""
    try:
        doc = json.loads(schema_data if isinstance(schema_data, str) else
                         _as_bytes(schema_data))
    except (ValueError, RecursionError):
        return None
    return doc if isinstance(doc, dict) else None


def _checked(decode: Callable[[bytes], Any], encoding: str) -> Callable[[bytes], Any]:
    """``decode`` raising ValueError (one of :data:`fretc.logs.decoding.DECODE_ERRORS`) for any
    payload it cannot decode: the libraries raise their own errors (protobuf's
    ``DecodeError``, cbor2's, a RecursionError on deep nesting)."""
    def checked(raw: bytes) -> Any:
        try:
            return decode(raw)
        except (RecursionError, Exception) as exc:  # noqa: BLE001 - each library its own
            raise ValueError(f"not a {encoding} message ({type(exc).__name__}: "
                             f"{str(exc)[:200]})") from None
    return checked


def _typed(msg: Any, typ: str | None) -> Any:
    """``msg`` with its message type as rosbags objects carry it (``__msgtype__``)."""
    if typ is not None and isinstance(msg, SimpleNamespace):
        msg.__msgtype__ = typ
    return msg


# --------------------------------------------------------------------------- protobuf
_PB_DTYPES = {1: np.float64, 2: np.float32, 3: np.int64, 4: np.uint64, 5: np.int32,
              6: np.uint64, 7: np.uint32, 8: bool, 13: np.uint32, 14: np.int32,
              15: np.int32, 16: np.int64, 17: np.int32, 18: np.int64}
_PB_ROS = {1: "float64", 2: "float32", 3: "int64", 4: "uint64", 5: "int32", 6: "uint64",
           7: "uint32", 8: "bool", 9: "string", 12: "uint8[]", 13: "uint32", 14: "int32",
           15: "int32", 16: "int64", 17: "int32", 18: "int64"}
_MESSAGE, _ENUM, _BYTES = 11, 14, 12


def _protobuf_decoder(name: str, fds: bytes, tree: dict | None = None
                      ) -> Callable[[bytes], Any]:
    make = _protobuf_make(name, fds)
    if tree is None:
        return lambda raw: _pb_message(make(raw))
    picks: dict[Any, Callable[[Any], SimpleNamespace]] = {}

    def selected(raw: bytes) -> SimpleNamespace:
        msg = make(raw)
        pick = picks.get(msg.DESCRIPTOR)
        if pick is None:
            pick = picks[msg.DESCRIPTOR] = protobuf_picker(msg.DESCRIPTOR, tree, pb_value,
                                                           _pb_plan, _pb_lies)
        return pick(msg)
    return selected


def _protobuf_make(name: str, fds: bytes) -> Callable[[bytes], Any]:
    """mcap-protobuf-support's decoder of ``name`` in the FileDescriptorSet ``fds``
    (payload -> parsed protobuf message).

    Raises:
        EncodingError: no schema, one protobuf cannot read, or one without ``name``."""
    from mcap.records import Schema
    from mcap_protobuf.decoder import DecoderFactory

    if not fds:
        raise EncodingError("the protobuf channel has no schema (a FileDescriptorSet)")
    try:
        make = DecoderFactory().decoder_for("protobuf", Schema(id=1, name=name,
                                                               encoding="protobuf", data=fds))
    except Exception as exc:  # protobuf raises its own errors on a bad descriptor set
        raise EncodingError(f"the protobuf schema of {name!r} cannot be read "
                            f"({type(exc).__name__}: {exc})") from None
    if make is None:
        raise EncodingError(f"the protobuf schema does not define {name!r}")
    return make


def _protobuf_selected(name: str, fds: bytes, tree: dict, typ: str | None, encoding: str
                       ) -> Callable[[bytes], Any]:
    """A decoder of ``name``'s protobuf messages to objects holding the fields of ``tree``
    (:func:`fretc.logs.field_select.protobuf_picker`), with the message type ``typ``: what
    :func:`_checked` of :func:`_protobuf_decoder`'s gives, in one function a message (the
    message class parsed from the payload and picked, without the decoder, checker and
    typing wrappers around it: four Python calls a message fewer).

    Raises:
        EncodingError: the schema cannot be read or does not define ``name``."""
    make = _protobuf_make(name, fds)  # (its message class: the type of what it makes)
    try:
        cls = type(make(b""))
    except Exception as exc:  # noqa: BLE001 - a class protobuf will not make: its error
        raise EncodingError(f"the protobuf schema of {name!r} cannot be read "
                            f"({type(exc).__name__}: {exc})") from None
    pick = protobuf_picker(cls.DESCRIPTOR, tree, pb_value, _pb_plan, _pb_lies)

    def decode(raw: bytes) -> Any:
        try:
            msg = cls()
            msg.ParseFromString(raw)
            out = pick(msg)
        except (RecursionError, Exception) as exc:  # noqa: BLE001 - protobuf's own errors
            raise ValueError(f"not a {encoding} message ({type(exc).__name__}: "
                             f"{str(exc)[:200]})") from None
        if typ is not None:
            out.__msgtype__ = typ
        return out
    return decode


def _repeated(field) -> bool:
    """A repeated protobuf field (``is_repeated`` in protobuf >= 5.29, ``label`` before)."""
    flag = getattr(field, "is_repeated", None)
    return bool(flag) if flag is not None else field.label == field.LABEL_REPEATED


def _pb_plan(descriptor) -> list[tuple[str, int, Any]]:
    """(field name, how to convert it, numpy dtype) per field of a protobuf message type:
    0 as it is, 1 a message, 2 repeated messages, 3 bytes, 4 repeated bytes, 5 a repeated
    number or bool (an array), 6 another repeated value (a list). Made once per type."""
    plan = _PB_PLANS.get(descriptor)
    if plan is None:
        plan = []
        for f in descriptor.fields:
            rep = _repeated(f)
            if f.type == _MESSAGE:
                how = 2 if rep else 1
            elif f.type == _BYTES:
                how = 4 if rep else 3
            elif rep:
                how = 5 if f.type in _PB_DTYPES else 6
            else:
                how = 0
            plan.append((f.name, how, _PB_DTYPES.get(f.type)))
        _PB_PLANS[descriptor] = plan
    return plan


_PB_PLANS: dict[Any, list[tuple[str, int, Any]]] = {}
_UNKNOWN: Any = None  # protobuf's UnknownFieldSet, once a protobuf message is checked


def _pb_lies(msg, numbers: frozenset[int] | None = None) -> None:
    """Raise ``ValueError`` when the payload holds a field the schema declares with another
    wire type (a float field over varint bytes, say): protobuf keeps such a field as an
    unknown field and leaves the declared one at its default, 0, which would be read as a
    value (protobuf encoding, "Message Structure": wire types). Unknown field numbers are
    newer fields, not lies. ``numbers``: only those fields are checked (None: all)."""
    global _UNKNOWN
    if _UNKNOWN is None:  # (imported once: this runs for every message and nested message)
        from google.protobuf.unknown_fields import UnknownFieldSet as _UNKNOWN
    unknown = _UNKNOWN(msg)
    if not len(unknown):
        return
    declared = msg.DESCRIPTOR.fields_by_number
    for f in unknown:  # (a sequence: len, [i])
        if f.field_number in declared and (numbers is None or f.field_number in numbers):
            field = declared[f.field_number]
            raise ValueError(f"field {field.name} (number {f.field_number}) is declared "
                             f"{_PB_ROS.get(field.type, 'of another type')} but the payload "
                             f"has wire type {f.wire_type} there: the schema does not "
                             "describe these bytes")


def _pb_message(msg) -> SimpleNamespace:
    """A decoded protobuf message as a message object: nested messages as objects, repeated
    numbers as numpy arrays of the field's type, bytes as uint8 arrays (module docstring).
    Raises ``ValueError`` for a payload the schema does not describe (:func:`_pb_lies`)."""
    _pb_lies(msg)
    out = SimpleNamespace()
    d = out.__dict__
    for name, how, dtype in _pb_plan(msg.DESCRIPTOR):
        d[name] = pb_value(getattr(msg, name), how, dtype)
    return out


def pb_value(value: Any, how: int, dtype: Any) -> Any:
    """One field's value of a parsed protobuf message converted by its plan (:func:`_pb_plan`:
    ``how``, numpy ``dtype``)."""
    if how == 0:
        return value
    if how == 5:
        return np.array(value, dtype=dtype)
    if how == 1:
        return _pb_message(value)
    if how == 2:
        return [_pb_message(x) for x in value]
    if how == 3:
        return np.frombuffer(value, dtype=np.uint8)
    if how == 4:
        return [np.frombuffer(x, dtype=np.uint8) for x in value]
    return list(value)


def type_name(name: str) -> str:
    """A ROS-style type name for a protobuf or JSON Schema type name: ``foxglove.Log`` ->
    ``foxglove/msg/Log``; a ROS name stays ROS's (``sensor_msgs/msg/LaserScan``, so the
    ROS type rules, such as REP 117 for LaserScan ranges, apply on every encoding); a name
    without a package goes to the package ``schema``."""
    if "/" in name:
        from rosbags.typesys.msg import normalize_msgtype

        try:
            return normalize_msgtype(name)
        except Exception:  # noqa: BLE001 - not a ROS name after all: made one below
            pass
    parts = [p for p in name.replace("/", ".").split(".") if p]
    if not parts:
        return "schema/msg/Message"
    if len(parts) > 2 and parts[-2] == "msg":  # pkg.msg.Type: a ROS type in protobuf's naming
        parts = parts[:-3] + [parts[-3], parts[-1]]
    base = "".join(c if c.isalnum() or c == "_" else "_" for c in parts[-1]) or "Message"
    pkg = "_".join(parts[:-1]).lower() if len(parts) > 1 else "schema"
    pkg = "".join(c if c.isalnum() or c == "_" else "_" for c in pkg)
    return f"{pkg}/msg/{base}"


def definition(message_encoding: str, schema_encoding: str, schema_name: str,
               schema_data: bytes | str | None) -> tuple[str, str] | None:
    """(ROS type name, ROS 2 message definition text with ``MSG:`` sections) of a channel's
    schema; None when it has none (``cbor``, schemaless ``json``) or it cannot be read."""
    try:
        if message_encoding == "protobuf":
            return _pb_definition(schema_name, _as_bytes(schema_data or b""))
        if message_encoding == "json" and schema_encoding == "jsonschema" and schema_data:
            doc = json.loads(_as_bytes(schema_data) if not isinstance(schema_data, str)
                             else schema_data)
            return _json_definition(schema_name, doc)
    except Exception:  # noqa: BLE001 - no definition: the topic's fields are not checked
        return None
    return None


def _sections(top: str, parts: list[tuple[str, str]]) -> str:
    return top + "".join("=" * 80 + f"\nMSG: {n}\n{body}" for n, body in parts)


def _pb_definition(name: str, fds: bytes) -> tuple[str, str] | None:
    from google.protobuf import descriptor_pb2, descriptor_pool

    files = descriptor_pb2.FileDescriptorSet.FromString(fds)
    pool = descriptor_pool.DescriptorPool()
    for fd in files.file:
        pool.Add(fd)
    top = pool.FindMessageTypeByName(name)
    parts: list[tuple[str, str]] = []
    seen: set[str] = {top.full_name}

    def fields(desc) -> str:
        lines: list[str] = []
        consts: dict[str, str] = {}
        for f in desc.fields:
            repeated = _repeated(f)
            if f.type == _MESSAGE:
                sub = f.message_type
                ros = type_name(sub.full_name)
                if sub.full_name not in seen:
                    seen.add(sub.full_name)
                    parts.append((ros, fields(sub)))
            elif f.type == _ENUM:
                ros = "int32"
                for v in f.enum_type.values:
                    consts.setdefault(v.name, v.number)
            else:
                ros = _PB_ROS.get(f.type, "string")
            if repeated and not ros.endswith("[]"):
                ros += "[]"
            lines.append(f"{ros} {f.name}")
        head = [f"int32 {k}={v}" for k, v in consts.items()
                if k not in {f.name for f in desc.fields}]
        return "\n".join(head + lines) + "\n"

    return type_name(top.full_name), _sections(fields(top), parts)


_JSON_ROS = {"number": "float64", "integer": "int64", "boolean": "bool", "string": "string"}
_NOT_NAME = re.compile(r"[^A-Z0-9_]+")


def constant_name(title: str) -> str | None:
    """A JSON Schema enum choice's ``title`` as a constant of the ROS definition built for
    it: upper case, other characters as ``_`` (ROS constants are ``[A-Z][A-Z0-9_]*``;
    ``"Video"`` is ``VIDEO``); a binding names it as the schema writes it, in any case
    (:mod:`fretc.signals.bindings.typecheck`). None when nothing of it is a name."""
    name = _NOT_NAME.sub("_", title.strip().upper()).strip("_")
    return name if name and name[0].isalpha() else None


def _json_definition(name: str, doc: dict) -> tuple[str, str]:
    parts: list[tuple[str, str]] = []
    root = type_name(name)

    def kind(spec: dict) -> str | None:
        t = spec.get("type")
        if isinstance(t, list):
            t = next((x for x in t if x != "null"), None)
        return t

    def fields(spec: dict, prefix: str) -> str:
        lines: list[str] = []
        consts: dict[str, str] = {}
        for field, sub in (spec.get("properties") or {}).items():
            if not isinstance(sub, dict) or not field.isidentifier():
                continue
            ros = field_type(sub, f"{prefix}_{field}")
            if ros is None:
                continue
            for choice in sub.get("oneOf") or sub.get("anyOf") or ():
                if isinstance(choice, dict) and "const" in choice:
                    const = constant_name(str(choice.get("title", "")))
                    if const:
                        consts.setdefault(const, choice["const"])
            lines.append(f"{ros} {field}")
        head = [f"int64 {k}={v}" for k, v in consts.items() if isinstance(v, int)]
        return "\n".join(head + lines) + "\n"

    def field_type(sub: dict, nested: str) -> str | None:
        t = kind(sub)
        if t == "object":
            typ = type_name(nested)
            parts.append((typ, fields(sub, nested)))
            return typ
        if t == "array":
            items = sub.get("items")
            item = items if isinstance(items, dict) else {}
            inner = field_type(item, nested)
            return None if inner is None or inner.endswith("[]") else inner + "[]"
        if t is None and sub.get("oneOf"):
            return "int64"
        return None if t is None else _JSON_ROS.get(t)

    return root, _sections(fields(doc, root.split("/")[-1]), parts)
