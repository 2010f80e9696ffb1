"""Entities carried one per message, alternating (docs/bindings.md, "One verdict per entity",
"Entities held on their own"): two 1:10 cars in a motion-capture arena, each car's pose a
transform of ``/tf`` in a message of its own, the two cars' messages interleaved. Ticks of
100 ms always hold the other car's message (it comes on the tick), so in the filter form
(``{child_frame_id==$car}`` on the held message) the ego car is read absent at every tick:
its verdict says its values were read at no tick (``unknown``), never a silent ``vacuous``.
Held on their own (``hold = "entity"``) or read through the TF buffer (``tf("map", $car)``,
each frame its newest transform), the ego car is judged on its own poses: violated where
its y leaves the lane, and C1 with it (exit 1); its staleness is readable (``age($car)``,
``tf("map", $car).age``)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from _arena import C1, EGO_Y, FILTER, HELD, MS, TF, arena_log
from _logs import S
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main

def _plan(tmp: Path, bindings: str, fret: str = C1):
    (tmp / "c.fret").write_text("@tick_period 100 ms\n" + fret)
    (tmp / "c.bindings.toml").write_text(bindings)
    return load_plan(AuditConfig(requirements=(str(tmp / "c.fret"),)))


def _verdicts(tmp: Path, bindings: str, log: Path, fret: str = C1) -> dict:
    return {v.requirement: v for v in audit_log(_plan(tmp, bindings, fret), str(log)).verdicts}


def _first_out_of_lane(ego=EGO_Y) -> int:
    """The log time (ns) of the ego car's first message out of the lane."""
    k = next(k for k, y in enumerate(ego) if not -1.0 < y < 0.85)
    return S + k * 50 * MS + 25 * MS


@pytest.mark.tor("TOR-BND-003")
def test_an_entity_the_ticks_never_hold_is_unknown_not_vacuous(tmp_path):
    """The filter form reads each car in the message held at the tick: the ego car's never
    is (the other car's comes on every tick). Its verdict says so and C1 is not satisfied."""
    got = _verdicts(tmp_path, FILTER, arena_log(tmp_path / "arena.mcap"))
    ego = got["C1[car=car_ego]"]
    assert ego.verdict == "unknown", (ego.verdict, ego.notes)
    assert "read at no tick" in ego.unknown_reason
    assert "hold = \"entity\"" in ego.unknown_reason  # (what to write instead)
    assert got["C1[car=car_other]"].verdict == "satisfied"
    assert got["C1"].verdict == "unknown"
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "c.fret"),
                                    str(tmp_path / "arena.mcap"), "--no-progress"])
    assert res.exit_code == 3, res.output


@pytest.mark.parametrize("form", ["held", "tf"])
def test_each_car_judged_on_its_own_newest_pose(tmp_path, form):
    """``hold = "entity"`` and ``tf("map", $car)``: the ego car violated at the first tick
    after its first pose out of the lane, the other car satisfied, C1 violated, exit 1."""
    log = arena_log(tmp_path / "arena.mcap")
    got = _verdicts(tmp_path, {"held": HELD, "tf": TF}[form], log)
    ego = got["C1[car=car_ego]"]
    assert ego.verdict == "violated", (ego.verdict, ego.error, ego.unknown_reason)
    out = _first_out_of_lane()
    tick = -(-out // (100 * MS)) * 100 * MS
    assert ego.first_violation.at.time_ns == tick
    assert got["C1[car=car_other]"].verdict == "satisfied"
    assert got["C1"].verdict == "violated"
    assert got["C1"].first_violation.at.time_ns == tick
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "c.fret"), str(log),
                                    "--no-progress", "--json", "-"])
    assert res.exit_code == 1, res.output


