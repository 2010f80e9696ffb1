"""``fretc audit --write-csv`` of per-entity requirements (audit/sampled/entities.py): every
entity is a clock of the file, so the audit of the CSV gives the log's verdicts, verdict for
verdict (the requirement's over its entities and each entity's: verdict, LTL3 verdict and
tick, ticks evaluated, unknown ticks, in the log's order), and the C monitors' runner on it
gives every entity and every requirement the log's verdict (``unknown`` where it stops at an
unread tick). On random logs of tracked objects (numeric keys) and diagnostics (text keys
with a filter), a damaged one (truncated: unknown entities), parameters logged once
(DataFlash), entities past ``--max-entities``, no entity at all, a key topic absent, and the
joints of a real arm's bag (../shared)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _c_monitors import build, c_compiler
from _logs import DIAG_BINDINGS, S, TRACK_BINDINGS, diag_array, write_mcap
from _logs import track_types as _track_types
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.sampled.csv import write_sampled_csv
from fretc.cli import main
from fretc.logs.csv.source import per_entity_lines, unescape_id

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "foreign_logs"
DECIDED = ("satisfied", "vacuous", "violated")

TRACKS = TRACK_BINDINGS + "near = 'min(/tracks.tracks[:].distance) < 0.5'\n"
TRACK_FRET = ("@tick_period 100 ms\n"
              "T: in present mode the robot shall always satisfy dist > 0.5\n"
              "U: upon present the robot shall within 3 ticks satisfy dist > 1.5\n"
              "N: the robot shall always satisfy !near\n")


def _tracks_log(path: Path, rows: list[dict[int, float]], **kw) -> Path:
    Track, TrackArray = _track_types()
    return write_mcap(path, [("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10,
                              TrackArray(tracks=[Track(id=i, distance=d)
                                                 for i, d in sorted(r.items())]))
                             for k, r in enumerate(rows)], **kw)


def _seen(v) -> tuple:
    return (v.requirement, v.verdict, v.ltl3.status if v.ltl3 else None,
            v.ltl3.tick if v.ltl3 else None,
            v.ticks_evaluated if v.verdict != "error" else None, v.unknown_ticks)


_RUNNERS: dict[str, Path | None] = {}


def _runner(fret: Path, tmp: Path) -> Path | None:
    """The C runner of ``fret``'s requirements (built once per text)."""
    text = fret.read_text()
    if text not in _RUNNERS:
        if c_compiler() is None:
            _RUNNERS[text] = None
        else:
            folder = tmp / "c"
            res = CliRunner().invoke(main, [str(fret), "--emit", "c", "-o", str(folder)])
            assert res.exit_code == 0, res.output
            _RUNNERS[text] = build(folder, sorted(p.name for p in folder.glob("*.c")), "runner",
                                   sanitize=False)
    return _RUNNERS[text]


def check(fret: Path, log: Path, tmp: Path, **config) -> list:
    """The relation on one log; the log's verdicts."""
    plan = load_plan(AuditConfig(requirements=(str(fret),), **config))
    la = audit_log(plan, str(log))
    csv = tmp / "s.csv"
    write_sampled_csv(plan, str(log), csv)
    got = audit_log(plan, str(csv))
    assert [_seen(v) for v in got.verdicts] == [_seen(v) for v in la.verdicts]
    exe = _runner(fret, tmp)
    if exe is None:
        return la.verdicts
    run = subprocess.run([str(exe), str(csv)], capture_output=True, text=True)
    assert run.returncode in (0, 1, 2, 3) and not run.stderr, run.stderr
    words = {v.requirement: v.verdict for v in la.verdicts}
    said = {}
    for row in run.stdout.splitlines():
        rid, word, *rest = row.split("\t")
        rid = unescape_id(rid)  # (the runner prints a backslash, a control byte as \xNN)
        said[rid] = word
        unread = any(c.startswith("unread=") for c in rest)
        if word in DECIDED or not unread:
            assert word == words[rid], (rid, row, words[rid])
        else:
            assert word == "unknown", row
    assert set(words) <= set(said), set(words) - set(said)  # every entity has its line
    return la.verdicts


