"""One verdict per entity (docs/bindings.md, "One verdict per entity"): a requirement reading
``$motor`` (an entity of ``[entities]``) is judged for every status name matching ``motor*``
that appears in the log, each verdict equal to an independent recomputation from the
generated messages; an entity is read through a filter, so a disappeared one is not held
over; no entity at all is vacuous."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import ROS2, S, T, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan

BINDINGS = '''[tick]
period = "100 ms"
[entities]
motor = { key = "/diagnostics.status[:].name", matching = "motor*" }
[variables]
motor_level = 'max(/diagnostics.status[:]{name==$motor}.level)'
present = 'count(/diagnostics.status[:]{name==$motor}.level >= 0) = 1'
battery_ok = 'max(/diagnostics.status[:]{name=="battery"}.level) < 2'
'''
FRET = ("@tick_period 100 ms\n"
        "M: in present mode the robot shall always satisfy motor_level < 2\n"
        "B: the robot shall always satisfy battery_ok\n")


def _diag(statuses):
    St, Arr = T(ROS2, "diagnostic_msgs/msg/DiagnosticStatus"), T(ROS2, "diagnostic_msgs/msg/DiagnosticArray")
    return Arr(header=T(ROS2, "std_msgs/msg/Header")(
        stamp=T(ROS2, "builtin_interfaces/msg/Time")(sec=0, nanosec=0), frame_id=""),
        status=[St(level=lvl, name=n, message="", hardware_id="", values=[])
                for n, lvl in statuses])


def _audit(tmp: Path, log: Path):
    (tmp / "e.fret").write_text(FRET)
    (tmp / "e.bindings.toml").write_text(BINDINGS)
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp / "e.fret"),))), str(log))
    return {v.requirement: v for v in la.verdicts}


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.lists(st.tuples(st.sampled_from(["motor_l", "motor_r", "motor_3",
                                                            "lidar"]), st.integers(0, 2)),
                              max_size=4, unique_by=lambda x: x[0]),
                     min_size=2, max_size=25))
def test_one_verdict_per_entity_equals_a_recomputation(tmp_path_factory, rows):
    tmp = tmp_path_factory.mktemp("ent")
    msgs = [("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", S + k * S // 10,
             _diag(list(r) + [("battery", 0)])) for k, r in enumerate(rows)]
    got = _audit(tmp, write_mcap(tmp / "d.mcap", msgs))
    assert got["B"].verdict == "satisfied"
    motors = []
    for r in rows:  # first appearance order
        for n, _l in r:
            if n.startswith("motor") and n not in motors:
                motors.append(n)
    if not motors:
        assert got["M"].verdict == "vacuous"
        return
    assert sorted(k for k in got if k.startswith("M[")) == sorted(f"M[motor={m}]" for m in motors)
    for m in motors:
        # while present: violated at the first message whose level for m is >= 2
        bad = [k for k, r in enumerate(rows) if dict(r).get(m, -1) >= 2]
        v = got[f"M[motor={m}]"]
        assert v.verdict == ("violated" if bad else "satisfied"), (m, rows, v.error)
        if bad:
            assert v.first_violation.at.time_ns == S + bad[0] * S // 10
        assert any("over" in n and "entities motor" in n for n in v.notes)


def test_the_requirement_has_a_verdict_over_its_entities_in_the_reports(tmp_path):
    rows = [[("motor_l", 0)], [("motor_l", 0), ("motor_r", 1)], [("motor_r", 2)],
            [("lidar", 2)], [("motor_l", 0)]]
    msgs = [("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", S + k * S // 10,
             _diag(list(r) + [("battery", 0)])) for k, r in enumerate(rows)]
    got = _audit(tmp_path, write_mcap(tmp_path / "d.mcap", msgs))
    assert got["M[motor=motor_l]"].verdict == "satisfied"
    assert got["M[motor=motor_r]"].verdict == "violated"
    m = got["M"]  # all entities: violated by one
    assert m.verdict == "violated"
    assert m.first_violation.at.time_ns == S + 2 * S // 10
    assert "M over 2 entities motor: 1 satisfied, 1 violated" in m.notes
    assert "violated by: M[motor=motor_r]" in m.notes
