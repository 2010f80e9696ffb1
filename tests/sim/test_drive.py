"""The Safe-ROS simulator driven by a test trace (``python -m fretc.sim drive``) and generated
tests run against it (``fretc testrun``): the driven inputs read back from the system's log as
the trace has them, the outputs are the robot's own, and the pass rule gives pass, fail and
not exercised where the robot earns them."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.testing.testrun import judge
from fretc.cli import main
from fretc.logs import open_log
from fretc.signals.bindings.files import load_bindings
from fretc.signals.clock import sample
from fretc.sim.drive import DriveError, drive
from fretc.testing.drive_plan import classify

ROOT = Path(__file__).resolve().parents[2]
REQS = ROOT / "requirements"
BINDINGS = REQS / "safe_ros.bindings.toml"
NAMES = ["too_close", "stopped", "stop_requested", "forwarded_zero", "linear_speed",
         "angular_speed", "clearance", "scan_stale"]


def _rows(too_close: list[bool], stale: list[bool] | None = None) -> list[dict]:
    stale = stale or [False] * len(too_close)
    return [{**{n: 0.0 for n in NAMES}, "stopped": False, "stop_requested": False,
             "forwarded_zero": False, "too_close": c, "scan_stale": s}
            for c, s in zip(too_close, stale)]


def _ticks(path: Path, b) -> list[dict]:
    src = open_log(path)
    try:
        return [t.values for t in sample(src, b)]
    finally:
        src.close()


def test_roles_of_the_safe_ros_variables():
    roles = classify(NAMES, load_bindings(BINDINGS))
    assert roles.driven == ["too_close", "scan_stale"]
    assert roles.system == ["stopped", "stop_requested", "forwarded_zero", "linear_speed",
                            "angular_speed"]
    assert list(roles.not_drivable) == ["clearance"]
    assert "ground truth" in roles.not_drivable["clearance"]


def test_driven_inputs_read_back_and_the_sif_answers(tmp_path):
    """The log's too_close and scan_stale over the trace's ticks are the trace's (differential:
    the audit's sampler on the system's log); stop_requested is the SIF's own answer."""
    b = load_bindings(BINDINGS)
    too_close = [False] * 4 + [True] * 3 + [False] * 7
    stale = [False] * 11 + [True, True, True]
    rows = _rows(too_close, stale)
    # silent from tick 8 on (age > 0.3 s at 11): the scan of tick 7 is held
    roles, res = drive(rows, b, tmp_path / "run.mcap", lead_in=2.0, lead_out=0.0)
    ticks = _ticks(tmp_path / "run.mcap", b)
    first = len(ticks) - len(rows)  # the lead-in ticks come first; the run ends at the trace's
    assert first > 0
    window = ticks[first:]
    assert [t["too_close"] for t in window] == too_close
    assert [t["scan_stale"] for t in window] == stale
    answered = [t["stop_requested"] for t in window]
    assert not answered[3] and answered[4]  # a stop on the scan that saw the obstacle
    assert roles.driven == ["too_close", "scan_stale"]


def test_same_trace_same_log(tmp_path):
    b = load_bindings(BINDINGS)
    rows = _rows([False, True, True, False])
    drive(rows, b, tmp_path / "a.mcap", lead_in=1.0, lead_out=0.5)
    drive(rows, b, tmp_path / "b.mcap", lead_in=1.0, lead_out=0.5)
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


def test_trace_without_binding_refused(tmp_path):
    b = load_bindings(BINDINGS)
    with pytest.raises(DriveError, match="no binding"):
        drive([{"battery_low": True}], b, tmp_path / "x.mcap")


def test_inputs_no_scan_can_give_refused(tmp_path):
    """too_close changing while the scan must be silent: no /scan messages give it."""
    b = load_bindings(BINDINGS)
    rows = _rows([False] * 4 + [True] * 3 + [False] * 3, [False] * 8 + [True] * 2)
    with pytest.raises(DriveError, match="cannot be"):
        drive(rows, b, tmp_path / "x.mcap")


def _test(gen_for: tuple[str, str], covers: list[tuple[str, str]]) -> dict:
    return {"id": "T", "generated_for": {"requirement": gen_for[0], "obligation": gen_for[1]},
            "covers": [{"requirement": r, "obligation": o, "tick": 0} for r, o in covers]}


def _doc(verdicts: dict[str, str], covered: list[tuple[str, str]]) -> dict:
    reqs = sorted({r for r, _ in covered} | set(verdicts))
    return {"logs": [{"log": "x", "error": None, "verdicts": [
        {"requirement": r, "verdict": v} for r, v in verdicts.items()]}],
        "coverage": {"requirements": [{"requirement": r, "obligations": [
            {"obligation": o, "status": "covered"} for q, o in covered if q == r]}
            for r in reqs]}}


