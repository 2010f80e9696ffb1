"""``--tick-period`` as an override, and durations under one tick per message."""

from __future__ import annotations

from pathlib import Path

from fretc.audit import AuditConfig, audit_log, load_plan

ROOT = Path(__file__).resolve().parents[2]
NOMINAL = str(ROOT / "traces" / "nominal.mcap")
FRET = """@tick_period 100 ms
T1: upon too_close agilex_agent shall within 1 second satisfy stopped
T2: the scout_mini shall always satisfy clearance > 0
T3: upon too_close agilex_agent shall within 150 milliseconds satisfy stopped
"""


def _plan(tmp_path, bindings=None, **kw):
    (tmp_path / "t.fret").write_text(FRET)
    text = bindings or (ROOT / "requirements" / "safe_ros.bindings.toml").read_text()
    (tmp_path / "t.bindings.toml").write_text(text)
    return load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),), **kw))


def test_tick_period_flag_converts_every_duration_again(tmp_path):
    """Today every requirement of a file declaring @tick_period failed, blaming the file."""
    plan = _plan(tmp_path, tick_period="50 ms")
    r = {x.id: x for x in plan.requirements}
    assert all(x.error is None for x in r.values()), [x.error for x in r.values()]
    assert r["T1"].formalization.ticks == 20 and r["T3"].formalization.ticks == 3
    assert any("--tick-period" in n for n in r["T1"].notes)


def test_tick_period_flag_fails_only_requirements_whose_durations_do_not_convert(tmp_path):
    plan = _plan(tmp_path, tick_period="30 ms")
    r = {x.id: x for x in plan.requirements}
    assert r["T1"].error is not None and "--tick-period" in r["T1"].error  # 1 s / 30 ms
    assert r["T2"].error is None and r["T3"].error is None  # 150 ms = 5 ticks
    la = audit_log(plan, NOMINAL)
    v = {x.requirement: x.verdict for x in la.verdicts}
    assert v == {"T1": "error", "T2": "satisfied", "T3": "satisfied"}


TOPIC_TICK = """[tick]
topic = "/scan"
{extra}
[variables]
too_close = "min(/scan.ranges) < 0.9"
stopped = "abs(/cmd_vel_filtered.linear.x) < 1e-3 & abs(/cmd_vel_filtered.angular.z) < 1e-3"
clearance = "/ground_truth/clearance.data"
"""


def test_durations_with_per_message_ticks_need_a_nominal_rate(tmp_path):
    """Today ``@tick_period`` with one tick per message was accepted: ``within 1 second``
    silently meant ten messages whatever their rate."""
    plan = _plan(tmp_path, TOPIC_TICK.format(extra=""))
    r = {x.id: x for x in plan.requirements}
    assert r["T1"].error is not None and "nominal_rate" in r["T1"].error
    assert r["T2"].error is None  # no duration: no rate needed


def test_a_declared_nominal_rate_converts_and_a_wrong_one_warns(tmp_path):
    plan = _plan(tmp_path, TOPIC_TICK.format(extra='nominal_rate = "10 Hz"'))
    r = {x.id: x for x in plan.requirements}
    assert r["T1"].error is None and r["T1"].formalization.ticks == 10
    la = audit_log(plan, NOMINAL)
    assert not la.warnings  # /scan runs at 10 Hz
    bad = tmp_path / "bad"
    bad.mkdir()
    plan = _plan(bad, TOPIC_TICK.format(extra='nominal_rate = "20 Hz"')
                 .replace("@tick_period 100 ms", ""))
    (bad / "t.fret").write_text(FRET.replace("@tick_period 100 ms\n", ""))
    plan = load_plan(AuditConfig(requirements=(str(bad / "t.fret"),)))
    la = audit_log(plan, NOMINAL)
    assert any("/scan runs at 9.99 Hz, not its nominal 20 Hz" in w for w in la.warnings), la.warnings


def test_the_nominal_rate_hint_gives_the_measured_rate(tmp_path):
    """Before, the hint said "10 Hz" for a topic measured at 50 Hz."""
    from _logs import MS, float64, write_mcap
    log = write_mcap(tmp_path / "fast.mcap", [("/fast", "std_msgs/msg/Float64", k * 20 * MS,
                                               float64(k % 7)) for k in range(101)])
    (tmp_path / "f.fret").write_text(
        "F1: upon high the bot shall within 1 second satisfy low\n"
        "F2: the bot shall always satisfy x < 100\n")
    (tmp_path / "f.bindings.toml").write_text(
        '[tick]\ntopic = "/fast"\n[variables]\nhigh = "/fast.data > 5"\nlow = "/fast.data < 1"\n'
        'x = "/fast.data"\n')
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "f.fret"),)))
    la = audit_log(plan, str(log))
    v = {x.requirement: x for x in la.verdicts}
    assert v["F2"].verdict == "satisfied"
    assert v["F1"].verdict == "error"
    assert v["F1"].error.endswith('/fast runs at 50 Hz in this log: nominal_rate = "50 Hz"')
    assert "10 Hz" not in v["F1"].error
    # alone, the tick topic is not read for another requirement: counted for the hint
    (tmp_path / "f.fret").write_text("F1: upon high the bot shall within 1 second satisfy low\n")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "f.fret"),)))
    assert 'nominal_rate = "50 Hz"' in audit_log(plan, str(log)).verdicts[0].error
