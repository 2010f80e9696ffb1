"""MCAP in its other well-known encodings (json with JSON Schema, protobuf with a
FileDescriptorSet, cbor without schema), written here with the ``mcap`` writer from a shipped
CDR trace: the same message paths bind, and the json and protobuf copies audit exactly like
the CDR original. flatbuffer is refused by name; a payload that does not decode is an
``undecodable`` problem, never an internal error. The protobuf log a robotics framework
wrote with foxglove_bridge (``../shared/data/foreign_logs/basis_pb``) inspects."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings

pytest.importorskip("mcap_protobuf")
pytest.importorskip("cbor2")

from _encode import copy_as, json_strategies, same_value  # noqa: E402
from _shared import SHARED, needs_shared  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.logs import open_log  # noqa: E402
from fretc.logs.schema import log_schemas  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TRACE = ROOT / "traces" / "stop_delay.mcap"


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))


def _summary(la) -> list:
    """What must not change with the encoding: per requirement the verdict, the ticks, the
    first violation's trigger and miss ticks and times, the LTL3 verdict."""
    doc = la.to_json()
    out = []
    for v in doc["verdicts"]:
        fv = v.get("first_violation") or {}
        out.append((v["requirement"], v["verdict"], v.get("ticks_evaluated"),
                    json.dumps(fv.get("trigger"), sort_keys=True),
                    json.dumps(fv.get("at"), sort_keys=True),
                    json.dumps(v.get("ltl3"), sort_keys=True), v.get("violations")))
    return out


@pytest.mark.parametrize("encoding", ["json", "protobuf"])
def test_a_copy_in_another_encoding_audits_exactly_like_the_cdr_original(tmp_path, plan,
                                                                        encoding):
    copy = copy_as(TRACE, tmp_path / f"stop_delay_{encoding}.mcap", encoding)
    original = audit_log(plan, str(TRACE))
    la = audit_log(plan, str(copy))
    assert la.problems == [] and la.error is None
    assert _summary(la) == _summary(original)
    assert "violated" in [v.verdict for v in la.verdicts]


def test_cbor_messages_read_as_the_cdr_ones(tmp_path):
    copy = copy_as(TRACE, tmp_path / "stop_delay_cbor.mcap", "cbor")
    want = [(m.log_time, m.data.linear.x, m.data.angular.z)
            for m in open_log(TRACE).messages({"/cmd_vel_filtered"})]
    got = [(m.log_time, m.data.linear.x, m.data.angular.z)
           for m in open_log(copy).messages({"/cmd_vel_filtered"})]
    assert got == want and len(got) > 800
    scans = [m.data for m in open_log(copy).messages({"/scan"})]
    first = next(iter(open_log(TRACE).messages({"/scan"}))).data
    assert scans[0].ranges.dtype.kind == "f"
    assert scans[0].ranges.tolist() == first.ranges.tolist()


def test_json_schemas_give_field_types_for_the_binding_checks(tmp_path):
    copy = copy_as(TRACE, tmp_path / "j.mcap", "json")
    sch = log_schemas(open_log(copy))
    assert sch["/scan"].typename == "sensor_msgs/msg/LaserScan"
    assert dict(sch["/scan"].fields())["ranges"].kind == "array"
    assert dict(sch["/cmd_vel_filtered"].fields())["linear"].kind == "message"


def _one_channel_mcap(path: Path, encoding: str, schema_encoding: str, schema: bytes,
                      payloads: list[bytes]) -> Path:
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="", library="fretc tests")
        sid = w.register_schema("pkg.Thing", schema_encoding, schema) if schema_encoding else 0
        cid = w.register_channel("/v", encoding, sid)
        for i, p in enumerate(payloads):
            t = 1_700_000_000_000_000_000 + i * 100_000_000
            w.add_message(cid, log_time=t, publish_time=t, data=p, sequence=i)
        w.finish()
    return path


