"""Per-entity requirements in ``fretc watch`` (docs/bindings.md, "One verdict per entity"):
a foxglove-sdk server on 127.0.0.1 publishes a ``/tracks`` topic whose track ids appear and
disappear (the messages of a generated MCAP, replayed); the watch gives one verdict per track
(ids, verdicts, first violations) equal to ``fretc audit``'s of the same MCAP and to a
recomputation in plain Python from the published values, and the verdict over all tracks."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from _logs import DIAG_BINDINGS, ROS2, S, TRACK_BINDINGS, float64, write_mcap  # noqa: E402
from _logs import track_types as _types  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.live.websocket.serve import FoxgloveServer, advertise_mcap, replay_mcap  # noqa: E402
from test_watch import _watch_trace, jsonl_finals  # noqa: E402

pytestmark = pytest.mark.watch

BINDINGS = TRACK_BINDINGS + "slow = '/speed.data < 2'\n"
FRET_T = "T: in present mode the robot shall always satisfy dist > 0.5\n"
FRET_P = "P: the robot shall always satisfy slow\n"

#: track id -> distance per message (every 100 ms): ids appear, disappear and come back
ROWS = [{1: 2.0}, {1: 2.0, 2: 0.8}, {2: 0.8, 3: 2.0}, {2: 0.4, 3: 2.0}, {3: 2.0}, {},
        {1: 0.3}, {4: 2.0}, {4: 2.0, 3: 0.9}, {4: 0.9}, {5: 1.5, 4: 0.7}, {5: 1.5},
        {}, {6: 0.2, 5: 1.0}, {5: 1.0}, {5: 0.6, 3: 2.0}, {3: 0.5}, {}, {7: 3.0}, {7: 3.0}]
SPEED = [1.0] * 9 + [2.5] + [1.0] * 10  # P violated at message 9




def _log(tmp: Path, rows, speed=None) -> Path:
    Track, TrackArray = _types()
    msgs = []
    for k, r in enumerate(rows):
        t = S + k * S // 10
        msgs.append(("/tracks", "tracking_msgs/msg/TrackArray", t,
                     TrackArray(tracks=[Track(id=i, distance=d) for i, d in r.items()])))
        if speed is not None:
            msgs.append(("/speed", "std_msgs/msg/Float64", t, float64(speed[k])))
    return write_mcap(tmp / "tracks.mcap", msgs)


def _plan(tmp: Path, fret: str):
    (tmp / "t.fret").write_text("@tick_period 100 ms\n" + fret, encoding="utf-8")
    (tmp / "t.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp / "t.fret"),)))


def _watch(plan, log: Path, record=None, rate=40.0, at=None):
    """Serve the messages of ``log`` on a foxglove-sdk server, then close it: the watch ends
    at the close (bounded: 60 s); ``at(i, watch)`` runs before message ``i``."""
    return _watch_trace(plan, log, rate=rate, record=record,
                        at=(lambda i, _server, w: at(i, w)) if at else None)


def _key(v):
    fv = v.first_violation
    return (v.requirement, v.verdict, v.error,
            None if fv is None else (fv.at.tick, fv.at.time_ns),
            v.ltl3.status, v.violations, v.ticks_evaluated, v.warmup_ticks, tuple(v.notes))


def _recompute(rows):
    """Plain Python over the published values: track id -> log time (ns) of its first
    distance <= 0.5 while present (None: never), in order of first appearance."""
    out = {}
    for k, r in enumerate(rows):
        for i, d in r.items():
            out.setdefault(i, None)
            if d <= 0.5 and out[i] is None:
                out[i] = S + k * S // 10
    return out


def test_watch_gives_one_verdict_per_track_equal_to_the_audit(tmp_path):
    plan = _plan(tmp_path, FRET_T + FRET_P)
    log = _log(tmp_path, ROWS, SPEED)
    w, la, done = _watch(plan, log)
    ref = audit_log(plan, str(log))
    assert done["sent"] == 2 * len(ROWS) and la.error is None and not la.partial
    assert "/tracks" in w.needed and "/speed" in w.needed
    # the watch's verdicts are the audit's, entity by entity and over all entities
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
    got = {v.requirement: v for v in la.verdicts}
    # and a recomputation from the published values
    want = _recompute(ROWS)
    assert [v.requirement for v in la.verdicts] == (
        ["P", "T"] + [f"T[track={i}]" for i in want])
    for i, bad in want.items():
        v = got[f"T[track={i}]"]
        assert v.verdict == ("violated" if bad else "satisfied"), (i, v.error, v.notes)
        if bad:  # ticks counted from the entity's first message (its life)
            seen = S + next(k for k, r in enumerate(ROWS) if i in r) * S // 10
            assert v.first_violation.at.time_ns == bad
            assert v.first_violation.at.tick == (bad - seen) // (S // 10)
    assert got["T"].verdict == "violated"
    first = min(t for t in want.values() if t is not None)
    assert got["T"].first_violation.at.time_ns == first
    assert "violated by: " + ", ".join(f"T[track={i}]" for i, t in want.items() if t) in (
        got["T"].notes)
    # the ordinary requirement on another topic is still watched live
    assert got["P"].verdict == "violated"
    assert got["P"].first_violation.at.time_ns == S + 9 * S // 10
    assert any(e.kind == "ltl3" and e.requirement == "P" for e in w.events)
    finals = {e.requirement: e.verdict for e in w.events if e.kind == "final"}
    assert finals == {v.requirement: v.verdict for v in ref.verdicts}


def test_watch_of_per_entity_requirements_only(tmp_path):
    """No ordinary requirement: the watch still reads the run (every track satisfies it);
    its recording audits to the same verdicts."""
    rows = [{1: 2.0}, {1: 2.0, 2: 0.9}, {2: 0.9}, {}, {3: 1.0}, {3: 1.0, 1: 0.7}]
    plan = _plan(tmp_path, FRET_T)
    log = _log(tmp_path, rows)
    _w, la, _done = _watch(plan, log, record=str(tmp_path / "watched.mcap"))
    ref = audit_log(plan, str(log))
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
    again = audit_log(plan, str(tmp_path / "watched.mcap"))
    assert [_key(v) for v in again.verdicts] == [_key(v) for v in ref.verdicts]
    assert [(v.requirement, v.verdict) for v in la.verdicts] == [
        ("T", "satisfied"), ("T[track=1]", "satisfied"), ("T[track=2]", "satisfied"),
        ("T[track=3]", "satisfied")]


def test_watch_with_no_entity_is_vacuous(tmp_path):
    plan = _plan(tmp_path, FRET_T)
    log = _log(tmp_path, [{}, {}, {}])
    _w, la, _done = _watch(plan, log)
    ref = audit_log(plan, str(log))
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
    assert [(v.requirement, v.verdict) for v in la.verdicts] == [("T", "vacuous")]


def test_watch_judges_at_most_max_entities(tmp_path):
    """The audit's bound (--max-entities) holds in the watch: past it, an error verdict
    says how to raise it."""
    import dataclasses

    plan = _plan(tmp_path, FRET_T)
    plan = dataclasses.replace(plan, config=dataclasses.replace(plan.config, max_entities=3))
    log = _log(tmp_path, ROWS)
    _w, la, _done = _watch(plan, log)
    ref = audit_log(plan, str(log))
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
    assert [v.requirement for v in la.verdicts] == ["T", "T[track=1]", "T[track=2]",
                                                    "T[track=3]", "T[track=...]"]
    assert "only the first 3 are judged (raise the bound with --max-entities)" in (
        la.verdicts[-1].error)


def test_a_gap_is_never_a_pass_for_an_entity(tmp_path):
    """The connection drops mid-run: a track violated before the gap stays violated, every
    other per-entity verdict is unknown (what was lost is not judged as if not sent)."""
    plan = _plan(tmp_path, FRET_T + FRET_P)
    log = _log(tmp_path, ROWS, SPEED)
    state = {}

    def at(i, w):
        if i == 20 and not state:  # row 10: the network fails, the server goes on
            state["drop"] = True
            w.client.drop()

    _w, la, _done = _watch(plan, log, rate=5.0, at=at)
    assert state and la.partial and la.damage_time_ns is not None
    got = {v.requirement: v for v in la.verdicts}
    assert got["T[track=2]"].verdict == "violated"  # at row 3, before the gap
    assert got["T"].verdict == "violated"
    for name, v in got.items():
        if name.startswith("T"):
            assert v.partial
            assert v.verdict in ("violated", "unknown"), (name, v.verdict)
            if v.verdict == "violated":
                assert v.first_violation.at.time_ns < la.damage_time_ns
            else:
                assert "damaged from log time" in v.unknown_reason
    # satisfied over the messages used (track 7 after the gap, at least): unknown
    assert any(v.verdict == "unknown" for n, v in got.items() if n.startswith("T["))


def test_cli_watch_prints_and_exits_with_the_per_entity_verdicts(tmp_path):
    """``fretc watch --jsonl --json``: one ``final`` event per verdict, the audit JSON of the
    per-entity verdicts, exit 1 (a track violates T)."""
    import json

    from click.testing import CliRunner

    from fretc.cli import main

    _plan(tmp_path, FRET_T)
    log = _log(tmp_path, ROWS)
    server = FoxgloveServer(port=0)
    try:
        advertise_mcap(str(log), server)

        def publish():
            try:
                server.wait_subscribed({"/tracks"}, timeout=20)
                replay_mcap(str(log), server, 40.0)
                time.sleep(0.3)
            finally:
                server.stop()

        t = threading.Thread(target=publish, daemon=True)
        t.start()
        res = CliRunner().invoke(main, ["watch", server.url, "-r", str(tmp_path / "t.fret"),
                                        "--jsonl", "--no-live", "--duration", "60",
                                        "--json", str(tmp_path / "w.json")])
        t.join(20)
    finally:
        server.stop()
    assert res.exit_code == 1, res.output
    lines, finals = jsonl_finals(res.output)
    ref = {v.requirement: v.verdict for v in audit_log(_plan(tmp_path, FRET_T),
                                                        str(log)).verdicts}
    assert finals == ref and finals["T[track=2]"] == "violated"
    doc = json.loads((tmp_path / "w.json").read_text())
    got = {v["requirement"]: v["verdict"] for lg in doc["logs"] for v in lg["verdicts"]}
    assert got == ref


def test_a_key_topic_never_advertised_is_an_error_not_vacuous(tmp_path):
    """The server never advertises /tracks: T is an error naming it (as a watch's other
    requirements reading a topic not advertised), never vacuous over no entity; P is
    watched."""
    plan = _plan(tmp_path, FRET_T + FRET_P)
    log = write_mcap(tmp_path / "speed.mcap", [
        ("/speed", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0)) for k in range(10)])
    _w, la, _done = _watch(plan, log)
    got = {v.requirement: v for v in la.verdicts}
    assert list(got) == ["P", "T"]
    assert got["P"].verdict == "satisfied"
    assert got["T"].verdict == "error" and "topic /tracks is not advertised" in got["T"].error
    assert "not_advertised" in {p["kind"] for p in la.problems}


def _diagnostics_log(tmp: Path) -> Path:
    """The motors of tests/audit/test_entities.py: entities by name, through a glob."""
    St = ROS2.types["diagnostic_msgs/msg/DiagnosticStatus"]
    Arr, H = ROS2.types["diagnostic_msgs/msg/DiagnosticArray"], ROS2.types["std_msgs/msg/Header"]
    Time = ROS2.types["builtin_interfaces/msg/Time"]
    rows = [[("motor_l", 0)], [("motor_l", 0), ("motor_r", 1)], [("motor_r", 2)],
            [("lidar", 2)], [("motor_l", 0), ("motor_3", 1)], [("motor_3", 2)]]
    msgs = [("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", S + k * S // 10,
             Arr(header=H(stamp=Time(sec=0, nanosec=0), frame_id=""),
                 status=[St(level=lvl, name=n, message="", hardware_id="", values=[])
                         for n, lvl in r + [("battery", 0)]]))
            for k, r in enumerate(rows)]
    return write_mcap(tmp / "diag.mcap", msgs)


FRET_M = "M: in present mode the robot shall always satisfy motor_level < 2\n"


def _evidence(v):
    """A verdict as the metamorphic test compares it (an error's text names the log or the
    server: only that there is one)."""
    fv = v.first_violation
    return (v.requirement, v.verdict, v.error is not None,
            None if fv is None else (fv.at.tick, fv.at.time_ns), v.violations,
            v.ticks_evaluated, v.warmup_ticks)


@pytest.mark.parametrize("case", ["tracks", "tracks_and_speed", "no_entity", "motors",
                                  "key_topic_absent"])
def test_audit_and_watch_give_the_same_per_entity_verdicts(tmp_path, case):
    """Metamorphic: one per-entity requirement over one log, audited and watched (the log
    replayed on a server), gives the same verdicts entity by entity, on every log of the
    entity tests; a key topic absent from the log is an error in both (as a plain
    requirement's absent topic), never vacuous."""
    if case == "motors":
        (tmp_path / "t.fret").write_text("@tick_period 100 ms\n" + FRET_M, encoding="utf-8")
        (tmp_path / "t.bindings.toml").write_text(DIAG_BINDINGS, encoding="utf-8")
        plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
        log = _diagnostics_log(tmp_path)
    else:
        speed = case in ("tracks_and_speed", "key_topic_absent")
        plan = _plan(tmp_path, FRET_T + (FRET_P if speed else ""))
        log = {"tracks": lambda: _log(tmp_path, ROWS),
               "tracks_and_speed": lambda: _log(tmp_path, ROWS, SPEED),
               "no_entity": lambda: _log(tmp_path, [{}, {}, {}]),
               "key_topic_absent": lambda: write_mcap(tmp_path / "speed.mcap", [
                   ("/speed", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0))
                   for k in range(10)])}[case]()
    _w, la, _done = _watch(plan, log)
    ref = audit_log(plan, str(log))
    assert [_evidence(v) for v in la.verdicts] == [_evidence(v) for v in ref.verdicts]
    verdicts = {v.requirement: v.verdict for v in ref.verdicts}
    if case == "key_topic_absent":
        assert verdicts["T"] == "error" and "/tracks" in ref.verdicts[-1].error
    elif case == "no_entity":
        assert verdicts == {"T": "vacuous"}
    else:
        assert len(verdicts) > 2  # the entities were judged