@settings(max_examples=10, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.dictionaries(st.integers(1, 5), st.sampled_from([0.2, 0.8, 2.0]),
                                     max_size=3), min_size=2, max_size=20))
def test_tracked_objects_written_as_a_csv_give_the_audit_of_the_log(tmp_path_factory, rows):
    tmp = tmp_path_factory.mktemp("trk")
    (tmp / "t.fret").write_text(TRACK_FRET)
    (tmp / "t.bindings.toml").write_text(TRACKS)
    verdicts = check(tmp / "t.fret", _tracks_log(tmp / "t.mcap", rows), tmp)
    ids = list(dict.fromkeys(i for r in rows for i in sorted(r)))
    assert sum(v.requirement.startswith("T[") for v in verdicts) == len(ids)


DIAG = DIAG_BINDINGS


def _diag(statuses):
    return diag_array(statuses)


@settings(max_examples=8, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.lists(st.tuples(st.sampled_from(["motor l", "motor,r", "motor\\3",
                                                            "lidar"]), st.integers(0, 2)),
                              max_size=4, unique_by=lambda x: x[0]), min_size=2, max_size=20))
def test_text_keys_written_as_a_csv_give_the_audit_of_the_log(tmp_path_factory, rows):
    """Entity names with a space, a comma and a backslash: escaped in the file, named as
    the audit of the log names them by the audit of the CSV and the runner."""
    tmp = tmp_path_factory.mktemp("diag")
    (tmp / "d.fret").write_text("@tick_period 100 ms\n"
                                "M: in present mode the robot shall always satisfy "
                                "motor_level < 2\n")
    (tmp / "d.bindings.toml").write_text(DIAG)
    log = write_mcap(tmp / "d.mcap", [("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray",
                                       S + k * S // 10, _diag(r)) for k, r in enumerate(rows)])
    check(tmp / "d.fret", log, tmp)


def test_a_truncated_log_gives_the_same_unknown_entities(tmp_path):
    """The log cut in its middle: the entities alive at the cut are unknown past it, on
    the log, on its CSV and in the runner alike."""
    rows = [{1: 2.0, 2: 2.0 if k < 30 else 0.2, 3: 1.0} for k in range(120)]
    whole = _tracks_log(tmp_path / "w.mcap", rows, chunk_size=2048)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole.read_bytes()[:int(whole.stat().st_size * 0.55)])
    (tmp_path / "t.fret").write_text(TRACK_FRET)
    (tmp_path / "t.bindings.toml").write_text(TRACKS)
    verdicts = {v.requirement: v for v in check(tmp_path / "t.fret", cut, tmp_path)}
    assert verdicts["T[track=1]"].partial and verdicts["T[track=2]"].verdict == "violated"
    assert "cut" in (tmp_path / "s.csv").read_text()


def test_parameters_logged_once_are_each_a_clock(tmp_path):
    """ArduPilot's parameters, each logged once: each judged on its clock of one tick, the
    out-of-range ones violated, on the CSV as on the log."""
    import sys

    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    from _dataflash import write_dataflash

    bad = {7: 250.0, 123: -3.0}
    rows = [("PARM", [1_000_000 + k * 3, f"P_{k:04d}", bad.get(k, float(k % 100))])
            for k in range(200)]
    log = write_dataflash(tmp_path / "params.bin", rows)
    (tmp_path / "p.fret").write_text("@tick_period 100 ms\n"
                                     "P: the copter shall always satisfy value >= 0 & value <= 200\n")
    (tmp_path / "p.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[entities]\nparam = \'"PARM".Name\'\n[variables]\n'
        'value = \'"PARM"{Name==$param}.Value\'\n')
    got = {v.requirement: v.verdict for v in check(tmp_path / "p.fret", log, tmp_path)}
    assert got["P"] == "violated" and len(got) == 201
    assert {k for k, w in got.items() if w == "violated"} == {"P", "P[param=P_0007]",
                                                              "P[param=P_0123]"}
    name, ids = per_entity_lines(tmp_path / "s.csv")["P"]
    assert name == "param" and len(ids) == 200


def test_entities_past_the_bound_and_none_at_all(tmp_path):
    """Past --max-entities: the entities judged are clocks, the rest a not-sampled
    ``T[track=...]`` error; the requirement violated by one of them all the same. No
    entity at all: vacuous. A key topic absent: an error."""
    (tmp_path / "t.fret").write_text(TRACK_FRET)
    (tmp_path / "t.bindings.toml").write_text(TRACKS)
    rows = [{i: 0.2 if i == 2 and k == 3 else 2.0 for i in range(1, 8)} for k in range(6)]
    got = {v.requirement: v for v in check(tmp_path / "t.fret", _tracks_log(
        tmp_path / "b.mcap", rows), tmp_path, max_entities=5)}
    assert got["T"].verdict == "violated" and got["T[track=...]"].verdict == "error"
    got = {v.requirement: v.verdict for v in check(tmp_path / "t.fret", _tracks_log(
        tmp_path / "none.mcap", [{}, {}, {}]), tmp_path)}
    assert got == {"T": "vacuous", "U": "vacuous", "N": "satisfied"}
    from _logs import float64

    got = {v.requirement: v.verdict for v in check(tmp_path / "t.fret", write_mcap(
        tmp_path / "other.mcap", [("/speed", "std_msgs/msg/Float64", S, float64(1.0))]),
        tmp_path)}
    assert got == {"N": "error", "T": "error", "U": "error"}


@pytest.mark.skipif(not (SHARED / "kuka_lwr" / "test.bag").exists(),
                    reason="needs ../shared/data/foreign_logs/kuka_lwr/test.bag")
def test_the_joints_of_a_real_arm(tmp_path):
    """A real ROS 1 bag of a 7-joint arm, one verdict per joint: the CSV, its audit and
    the runner give the log's verdicts (lwr_arm_3_joint leaves its range)."""
    (tmp_path / "k.fret").write_text(
        "@tick_period 100 ms\n"
        "J: the arm shall always satisfy in_limits\n"
        "U: upon moving the arm shall within 1 second satisfy in_limits\n"
        "V: the arm shall always satisfy slow\n")
    (tmp_path / "k.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[entities]\njoint = "/joint_states.name[:]"\n'
        "[variables]\nin_limits = 'joint(/joint_states.position, $joint) < 1.5'\n"
        "moving = 'abs(joint(/joint_states.velocity, $joint)) > 0.5'\n"
        "slow = 'max(/joint_states.velocity[0:7]) < 1.6'\n")
    got = {v.requirement: v.verdict for v in check(tmp_path / "k.fret",
                                                   SHARED / "kuka_lwr" / "test.bag", tmp_path)}
    assert got["J[joint=lwr_arm_3_joint]"] == got["J"] == "violated"
    assert sum(k.startswith("J[") for k in got) == 7


def test_write_csv_of_per_entity_requirements_only(tmp_path):
    """The command: a set of per-entity requirements only is written (it was refused), the
    terminal counts each requirement's entities, and the file's audit equals the log's."""
    (tmp_path / "t.fret").write_text(TRACK_FRET.replace(
        "N: the robot shall always satisfy !near\n", ""))
    (tmp_path / "t.bindings.toml").write_text(TRACKS)
    log = _tracks_log(tmp_path / "t.mcap", [{1: 2.0, 2: 0.3}, {1: 2.0}, {1: 2.0, 3: 2.0}])
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "t.fret"), str(log),
                                    "--write-csv", str(tmp_path / "out"), "--no-progress"])
    assert res.exit_code == 1, res.output
    assert "T 3 entities" in res.output and "U 3 entities" in res.output
    a = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "t.fret"), str(log),
                                  "--json", "-", "--no-progress"])
    b = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "t.fret"),
                                  str(tmp_path / "out" / "t.csv"), "--json", "-",
                                  "--no-progress"])
    assert a.exit_code == b.exit_code == 1
    import json

    def words(out):
        doc = json.loads(out[out.index("{"):])
        return [(v["requirement"], v["verdict"]) for v in doc["logs"][0]["verdicts"]]

    assert words(a.output) == words(b.output)
    assert ("T[track=2]", "violated") in words(b.output)


