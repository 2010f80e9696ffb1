"""Metamorphic tests of the audit on every log the tests have: the verdicts are what the
field data say, whatever else is audited beside them, in which order, how, in which
encoding, and whatever damage lies elsewhere (../shared/DESIGN.md, "Each verdict stands
alone", "Damage is a gap").

The logs: the shipped runs (``traces/``) with the shipped requirements, the real logs of
``../shared/data/logs`` with ``requirements/real_logs``, and every foreign log (ROS 1 bags,
MCAP, PX4 ULog) and MCAP conformance file of ``../shared/data`` with requirement sets drawn
from what ``fretc inspect`` lists of them (``_metamorphic.generated_set``: bindings using
every function and modifier of the binding language; hypothesis draws more). The relations,
each comparing the whole per-requirement JSON (``log`` and ``source`` aside):

1. each requirement audited alone (its own file) = in its set;
2. the order of the requirements and of the binding entries changes nothing;
3. ``-j 1`` = ``-j 2`` (the Ray path: tests/audit/test_fleet.py, marker ``ray``);
4. the same log re-encoded (json, protobuf; ROS 1: ``nominal_ros1.mcap``; CSV of the
   sampled variables: tests/audit/test_sampled_csv.py) gives the same verdicts;
5. a log cut in two with a gap between the halves (a chunk failing its CRC) agrees with the
   whole wherever it is decided: never a verdict the whole contradicts, and every violation
   the whole decides before the gap;
6. a corrupted chunk elsewhere never turns a violation into anything else;
7. ``fretc watch`` over a replay = ``fretc audit`` (tests/live/test_watch.py, on the shipped
   runs);
8. the audit on the tick-by-tick clock of ``fretc watch`` (:func:`fretc.signals.sample_groups`)
   = the audit on its block sampler: the same ticks, the last one included (the first grid
   tick at or after the last message, docs/guide/ticks.md), and the same verdicts;
9. the audit of the CSV that ``--write-csv`` writes of a log gives every requirement (each on
   its own clock of the file) the log's verdict, ticks, unknown ticks and LTL3 verdict
   (with the C runner on it: tests/audit/test_csv_metamorphic.py, relation 10).

The default run takes a bounded sample (a shipped run, a real log, a flight log, a foreign
bag; a few hypothesis examples); ``-m slow`` sweeps every log.
"""

from __future__ import annotations

import itertools
import random
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import _metamorphic as M
from _shared import PRESENT, needs_shared

pytest.importorskip("mcap_protobuf")

ROOT = Path(__file__).resolve().parents[2]
PASSED = ("satisfied", "vacuous")
sys.path.insert(0, str(ROOT / "tests" / "logs"))  # _encode: logs re-encoded


def _cases(full: bool) -> list:
    """(id, Case or (log, seed) to generate) of the sweep, or of the default sample."""
    out = [(c.id, c) for c in M.shipped_cases()]
    out += [(c.id, c) for c in M.real_cases()]
    for log in M.foreign_logs():
        for seed in ((1, 2) if full else (1,)):
            out.append((f"{log.parent.name}/{log.name}#{seed}", (log, seed)))
    for log in M.conformance_logs()[:None if full else 1]:
        out.append((f"conformance/{log.name}#1", (log, 1)))
    if full:
        return out
    sample = {"traces/stop_delay.mcap", "logs/stage_mapping1.bag", "px4/sample.ulg#1",
              "husky/rl_test1.bag#1"}
    return [c for c in out if c[0] in sample]


def _params(full: bool):
    marks = [] if not full else [pytest.mark.slow]
    return [pytest.param(case, id=cid, marks=marks + ([] if cid.startswith("traces/")
                                                      else [needs_shared]))
            for cid, case in _cases(full)]


ALL = _params(True) if PRESENT else _params(False)
SAMPLE = _params(False)


def _case(case) -> M.Case:
    if isinstance(case, M.Case):
        return case
    got = M.generated_case(*case)
    if got is None:
        pytest.skip("the log has no field to bind")
    return got


def _same(a: dict, b: dict, what: str) -> None:
    assert a.keys() == b.keys(), what
    for rid in a:
        assert a[rid] == b[rid], f"{what}: {rid} differs"