def test_pass_rule():
    t = _test(("R2", "trigger"), [("R2", "trigger"), ("R5", "x")])
    ok = _doc({"R2": "satisfied", "R5": "satisfied"}, [("R2", "trigger")])
    assert judge(t, ok).outcome == "pass"
    assert judge(t, ok, "all").outcome == "not exercised"
    assert judge(t, _doc({"R2": "satisfied"}, [])).outcome == "not exercised"
    assert judge(t, _doc({"R2": "violated"}, [("R2", "trigger")])).outcome == "fail"
    assert judge(t, _doc({"R2": "unknown"}, [("R2", "trigger")])).outcome == "unknown"
    assert judge(t, {"logs": []}).outcome == "unknown"  # nothing audited is never a pass


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    out = tmp_path_factory.mktemp("tests")
    res = CliRunner().invoke(main, ["testgen", str(REQS), "-o", str(out)])
    assert res.exit_code == 0, res.output
    return out, json.loads((out / "tests.json").read_text())


def _pick(doc, pred) -> str:
    return next(t["id"] for t in doc["tests"] if pred(t))


def test_testrun_on_the_simulator(generated, tmp_path):
    """Three generated tests against the simulated robot: one whose trace is all the robot
    does right passes; the one generated for R2's missed deadline is not exercised (the SIF
    meets it); one with a stale scan fails R6 (the SIF has no fail-safe for stale scans, as
    the lidar_dropout run shows)."""
    out, doc = generated
    target = _pick(doc, lambda t: t["generated_for"]["obligation"] == "deadline-missed")
    stale = _pick(doc, lambda t: t["expected"]["R6"] != "vacuous"  # scan_stale rises
                  and t["generated_for"]["obligation"].startswith("deadline-"))
    clean = _pick(doc, lambda t: t["generated_for"] == {"requirement": "R5",
                                                          "obligation": "response:clearance > 0+"})
    cmd = f"{sys.executable} -m fretc.sim drive -b {BINDINGS} --lead-in 2"
    j = tmp_path / "run.json"
    args = ["testrun", str(out), "--command", cmd, "--logs", str(tmp_path / "runs"),
            "--json", str(j)]
    for i in (target, stale, clean):
        args += ["--test", i]
    res = CliRunner().invoke(main, args)
    got = {t["id"]: t for t in json.loads(j.read_text())["tests"]}
    assert res.exit_code == 1, res.output  # one failed
    assert got[target]["outcome"] == "not exercised", res.output
    assert got[stale]["outcome"] == "fail" and "R6" in got[stale]["violated"], res.output
    assert got[clean]["outcome"] == "pass", res.output


def test_input_errors_exit_2(tmp_path):
    res = CliRunner().invoke(main, ["testrun", str(tmp_path), "--command", "true"])
    assert res.exit_code == 2 and "tests.json" in res.output
    from fretc.sim.__main__ import main as sim_main

    bad = tmp_path / "t.csv"
    bad.write_text("time,battery_low\n0.0,true\n")
    res = CliRunner().invoke(sim_main, ["drive", str(bad), str(tmp_path / "x.mcap"),
                                        "-b", str(BINDINGS)])
    assert res.exit_code == 2 and "battery_low: no binding" in res.output


def test_command_without_log_is_unknown(generated, tmp_path):
    out, doc = generated
    first = doc["tests"][0]["id"]
    res = CliRunner().invoke(main, ["testrun", str(out), "--command", "true", "--test", first,
                                    "--logs", str(tmp_path)])
    assert res.exit_code == 3, res.output
    assert f"{first}: unknown: the command exited 0 without a log" in res.output


# --------------------------------------------------------------------------- hostile round 7
def _sim_drive(tmp_path, *extra, trace=None):
    from fretc.sim.__main__ import main as sim_main

    if trace is None:
        trace = tmp_path / "t.csv"
        trace.write_text("time,too_close\n" + "".join(f"{k / 10},{'true' if 3 <= k < 6 else 'false'}\n"
                                                      for k in range(12)))
    return CliRunner().invoke(sim_main, ["drive", str(trace), str(tmp_path / "x.mcap"),
                                         "-b", str(BINDINGS), *extra])


@pytest.mark.parametrize("option,value", [("--lead-in", "nan"), ("--lead-in", "inf"),
                                          ("--lead-in", "-1"), ("--lead-out", "-100"),
                                          ("--lead-out", "nan"), ("--lead-out", "-inf")])
def test_drive_options_must_be_finite_and_not_negative(tmp_path, option, value):
    """``--lead-in nan|inf`` was a traceback, ``--lead-out -100`` a run that ended before the
    trace did, exit 0: each is an input error naming the option, exit 2."""
    res = _sim_drive(tmp_path, option, value)
    assert res.exit_code == 2 and option in res.output, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit)
    assert not (tmp_path / "x.mcap").exists()


def test_a_drive_that_does_not_apply_the_whole_trace_fails(tmp_path):
    """``--lead-in 1e9``: the mission ends long before the trace's first tick; the run used to
    be recorded, exit 0, and testrun turned failing tests into "not exercised"."""
    res = _sim_drive(tmp_path, "--lead-in", "1e9")
    assert res.exit_code == 2 and "trace" in res.output and "tick" in res.output, res.output


