"""Time bases as logs have them: ``time = "header-where-stamped"`` places a message with a
header at its ``header.stamp`` and one without (a ``geometry_msgs/Twist`` command) at its log
time, where ``time = "header"`` refuses the unstamped topic and names the other choice; a
topic whose messages could not be decoded is never called "never published"."""

from __future__ import annotations

from pathlib import Path

from fretc.audit import AuditConfig, audit_log, load_plan

ROOT = Path(__file__).resolve().parents[2]
TRACE = ROOT / "traces" / "stop_delay.mcap"


def _verdicts(time_base: str | None):
    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),),
                                 time_base=time_base))
    la = audit_log(plan, str(TRACE))
    return la, {v.requirement: v for v in la.verdicts}


def test_header_where_stamped_reads_stamped_and_unstamped_topics_together():
    _la, log = _verdicts(None)
    la, mixed = _verdicts("header-where-stamped")
    assert la.time_base == "header-where-stamped"
    # the simulator stamps each message at its log time: the same verdicts and violations
    for rid, v in log.items():
        assert (mixed[rid].verdict, mixed[rid].violations) == (v.verdict, v.violations), rid
    assert "violated" in {v.verdict for v in mixed.values()}
    _la, header = _verdicts("header")
    unstamped = [v for v in header.values() if v.verdict == "error"]
    assert unstamped and all("header-where-stamped" in v.error for v in unstamped)