# --------------------------------------------------------------------------- 1, 2
def check_alone_and_order(case: M.Case, tmp: Path) -> dict:
    """Relations 1 and 2 on one case; the set's verdicts."""
    whole = M.verdicts(M.audit(M.write(tmp / "set", case), case.log))
    for rid, text in M.alone_files(case.fret):
        # the same file, with the other requirements' lines blank: the same source lines
        alone = M.verdicts(M.audit(M.write(tmp / "set", case, text), case.log))
        assert list(alone) == [rid]
        assert alone[rid] == whole[rid], f"{case.id}: {rid} alone differs from in its set"
    head = M.header(case.fret)
    reqs = M.lines(case.fret)
    shuffled = reqs[:]
    random.Random(case.id).shuffle(shuffled)
    again = M.verdicts(M.audit(M.write(tmp / "set", case, head + "\n".join(
        list(reversed(shuffled))) + "\n", M.reversed_bindings(case.bindings)), case.log))
    _same(again, whole, f"{case.id}: requirements and bindings reordered")
    return whole


@pytest.mark.parametrize("case", SAMPLE)
@pytest.mark.tor("TOR-TCK-001")
def test_each_verdict_alone_and_in_any_order(case, tmp_path):
    check_alone_and_order(_case(case), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("case", ALL)
def test_each_verdict_alone_and_in_any_order_on_every_log(case, tmp_path):
    check_alone_and_order(_case(case), tmp_path)


@needs_shared
@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(log=st.sampled_from(["husky/rl_test1.bag", "px4/sample.ulg", "nav2/nav2_turtlebot.mcap",
                            "tb3_amr/rosbag_demo.bag", "kuka_lwr/test.bag"]),
       seed=st.integers(0, 10_000))
def test_hypothesis_bindings_alone_and_in_any_order(tmp_path_factory, log, seed):
    """Requirement sets drawn by hypothesis over the binding forms, on foreign logs."""
    case = M.generated_case(M.DATA / "foreign_logs" / log, seed)
    if case is not None:
        check_alone_and_order(case, tmp_path_factory.mktemp("h"))


# --------------------------------------------------------------------------- 3
@needs_shared
def test_jobs_change_nothing(tmp_path):
    from fretc.audit import AuditConfig, audit_logs, load_plan

    cases = [M.shipped_cases()[0]] + [_case(c) for _id, c in _cases(False)
                                      if not isinstance(c, M.Case)][:1]
    for case in cases:
        fret = M.write(tmp_path / case.id.replace("/", "_"), case)
        plan = load_plan(AuditConfig(requirements=(str(fret),)))
        logs = [str(case.log)] * 2 + [str(p) for p in sorted((ROOT / "traces").glob("*.mcap"))[:1]]
        one = [la.to_json() for la in audit_logs(plan, logs, jobs=1)]
        two = [la.to_json() for la in audit_logs(plan, logs, jobs=2)]
        assert one == two, case.id


# --------------------------------------------------------------------------- 4
@pytest.mark.parametrize("encoding", ["json", "protobuf"])
@pytest.mark.tor("TOR-LOG-001")
def test_a_log_re_encoded_gives_the_same_verdicts(encoding, tmp_path):
    """(cbor carries no schema: a LaserScan's ranges are not known as such there, so REP
    117's reading of their infinities does not apply, and verdicts on them differ.)"""
    from _encode import copy_as

    case = next(c for c in M.shipped_cases() if c.log.name == "stop_delay.mcap")
    fret = M.write(tmp_path / "r", case)
    original = M.verdicts(M.audit(fret, case.log))
    copy = copy_as(case.log, tmp_path / f"copy.{encoding}.mcap", encoding)
    _same(M.verdicts(M.audit(fret, copy)), original, f"{case.id} as {encoding}")


def test_the_ros1_encoding_of_a_run_gives_its_verdicts(tmp_path):
    case = next(c for c in M.shipped_cases() if c.log.name == "nominal.mcap")
    fret = M.write(tmp_path / "r", case)
    _same(M.verdicts(M.audit(fret, ROOT / "traces" / "nominal_ros1.mcap")),
          M.verdicts(M.audit(fret, case.log)), "nominal as ROS 1")


# --------------------------------------------------------------------------- 5, 6
def check_gap(case: M.Case, tmp: Path, damaged: Path, gap: tuple[int, int, frozenset]) -> None:
    """The damaged copy's verdicts against the intact log's (relations 5 and 6)."""
    fret = M.write(tmp / "r", case)
    whole = M.verdicts(M.audit(fret, case.log))
    got = M.verdicts(M.audit(fret, damaged))
    start = gap[0]
    for rid, v in got.items():
        w = whole[rid]
        who = f"{case.id} {rid} (gap from {start})"
        if v["verdict"] == "violated":
            assert w["verdict"] == "violated", f"{who}: violated, the whole log is {w['verdict']}"
        if v["verdict"] in PASSED:
            assert w["verdict"] in PASSED, f"{who}: {v['verdict']}, the whole is {w['verdict']}"
        l3 = w.get("ltl3") or {}
        decided = l3.get("time_ns") if l3.get("status") == "violated" else None
        if w["verdict"] == "violated" and decided is not None and decided < start and \
                w["first_tick_ns"] == v["first_tick_ns"]:
            assert v["verdict"] == "violated", f"{who}: {v['verdict']}, but violated at " \
                                               f"{decided} before the gap"


def _mcap_cases(full: bool) -> list:
    return [p for p in _params(full)
            if (p.values[0].log if isinstance(p.values[0], M.Case) else p.values[0][0]
                ).suffix == ".mcap"]


@pytest.mark.parametrize("case", _mcap_cases(False))
@pytest.mark.tor("TOR-DMG-002")
def test_a_log_cut_in_two_with_a_gap_agrees_with_the_whole(case, tmp_path):
    case = _case(case)
    halves = M.rechunked(case.log, tmp_path / "rechunked.mcap")
    gap = M.corrupt_chunk(halves, tmp_path / "halves.mcap", 0.5)
    if gap is None:
        pytest.skip("too few chunks")
    check_gap(M.Case(case.id, halves, case.fret, case.bindings), tmp_path,
              tmp_path / "halves.mcap", gap)


@pytest.mark.slow
@pytest.mark.parametrize("case", _mcap_cases(True))
@pytest.mark.parametrize("where", [0.2, 0.5, 0.8])
def test_a_corrupted_chunk_never_hides_a_violation_elsewhere(case, where, tmp_path):
    case = _case(case)
    gap = M.corrupt_chunk(case.log, tmp_path / "bad.mcap", where)
    if gap is None:
        pytest.skip("too few chunks")
    check_gap(case, tmp_path, tmp_path / "bad.mcap", gap)


@pytest.mark.tor("TOR-DMG-001", "TOR-VER-004")
def test_a_violation_after_a_corrupted_chunk_is_violated(tmp_path):
    """The issue's MCAP: a chunk corrupted at 30 % of the run, a violation at 80 %: still
    violated, with the same first violation; an invariant that holds on every message read
    is unknown, the gap named."""
    from _logs import S, float64, write_mcap

    msgs = [("/v", "std_msgs/msg/Float64", S + k * S // 10,
             float64(9.0 if k == 240 else 1.0)) for k in range(300)]
    msgs += [("/w", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0)) for k in range(300)]
    log = write_mcap(tmp_path / "v.mcap", sorted(msgs, key=lambda m: (m[2], m[0])),
                     chunk_size=2048)
    case = M.Case("v", log, "RV: the sys shall always satisfy v < 5\n"
                            "RW: the sys shall always satisfy w < 5\n",
                  '[tick]\nperiod = "100 ms"\n[variables]\nv = "/v.data"\nw = "/w.data"\n')
    gap = M.corrupt_chunk(log, tmp_path / "bad.mcap", 0.3)
    assert gap is not None and gap[1] < S + 240 * S // 10
    fret = M.write(tmp_path / "r", case)
    whole, got = (M.verdicts(M.audit(fret, p)) for p in (log, tmp_path / "bad.mcap"))
    assert got["RV"]["verdict"] == "violated"
    assert got["RV"]["first_violation"]["tick_time_ns"] == \
        whole["RV"]["first_violation"]["tick_time_ns"] == S + 240 * S // 10
    assert got["RW"]["verdict"] == "unknown" and "chunk" in got["RW"]["unknown_reason"]
    assert got["RW"]["unknown_ticks"] > 0


