"""NaN has one meaning: a requirement's comparison with NaN is neither true nor
false. The tick is unknown, reported per requirement as a data problem of kind ``nan``, and
judged in three-valued semantics with the rest of the run: a violation on another tick
stands, before or after it, and a verdict that the tick could change is ``unknown``; a
binding file may choose IEEE 754 instead (``[tick] nan = "false"``), which the report
shows."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.common.problems import BindingError
from fretc.fretish.parser import parse
from fretc.monitors.judge import nan_ticks
from fretc.signals.bindings import parse_bindings

from _logs import S, float64, write_mcap

REQS = """\
R1: agent shall always satisfy v < 5
R2: agent shall always satisfy !(v >= 5)
R3: agent shall always satisfy v / 0 < 5
R4: agent shall always satisfy w < 5
"""
TOML = """\
[tick]
period = "100 ms"
time = "log"
{extra}
[variables]
v = "/v.data"
w = "/w.data"
"""


def _plan(tmp_path: Path, extra: str = ""):
    (tmp_path / "r.fret").write_text(REQS)
    (tmp_path / "b.toml").write_text(TOML.format(extra=extra))
    return load_plan(AuditConfig((str(tmp_path / "r.fret"),), (str(tmp_path / "b.toml"),)))


def _log(path: Path, values: list[float]) -> Path:
    msgs = [("/v", "std_msgs/msg/Float64", S + i * S // 10, float64(x))
            for i, x in enumerate(values)]
    msgs += [("/w", "std_msgs/msg/Float64", S + i * S // 10, float64(1.0))
             for i in range(len(values))]
    return write_mcap(path, sorted(msgs, key=lambda m: (m[2], m[0])))


def _got(la) -> dict:
    return {v.requirement: v for v in la.verdicts}


def test_a_nan_only_field_decides_nothing(tmp_path):
    la = audit_log(_plan(tmp_path), str(_log(tmp_path / "nan.mcap", [math.nan] * 5)))
    got = _got(la)
    for rid in ("R1", "R2", "R3"):  # two spellings of one requirement: one verdict
        assert got[rid].verdict == "unknown", rid
        assert "comparisons with NaN" in got[rid].unknown_reason
    assert got["R4"].verdict == "satisfied"  # reads no NaN
    assert la.problem_counts["nan R1"] == la.problem_counts["nan R2"] == 5
    p = next(p for p in la.problems if p["kind"] == "nan" and "of R1" in p["detail"])
    assert (p["log_time_ns"], p["end_time_ns"]) == (S, S + 4 * S // 10)


def test_division_by_zero_in_the_requirement_is_nan(tmp_path):
    la = audit_log(_plan(tmp_path), str(_log(tmp_path / "z.mcap", [1.0, 0.0, 1.0])))
    got = _got(la)
    assert got["R1"].verdict == "satisfied"
    # 1/0 is NaN in FRETish arithmetic (as the generated monitors): unread from tick 0
    assert got["R3"].verdict == "unknown"


@pytest.mark.parametrize("values, r1", [
    ([1.0, 7.0, math.nan, 1.0], "violated"),  # decided before the NaN: stands
    ([1.0, 1.0, math.nan, 7.0], "violated"),  # and after it
    ([1.0, 1.0, math.nan, 1.0], "unknown"),   # an invariant that held on every tick read
    ([1.0, 1.0, 1.0], "satisfied"),
])
@pytest.mark.tor("TOR-DMG-004")
def test_verdicts_decided_around_the_nan_stand(tmp_path, values, r1):
    la = audit_log(_plan(tmp_path), str(_log(tmp_path / "m.mcap", values)))
    got = _got(la)
    assert got["R1"].verdict == got["R2"].verdict == r1


def test_a_binding_file_may_choose_ieee(tmp_path):
    plan = _plan(tmp_path, 'nan = "false"')
    assert plan.bindings_json()["tick"]["nan"] == "false"
    la = audit_log(plan, str(_log(tmp_path / "nan.mcap", [math.nan] * 5)))
    got = _got(la)
    assert got["R1"].verdict == "violated" and got["R2"].verdict == "satisfied"
    assert any("nan = \"false\"" in n for n in got["R1"].notes)
    assert not any(p["kind"] == "nan" for p in la.problems)


def test_an_unknown_nan_policy_is_an_input_error():
    with pytest.raises(BindingError) as e:
        parse_bindings(TOML.format(extra='nan = "true"'), "b.toml")
    assert str(e.value).startswith("b.toml:4:")
    with pytest.raises(BindingError):
        parse_bindings(TOML.format(extra="nan = 1"), "b.toml")


@settings(max_examples=200, deadline=None)
@given(x=st.lists(st.sampled_from([0.0, 1.0, 7.0, math.nan, math.inf]), min_size=1,
                  max_size=12),
       c=st.sampled_from(["x < 5", "!(x >= 5)", "x = 1", "x", "persisted(2, x > 0)",
                          "x + 1 < 5 & y"]))
@pytest.mark.tor("TOR-DMG-004")
def test_nan_ticks_are_where_a_comparison_reads_nan(x, c):
    req = parse(f"agent shall always satisfy {c}")
    n = len(x)
    cols = {"x": np.array(x, dtype=np.float64), "y": np.ones(n, dtype=np.bool_)}
    got = nan_ticks(req, cols, n)
    assert got.tolist() == np.isnan(cols["x"]).tolist()


BOOL_TOML = """\
[tick]
period = "100 ms"
time = "log"
{extra}
[variables]
high = "/v.data > 5"
low = "!(/v.data >= 5)"
ok = "/w.data < 5"
"""
BOOL_REQS = """\
H1: agent shall always satisfy !high
H2: agent shall always satisfy low
H3: agent shall always satisfy ok
"""


@pytest.mark.parametrize("values, want", [
    ([1.0, 1.0, math.nan, 1.0], {"H1": "unknown", "H2": "unknown", "H3": "satisfied"}),
    ([1.0, 7.0, math.nan, 1.0], {"H1": "violated", "H2": "violated", "H3": "satisfied"}),
])
@pytest.mark.tor("TOR-DMG-004")
def test_a_comparison_with_nan_inside_a_binding_is_unread(tmp_path, values, want):
    """The schema-free spelling of the NaN case: the comparison sits in the binding file, not
    in the requirement; the two spellings (``high``/``low``) still get one verdict."""
    (tmp_path / "r.fret").write_text(BOOL_REQS)
    (tmp_path / "b.toml").write_text(BOOL_TOML.format(extra=""))
    plan = load_plan(AuditConfig((str(tmp_path / "r.fret"),), (str(tmp_path / "b.toml"),)))
    la = audit_log(plan, str(_log(tmp_path / "b.mcap", values)))
    assert {r: v.verdict for r, v in _got(la).items()} == want
    assert la.problem_counts["nan H1"] == la.problem_counts["nan H2"] == 1
    assert "nan H3" not in la.problem_counts


def test_the_binding_nan_policy_false_is_ieee_inside_bindings_too(tmp_path):
    (tmp_path / "r.fret").write_text(BOOL_REQS)
    (tmp_path / "b.toml").write_text(BOOL_TOML.format(extra='nan = "false"'))
    plan = load_plan(AuditConfig((str(tmp_path / "r.fret"),), (str(tmp_path / "b.toml"),)))
    la = audit_log(plan, str(_log(tmp_path / "f.mcap", [1.0, 1.0, math.nan, 1.0])))
    # IEEE 754: NaN > 5 is false (H1 holds) and !(NaN >= 5) is true (H2 holds)
    assert {r: v.verdict for r, v in _got(la).items()} == {
        "H1": "satisfied", "H2": "satisfied", "H3": "satisfied"}
    assert not any(k.startswith("nan ") for k in la.problem_counts)


@pytest.mark.parametrize("extra, want", [
    ("", {"R1": "unknown", "R2": "unknown", "R4": "satisfied"}),  # undeclared: unread
    ('inf = "value"', {"R1": "violated", "R2": "violated", "R4": "satisfied"}),
])
def test_inf_read_from_a_log_field_is_unread_unless_declared(tmp_path, extra, want):
    la = audit_log(_plan(tmp_path, extra), str(_log(tmp_path / "inf.mcap",
                                                    [1.0, math.inf, 1.0, -math.inf])))
    got = {r: _got(la)[r].verdict for r in want}
    assert got == want
    if not extra:
        assert la.problem_counts["nan R1"] == 2


def test_range_inf_keeps_its_rep117_meaning(tmp_path):
    """sensor_msgs/Range: +inf is "no object detected" (REP 117), a declared value."""
    from _logs import ROS2, T, header
    R = T(ROS2, "sensor_msgs/msg/Range")
    msgs = [("/sonar", "sensor_msgs/msg/Range", S + i * S // 10,
             R(header=header(S + i * S // 10), radiation_type=0, field_of_view=0.5,
               min_range=0.02, max_range=4.0, range=r))
            for i, r in enumerate([1.0, math.inf, 2.0])]
    log = write_mcap(tmp_path / "r.mcap", msgs)
    (tmp_path / "r.fret").write_text("C: agent shall always satisfy clear\n")
    (tmp_path / "b.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                     'clear = "/sonar.range > 0.5"\n')
    la = audit_log(load_plan(AuditConfig((str(tmp_path / "r.fret"),),
                                         (str(tmp_path / "b.toml"),))), str(log))
    assert la.verdicts[0].verdict == "satisfied" and not la.problem_counts


def test_a_violation_every_completion_shows_is_not_hidden_by_an_unknown_mode(tmp_path):
    """``in m`` reads ``m`` at the mode's entry and at its exit: Kleene's reading takes the
    NaN at tick 2 for two independent unknowns and called the verdict unknown, yet ``m``
    holds and ``y`` fails at tick 0, so every way of filling the NaN violates the
    requirement there (bench/fuzz_hostile.py --classes crunner:300 --seed 78, input 31; the
    C runner said violated at 0)."""
    (tmp_path / "t.csv").write_text("time,m,y\n0,2,0\n0.1,2,1\n0.2,nan,0.5\n0.3,0,2\n")
    (tmp_path / "r.fret").write_text("A2: in m the sw shall always satisfy y\n"
                                     "A3: in m the sw shall always satisfy y > -1\n")
    plan = load_plan(AuditConfig((str(tmp_path / "r.fret"),)))
    got = {v.requirement: v for v in audit_log(plan, str(tmp_path / "t.csv")).verdicts}
    assert got["A2"].verdict == "violated", got["A2"].unknown_reason
    assert got["A2"].ltl3.status == "violated" and got["A2"].ltl3.tick == 0
    # and one that every completion satisfies (y > -1 throughout) is satisfied
    assert got["A3"].verdict == "satisfied", got["A3"].unknown_reason


def test_past_the_search_bound_the_verdict_stays_unknown_and_says_why(tmp_path, monkeypatch):
    """Where the ways of filling the unknown ticks are too many to follow, the verdict is
    Kleene's unknown, and the reason says the search stopped (never a guess)."""
    import fretc.monitors.completions as completions

    monkeypatch.setattr(completions, "MAX_STATES", 1)
    (tmp_path / "t.csv").write_text("time,m,y\n0,2,0\n0.1,2,1\n0.2,nan,0.5\n0.3,0,2\n")
    (tmp_path / "r.fret").write_text("A2: in m the sw shall always satisfy y\n")
    plan = load_plan(AuditConfig((str(tmp_path / "r.fret"),)))
    (v,) = audit_log(plan, str(tmp_path / "t.csv")).verdicts
    assert v.verdict == "unknown"
    assert "may depend on them (not every way of filling them was followed" in v.unknown_reason


