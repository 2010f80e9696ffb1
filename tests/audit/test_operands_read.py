"""The operands of a violation (audit/operands.py) are read only up to the last tick shown
(``sample_blocks(until_ns=...)``: the read stops at the first message past it): the audit
JSON, its values and sources included, equals that of a read of the whole log, on every
shipped run (MCAP, read by the columnar pass), a protobuf copy of one
(message by message), and a clock that reads ``age()`` (its ticks to the log's end)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

import fretc.audit.operands as O
from fretc.audit import AuditConfig, audit_log, load_plan

ROOT = Path(__file__).resolve().parents[2]
TRACES = sorted((ROOT / "traces").glob("*.mcap"))


def _both(plan, log) -> tuple[str, str]:
    """The audit JSON of ``log`` with the operands read up to the last tick shown, and read
    to the log's end."""
    bounded = audit_log(plan, str(log)).to_json()
    real = O._last_time
    O._last_time = lambda *_a: None
    try:
        whole = audit_log(plan, str(log)).to_json()
    finally:
        O._last_time = real
    return json.dumps(bounded, sort_keys=True), json.dumps(whole, sort_keys=True)


@pytest.mark.parametrize("log", TRACES, ids=[t.stem for t in TRACES])
def test_operands_read_to_the_last_tick_shown_are_those_of_the_whole_read(log):
    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))
    bounded, whole = _both(plan, log)
    assert bounded == whole


def test_operands_of_protobuf_messages_and_a_staleness_clock(tmp_path):
    """A protobuf copy of a run (its messages read one by one), R6's clock reading age()."""
    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    from _encode import copy_as

    log = copy_as(ROOT / "traces" / "stop_delay.mcap", tmp_path / "stop.mcap", "protobuf")
    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))
    bounded, whole = _both(plan, log)
    assert bounded == whole
    doc = json.loads(bounded)
    shown = [v for v in doc["verdicts"] if v["verdict"] == "violated" and v["values"]]
    assert shown  # (operands were read and shown)