# --------------------------------------------------------------------------- 8, 9
def check_watch_clock_and_csv(case: M.Case, tmp: Path, monkeypatch) -> None:
    """Relations 8 and 9 on one case."""
    import fretc.audit.passes as passes
    from fretc.audit import AuditConfig, audit_log, load_plan
    from fretc.audit.sampled.csv import write_sampled_csv

    fret = M.write(tmp / "r", case)
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    la = audit_log(plan, str(case.log))
    whole = M.verdicts(la.to_json())
    with monkeypatch.context() as m:
        m.setattr(passes, "sample_blocks", M.tick_by_tick)
        _same(M.verdicts(M.audit(fret, case.log)), whole, f"{case.id}: the watch's clock")
    try:
        write_sampled_csv(plan, str(case.log), tmp / "s.csv")
    except ValueError:
        return  # no bound variable to write
    csv = M.verdicts(M.audit(fret, tmp / "s.csv"))

    def seen(v: dict) -> dict:  # (every requirement on its own clock of the file)
        ltl3 = v["ltl3"] or {}
        return {"ltl3": (ltl3.get("status"), ltl3.get("tick")),
                **{k: v[k] for k in ("verdict", "ticks_evaluated", "unknown_ticks")}}

    for rid, v in whole.items():
        if v["verdict"] != "error":
            assert seen(csv[rid]) == seen(v), f"{case.id}: {rid} on its sampled CSV"
        else:
            assert csv[rid]["verdict"] == "error", f"{case.id}: {rid} on its sampled CSV"


