"""One verdict per entity (docs/bindings.md, "One verdict per entity"): a requirement reading
``$motor`` (an entity of ``[entities]``) is judged for every status name matching ``motor*``
that appears in the log, each verdict equal to an independent recomputation from the
generated messages; an entity is read through a filter, so a disappeared one is not held
over; no entity at all is vacuous."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import DIAG_BINDINGS, S, TRACK_BINDINGS, diag_array, write_mcap
from _logs import track_types as _track_types
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.verdict import Ltl3

BINDINGS = DIAG_BINDINGS + '''battery_ok = 'max(/diagnostics.status[:]{name=="battery"}.level) < 2'
'''
FRET = ("@tick_period 100 ms\n"
        "M: in present mode the robot shall always satisfy motor_level < 2\n"
        "B: the robot shall always satisfy battery_ok\n")


def _diag(statuses):
    return diag_array(statuses)


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




@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.dictionaries(st.integers(1, 4), st.sampled_from([0.2, 0.8, 2.0]),
                                     max_size=3), min_size=2, max_size=20))
def test_one_verdict_per_tracked_object(tmp_path_factory, rows):
    """Obstacles by numeric id: each judged while tracked, equal to a recomputation."""
    Track, TrackArray = _track_types()
    tmp = tmp_path_factory.mktemp("trk")
    msgs = [("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
             TrackArray(tracks=[Track(id=i, distance=d) for i, d in sorted(r.items())]))
            for k, r in enumerate(rows)]
    (tmp / "t.fret").write_text("@tick_period 100 ms\n"
                                "T: in present mode the robot shall always satisfy dist > 0.5\n")
    (tmp / "t.bindings.toml").write_text(TRACK_BINDINGS)
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp / "t.fret"),))),
                   str(write_mcap(tmp / "t.mcap", msgs)))
    got = {v.requirement: v for v in la.verdicts}
    ids = list(dict.fromkeys(i for r in rows for i in sorted(r)))
    assert [k for k in got if k != "T"] == [f"T[track={i}]" for i in ids]
    for i in ids:
        bad = [k for k, r in enumerate(rows) if r.get(i, 1.0) <= 0.5]
        v = got[f"T[track={i}]"]
        assert v.verdict == ("violated" if bad else "satisfied"), (i, rows, v.error)
        if bad:
            assert v.first_violation.at.time_ns == S + bad[0] * S // 10
    if not ids:
        assert got["T"].verdict == "vacuous"
    else:
        assert got["T"].verdict == ("violated" if any(
            got[f"T[track={i}]"].verdict == "violated" for i in ids) else "satisfied")


def test_a_key_topic_absent_from_the_log_is_an_error_not_vacuous(tmp_path):
    """As a plain requirement whose bound topic is not in the log: no entity was looked
    for, so nothing holds of none of them."""
    from _logs import float64

    log = write_mcap(tmp_path / "s.mcap", [("/speed", "std_msgs/msg/Float64", S, float64(1.0))])
    got = _audit(tmp_path, log)
    assert got["M"].verdict == "error"
    assert got["M"].error.startswith("topic /diagnostics (the key /diagnostics.status[:].name "
                                     "of entity motor) is not in the log (it has /speed)")


def test_past_the_entity_bound_a_violated_entity_violates_the_requirement(tmp_path, monkeypatch):
    """More entities than the bound (here 5 for 6 tracks; 1,000 for 1,001 in the issue),
    track 2 violated: the requirement is violated (a violated instance decides it, whatever
    is left unjudged), the unjudged entities named in its notes and in their own error
    verdict; with no violation it stays an error."""
    import dataclasses

    Track, TrackArray = _track_types()
    (tmp_path / "t.fret").write_text("@tick_period 100 ms\n"
                                     "T: in present mode the robot shall always satisfy dist > 0.5\n")
    (tmp_path / "t.bindings.toml").write_text(TRACK_BINDINGS)
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),), max_entities=5))
    assert dataclasses.replace(plan.config).max_entities == 5
    for bad, want in ((2, "violated"), (None, "error")):
        msgs = [("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
                 TrackArray(tracks=[Track(id=i, distance=0.2 if i == bad and k == 3 else 2.0)
                                    for i in range(1, 7)])) for k in range(6)]
        got = {v.requirement: v for v in audit_log(plan, str(write_mcap(
            tmp_path / f"t{bad}.mcap", msgs))).verdicts}
        assert got["T"].verdict == want, got["T"]
        assert [v.verdict for k, v in got.items() if k.startswith("T[")] == [
            "violated" if i == bad else "satisfied" for i in range(1, 6)] + ["error"]
        assert "more than 5 entities track" in got["T[track=...]"].error
        if want == "violated":
            assert got["T"].first_violation.at.time_ns == S + 3 * S // 10
            assert any("more than 5 entities track" in n for n in got["T"].notes)


_ENTITY = st.builds(
    dict, verdict=st.sampled_from(["satisfied", "vacuous", "violated", "unknown", "error"]),
    at=st.none() | st.integers(0, 3), rob=st.none() | st.sampled_from(
        [-1.0, 0.0, 0.5, float("nan"), float("-inf")]),
    error=st.none() | st.just("no tick"), partial=st.booleans())


@settings(max_examples=200, deadline=None)
@given(st.lists(_ENTITY, min_size=1, max_size=8))
def test_the_requirement_verdict_over_its_entities_is_their_definition(entities):
    """summary_verdict (one pass over the entities) equals its definition read field by
    field: the first verdict of the precedence some entity has, the earliest violation (the
    first in order among equals), the least margin (as ``min`` takes NaN) where its sign
    agrees with the verdict (none otherwise, and none unknown or error), every error
    listed, the unknown reasons, partial when one is."""
    from fretc.audit.entities.summary import _PRECEDENCE, _listed, summary_verdict
    from fretc.audit.verdict import FirstViolation, TimePoint, Verdict

    class R:
        id, text, source = "R", "the robot shall always satisfy x", "r.fret:1"

    out = []
    for k, e in enumerate(entities):
        v = Verdict("log", f"R[e={k}]", verdict=e["verdict"], robustness=e["rob"],
                    error=e["error"], partial=e["partial"],
                    unknown_reason="gap" if e["verdict"] == "unknown" else None)
        if e["verdict"] == "violated" and e["at"] is not None:
            v.first_violation = FirstViolation(at=TimePoint(e["at"], e["at"] * 10))
        out.append(v)
    got = summary_verdict(R, "log", out, "R over n entities e")
    kinds = {x.verdict for x in out}
    verdict = next(k for k in _PRECEDENCE if k in kinds)
    assert got.verdict == verdict and got.requirement == "R"
    bad = [x for x in out if x.verdict == "violated" and x.first_violation is not None]
    if verdict == "violated" and bad:
        first = min(bad, key=lambda x: x.first_violation.at.time_ns)
        assert got.first_violation is first.first_violation
        assert f"first violated by {first.requirement}" in got.notes
    else:
        assert got.first_violation is None
    margins = [x.robustness for x in out if x.robustness is not None]
    want = min(margins) if margins else None
    if want is not None and not (want < 0 if verdict == "violated" else want >= 0
                                 if verdict in ("satisfied", "vacuous") else False):
        want = None  # (a margin whose sign disagrees with the verdict is never reported)
    assert (got.robustness is None) == (want is None)
    if want is not None:
        assert repr(got.robustness) == repr(want)
    errors = _listed([f"{x.requirement}: {x.error}" for x in out if x.error])
    assert got.error == (errors if verdict == "error" else None)
    assert (f"not judged: {errors}" in got.notes) == (verdict != "error" and bool(errors))
    reasons = _listed([f"{x.requirement}: {x.unknown_reason}" for x in out
                       if x.verdict == "unknown"])
    assert got.unknown_reason == (reasons if verdict == "unknown" else None)
    assert got.partial == any(x.partial for x in out)
    assert got.notes[-2:] == ["R over n entities e", "violated by: " + (
        _listed([x.requirement for x in out if x.verdict == "violated"], ", ") or "none")]


def test_the_entities_judged_at_once_are_records_read_as_verdicts(tmp_path):
    """The satisfied entities (judged at once) are records read as verdicts
    (audit/entities/verdicts.py): the audit's JSON, and a pickle (as a fleet worker sends
    it) read back, are those of the same verdicts as :class:`Verdict` objects; their
    evidence containers cannot change (a change raises, never lost), a change of a field
    makes the record a verdict of its own (the others unchanged); a violated entity (judged
    alone) is a :class:`Verdict`."""
    import json
    import pickle

    import pytest

    from fretc.audit.entities.verdicts import EntityVerdict
    from fretc.audit.verdict import Verdict

    Track, TrackArray = _track_types()
    rows = [{1: 2.0, 2: 2.0}, {1: 2.0, 2: 0.2, 3: 2.0}, {3: 2.0, 4: 2.0}, {4: 2.0}]
    log = write_mcap(tmp_path / "t.mcap", [
        ("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
         TrackArray(tracks=[Track(id=i, distance=d) for i, d in sorted(r.items())]))
        for k, r in enumerate(rows)])
    (tmp_path / "t.fret").write_text("@tick_period 100 ms\n"
                                     "T: in present mode the robot shall always satisfy dist > 0.5\n")
    (tmp_path / "t.bindings.toml").write_text(TRACK_BINDINGS)
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
    la = audit_log(plan, str(log))
    got = {v.requirement: v for v in la.verdicts}
    at_once = [got[f"T[track={i}]"] for i in (1, 3, 4)]
    assert all(type(v) is EntityVerdict and v.verdict == "satisfied" for v in at_once)
    assert type(got["T[track=2]"]) is Verdict and got["T[track=2]"].verdict == "violated"
    plain = [v.verdict_of() if isinstance(v, EntityVerdict) else v for v in la.verdicts]
    as_json = json.dumps(la.to_json(), sort_keys=True)
    la_plain = dataclasses.replace(la, verdicts=plain)
    assert as_json == json.dumps(la_plain.to_json(), sort_keys=True)
    back = pickle.loads(pickle.dumps(la))
    assert json.dumps(back.to_json(), sort_keys=True) == as_json
    assert at_once[0].robustness == 1.5 and at_once[0].margin == [(0, S, 1.5), (1, S + S // 10, 1.5)]
    with pytest.raises(TypeError, match="assign the verdict a container of its own"):
        at_once[0].values["dist"] = []
    with pytest.raises(AttributeError):
        at_once[0].notes.append("x")  # (a tuple: a change is never lost silently)
    at_once[0].log = "ws://robot:8765"  # (a field changed: a verdict of its own from now)
    at_once[0].notes.append("watched")
    at_once[0].values["dist"] = []
    assert at_once[0].log == "ws://robot:8765" and at_once[0].notes[-1] == "watched"
    assert at_once[1].log == str(log) and at_once[1].values == {}
    assert "watched" not in at_once[1].notes
    assert at_once[0].ltl3 == Ltl3("unknown", None, None)


_CONSISTENT = st.one_of(
    st.tuples(st.just("violated"), st.none() | st.floats(-1e9, -1e-9)),
    st.tuples(st.sampled_from(["satisfied", "vacuous"]), st.none() | st.floats(0.0, 1e9)),
    st.tuples(st.sampled_from(["unknown", "error"]), st.none() | st.floats(-1e9, 1e9)))


@settings(max_examples=300, deadline=None)
@given(st.lists(_CONSISTENT, min_size=1, max_size=8))
def test_the_margin_over_entities_agrees_in_sign_with_its_verdict(entities):
    """Hostile round 9, E2: entities whose own margins agree with their verdicts (a violated one
    may have none: a violation at distance 0) give a requirement whose margin agrees with
    its verdict: violated, negative (never the positive margin of a satisfied entity beside
    a violated one without a margin); satisfied or vacuous, >= 0; unknown or error, none.
    Smallest input that failed before: [violated with no margin, satisfied with 2.0]."""
    from fretc.audit.entities.summary import summary_verdict
    from fretc.audit.verdict import Verdict

    class R:
        id, text, source = "R", "the robot shall always satisfy x", "r.fret:1"

    out = [Verdict("log", f"R[e={k}]", verdict=kind, robustness=rob,
                   error="no tick" if kind == "error" else None,
                   unknown_reason="gap" if kind == "unknown" else None)
           for k, (kind, rob) in enumerate(entities)]
    got = summary_verdict(R, "log", out, "R over n entities e")
    if got.robustness is not None:
        if got.verdict == "violated":
            assert got.robustness < 0, got
        else:
            assert got.verdict in ("satisfied", "vacuous") and got.robustness >= 0, got
    # metamorphic: the margin, when there is one, is the least of the entities'
    margins = [r for _k, r in entities if r is not None]
    if got.robustness is not None:
        assert got.robustness == min(margins)
    elif got.verdict == "violated" and margins and min(margins) < 0:
        raise AssertionError(f"a negative least margin dropped: {got}")


def test_a_violated_entity_without_margin_beside_a_satisfied_one_gives_no_positive_margin():
    """The smallest input of E2: the satisfied entity's 2.0 was the violated requirement's
    robustness; now none, and a note says why."""
    from fretc.audit.entities.summary import summary_verdict
    from fretc.audit.verdict import Verdict

    class R:
        id, text, source = "R", "the robot shall always satisfy x", "r.fret:1"

    got = summary_verdict(R, "log", [Verdict("log", "R[e=1]", verdict="violated"),
                                     Verdict("log", "R[e=2]", verdict="satisfied",
                                             robustness=2.0)], "R over 2 entities e")
    assert got.verdict == "violated" and got.robustness is None
    assert any("disagrees in sign with the verdict" in n for n in got.notes)
    assert got.to_json(None)["robustness"]["value"] is None
