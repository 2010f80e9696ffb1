"""The ``*_s`` times of a verdict count from the log's first message, whatever topics the
requirements read (audit-json reference: "seconds since the log's start"): a requirement
audited alone prints the seconds it prints in a set, on an indexed MCAP (its statistics
give the start) and on one without summary or index (the start found by the pass), where
an unbound topic publishes 10 s before the bound ones."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import IndexType, Writer

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.verdict import audit_json

from _logs import MS, S, float64, write_mcap

T0 = 1_700_000_000 * S


def _unindexed(src: Path, out: Path) -> Path:
    """``src`` rewritten without summary, index or statistics."""
    with open(src, "rb") as f, open(out, "wb") as o:
        w = Writer(o, index_types=IndexType.NONE, use_statistics=False,
                   use_summary_offsets=False, repeat_channels=False, repeat_schemas=False)
        w.start(profile="ros2", library="fretc-tests")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for s, c, m in make_reader(f).iter_messages(log_time_order=False):
            if s.id not in schemas:
                schemas[s.id] = w.register_schema(s.name, s.encoding, s.data)
            if c.id not in channels:
                channels[c.id] = w.register_channel(c.topic, c.message_encoding,
                                                    schemas[s.id], c.metadata)
            w.add_message(channels[c.id], m.log_time, m.data, m.publish_time, m.sequence)
        w.finish()
    return out


def _times(doc: dict, rid: str) -> dict:
    (log,) = doc["logs"]
    (v,) = [v for v in log["verdicts"] if v["requirement"] == rid]
    out = {k: x for k, x in (v.get("first_violation") or {}).items() if k.endswith("_s")}
    return {"start": log["start_time_ns"], **out}


@pytest.mark.parametrize("indexed", [True, False])
def test_seconds_alone_equal_seconds_in_a_set(tmp_path, indexed):
    msgs = [("/early", "std_msgs/msg/Float64", T0 - 10 * S, float64(1.0))]
    msgs += [("/x", "std_msgs/msg/Float64", T0 + k * 100 * MS, float64(k / 10))
             for k in range(60)]
    log = write_mcap(tmp_path / "indexed.mcap", msgs)
    if not indexed:
        log = _unindexed(log, tmp_path / "unindexed.mcap")
    b = tmp_path / "b.toml"
    b.write_text('[tick]\nperiod = "100 ms"\n[variables]\nx = "/x.data"\n'
                 'early = "/early.data"\n')
    alone, both = tmp_path / "alone.fret", tmp_path / "both.fret"
    alone.write_text("@tick_period 100 ms\nX: the sw shall always satisfy x < 3\n")
    both.write_text(alone.read_text() + "E: the sw shall always satisfy early > 0\n")
    got = []
    for fret in (alone, both):
        plan = load_plan(AuditConfig(requirements=(str(fret),), bindings=(str(b),)))
        doc = audit_json([audit_log(plan, str(log))], plan.requirements_json(),
                         plan.bindings_json())
        got.append(_times(json.loads(doc), "X"))
    assert got[0] == got[1], got
    assert got[0]["start"] == T0 - 10 * S
    assert got[0]["tick_time_s"] == pytest.approx(13.0), got  # x = 3.0 at T0 + 3 s