def test_a_trace_of_many_clocks_read_once_gives_what_each_clock_read_apart_gives(
        tmp_path, monkeypatch):
    """The audit of a trace of more than SPLIT_CLOCKS clocks reads it once and splits its
    rows by clock (logs/csv/clocks.py): the same verdicts, JSON for JSON, as each clock read
    from the file; a file whose rows are not a trace of several clocks (a time going
    backwards, a clock no line names) is read clock by clock, whose errors name the line."""
    import json

    import fretc.audit.log as L

    (tmp_path / "t.fret").write_text(TRACK_FRET)
    (tmp_path / "t.bindings.toml").write_text(TRACKS)
    rows = [{i: (0.2 if (i, k) == (3, 7) else 0.8 if i == 5 else 2.0) for i in range(1 + k % 4,
                                                                          6 + k % 3)}
            for k in range(40)]
    log = _tracks_log(tmp_path / "t.mcap", rows)
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
    csv = tmp_path / "s.csv"
    write_sampled_csv(plan, str(log), csv)
    from fretc.logs.csv.source import clock_lines

    assert len(clock_lines(csv)) > L.SPLIT_CLOCKS

    def dump(path):
        return json.dumps(audit_log(plan, str(path)).to_json(), sort_keys=True)

    once = dump(csv)
    monkeypatch.setattr(L, "SPLIT_CLOCKS", 10**9)
    assert dump(csv) == once
    text = csv.read_text().splitlines()
    at = next(i for i, x in enumerate(text) if x.startswith("time,"))
    bad = tmp_path / "bad.csv"
    for damage in ("backwards", "label"):
        lines = list(text)
        cells = lines[at + 5].split(",")
        if damage == "backwards":
            cells[0] = "0.5"
        else:
            cells[1] = "99999"
        lines[at + 5] = ",".join(cells)
        bad.write_text("\n".join(lines) + "\n")
        monkeypatch.setattr(L, "SPLIT_CLOCKS", 10**9)
        apart = dump(bad)
        monkeypatch.setattr(L, "SPLIT_CLOCKS", 8)
        assert dump(bad) == apart
        assert f"bad.csv:{at + 6}" in apart, apart[:2000]