def test_flatbuffer_is_refused_by_name_and_a_bad_payload_is_undecodable(tmp_path):
    fb = _one_channel_mcap(tmp_path / "fb.mcap", "flatbuffer", "flatbuffer", b"\x00" * 8,
                           [b"\x00" * 16])
    src = open_log(fb)
    list(src.messages())
    probs = [p for p in src.problems if p.topic == "/v"]
    assert probs and probs[0].kind == "unknown_encoding"
    assert "flatbuffer" in probs[0].detail and "reflection" in probs[0].detail
    bad = _one_channel_mcap(tmp_path / "bad.mcap", "json", "", b"",
                            [b'{"data": 1.0}', b"{not json", b"[" * 100_000, b'{"data": 2.0}'])
    src = open_log(bad)
    got = [m.data.data for m in src.messages()]
    assert got == [1.0, 2.0]
    assert sum(n for (k, t), n in src.problem_counts.items() if k == "undecodable") == 2


@needs_shared
def test_the_basis_protobuf_log_inspects_with_the_log_levels_as_constants(tmp_path):
    log = SHARED / "data" / "foreign_logs" / "basis_pb" / "demo_81739.567984327.mcap"
    src = open_log(log)
    sch = log_schemas(src)
    assert sch["/log"].typename == "foxglove/msg/Log"
    assert sch["/log"].constants()["ERROR"] == 4
    levels = [m.data.level for m in src.messages({"/log"})]
    assert len(levels) == 40 and levels.count(4) == 1
    chatter = [m.data.message for m in src.messages({"/chatter"})]
    assert chatter and set(chatter) == {"Hello, world!"}


def _as_message_by_rule(value):
    """as_message's rule written out element by element (the reference for the test below):
    a list of bools -> bool array; of non-bool ints -> int64 (float64 past int64); of
    non-bool numbers -> float64; anything else -> a list; an int past int64 -> float (inf
    past the largest float)."""
    import numpy as np
    from types import SimpleNamespace

    if isinstance(value, dict):
        return SimpleNamespace(**{k: _as_message_by_rule(v) for k, v in value.items()})
    if isinstance(value, list):
        if value and all(isinstance(x, bool) for x in value):
            return np.array(value, dtype=bool)
        if value and all(isinstance(x, int) and not isinstance(x, bool) for x in value):
            try:
                return np.array(value, dtype=np.int64)
            except OverflowError:
                return np.array([_float(x) for x in value], dtype=np.float64)
        if value and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                         for x in value):
            return np.array([_float(x) for x in value], dtype=np.float64)
        return [_as_message_by_rule(x) for x in value]
    if type(value) is int and not -2**63 <= value < 2**63:  # past int64: the float
        return _float(value)
    return value


def _float(x):
    if isinstance(x, float) or abs(x) < 2**1024 - 2**970:  # (rounds below the largest)
        return float(x)
    return float("inf") if x > 0 else float("-inf")


_same = same_value


def test_json_values_become_the_arrays_and_objects_of_the_rule():
    from hypothesis import given, settings, strategies as st
    from fretc.logs.mcap.encodings import as_message

    scalars = st.one_of(st.booleans(), st.integers(min_value=-2**70, max_value=2**70), st.integers(min_value=10**300, max_value=10**400),
                        st.floats(allow_nan=True), st.text(max_size=3), st.none())
    values = st.recursive(scalars, lambda inner: st.one_of(
        st.lists(inner, max_size=6),
        st.dictionaries(st.sampled_from(["a", "b", "c"]), inner, max_size=3)), max_leaves=20)

    @settings(max_examples=300, deadline=None, derandomize=True)
    @given(values)
    def check(v):
        assert _same(as_message(v), _as_message_by_rule(v))

    check()


#: a JSON Schema as a non-ROS writer (a camera SDK) writes one: enum choices whose titles are
#: not in capitals, keywords no ROS type has
_CAMERA_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema", "title": "ImgFrame",
    "$comment": "written by a camera SDK", "type": "object", "additionalProperties": False,
    "properties": {
        "sequenceNumber": {"type": "integer", "minimum": 0, "examples": [1]},
        "iso": {"type": "number", "format": "float"},
        "kind": {"title": "kind", "description": "frame kind",
                 "oneOf": [{"title": "Video", "const": 0}, {"title": "Still", "const": 1},
                           {"title": "raw 8-bit", "const": 2}]},
        "meta": {"type": "object", "properties": {"exposureUs": {"type": "integer"}},
                 "required": ["exposureUs"], "patternProperties": {"^x-": {}}},
    },
}


