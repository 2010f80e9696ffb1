"""Copies of a ROS 2 (CDR) MCAP in MCAP's other encodings, written here with the ``mcap``
writer: ``json`` with a JSON Schema per type, ``protobuf`` with a ``FileDescriptorSet`` per
type (one ``.proto`` file per ROS package, ``pkg.msg.Type``), ``cbor`` without schema. The
ROS messages are read with rosbags' own typestore (Humble), not with fretc."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from mcap.reader import make_reader
from mcap.writer import Writer
from rosbags.typesys import Stores, get_typestore

_STORE = get_typestore(Stores.ROS2_HUMBLE)
_INTS = {"int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64", "byte",
         "char", "octet"}
_PB = {"float64": 1, "float32": 2, "int64": 3, "uint64": 4, "int32": 5, "int16": 5,
       "int8": 5, "uint32": 13, "uint16": 13, "uint8": 13, "byte": 13, "char": 13,
       "octet": 13, "bool": 8, "string": 9}


def _fields(typ: str):
    return _STORE.fielddefs[typ][1]


def to_dict(msg, typ: str) -> dict:
    """A rosbags message as plain JSON-able values."""
    out = {}
    for name, (node, sub) in _fields(typ):
        v = getattr(msg, name)
        if int(node) == 1:
            out[name] = v.item() if hasattr(v, "item") else v
        elif int(node) == 2:
            out[name] = to_dict(v, sub)
        else:
            item = sub[0]
            if int(item[0]) == 2:
                out[name] = [to_dict(x, item[1]) for x in v]
            else:
                out[name] = np.asarray(v).tolist() if not isinstance(v, list) else list(v)
    return out


def json_schema(typ: str) -> dict:
    """A JSON Schema of ROS type ``typ``."""
    def base(t: str) -> dict:
        if t in _INTS:
            return {"type": "integer"}
        if t in ("float32", "float64"):
            return {"type": "number"}
        if t == "bool":
            return {"type": "boolean"}
        return {"type": "string"}

    def spec(node, sub) -> dict:
        if int(node) == 1:
            return base(sub[0])
        if int(node) == 2:
            return json_schema(sub)
        return {"type": "array", "items": spec(*sub[0])}

    return {"type": "object", "title": typ,
            "properties": {n: spec(*d) for n, d in _fields(typ)}}


def _types_of(typ: str, out: dict) -> dict:
    if typ in out:
        return out
    out[typ] = True
    for _n, (node, sub) in _fields(typ):
        inner = sub if int(node) == 2 else (sub[0][1] if int(node) in (3, 4)
                                             and int(sub[0][0]) == 2 else None)
        if inner is not None:
            _types_of(inner, out)
    return out


def _pb_name(typ: str) -> str:
    return typ.replace("/", ".")


def descriptor_set(typ: str) -> bytes:
    """A FileDescriptorSet of ``typ`` and every type it uses, one file per ROS package."""
    from google.protobuf import descriptor_pb2

    by_pkg: dict[str, list[str]] = {}
    for t in _types_of(typ, {}):
        by_pkg.setdefault(t.rsplit("/", 1)[0], []).append(t)
    fds = descriptor_pb2.FileDescriptorSet()
    done: set[str] = set()

    def add(pkg: str) -> None:
        if pkg in done:
            return
        done.add(pkg)
        f = descriptor_pb2.FileDescriptorProto(name=f"{pkg}.proto", package=pkg.replace("/", "."),
                                               syntax="proto3")
        deps = set()
        for t in by_pkg[pkg]:
            m = f.message_type.add(name=t.rsplit("/", 1)[1])
            for k, (n, (node, sub)) in enumerate(_fields(t), start=1):
                fld = m.field.add(name=n, number=k)
                item = (node, sub) if int(node) in (1, 2) else sub[0]
                fld.label = 1 if int(node) in (1, 2) else 3
                if int(item[0]) == 2:
                    inner = item[1]
                    fld.type = 11
                    fld.type_name = "." + _pb_name(inner)
                    if inner.rsplit("/", 1)[0] != pkg:
                        deps.add(inner.rsplit("/", 1)[0])
                else:
                    fld.type = _PB[item[1][0]]
        for d in sorted(deps):
            add(d)
            f.dependency.append(f"{d}.proto")
        fds.file.append(f)

    add(typ.rsplit("/", 1)[0])
    return fds.SerializeToString()


def copy_as(src: Path, dst: Path, encoding: str) -> Path:
    """``src`` (CDR) copied with every message in ``encoding`` (json, protobuf or cbor), the
    same topics, log and publish times."""
    classes = {}
    with open(src, "rb") as f, open(dst, "wb") as out:
        reader = make_reader(f)
        summary = reader.get_summary()
        w = Writer(out)
        w.start(profile="", library="fretc tests")
        chans = {}
        for sc, ch, msg in reader.iter_messages():
            typ = sc.name
            if ch.id not in chans:
                if encoding == "json":
                    sid = w.register_schema(typ, "jsonschema",
                                            json.dumps(json_schema(typ)).encode())
                elif encoding == "protobuf":
                    sid = w.register_schema(_pb_name(typ), "protobuf", descriptor_set(typ))
                else:
                    sid = 0
                chans[ch.id] = w.register_channel(ch.topic, encoding, sid)
            doc = to_dict(_STORE.deserialize_cdr(msg.data, typ), typ)
            if encoding == "json":
                data = json.dumps(doc).encode()
            elif encoding == "cbor":
                import cbor2
                data = cbor2.dumps(doc)
            else:
                data = _pb_bytes(classes, typ, doc)
            w.add_message(chans[ch.id], log_time=msg.log_time, publish_time=msg.publish_time,
                          data=data, sequence=msg.sequence)
        w.finish()
    assert summary is not None
    return dst


def _pb_bytes(classes: dict, typ: str, doc: dict) -> bytes:
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    cls = classes.get(typ)
    if cls is None:
        pool = descriptor_pool.DescriptorPool()
        fds = descriptor_pb2.FileDescriptorSet.FromString(descriptor_set(typ))
        for fd in fds.file:
            pool.Add(fd)
        cls = classes[typ] = message_factory.GetMessageClass(
            pool.FindMessageTypeByName(_pb_name(typ)))
    msg = cls()
    _fill(msg, doc)
    return msg.SerializeToString()


def _fill(msg, doc: dict) -> None:
    """Set the fields of protobuf message ``msg`` from ``doc`` (json_format refuses inf)."""
    for f in msg.DESCRIPTOR.fields:
        v = doc[f.name]
        if f.type == 11:
            if isinstance(v, list):
                for x in v:
                    _fill(getattr(msg, f.name).add(), x)
            else:
                _fill(getattr(msg, f.name), v)
        elif isinstance(v, list):
            getattr(msg, f.name).extend(v)
        else:
            setattr(msg, f.name, v)


def same_value(a, b) -> bool:
    """Whether two decoded values are equal in type, dtype and value (NaN equal to NaN), down
    through lists and SimpleNamespace messages."""
    from types import SimpleNamespace

    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (type(a) is type(b) and a.dtype == b.dtype
                and np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    if isinstance(a, SimpleNamespace):
        return (isinstance(b, SimpleNamespace) and vars(a).keys() == vars(b).keys()
                and all(same_value(vars(a)[k], vars(b)[k]) for k in vars(a)))
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(same_value, a, b))
    return type(a) is type(b) and (a == b or a != a and b != b)


def json_strategies(*extra_scalars) -> tuple:
    """Hypothesis strategies (values, schemas): JSON values of small scalars (and
    ``extra_scalars``) in lists and objects of keys a, b, c, and JSON schemas of any types
    over arrays and objects of those keys."""
    from hypothesis import strategies as st

    types = ["number", "integer", "boolean", "string", "object", "array", "null"]
    scalars = st.one_of(st.integers(-5, 5), st.floats(allow_nan=False, width=32), st.booleans(),
                        st.text(max_size=3), st.none(), st.sampled_from([1.0, 2.5, *extra_scalars]))
    values = st.recursive(scalars, lambda c: st.one_of(
        st.lists(c, max_size=4), st.dictionaries(st.sampled_from(["a", "b", "c"]), c, max_size=3)),
        max_leaves=12)
    schemas = st.recursive(
        st.fixed_dictionaries({}, optional={"type": st.one_of(st.sampled_from(types), st.lists(
            st.sampled_from(types), max_size=2))}),
        lambda c: st.one_of(
            st.fixed_dictionaries({"type": st.just("array"), "items": c}),
            st.fixed_dictionaries({"type": st.just("object"), "properties": st.dictionaries(
                st.sampled_from(["a", "b", "c"]), c, max_size=3)})), max_leaves=8)
    return values, schemas
