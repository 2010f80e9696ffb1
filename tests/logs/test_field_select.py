"""json and protobuf messages decoded with the fields the bindings read
(:mod:`fretc.logs.field_select`) against the full decode: on json and protobuf copies of
the shipped logs and on generated JSON messages and schemas, each field read has the value
of the full decode, and a message the selective decode refuses is refused by the full one
(a type error in a field read is never let through; protobuf: a field read written with a
wire type its declaration does not have)."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest
from hypothesis import given, settings, strategies as st
from mcap.reader import make_reader

from _encode import copy_as, json_strategies, same_value
from fretc.logs.decoding import schema_decoder
from fretc.logs.field_select import field_tree
from fretc.logs.ros.selective import HEADER_STAMP

ROOT = Path(__file__).resolve().parents[2]
_MISSING = object()


def _at(msg, path):
    for name in path:
        if not isinstance(name, str):
            break
        msg = getattr(msg, name, _MISSING)
        if msg is _MISSING:
            return msg
    return msg


_same = same_value


def _leaf_paths(msg, prefix=()):
    """Every attribute path of a fully decoded message object (nested objects walked)."""
    out = []
    for name, value in vars(msg).items():
        if name.startswith("__"):
            continue
        if isinstance(value, SimpleNamespace):
            out += _leaf_paths(value, prefix + (name,))
        else:
            out.append(prefix + (name,))
    return out


#: messages of each topic compared (the first ones: every field set decodes each)
MESSAGES_PER_TOPIC = 150


@pytest.mark.parametrize("encoding", ["json", "protobuf"])
@pytest.mark.parametrize("log", ["stop_delay.mcap", "dynamic_obstacle.mcap"])
def test_the_fields_read_have_the_values_of_the_full_decode(tmp_path, encoding, log):
    if not (ROOT / "traces" / log).exists():
        pytest.skip(f"traces/{log} is absent")
    path = copy_as(ROOT / "traces" / log, tmp_path / f"{encoding}.mcap", encoding)
    decoders: dict = {}
    seen = 0
    per_topic: dict[str, int] = {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            key = channel.topic
            per_topic[key] = per_topic.get(key, 0) + 1
            if per_topic[key] > MESSAGES_PER_TOPIC:
                continue
            if key not in decoders:
                args = (channel.message_encoding, schema.encoding, schema.name, schema.data)
                full = schema_decoder(*args)
                paths = _leaf_paths(full(message.data))
                # one field at a time, pairs of nested fields, all together, header.stamp
                sets = [frozenset([p]) for p in paths] + [frozenset(paths),
                                                          frozenset([HEADER_STAMP]),
                                                          frozenset()]
                decoders[key] = (full, [(s, schema_decoder(*args, s)) for s in sets])
            full, selective = decoders[key]
            want = full(message.data)
            for paths, dec in selective:
                got = dec(message.data)
                assert got.__msgtype__ == want.__msgtype__
                tree = field_tree(paths)
                for p in paths:
                    p = ("header", "stamp") if p == HEADER_STAMP else p
                    assert _same(_at(got, p), _at(want, p)), (key, p)
                assert set(vars(got)) - {"__msgtype__"} <= set(tree)
            seen += 1
    assert seen > 100


def _restricted(value, tree):
    if tree is None or type(value) is not dict:
        return value
    return {k: _restricted(value[k], sub) for k, sub in tree.items() if k in value}


_values, _schemas = json_strategies(2**70)
_paths = st.frozensets(st.lists(st.sampled_from(["a", "b", "c"]), min_size=1, max_size=3)
                       .map(tuple), min_size=1, max_size=3)


@settings(max_examples=400, deadline=None)
@given(schema=_schemas, value=st.dictionaries(st.sampled_from(["a", "b", "c"]), _values,
                                              max_size=3), paths=_paths)
def test_generated_json_messages_read_selectively_as_in_full(schema, value, paths):
    schema = {**schema, "type": "object"}
    args = ("json", "jsonschema", "t.T", json.dumps(schema).encode())
    raw = json.dumps(value).encode()
    full, selective = schema_decoder(*args), schema_decoder(*args, paths)
    try:
        want = full(raw)
    except ValueError:
        want = None  # the full decode refuses: the selective one may accept (a field unread)
    tree = field_tree(paths)
    try:  # the full decode of the fields read alone: the selective one refuses exactly it,
        full(json.dumps(_restricted(value, tree)).encode())  # with the same message
        refused = None
    except ValueError as exc:
        refused = str(exc)
    try:
        got = selective(raw)
    except ValueError as exc:
        assert want is None and refused == str(exc), "refused selectively but not in full"
        return
    assert refused is None, "a type error in a field read let through"
    if want is not None:
        for p in paths:
            assert _same(_at(got, p), _at(want, p)), p


def _pb_thing():
    """A FileDescriptorSet of ``pkg.Thing`` (scalars, a packed array, bytes, a nested message
    and an array of them) and its message class."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    F = descriptor_pb2.FieldDescriptorProto
    fds = descriptor_pb2.FileDescriptorSet()
    f = fds.file.add(name="thing.proto", package="pkg", syntax="proto3")
    inner = f.message_type.add(name="Inner")
    inner.field.add(name="y", number=1, type=F.TYPE_INT32, label=F.LABEL_OPTIONAL)
    inner.field.add(name="z", number=2, type=F.TYPE_DOUBLE, label=F.LABEL_OPTIONAL)
    m = f.message_type.add(name="Thing")
    for name, number, typ, label, sub in [
            ("x", 1, F.TYPE_DOUBLE, F.LABEL_OPTIONAL, None),
            ("arr", 2, F.TYPE_FLOAT, F.LABEL_REPEATED, None),
            ("inner", 3, F.TYPE_MESSAGE, F.LABEL_OPTIONAL, ".pkg.Inner"),
            ("items", 4, F.TYPE_MESSAGE, F.LABEL_REPEATED, ".pkg.Inner"),
            ("blob", 5, F.TYPE_BYTES, F.LABEL_OPTIONAL, None),
            ("n", 6, F.TYPE_INT32, F.LABEL_OPTIONAL, None)]:
        field = m.field.add(name=name, number=number, type=typ, label=label)
        if sub:
            field.type_name = sub
    pool = descriptor_pool.DescriptorPool()
    pool.Add(f)
    return fds.SerializeToString(), message_factory.GetMessageClass(
        pool.FindMessageTypeByName("pkg.Thing"))