def test_a_requirements_nan_ticks_are_found_once_per_pass_and_follow_its_columns(
        tmp_path, monkeypatch):
    """finalize finds a requirement's NaN ticks once per clock pass (its NaN problem, its
    unknown ticks and its verdict read them), each requirement its own; a pass whose
    columns were replaced, or a copy of it, never reads what another set of columns gave."""
    import dataclasses

    from fretc.audit import finalize as F
    from fretc.audit.columns import ClockPass

    calls: list[int] = []
    real = F.nan_ticks

    def counted(req, columns, n):
        calls.append(n)
        return real(req, columns, n)

    monkeypatch.setattr(F, "nan_ticks", counted)
    la = audit_log(_plan(tmp_path), str(_log(tmp_path / "m.mcap", [1.0, 1.0, math.nan, 1.0])))
    assert _got(la)["R1"].verdict == "unknown"
    assert len(calls) == 4  # (R1 to R4: one each)

    plan = _plan(tmp_path)
    r1, r4 = (next(r for r in plan.requirements if r.id == i) for i in ("R1", "R4"))
    res = ClockPass(None, np.arange(3), {"v": np.array([1.0, math.nan, 1.0]),
                                         "w": np.array([math.nan, 1.0, 1.0])}, {})
    assert F._nan_index(r1, res).tolist() == [1]
    assert F._nan_index(r4, res).tolist() == [0]
    res.columns = {"v": np.array([math.nan, 1.0, 1.0]), "w": res.columns["w"]}
    assert F._nan_index(r1, res).tolist() == [0]
    copy = dataclasses.replace(res, columns={"v": np.ones(3), "w": np.ones(3)})
    assert copy.nan_ticks == {} and F._nan_index(r1, copy).tolist() == []
    assert F._nan_index(r1, res).tolist() == [0]