@pytest.mark.parametrize("case", SAMPLE)
@pytest.mark.tor("TOR-LOG-001", "TOR-WCH-001")
def test_the_watch_clock_and_the_sampled_csv_give_the_audit(case, tmp_path, monkeypatch):
    check_watch_clock_and_csv(_case(case), tmp_path, monkeypatch)


@pytest.mark.slow
@pytest.mark.parametrize("case", ALL)
def test_the_watch_clock_and_the_sampled_csv_give_the_audit_on_every_log(case, tmp_path,
                                                                         monkeypatch):
    check_watch_clock_and_csv(_case(case), tmp_path, monkeypatch)


# --------------------------------------------------------------------------- generation
#: the geometry of scans, clouds and polygons: tests/signals/test_geometry.py judges them on
#: the raw scans of a shipped trace, TF and generated clouds
GEOMETRY = ("scan_points", "cloud_points", "polygon", "points_in", "collision_time")


def test_the_generated_sets_use_every_function_and_modifier():
    """The forms the sweep draws from cover the binding language's functions and
    modifiers (a new function must be added to them)."""
    from fretc.signals.bindings.expression import FUNCS, MODIFIERS

    text = " ".join(M.NUMBER_FORMS + M.ARRAY_FORMS + M.BOOL_FORMS)
    missing = [f for f in FUNCS if f"{f}(" not in text and f not in ("any", "all", "joint",
                                                                     "tf", "waiting", "goal_waiting",
                                                                     "sector",
                                                                     *GEOMETRY)]
    missing += [m for m in MODIFIERS if f"@{m}" not in text]
    assert missing == []
    # any/all over items, joint() and tf() need arrays of names and transforms: the robot
    # log of docs/bindings.md binds them (tests/docs/test_bindings_examples.py); waiting()
    # and goal_waiting() a service's or an action's topics (tests/signals/test_services.py);
    # sector() a LaserScan's ranges with its angles (tests/signals/test_sector.py: on every
    # shipped trace, the sectors equal the beam slices at every tick)


def test_a_generated_set_is_the_same_for_the_same_seed():
    doc = {"duration_s": 10.0, "topics": [
        {"topic": "/a", "messages": 10, "fields": {
            "/a.x": {"type": "float64", "min": 0.0, "max": 2.0},
            "/a.ok": {"type": "bool", "true": 3, "false": 7},
            "/a.r": {"type": "float32[]", "min": 0.1, "max": 5.0, "lengths": [4, 4]}}}]}
    one, two = M.generated_set(doc, 7), M.generated_set(doc, 7)
    assert one == two and M.generated_set(doc, 8) != one
    fret, bindings = one
    assert len(M.lines(fret)) == 4 and bindings.startswith("[tick]\n")
    assert all(itertools.chain(f"v{i} =" in bindings for i in range(8)))