@pytest.mark.parametrize("case", ["tracks", "motors"])
def test_live_events_per_entity_agree_with_the_final_verdicts(tmp_path, case):
    """Each entity's ``pt``/``ltl3`` events are made while watching, named by the instance:
    an entity's first ``ltl3`` violated event is at its final verdict's first violation (tick
    and time); an entity that satisfies the requirement has none; the ``pt`` violations of
    an entity are at ticks of its own clock."""
    if case == "motors":
        (tmp_path / "t.fret").write_text("@tick_period 100 ms\n" + FRET_M, encoding="utf-8")
        (tmp_path / "t.bindings.toml").write_text(DIAG_BINDINGS, encoding="utf-8")
        plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
        log, base = _diagnostics_log(tmp_path), "M"
    else:
        plan, log, base = _plan(tmp_path, FRET_T), _log(tmp_path, ROWS), "T"
    w, la, _done = _watch(plan, log)
    finals = {v.requirement: v for v in la.verdicts if v.requirement.startswith(base + "[")}
    assert finals and any(v.verdict == "violated" for v in finals.values())
    ltl3 = {}
    for e in w.events:
        if e.kind == "ltl3" and e.verdict == "violated":
            ltl3.setdefault(e.requirement, (e.extra["status_tick"], e.time_ns))
    assert set(ltl3) <= set(finals)  # named by the instance, never the plain id
    for name, v in finals.items():
        if v.verdict == "violated":
            fv = v.first_violation
            assert ltl3[name][0] == fv.at.tick, (name, ltl3[name], fv.at)
            assert ltl3[name][1] >= fv.at.time_ns
        else:
            assert name not in ltl3, (name, v.verdict)
    pts = [e for e in w.events if e.kind == "pt" and e.requirement in finals]
    assert pts and all(e.verdict in ("holds", "violated") for e in pts)


