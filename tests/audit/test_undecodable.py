"""Messages present but not decoded are a gap of their topic: a schema that lies, a
payload that does not deserialize (bad CDR, a truncated body), an unknown message encoding.
Each ends the held value of its topic at its log time until the topic's next decoded message
(../shared/DESIGN.md "Damage is a gap"): the ticks between are unknown for the requirements
reading the topic, nothing is held over them, and every decoded message is still judged: a
value read that breaks a requirement violates it wherever it lies; one that holds on every
value read is unknown when a message was lost; requirements on other topics are unchanged,
and the problem counts messages and names topic, channel, first and last log time. The
audit's columnar pass and the message-by-message reference agree."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from mcap.writer import CompressionType, Writer

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.logs.mcap.source import McapSource

from _logs import ROS2, S

REQS = """\
R1: agent shall always satisfy v < 5
R2: agent shall always satisfy !(v >= 5)
R3: agent shall always satisfy w < 5
"""
BINDINGS = """\
[tick]
period = "100 ms"
time = "log"
[variables]
v = "/v.data"
w = "/w.data"
"""
F64 = "std_msgs/msg/Float64"


def _cdr(value: float) -> bytes:
    return bytes(ROS2.serialize_cdr(ROS2.types[F64](data=float(value)), F64))


#: the second channel's payload for each way a message can be present but not decoded
BAD = {
    "lie": (b"float32 data", "cdr", lambda v: b"\x00\x01\x00\x00" + struct.pack("<f", v)),
    "bad_cdr": (b"float64 data", "cdr", lambda v: b"\x00\x01\x00\x00\x01"),
    "truncated_body": (b"float64 data", "cdr", lambda v: _cdr(v)[:7]),
    # an encoding fretc does not read (json is read: a FlatBuffers table of 9.0 here)
    "encoding": (b"float64 data", "flatbuffer", lambda v: b"\x08\x00\x00\x00" + struct.pack("<d", v)),
}
KIND = {"lie": "unknown_schema", "bad_cdr": "undecodable", "truncated_body": "undecodable",
        "encoding": "unknown_encoding"}


def _write(path: Path, v_values: list[tuple[int, float | None]], how: str = "lie",
           w_values: list[tuple[int, float]] | None = None) -> Path:
    """/v: (log time, value) on a good channel, value None: a message on the bad channel
    (:data:`BAD`); /w: good messages only."""
    text, enc, payload = BAD[how]
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=512)
        w.start(profile="ros2", library="fretc-tests")
        good = w.register_schema(F64, "ros2msg", b"float64 data")
        bad_schema = w.register_schema(F64, "ros2msg", text)
        c_good = w.register_channel("/v", "cdr", good)
        c_bad = w.register_channel("/v", enc, bad_schema)
        c_w = w.register_channel("/w", "cdr", good)
        rows = [(t, c_good if x is not None else c_bad,
                 _cdr(x) if x is not None else payload(9.0)) for t, x in v_values]
        rows += [(t, c_w, _cdr(x)) for t, x in (w_values or [])]
        for i, (t, ch, raw) in enumerate(sorted(rows, key=lambda r: (r[0], r[1]))):
            w.add_message(ch, log_time=t, data=raw, publish_time=t, sequence=i)
        w.finish()
    return path


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    (d / "v.fret").write_text(REQS)
    (d / "v.bindings.toml").write_text(BINDINGS)
    return load_plan(AuditConfig((str(d / "v.fret"),), (str(d / "v.bindings.toml"),)))


def _issue_log(path: Path, how: str) -> Path:
    """The log of the report: 10 messages of 1.0 on /v, then 10 on the bad channel (9.0);
    /w every 100 ms throughout."""
    v = [(S + i * S // 10, 1.0) for i in range(10)] + [(2 * S + i * S // 10, None)
                                                        for i in range(10)]
    w = [(S + i * S // 10, 2.0) for i in range(20)]
    return _write(path, v, how, w)


def _verdicts(la) -> dict[str, tuple]:
    return {v.requirement: (v.verdict, v.unknown_reason, v.ticks_evaluated) for v in la.verdicts}


@pytest.mark.parametrize("how", sorted(BAD))
def test_no_requirement_reading_the_topic_is_satisfied_past_the_gap(plan, tmp_path, how):
    la = audit_log(plan, str(_issue_log(tmp_path / f"{how}.mcap", how)))
    got = {v.requirement: v for v in la.verdicts}
    for rid in ("R1", "R2"):  # two spellings of one requirement: one verdict
        assert got[rid].verdict == "unknown", (rid, got[rid].verdict)
        assert "10 messages of /v on channel 2 not decoded" in got[rid].unknown_reason
        assert KIND[how] in got[rid].unknown_reason
        assert got[rid].last_tick_ns < 2 * S  # the ticks before the first lost message
    kind = KIND[how]
    assert la.problem_counts[f"{kind} /v"] == 10  # messages, not channels
    p = next(p for p in la.problems if p["kind"] == kind)
    assert (p["topic"], p["log_time_ns"], p["end_time_ns"]) == ("/v", 2 * S, 2 * S + 9 * S // 10)
    assert "on channel 2" in p["detail"]
    # the requirement on /w alone reads nothing that was lost: as on the log without /v's
    # bad channel
    clean = audit_log(plan, str(_write(tmp_path / "clean.mcap",
                                       [(S + i * S // 10, 1.0) for i in range(10)], how,
                                       [(S + i * S // 10, 2.0) for i in range(20)])))
    assert _verdicts(la)["R3"] == _verdicts(clean)["R3"] == ("satisfied", None, 20)


@pytest.mark.parametrize("how", ["lie", "bad_cdr"])
def test_a_violation_decided_before_the_gap_stands(plan, tmp_path, how):
    v = [(S, 1.0), (S + S // 10, 7.0), (S + 2 * S // 10, 1.0), (S + 3 * S // 10, None),
         (S + 4 * S // 10, 1.0)]
    la = audit_log(plan, str(_write(tmp_path / "v.mcap", v, how)))
    got = {v.requirement: v.verdict for v in la.verdicts}
    assert got["R1"] == got["R2"] == "violated"


def test_a_topic_lost_before_its_first_tick_is_unknown(plan, tmp_path):
    v = [(S, None), (S + S // 10, 1.0), (S + 2 * S // 10, 1.0)]
    la = audit_log(plan, str(_write(tmp_path / "v.mcap", v, "bad_cdr",
                                    [(S + i * S // 10, 2.0) for i in range(3)])))
    got = {v.requirement: v for v in la.verdicts}
    assert got["R1"].verdict == "unknown"
    assert "1 message of /v on channel 2 not decoded" in got["R1"].unknown_reason
    assert got["R1"].unknown_ticks == 1  # the start of the run, before the first tick


def _both_paths(plan, path: Path, monkeypatch) -> tuple[dict, dict]:
    fast = audit_log(plan, str(path)).to_json()
    with monkeypatch.context() as m:  # the message-by-message reference
        m.setattr(McapSource, "message_blocks", lambda self, topics: None)
        ref = audit_log(plan, str(path)).to_json()
    return fast, ref


@pytest.mark.parametrize("how", sorted(BAD))
def test_the_columnar_pass_and_the_reference_agree(plan, tmp_path, how, monkeypatch):
    fast, ref = _both_paths(plan, _issue_log(tmp_path / "v.mcap", how), monkeypatch)
    assert fast == ref


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(values=st.lists(st.one_of(st.none(), st.sampled_from([1.0, 2.0, 7.0])), min_size=1,
                       max_size=30),
       how=st.sampled_from(sorted(BAD)))
def test_verdicts_read_only_what_was_decoded(plan, tmp_path_factory, monkeypatch, values, how):
    """On any mix of decoded and lost /v messages: satisfied only when nothing of /v was
    lost; violated exactly when a value >= 5 was decoded (each decoded message is held at
    its own tick, which no earlier loss makes unknown); the columnar pass equals the
    reference."""
    path = _write(tmp_path_factory.mktemp("h") / "v.mcap",
                  [(S + i * S // 10, x) for i, x in enumerate(values)], how,
                  [(S + i * S // 10, 2.0) for i in range(len(values))])
    fast, ref = _both_paths(plan, path, monkeypatch)
    assert fast == ref
    got = {v["requirement"]: v["verdict"] for v in fast["verdicts"]}
    for rid in ("R1", "R2"):
        if any(x is not None and x >= 5 for x in values):
            assert got[rid] == "violated"
        elif None in values:
            assert got[rid] in ("unknown", "error")
        else:
            assert got[rid] == "satisfied"