#: a field of pkg.Thing written with a wire type its declaration does not have
_PB_LIES = {"x": b"\x08\x07", "arr": b"\x10\x07", "inner": b"\x18\x07",
            "items": b"\x25\x00\x00\x80\x3f", "blob": b"\x28\x07",
            "n": b"\x31" + bytes(8)}
_PB_PATHS = [("x",), ("arr",), ("inner",), ("inner", "y"), ("inner", "z"), ("items",),
             ("items", 0, "y"), ("blob",), ("n",)]
_floats = st.floats(allow_nan=False, width=32)


@settings(max_examples=300, deadline=None)
@given(x=_floats, arr=st.lists(_floats, max_size=5), inner=st.none() | st.tuples(
       st.integers(-2**31, 2**31 - 1), _floats), items=st.lists(st.tuples(
       st.integers(-5, 5), _floats), max_size=3), blob=st.binary(max_size=4),
       n=st.integers(-2**31, 2**31 - 1), lie=st.none() | st.sampled_from(sorted(_PB_LIES)),
       paths=st.frozensets(st.sampled_from(_PB_PATHS), min_size=1, max_size=4))
def test_generated_protobuf_messages_read_selectively_as_in_full(x, arr, inner, items, blob,
                                                                 n, lie, paths):
    fds, Thing = _pb_thing()
    msg = Thing(x=x, arr=arr, blob=blob, n=n)
    if inner is not None:
        msg.inner.y, msg.inner.z = inner
    for y, z in items:
        msg.items.add(y=y, z=z)
    raw = msg.SerializeToString() + (_PB_LIES[lie] if lie else b"")
    args = ("protobuf", "protobuf", "pkg.Thing", fds)
    full, selective = schema_decoder(*args), schema_decoder(*args, paths)
    read = {p[0] for p in paths}
    try:
        got = selective(raw)
    except ValueError as exc:
        assert lie in read and lie in str(exc), (lie, read, exc)
        with pytest.raises(ValueError):
            full(raw)
        return
    assert lie not in read, "a wire-type lie in a field read let through"
    want = full(msg.SerializeToString())  # (a lie in a field not read changes no value read)
    for p in paths:
        assert _same(_at(got, p), _at(want, p)), p
    assert got.__msgtype__ == "pkg/msg/Thing"
