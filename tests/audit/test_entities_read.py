"""Per-entity requirements in one read of the log (audit/entities/read.py): every entity of
every per-entity requirement sampled in one pass, each judged on its life (from the first
tick at or after its first message to the first tick at or after its last); an entity seen
in one message judged (ArduPilot's parameters, each logged once); no fixed bound on the
entities (``--max-entities``); entities over the parallel arrays of a message (JointState's
joints by name); the entities judged at once (audit/entities/batch.py) give the verdicts of
the judge one at a time."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fretc.audit.entities.log as E
from _logs import ROS2, S, T, TRACK_BINDINGS, write_mcap
from _logs import track_types as _track_types
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "logs"))
MS = S // 1000


def _plan(tmp: Path, fret: str, bindings: str, **config):
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "e.fret").write_text("@tick_period 100 ms\n" + fret)
    (tmp / "e.bindings.toml").write_text(bindings)
    return load_plan(AuditConfig(requirements=(str(tmp / "e.fret"),), **config))


def _by_id(la) -> dict:
    return {v.requirement: v for v in la.verdicts}


PARM_BINDINGS = """[tick]
period = "100 ms"
[entities]
param = '"PARM".Name'
[variables]
value = '"PARM"{Name==$param}.Value'
"""


def test_parameters_logged_once_are_each_judged_on_a_period_clock(tmp_path):
    """ArduPilot logs each parameter once (PARM, its name and value), 2,500 of them within
    a few milliseconds: every parameter is judged on its own stream (the tick at or after
    its message holds its value), none is an error, no bound of 1,000 cuts them, and the
    three out of range are violated at the tick after their message."""
    from _dataflash import write_dataflash

    bad = {17: 250.0, 1234: -3.0, 2499: 1e6}
    rows = [("PARM", [1_000_000 + k * 3, f"P_{k:04d}", bad.get(k, float(k % 100))])
            for k in range(2500)]
    rows += [("BAT", [1_000_000 + k * 100_000, 0, 12.0, 1.0, 50.0]) for k in range(5)]
    log = write_dataflash(tmp_path / "params.bin", sorted(rows, key=lambda r: r[1][0]))
    fret = "P: the copter shall always satisfy value >= 0 & value <= 200\n"
    la = audit_log(_plan(tmp_path, fret, PARM_BINDINGS), str(log))
    got = _by_id(la)
    assert len(got) == 2501 and got["P"].verdict == "violated"
    words = {k: v.verdict for k, v in got.items() if k != "P"}
    assert {k for k, w in words.items() if w == "violated"} == {
        f"P[param=P_{k:04d}]" for k in bad}
    assert set(words.values()) == {"satisfied", "violated"}
    v = got["P[param=P_1234]"]
    t = (1_000_000 + 1234 * 3) * 1000
    assert v.first_violation.at.time_ns == -(-t // (100 * MS)) * 100 * MS  # the tick after it
    assert v.ticks_evaluated >= 1


def test_one_read_for_every_entity_and_requirement(tmp_path, monkeypatch):
    """Two per-entity requirements over 60 tracked obstacles: the log's messages are read
    once (one pass of its reader), not once per entity."""
    from fretc.logs.mcap.source import McapSource

    Track, TrackArray = _track_types()
    rows = [{i: 2.0 + (k % 7) * 0.1 for i in range(k // 5, k // 5 + 4)} for k in range(250)]
    log = write_mcap(tmp_path / "t.mcap", [
        ("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
         TrackArray(tracks=[Track(id=i, distance=d) for i, d in r.items()]))
        for k, r in enumerate(rows)])
    calls = []
    real = McapSource.messages

    def counted(self, topics=None):
        calls.append(topics)
        return real(self, topics)

    monkeypatch.setattr(McapSource, "messages", counted)
    fret = ("T: in present mode the robot shall always satisfy dist > 1\n"
            "U: upon present the robot shall within 2 ticks satisfy dist > 1.5\n")
    la = audit_log(_plan(tmp_path, fret, TRACK_BINDINGS), str(log))
    assert len(calls) == 1, calls
    got = _by_id(la)
    assert sum(k.startswith("T[") for k in got) == sum(k.startswith("U[") for k in got) == 53
    assert got["T"].verdict == got["U"].verdict == "satisfied"




def test_joints_by_name_are_entities(tmp_path):
    """"Every joint within its limits, one verdict per joint": the joints are the names of
    /joint_states, each read by ``joint(/joint_states.position, $joint)`` whatever its
    index in the message (the order changes); the verdicts equal a recomputation."""
    JS = T(ROS2, "sensor_msgs/msg/JointState")
    names = ["shoulder", "elbow", "wrist"]
    pos = {n: [0.1 * k * (j + 1) for k in range(30)] for j, n in enumerate(names)}
    msgs = []
    for k in range(30):
        order = names if k % 2 else names[::-1]
        msgs.append(("/joint_states", "sensor_msgs/msg/JointState", S + k * S // 10, JS(
            header=T(ROS2, "std_msgs/msg/Header")(
                stamp=T(ROS2, "builtin_interfaces/msg/Time")(sec=1, nanosec=0), frame_id=""),
            name=order, position=np.array([pos[n][k] for n in order]),
            velocity=np.zeros(3), effort=np.zeros(3))))
    log = write_mcap(tmp_path / "arm.mcap", msgs)
    binds = ('[tick]\nperiod = "100 ms"\n[entities]\njoint = "/joint_states.name[:]"\n'
             '[variables]\npos = \'joint(/joint_states.position, $joint)\'\n')
    la = audit_log(_plan(tmp_path, "J: the arm shall always satisfy pos < 2.5\n", binds),
                   str(log))
    got = _by_id(la)
    assert list(got) == ["J"] + [f"J[joint={n}]" for n in names[::-1]]
    for n in names:
        over = [k for k in range(30) if pos[n][k] >= 2.5]
        v = got[f"J[joint={n}]"]
        assert v.verdict == ("violated" if over else "satisfied"), (n, v.error)
        if over:
            assert v.first_violation.at.time_ns == S + over[0] * S // 10
    assert got["J"].verdict == "violated"


def test_the_bound_on_entities_is_an_option(tmp_path):
    """--max-entities N judges N entities; the rest is an error saying how to raise it."""
    Track, TrackArray = _track_types()
    log = write_mcap(tmp_path / "t.mcap", [
        ("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
         TrackArray(tracks=[Track(id=k, distance=2.0)])) for k in range(6)])
    _plan(tmp_path, "T: in present mode the robot shall always satisfy dist > 1\n",
          TRACK_BINDINGS)
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "e.fret"), str(log),
                                    "--max-entities", "4", "--json", "-", "--no-progress"])
    assert res.exit_code == 2, res.output
    assert "only the first 4 are judged (raise the bound with --max-entities)" in res.output
    full = audit_log(_plan(tmp_path, "T: in present mode the robot shall always satisfy "
                           "dist > 1\n", TRACK_BINDINGS), str(log))
    assert [v.verdict for v in full.verdicts] == ["satisfied"] * 7


FRETS = ["in present mode the robot shall always satisfy dist > 0.5",
         "upon near the robot shall within 2 ticks satisfy !near",
         "whenever near the robot shall immediately satisfy present",
         "the robot shall eventually satisfy dist < 0.5",
         "after near the robot shall always satisfy dist > 0.3"]


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.dictionaries(st.integers(1, 6),
                                     st.sampled_from([0.2, 0.4, 0.8, 2.0, float("nan")]),
                                     max_size=4), min_size=1, max_size=25),
       which=st.integers(0, len(FRETS) - 1))
def test_the_entities_judged_at_once_give_the_judges_verdicts(tmp_path_factory, monkeypatch,
                                                              rows, which):
    """Random tracks: the verdict, LTL3 verdict and tick, and ticks of each entity judged
    at once (the pt formula over all their traces laid end to end) equal the judge's one
    entity at a time (an entity that reads NaN among them: judged alone either way)."""
    _fast_equals_slow(tmp_path_factory.mktemp("batch"), monkeypatch, rows, FRETS[which])


@pytest.mark.parametrize("fret", FRETS)
def test_an_entity_that_reads_nan_is_judged_alone(tmp_path, monkeypatch, fret):
    """Among entities judged at once, one whose distance is NaN at a tick gets the verdict
    the judge gives it alone (its NaN tick unknown), the others theirs."""
    nan = float("nan")
    rows = [{1: 2.0, 2: 2.0, 3: 0.2}, {1: 2.0, 2: nan, 3: 0.2}, {1: 0.4, 2: 2.0, 3: 2.0},
            {1: 2.0, 2: 2.0}, {2: 2.0}]
    fast = _fast_equals_slow(tmp_path, monkeypatch, rows, fret)
    if fret == FRETS[0]:
        assert fast["R[track=2]"][0] == "unknown"


def _fast_equals_slow(tmp: Path, monkeypatch, rows: list[dict], fret: str) -> dict:
    """Tracks ``rows`` (a message each: id -> distance) audited against ``R: fret`` with the
    entities judged at once and one at a time: the same verdicts (returned), the entities
    judged at once by the vectorized engine but those that read NaN."""
    Track, TrackArray = _track_types()
    log = write_mcap(tmp / "t.mcap", [
        ("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
         TrackArray(tracks=[Track(id=i, distance=d) for i, d in sorted(r.items())]))
        for k, r in enumerate(rows)])
    binds = TRACK_BINDINGS + "near = 'min(/tracks.tracks[:]{id==$track}.distance) < 0.5'\n"
    plan = _plan(tmp, f"R: {fret}\n", binds)

    def seen(la):
        return {v.requirement: (v.verdict, v.ltl3.status if v.ltl3 else None,
                                v.ltl3.tick if v.ltl3 else None, v.ticks_evaluated)
                for v in la.verdicts}

    fast = audit_log(plan, str(log))
    with monkeypatch.context() as m:
        m.setattr(E, "batchable", lambda plan, r: None)
        slow = audit_log(plan, str(log))
    assert seen(fast) == seen(slow), (rows, fret)
    nan = {f"R[track={i}]" for r in rows for i, d in r.items() if d != d}
    engines = {v.engine for v in fast.verdicts[1:]
               if v.verdict in ("satisfied", "vacuous") and v.requirement not in nan}
    assert engines <= {"vectorized"}  # (an entity that reads NaN: judged alone)
    return seen(fast)


@pytest.mark.parametrize("config", [{"max_entities": 2}])
def test_the_bound_in_the_plan(tmp_path, config):
    Track, TrackArray = _track_types()
    log = write_mcap(tmp_path / "t.mcap", [
        ("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
         TrackArray(tracks=[Track(id=k % 3, distance=0.2)])) for k in range(6)])
    plan = _plan(tmp_path, "T: in present mode the robot shall always satisfy dist > 1\n",
                 TRACK_BINDINGS, **config)
    got = _by_id(audit_log(plan, str(log)))
    assert list(got) == ["T", "T[track=0]", "T[track=1]", "T[track=...]"]
    assert got["T"].verdict == "violated"  # a judged entity violates it: decided
    assert dataclasses.replace(plan.config).max_entities == 2
