"""A schema that does not describe its payloads: the values are undecodable messages, never
defaults or coercions read as values. A protobuf payload that holds a declared field with
another wire type (a float field over varint bytes) left the field at 0; a JSON ``true``
where the JSON Schema says number was read as 1.0. Both were audited as values (satisfied,
exit 0)."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import pytest

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.logs import open_log

T0 = 1_700_000_000_000_000_000


def _mcap(path: Path, encoding: str, schema_encoding: str, schema: bytes,
          payloads: list[bytes]) -> Path:
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="", library="fretc tests")
        sid = w.register_schema("pkg.Thing", schema_encoding, schema)
        cid = w.register_channel("/v", encoding, sid)
        for i, p in enumerate(payloads):
            t = T0 + i * 100_000_000
            w.add_message(cid, log_time=t, publish_time=t, data=p, sequence=i)
        w.finish()
    return path


def _pb_schema() -> bytes:
    from google.protobuf import descriptor_pb2

    fds = descriptor_pb2.FileDescriptorSet()
    f = fds.file.add(name="thing.proto", package="pkg", syntax="proto3")
    m = f.message_type.add(name="Thing")
    m.field.add(name="speed", number=1, type=descriptor_pb2.FieldDescriptorProto.TYPE_FLOAT,
                label=descriptor_pb2.FieldDescriptorProto.LABEL_OPTIONAL)
    return fds.SerializeToString()


def _audit(tmp_path: Path, log: Path):
    (tmp_path / "r.fret").write_text("R: the robot shall always satisfy slow\n",
                                     encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(
        '[tick]\ntopic = "/v"\n[variables]\nslow = "/v.speed < 5"\n', encoding="utf-8")
    return audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),))),
                     str(log))


def _speeds(log: Path) -> tuple[list, int]:
    src = open_log(log)
    got = [float(m.data.speed) for m in src.messages()]
    bad = sum(n for (k, _t), n in src.problem_counts.items() if k == "undecodable")
    return got, bad


def test_a_protobuf_payload_the_schema_does_not_describe_is_undecodable(tmp_path):
    good = b"\x0d" + struct.pack("<f", 2.0)  # field 1, wire type 5 (fixed32): a float
    lie = b"\x08\x07"  # field 1 as a varint (wire type 0): protobuf keeps it unknown, speed 0
    newer = good + b"\x10\x01"  # field 2, not declared: a newer field, not a lie
    log = _mcap(tmp_path / "pb.mcap", "protobuf", "protobuf", _pb_schema(),
                [good, lie, newer, lie])
    got, bad = _speeds(log)
    assert got == [2.0, 2.0] and bad == 2
    src = open_log(log)
    list(src.messages())
    detail = next(p.detail for p in src.problems if p.kind == "undecodable")
    assert "speed" in detail and "wire type 0" in detail
    (v,) = _audit(tmp_path, _mcap(tmp_path / "lies.mcap", "protobuf", "protobuf",
                                  _pb_schema(), [lie] * 5)).verdicts
    assert v.verdict != "satisfied"


@pytest.mark.parametrize("value,ok", [("true", False), ('"3"', False), ("null", False),
                                      ("3", True), ("3.5", True), ("1e3", True)])
def test_a_json_value_of_another_type_than_the_schema_says_is_undecodable(tmp_path, value, ok):
    schema = json.dumps({"type": "object", "properties": {"speed": {"type": "number"}}})
    log = _mcap(tmp_path / "j.mcap", "json", "jsonschema", schema.encode(),
                [b'{"speed": 1.0}', f'{{"speed": {value}}}'.encode()])
    got, bad = _speeds(log)
    assert (len(got), bad) == ((2, 0) if ok else (1, 1))


def test_json_true_where_a_number_is_declared_is_not_read_as_one(tmp_path):
    schema = json.dumps({"type": "object", "properties": {"speed": {"type": "number"}}})
    log = _mcap(tmp_path / "t.mcap", "json", "jsonschema", schema.encode(),
                [b'{"speed": true}'] * 5)
    (v,) = _audit(tmp_path, log).verdicts
    assert v.verdict != "satisfied"


def test_a_401_digit_integer_in_json_is_read_or_refused_never_a_traceback(tmp_path):
    schema = json.dumps({"type": "object", "properties": {"speed": {"type": "number"}}})
    big = "9" * 401
    log = _mcap(tmp_path / "b.mcap", "json", "jsonschema", schema.encode(),
                [b'{"speed": 1.0}', f'{{"speed": {big}}}'.encode(), b'{"speed": 2.0}'])
    la = _audit(tmp_path, log)
    (v,) = la.verdicts
    # past the largest float it is read as inf, which the bindings read as no value
    # (docs/guide/bindings.md, NaN and infinities): unknown at that tick, never satisfied
    assert v.verdict == "unknown" and "NaN" in v.unknown_reason