def test_held_entity_evidence_names_its_own_message(tmp_path):
    """The deciding message of the ego car's violation is its own transform (its log time),
    not the newest ``/tf`` message at the tick (the other car's)."""
    got = _verdicts(tmp_path, HELD, arena_log(tmp_path / "arena.mcap"))
    fv = got["C1[car=car_ego]"].first_violation
    tick = fv.at.time_ns
    own = max(S + k * 50 * MS + 25 * MS for k in range(60) if S + k * 50 * MS + 25 * MS <= tick)
    assert fv.at.log_time_ns == own, (fv.at, own)
    assert fv.trigger is not None and fv.trigger.log_time_ns is not None
    assert (fv.trigger.log_time_ns - 25 * MS) % (50 * MS) == 0  # (an ego message)


@pytest.mark.parametrize("form", ["held", "tf"])
def test_a_car_that_stops_publishing_is_stale(tmp_path, form):
    """Staleness readable: the ego car's messages stop after 2 s of the 3 s run; held on its
    own it is judged to the end of the log, its age growing past 0.5 s: violated 0.5 s after
    its last message; the other car, publishing to the end, satisfied."""
    binds = (HELD + "car_age = 'age($car)'\n" if form == "held"
             else TF + "car_age = 'tf(\"map\", $car).age'\n")
    if form == "tf":
        binds = binds.replace('car = "/tf.transforms[:].child_frame_id"',
                              'car = { key = "/tf.transforms[:].child_frame_id", hold = '
                              '"entity" }')
    got = _verdicts(tmp_path, binds, arena_log(tmp_path / "arena.mcap", ego_stops=40),
                    "S: the car shall always satisfy car_age < 0.5\n")
    ego = got["S[car=car_ego]"]
    assert ego.verdict == "violated", (ego.verdict, ego.error, ego.unknown_reason)
    last = S + 39 * 50 * MS + 25 * MS
    assert ego.first_violation.at.time_ns == -(-(last + S // 2) // (100 * MS)) * 100 * MS
    assert got["S[car=car_other]"].verdict == "satisfied"


def test_hold_is_refused_when_unknown(tmp_path):
    """``hold`` is "message" (the default) or "entity": another value is an error naming
    the file and the entity."""
    bad = FILTER.replace('car = "/tf.transforms[:].child_frame_id"',
                         'car = { key = "/tf.transforms[:].child_frame_id", hold = "frame" }')
    (tmp_path / "c.fret").write_text("@tick_period 100 ms\n" + C1)
    (tmp_path / "c.bindings.toml").write_text(bad)
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "c.fret"),
                                    str(arena_log(tmp_path / "arena.mcap")), "--no-progress"])
    assert res.exit_code == 2, res.output
    assert "c.bindings.toml" in res.output and "hold" in res.output and "car" in res.output
    assert "Traceback" not in res.output


def test_the_json_of_the_held_form(tmp_path):
    """The audit JSON of the held form: C1 violated by the ego car, the other satisfied."""
    _plan(tmp_path, HELD)
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "c.fret"),
                                    str(arena_log(tmp_path / "arena.mcap")), "--no-progress",
                                    "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 1, res.output
    doc = json.loads((tmp_path / "a.json").read_text())
    got = {v["requirement"]: v["verdict"] for lg in doc["logs"] for v in lg["verdicts"]}
    assert got == {"C1": "violated", "C1[car=car_other]": "satisfied",
                   "C1[car=car_ego]": "violated"}


def test_entities_read_at_every_tick_are_bounded(tmp_path, monkeypatch):
    """Entities held on their own are read at every tick: past the bound on (entity, tick)
    values, the requirement is an error saying so and how to narrow it (exit 2), never a
    read whose memory grows without bound or an internal error."""
    import fretc.audit.entities.read as R

    monkeypatch.setattr(R, "MAX_EVERY_ROWS", 20)
    got = _verdicts(tmp_path, HELD, arena_log(tmp_path / "arena.mcap"))
    assert got["C1"].verdict == "error", got["C1"]
    assert "are read at every tick (held on their own): more than 20" in got["C1"].error
    assert "matching" in got["C1"].error