def _joint_case(log: Path) -> tuple[str, str]:
    """A per-joint set over the positions of ``log``'s /joint_states, with thresholds inside
    the range its inspection gives, and a plain requirement beside."""
    from fretc.cli.inspect import inspect_log

    doc = inspect_log(str(log))
    pos = next(t for t in doc["topics"] if t["topic"] == "/joint_states")["fields"][
        "/joint_states.position"]
    lo, hi = pos["min"], pos["max"]
    a, b = lo + (hi - lo) * 0.3, lo + (hi - lo) * 0.7
    return ("@tick_period 100 ms\n"
            "E0: the sys shall always satisfy above\n"
            "E1: upon below the sys shall within 3 ticks satisfy above\n"
            "E2: whenever below the sys shall immediately satisfy !above\n"
            "P0: the sys shall always satisfy spread\n",
            '[tick]\nperiod = "100 ms"\n[entities]\njoint = "/joint_states.name[:]"\n'
            f"[variables]\nabove = 'joint(/joint_states.position, $joint) > {a!r}'\n"
            f"below = 'joint(/joint_states.position, $joint) < {b!r}'\n"
            f"spread = 'max(/joint_states.position) - min(/joint_states.position) < {hi - lo!r}'\n")


ENTITY_LOGS = {
    "fuse_tb3/turtlebot3.bag": _joint_case,
    "husky_ekf/gps_data.bag": _joint_case,
    "kuka_lwr/test.bag": _joint_case,
    "husky_ekf/gps_data.bag#diagnostics": lambda log: (
        "@tick_period 100 ms\nD0: the sys shall always satisfy calm\n"
        "D1: upon alarm the sys shall within 5 ticks satisfy calm\n",
        '[tick]\nperiod = "100 ms"\n[entities]\nst = "/diagnostics.status[:].name"\n'
        "[variables]\ncalm = 'max(/diagnostics.status[:]{name==$st}.level) < 1'\n"
        "alarm = 'max(/diagnostics.status[:]{name==$st}.level) >= 2'\n"),
    "rosbag2_services/topics_and_services.mcap": lambda log: (
        "@tick_period 100 ms\nQ0: the sys shall always satisfy small\n",
        '[tick]\nperiod = "100 ms"\n[entities]\n'
        'par = "/parameter_events.new_parameters[:].name"\n[variables]\n'
        "small = 'max(/parameter_events.new_parameters[:]{name==$par}.value.type) < 3'\n"),
}


