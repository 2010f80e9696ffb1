"""Entities judged at once carry the evidence they carry judged alone (audit/entities/batch.py,
audit/entities/verdicts.py): for every entity, its verdict in the audit JSON (robustness,
its tick, time and deciding message, the margin over time, the scope intervals, triggers and
violations, the LTL3 verdict, the ticks, the notes) equals the one the judge gives it alone;
only the engine and the note saying it was judged at once differ. On random tracks against
requirements of every scope and condition kind, and on every entity of the other fixtures:
diagnostics by name, parameters logged once (DataFlash), cars held on their own on /tf."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fretc.audit.entities.log as E
from _arena import HELD, arena_log
from _logs import S, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.entities.batch import BATCH_NOTE
from test_entities import BINDINGS as MOTOR_BINDINGS, _diag
from test_entities_read import TRACK_BINDINGS, _track_types

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "logs"))
from _dataflash import write_dataflash  # noqa: E402

FRETS = ["in present mode the robot shall always satisfy dist > 0.5",
         "upon near the robot shall within 2 ticks satisfy !near",
         "whenever near the robot shall immediately satisfy present",
         "the robot shall eventually satisfy dist < 0.5",
         "after near the robot shall always satisfy dist > 0.3",
         "when not in present mode the robot shall always satisfy dist > 1",
         "only in present mode upon near the robot shall within 1 tick satisfy dist < 0.3",
         "before near the robot shall always satisfy dist >= 0.8",
         "only after near the robot shall never satisfy dist > 5",
         "in present mode upon persisted(2, near) the robot shall immediately satisfy near",
         "the robot shall always satisfy dist != 0.8"]


def _both(plan, log) -> tuple[list, list]:
    """Every verdict of the audit of ``log`` as JSON, the entities judged at once and each
    judged alone (the batch off)."""
    fast = audit_log(plan, str(log)).to_json()["verdicts"]
    batchable = E.batchable
    E.batchable = lambda plan, r: None
    try:
        slow = audit_log(plan, str(log)).to_json()["verdicts"]
    finally:
        E.batchable = batchable
    return fast, slow


def _same_evidence(plan, log) -> int:
    """Assert every verdict equal at once and alone but for the engine and the batch's note;
    returns how many were judged at once."""
    fast, slow = _both(plan, log)
    assert [v["requirement"] for v in fast] == [v["requirement"] for v in slow]
    at_once = 0
    for a, b in zip(fast, slow):
        if BATCH_NOTE in a["notes"]:
            at_once += 1
            a = dict(a, engine=b["engine"], notes=[n for n in a["notes"] if n != BATCH_NOTE])
        assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True), (
            a["requirement"], {k: (a[k], b[k]) for k in a if a[k] != b[k]})
    return at_once


def _tracks(tmp: Path, rows) -> Path:
    Track, TrackArray = _track_types()
    return write_mcap(tmp / "t.mcap", [
        ("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
         TrackArray(tracks=[Track(id=i, distance=d) for i, d in sorted(r.items())]))
        for k, r in enumerate(rows)])


def _plan(tmp: Path, fret: str, bindings: str):
    (tmp / "e.fret").write_text("@tick_period 100 ms\n" + fret)
    (tmp / "e.bindings.toml").write_text(bindings)
    return load_plan(AuditConfig(requirements=(str(tmp / "e.fret"),)))


NEAR = TRACK_BINDINGS + "near = 'min(/tracks.tracks[:]{id==$track}.distance) < 0.5'\n"


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.dictionaries(st.integers(1, 6), st.sampled_from([0.2, 0.4, 0.8, 2.0]),
                                     max_size=4), min_size=1, max_size=25),
       which=st.integers(0, len(FRETS) - 1))
def test_tracks_at_once_carry_the_evidence_of_each_alone(tmp_path_factory, rows, which):
    tmp = tmp_path_factory.mktemp("ev")
    _same_evidence(_plan(tmp, f"R: {FRETS[which]}\n", NEAR), _tracks(tmp, rows))


@pytest.mark.parametrize("fret", FRETS)
def test_every_form_at_once_carries_the_evidence_of_each_alone(tmp_path, fret):
    """A log where entities are judged at once under each requirement form (some of its
    entities satisfy it, some are vacuous, one is violated)."""
    rows = [{1: 2.0, 2: 0.8}, {1: 2.0, 2: 0.4, 3: 0.8}, {2: 2.0, 3: 0.2, 4: 5.5},
            {3: 2.0, 4: 2.0}, {4: 0.4, 5: 2.0}, {5: 0.8}, {5: 0.8, 6: 2.0}, {6: 2.0}]
    assert _same_evidence(_plan(tmp_path, f"R: {fret}\n", NEAR), _tracks(tmp_path, rows)) > 0


def test_motors_by_name_at_once_carry_the_evidence_of_each_alone(tmp_path):
    rows = [[("motor_l", 0)], [("motor_l", 0), ("motor_r", 1)], [("motor_r", 2)],
            [("lidar", 2)], [("motor_l", 0), ("motor_3", 1)], [("motor_3", 1)]]
    log = write_mcap(tmp_path / "d.mcap", [
        ("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", S + k * S // 10,
         _diag(list(r) + [("battery", 0)])) for k, r in enumerate(rows)])
    plan = _plan(tmp_path, "M: in present mode the robot shall always satisfy motor_level < 2\n",
                 MOTOR_BINDINGS)
    assert _same_evidence(plan, log) == 2


def test_parameters_logged_once_at_once_carry_the_evidence_of_each_alone(tmp_path):
    """One-value keys: the deciding message of each parameter is its own record."""
    rows = [("PARM", [1_000_000 + k * 7_000, f"P_{k:02d}", float(k % 5)]) for k in range(30)]
    rows += [("BAT", [1_000_000 + k * 100_000, 0, 12.0, 1.0, 50.0]) for k in range(6)]
    log = write_dataflash(tmp_path / "p.bin", sorted(rows, key=lambda r: r[1][0]))
    plan = _plan(tmp_path, "P: the plane shall always satisfy value >= 1\n",
                 "[tick]\nperiod = \"100 ms\"\n[entities]\nparam = '\"PARM\".Name'\n"
                 "[variables]\nvalue = '\"PARM\"{Name==$param}.Value'\n")
    assert _same_evidence(plan, log) == 24


def test_cars_held_on_their_own_at_once_carry_the_evidence_of_each_alone(tmp_path):
    log = arena_log(tmp_path / "arena.mcap", ego=[0.1] * 60)
    plan = _plan(tmp_path, "C: in present mode the car shall always satisfy car_y > -1.0\n",
                 HELD)
    assert _same_evidence(plan, log) == 2


def test_a_records_fields_read_one_by_one_are_its_verdicts(tmp_path):
    """Each field of an entity judged at once, read as an attribute, is the field of its
    verdict made whole (what the JSON and the summaries read alike)."""
    import dataclasses

    from fretc.audit.entities.verdicts import EntityVerdict
    from fretc.audit.verdict import Verdict

    rows = [{1: 2.0, 2: 0.8}, {1: 2.0, 2: 0.4, 3: 0.8}, {2: 2.0, 3: 0.2, 4: 5.5}, {4: 2.0}]
    la = audit_log(_plan(tmp_path, f"R: {FRETS[1]}\n", NEAR), str(_tracks(tmp_path, rows)))
    records = [v for v in la.verdicts if isinstance(v, EntityVerdict)]
    assert records
    for v in records:
        whole = v.verdict_of()
        for f in dataclasses.fields(Verdict):
            got, want = getattr(v, f.name), getattr(whole, f.name)
            assert (list(got) if f.name == "notes" else got) == want, f.name