def test_a_schema_from_any_writer_keeps_its_fields_and_named_constants(tmp_path):
    payloads = [json.dumps({"sequenceNumber": i, "iso": 100 + 400 * (i == 3),
                            "kind": 1 if i == 3 else 0, "meta": {"exposureUs": 5000}}).encode()
                for i in range(6)]
    log = _one_channel_mcap(tmp_path / "cam.mcap", "json", "jsonschema",
                            json.dumps(_CAMERA_SCHEMA).encode(), payloads)
    sch = log_schemas(open_log(log))["/v"]
    fields = dict(sch.fields())
    assert {"sequenceNumber", "iso", "kind", "meta"} <= set(fields)
    assert fields["meta"].kind == "message"
    assert sch.constants(sch.typename) == {"VIDEO": 0, "STILL": 1, "RAW_8_BIT": 2}
    (tmp_path / "r.fret").write_text("R1: the camera shall always satisfy is_video\n"
                                     "R2: the camera shall always satisfy low_iso\n")
    base = '[tick]\nperiod = "100 ms"\n[variables]\nlow_iso = "/v.iso < 300"\n'
    for written in ("Video", "VIDEO", "video"):  # the title as written, in any case
        (tmp_path / "r.bindings.toml").write_text(base + f'is_video = "/v.kind == {written}"\n')
        la = audit_log(load_plan(AuditConfig((str(tmp_path / "r.fret"),))), str(log))
        got = {v.requirement: v for v in la.verdicts}
        assert got["R1"].verdict == "violated", (written, got["R1"].error)
        assert got["R1"].first_violation.at.tick == 3 and got["R2"].verdict == "violated"
    # a misspelt field is an input error when the plan meets the log, naming the topic, the
    # field and the fields there are (not at the first tick)
    (tmp_path / "r.bindings.toml").write_text(base + 'is_video = "/v.exposre > 0"\n')
    la = audit_log(load_plan(AuditConfig((str(tmp_path / "r.fret"),))), str(log))
    err = {v.requirement: v for v in la.verdicts}["R1"].error
    assert "exposre" in err and "/v" in err and "sequenceNumber" in err, err
    assert "SimpleNamespace" not in err


def _reference_check(value, spec, where="", depth=0):
    """The JSON Schema type check, node by node and item by item (the rule the decoder's
    compiled check keeps): raises ValueError naming the first field of another type."""
    import json as _json

    from fretc.logs.mcap.json_values import _JSON_TYPES

    if not isinstance(spec, dict) or depth > 64:
        return
    t = spec.get("type")
    allowed = [t] if isinstance(t, str) else [x for x in t if isinstance(x, str)] \
        if isinstance(t, list) else []
    tests = [_JSON_TYPES[x] for x in allowed if x in _JSON_TYPES]
    if tests and not any(f(value) for f in tests):
        shown = _json.dumps(value)[:40] if not isinstance(value, (dict, list)) else \
            type(value).__name__
        raise ValueError(f"{where or 'the message'} is {shown}, but the schema says "
                         f"{' or '.join(allowed)}")
    if isinstance(value, dict):
        for name, sub in (spec.get("properties") or {}).items():
            if name in value:
                _reference_check(value[name], sub, f"{where}.{name}" if where else name,
                                 depth + 1)
    elif isinstance(value, list) and isinstance(spec.get("items"), dict):
        for i, item in enumerate(value):
            _reference_check(item, spec["items"], f"{where}[{i}]", depth + 1)


_values, _schemas = json_strategies()


@settings(max_examples=300, deadline=None)
@given(schema=_schemas, value=_values)
def test_the_json_type_check_compiled_once_is_the_rule(schema, value):
    """The check made once from the schema (arrays of scalars checked by the set of their
    items' types) accepts what the rule accepts and names the same field when it refuses."""
    import json as _json

    from fretc.logs.mcap.encodings import json_type_check

    check = json_type_check(_json.dumps(schema))
    try:
        _reference_check(value, schema)
        want = None
    except ValueError as exc:
        want = str(exc)
    if check is None:
        assert want is None
        return
    try:
        check(value)
        got = None
    except ValueError as exc:
        got = str(exc)
    assert got == want