@pytest.mark.parametrize("form", ["filter", "held", "tf", "tf_without_static"])
def test_watch_of_cars_alternating_on_tf_equals_the_audit(tmp_path, form):
    """Two cars whose transforms alternate on /tf (tests/audit/test_entities_held.py),
    served on a Foxglove server and watched: the per-entity verdicts the watch gives at the
    end equal the audit's of the same messages. The filter form: the ego car read at no tick
    (``unknown``, never a silent pass); held on its own or through ``tf("map", $car)``: the
    ego car violated, C1 violated; ``tf()`` judged on /tf alone when the server has no
    /tf_static (after the watch's wait for it)."""
    from _arena import C1, FILTER, HELD, TF, arena_log

    (tmp_path / "c.fret").write_text("@tick_period 100 ms\n" + C1, encoding="utf-8")
    (tmp_path / "c.bindings.toml").write_text(
        {"filter": FILTER, "held": HELD, "tf": TF, "tf_without_static": TF}[form],
        encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "c.fret"),)))
    log = arena_log(tmp_path / "arena.mcap", static=form != "tf_without_static")
    _w, la, _done = _watch(plan, log, rate=200.0)
    ref = audit_log(plan, str(log))
    assert [_evidence(v) for v in la.verdicts] == [_evidence(v) for v in ref.verdicts]
    got = {v.requirement: v.verdict for v in la.verdicts}
    want = "unknown" if form == "filter" else "violated"
    assert got == {"C1": want, "C1[car=car_other]": "satisfied", "C1[car=car_ego]": want}
