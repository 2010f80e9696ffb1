"""Bindings checked against the log's schemas: a string in
arithmetic, a boolean bound where a number is used and the reverse, field paths that walk
Python attributes, quoted FRETish variables; CSV traces follow the same binding rules."""

from __future__ import annotations

from pathlib import Path

import pytest

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.files import parse_bindings
from fretc.common.problems import BindingError

ROOT = Path(__file__).resolve().parents[2]
NOMINAL = str(ROOT / "traces" / "nominal.mcap")


def _audit(inline, log=NOMINAL, requirements=None):
    plan = load_plan(AuditConfig(requirements=(str(requirements or ROOT / "requirements"),),
                                 inline=tuple(inline)))
    return {v.requirement: v for v in audit_log(plan, log).verdicts}


def test_a_string_in_arithmetic_is_an_error_naming_variable_topic_and_field():
    """Item 7: ``abs(/scan.header.frame_id)`` crashed the audit with a numpy traceback."""
    v = _audit(["too_close=abs(/scan.header.frame_id) > 1"])
    for rid in ("R1", "R2"):
        assert v[rid].verdict == "error"
        e = v[rid].error
        assert "too_close" in e and "/scan" in e and "header.frame_id" in e and "string" in e
    assert v["R4"].verdict == "satisfied"  # the others are audited


def test_a_boolean_where_a_number_is_used_and_the_reverse_are_errors():
    """Item 13: R4 reads linear_speed as a number (<= 0.5); R3 reads stop_requested as a
    boolean. Both were accepted silently."""
    v = _audit(["linear_speed=/gwendolen_control.data",
                "stop_requested=/ground_truth/clearance.data"])
    assert v["R4"].verdict == "error" and "linear_speed" in v["R4"].error
    assert "boolean" in v["R4"].error and "number" in v["R4"].error
    assert v["R3"].verdict == "error" and "stop_requested" in v["R3"].error
    assert v["R5"].verdict == "satisfied"


def test_a_boolean_inside_arithmetic_is_an_error():
    v = _audit(["clearance=/gwendolen_control.data + 1"])
    assert v["R5"].verdict == "error"
    assert "/gwendolen_control" in v["R5"].error and "data" in v["R5"].error
    assert "boolean" in v["R5"].error


def test_an_attribute_walk_is_refused_before_the_audit():
    """Item 13: ``/scan.__class__.__init__.__code__.co_argcount`` evaluated."""
    from fretc.audit import AuditInputError
    with pytest.raises(AuditInputError, match="not a message field"):
        _audit(["too_close=/scan.__class__.__init__.__code__.co_argcount > 0"])


@pytest.mark.parametrize("expr", ["/scan.ranges.size > 0", "/scan.range_max.real > 0",
                                  "/scan.header.stamp.sec.bit_length > 0"])
def test_field_paths_resolve_only_through_declared_fields(expr):
    """Item 13: ``/scan.__class__...`` evaluated Python attributes of the decoded object."""
    v = _audit([f"too_close={expr}"])
    assert v["R1"].verdict == "error" and "too_close" in v["R1"].error
    assert "has no field" in v["R1"].error or "not a message field" in v["R1"].error


def test_dunder_fields_are_rejected_when_the_binding_is_parsed():
    with pytest.raises(BindingError, match="not a message field"):
        compile_expression("x", "/scan.__class__.__name__ > 0")


@pytest.mark.tor("TOR-BND-001")
def test_a_misspelt_field_lists_the_fields_and_suggests_the_closest():
    v = _audit(["stopped=abs(/cmd_vel_filtered.linear.xx) < 1e-3"])
    e = v["R1"].error
    assert "its fields: x, y, z" in e and "did you mean 'x'" in e


def test_quoted_fretish_variables_are_bindable(tmp_path):
    """Item 14: ``"wind speed"`` could not be bound at all."""
    (tmp_path / "q.fret").write_text(
        'Q1: the scout_mini shall always satisfy "ground clearance" > 0\n'
        'Q2: whenever "stop requested" the scout_mini shall immediately satisfy '
        '"forwarded zero"\n')
    (tmp_path / "q.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\n'
        '"ground clearance" = "/ground_truth/clearance.data"\n'
        '"stop requested" = "/gwendolen_control.data"\n')
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "q.fret"),),
                                 inline=('"forwarded zero"=/cmd_vel_filtered.linear.x = 0',)))
    v = {x.requirement: x for x in audit_log(plan, NOMINAL).verdicts}
    assert v["Q1"].verdict == "satisfied", v["Q1"].error
    assert v["Q2"].verdict == "satisfied", v["Q2"].error
    b = parse_bindings('[tick]\nperiod = "1 s"\n[variables]\n"wind speed" = "/w.data"\n')
    assert "wind speed" in b.variables


# --------------------------------------------------------------------------- CSV
CSV_FRET = "C1: the bot shall always satisfy speed <= 1\n"


def test_csv_binding_to_a_missing_column_is_an_error_naming_the_columns(tmp_path):
    """Regression: ``speed = "/x.nonexist"`` was ignored and the raw ``speed`` column audited."""
    (tmp_path / "t.csv").write_text("time,speed\n0,0.5\n1,2.0\n")
    (tmp_path / "c.fret").write_text(CSV_FRET)
    for expr, words in (('"/x.nonexist"', ["/x", "columns speed"]),
                        ('"/csv.sped"', ["sped", "columns: speed", "did you mean 'speed'"])):
        (tmp_path / "c.bindings.toml").write_text(
            f'[tick]\nperiod = "1 s"\n[variables]\nspeed = {expr}\n')
        v = _audit([], str(tmp_path / "t.csv"), tmp_path / "c.fret")["C1"]
        assert v.verdict == "error", (expr, v.verdict)
        for w in words:
            assert w in v.error, (w, v.error)


def test_csv_bound_variables_use_their_binding(tmp_path):
    (tmp_path / "t.csv").write_text("time,speed\n0,0.5\n1,2.0\n")
    (tmp_path / "c.fret").write_text(CSV_FRET)
    (tmp_path / "c.bindings.toml").write_text(
        '[tick]\nperiod = "1 s"\n[variables]\nspeed = "/csv.speed / 4"\n')
    v = _audit([], str(tmp_path / "t.csv"), tmp_path / "c.fret")["C1"]
    assert v.verdict == "satisfied"  # 2.0 / 4 <= 1, although the raw column is 2.0
