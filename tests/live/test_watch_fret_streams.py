"""``fretc watch`` of a FRET export whose requirement reads an Internal variable defined as a
stream with state (LMCPS's ``psiAtZero``: its Lustre definition reads itself through
``pre``), bound by nothing: the live monitor computes it from the variables it reads
(compiler/codegen.py's ``_Streamed``), the verdict at the end from the audit's columns
(audit/streams.py), and the watch's verdicts equal the audit's of the same log."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from test_watch import _key, _watch_trace  # noqa: E402

from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402

pytestmark = pytest.mark.watch

TRACE = Path(__file__).resolve().parents[2] / "traces" / "lidar_dropout.mcap"
EXPORT = {
    "requirements": [
        {"reqid": "M1", "fulltext": "Autopilot shall always satisfy Psi - psiAtZero <= 0.3"},
        {"reqid": "M2", "fulltext": "whenever hdg Autopilot shall immediately satisfy "
                                    "psiAtZero <= Psi + 0.5"}],
    "variables": [
        {"component_name": "Autopilot", "variable_name": "Psi", "idType": "Output",
         "dataType": "double"},
        {"component_name": "Autopilot", "variable_name": "hdg", "idType": "Input",
         "dataType": "boolean"},
        {"component_name": "Autopilot", "variable_name": "psiAtZero", "idType": "Internal",
         "dataType": "double",
         "assignment": "Psi -> if (hdg and not pre hdg) then Psi else pre psiAtZero"}]}


def test_the_watch_equals_the_audit(tmp_path):
    (tmp_path / "p.json").write_text(json.dumps(EXPORT), encoding="utf-8")
    plan = load_plan(AuditConfig(
        requirements=(str(tmp_path / "p.json"),), bindings=(), tick_period="100 ms",
        inline=("Psi=/ground_truth/clearance.data", "hdg=min(/scan.ranges) < 0.9")))
    assert sorted(plan.requirements[0].variables) == ["Psi", "hdg"]
    _w, la, _done = _watch_trace(plan, TRACE)
    offline = audit_log(plan, str(TRACE))
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in offline.verdicts]
    assert la.verdicts[0].verdict == "violated"