@pytest.mark.skipif(not SHARED.exists(), reason="needs ../shared/data/foreign_logs")
@pytest.mark.parametrize("name", sorted(ENTITY_LOGS))
def test_every_real_log_with_entities(name, tmp_path):
    """Every log of ../shared with entities (the joints of JointState, the statuses of a
    DiagnosticArray, the parameters of /parameter_events): per-entity sets written as a CSV
    give the log's verdicts, in Python and in the runner."""
    log = SHARED / name.split("#")[0]
    fret, bindings = ENTITY_LOGS[name](log)
    (tmp_path / "e.fret").write_text(fret)
    (tmp_path / "e.bindings.toml").write_text(bindings)
    verdicts = check(tmp_path / "e.fret", log, tmp_path)
    assert any("[" in v.requirement for v in verdicts), [v.requirement for v in verdicts]


def test_the_runner_reads_a_sampled_trace_as_the_audit_does(tmp_path):
    """Where the runner and the audit could part: a byte that is not UTF-8 in a comment
    line (both refuse the file, naming the line), a row of a clock no line names (both
    refuse), a bad cell in a row of a clock nothing is judged on (neither reads it: both
    judge the others), a column holding true/false in one clock and numbers in another
    (each clock read apart: both judge)."""
    fret = tmp_path / "t.fret"
    fret.write_text("@tick_period 100 ms\nA: the sw shall always satisfy y\n"
                    "E: the sw shall always satisfy x > 0\n")
    exe = _runner(fret, tmp_path)
    if exe is None:
        pytest.skip("no C compiler")
    head = ("# fretc sampled trace of t.mcap\n# fretc clock 1: A\n# fretc per entity: E: k\n"
            "# fretc clock 2: E[k=1]\n# fretc clock 3: Z\n")
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    cases = {
        "utf8": (head.replace("Z", "Z\xe9").encode("latin-1")
                 + b"time,tick,x,y\n0,1,,true\n0,2,1,\n", 5),
        "label": ((head + "time,tick,x,y\n0,1,,true\n0,7,1,\n").encode(), 8),
        "unused": ((head + "time,tick,x,y\n0,1,,true\n0,2,1,\n0.1,3,oops,oops\n").encode(),
                   None),
        "types": ((head + "time,tick,x,y\n0,1,true,true\n0,2,1,2\n").encode(), None),
    }
    for name, (data, line) in cases.items():
        csv = tmp_path / f"{name}.csv"
        csv.write_bytes(data)
        la = audit_log(plan, str(csv))
        run = subprocess.run([str(exe), str(csv)], capture_output=True, text=True)
        if line is not None:
            assert all(v.verdict == "error" for v in la.verdicts), name
            assert run.returncode == 2 and f"{csv}:{line}" in run.stderr, (name, run.stderr)
            assert any(f"{csv}:{line}" in (v.error or "") for v in la.verdicts), name
        else:
            words = {v.requirement: v.verdict for v in la.verdicts}
            said = dict(row.split("\t")[:2] for row in run.stdout.splitlines())
            assert not run.stderr and said == words, (name, run.stderr, said, words)