def test_a_trace_with_no_drivable_column_is_refused(tmp_path):
    """A trace without too_close or scan_stale drove the robot with no input at all, exit 0."""
    trace = tmp_path / "s.csv"
    trace.write_text("time,stopped\n0.0,true\n0.1,true\n")
    res = _sim_drive(tmp_path, trace=trace)
    assert res.exit_code == 2 and "drive" in res.output, res.output
    with pytest.raises(DriveError, match="drive"):
        drive([{"stopped": True}], load_bindings(BINDINGS), tmp_path / "y.mcap")


def test_a_test_without_an_obligation_is_not_a_pass():
    """``"covers": []`` and no ``generated_for``: nothing the test was meant to show, so it
    does not pass; a target its covers do not list is still required."""
    ok = _doc({"R2": "satisfied"}, [])
    bare = {"id": "T", "generated_for": None, "covers": []}
    assert judge(bare, ok).outcome == "not exercised"
    assert judge(bare, ok, "all").outcome == "not exercised"
    aside = _test(("R2", "deadline-missed"), [])
    assert judge(aside, ok).outcome == "not exercised"
    assert judge(_test(("R2", "trigger"), []), _doc({"R2": "satisfied"}, [("R2", "trigger")])
                 ).outcome == "pass"


def _tests_json(folder: Path, doc) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tests.json").write_text(doc if isinstance(doc, str) else json.dumps(doc))
    (folder / "T01.csv").write_text("too_close\nfalse\n")


def _one(**test):
    t = {"id": "T01", "trace": "T01.csv", "generated_for": {"requirement": "R2",
                                                            "obligation": "trigger"},
         "covers": [{"requirement": "R2", "obligation": "trigger", "tick": 0}],
         "expected": {"R2": "satisfied"}}
    t.update(test)
    return {"requirements": [str(REQS / "safe_ros.fret")], "tests": [t]}


@pytest.mark.parametrize("test_id", ["../../x/victim", "/tmp/fretc-victim", "a/b", "..",
                                     "a\\b", "x\x00y", "x" * 300, "", "."])
def test_a_test_id_never_names_a_file_outside_the_folder(tmp_path, test_id):
    """A test id becomes a file name only through one check (separators, ``..``, absolute
    paths, NUL, over-long names refused): ``../../../x/victim`` made testrun unlink and
    replace ``victim.mcap`` and ``victim.audit.json`` outside its folder."""
    victim = tmp_path / "x"
    victim.mkdir()
    (victim / "victim.mcap").write_text("precious")
    folder = tmp_path / "a" / "b"
    _tests_json(folder, _one(id=test_id))
    cmd = f"{sys.executable} -c \"import sys; open(sys.argv[2], 'w').write('log')\""
    res = CliRunner().invoke(main, ["testrun", str(folder), "--command", cmd])
    assert res.exit_code == 2 and "$.tests[0].id" in res.output, res.output
    assert (victim / "victim.mcap").read_text() == "precious"
    assert not (victim / "victim.audit.json").exists()
    assert not (folder / "runs").exists() or not any((folder / "runs").iterdir())


@pytest.mark.parametrize("doc,where", [
    ({"tests": []}, "$.requirements"),
    ({"requirements": [], "tests": []}, "$.requirements"),
    ({"requirements": "safe_ros.fret", "tests": []}, "$.requirements"),
    (dict(_one(), bindings=7), "$.bindings"),
    (_one(covers=None), "$.tests[0].covers"),
    (_one(covers=[{"requirement": "R2"}]), "$.tests[0].covers[0]"),
    (_one(covers=[{"requirement": 2, "obligation": "x"}]), "$.tests[0].covers[0].requirement"),
    (_one(generated_for="R2"), "$.tests[0].generated_for"),
    (_one(id=7), "$.tests[0].id"),
    (_one(trace="../T01.csv"), "$.tests[0].trace"),
    (_one(trace="/etc/passwd"), "$.tests[0].trace"),
    ({"requirements": ["r.fret"], "tests": [[[[]]]]}, "$.tests[0]"),
    ("[" * 100_000 + "]" * 100_000, "nested"),
    ("{\"requirements\": [\"r.fret\"], \"tests\": ", "not JSON"),
    ("[]", "$"),
])
def test_tests_json_is_checked_against_its_schema(tmp_path, doc, where):
    """Every refusal names the JSON path (or why it is not JSON), exit 2, no traceback."""
    _tests_json(tmp_path, doc)
    res = CliRunner().invoke(main, ["testrun", str(tmp_path), "--command", "true"])
    assert res.exit_code == 2, res.output
    assert where in res.output and "tests.json" in res.output, res.output
    assert "Traceback" not in res.output and isinstance(res.exception, SystemExit)
