"""fretc falsify and sim.falsify: the search finds the interceptor delay fault (a kept MCAP
whose audit, redone here, gives R2 violated), the same seed gives the same runs, the
environment-only space reports the nominal robot's smallest margins (each one the least of
its runs' robustness, checked against the runs' own audits), and space files with errors are
refused naming file:line. Small budgets; the searches stop at the first falsifying run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.sim.falsify import falsify
from fretc.sim.space import SpaceError, apply, load_space

ROOT = Path(__file__).resolve().parents[2]
SPACES = ROOT / "sim" / "spaces"
pytestmark = pytest.mark.xdist_group("sim")


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))


@pytest.fixture(scope="module")
def delay_search(plan, tmp_path_factory):
    out = tmp_path_factory.mktemp("falsify")
    space = load_space(SPACES / "interceptor_delay.toml")
    return out, falsify(plan, space, budget=12, seed=1, out=out, targets=["R2"], first=True)


def test_finds_the_interceptor_delay_fault(plan, delay_search):
    out, search = delay_search
    assert search.falsified and len(search.runs) <= 12
    last = search.runs[-1]
    assert last.violated == ["R2"] and last.mcap is not None
    # the run's own MCAP, audited again from the file: R2 violated, robustness negative
    la = audit_log(plan, str(out / last.mcap))
    r2 = next(v for v in la.verdicts if v.requirement == "R2")
    assert r2.verdict == "violated" and r2.robustness < 0
    # R2's deadline is 1 s: only a delay past it can break it
    assert last.parameters["interceptor_delay"] > 1.0
    for earlier in search.runs[:-1]:
        assert not earlier.violated and earlier.mcap is None
        assert not (out / f"runs/run-{earlier.index:04d}.mcap").exists()


def test_same_seed_same_runs(plan, delay_search, tmp_path):
    _out, search = delay_search
    space = load_space(SPACES / "interceptor_delay.toml")
    again = falsify(plan, space, budget=1, seed=1, out=tmp_path, targets=["R2"])
    assert [r.parameters for r in again.runs] == [r.parameters for r in search.runs[:1]]
    assert [r.robustness for r in again.runs] == [r.robustness for r in search.runs[:1]]
    other = falsify(plan, space, budget=1, seed=2, out=tmp_path / "s2", targets=["R2"])
    assert other.runs[0].parameters != search.runs[0].parameters


def test_cli_environment_space_reports_the_nominal_robots_smallest_margin(plan, tmp_path):
    out = tmp_path / "env"
    res = CliRunner().invoke(main, ["falsify", "-r", str(ROOT / "requirements"), "--space",
                                    str(SPACES / "environment.toml"), "--budget", "2",
                                    "--seed", "1", "-o", str(out), "--only", "R5"])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "falsify.json").read_text())
    assert doc["schema"] == "fretc-falsify/1" and not doc["falsified"]
    assert len(doc["runs"]) == 2 and not list((out / "runs").glob("*.mcap"))
    # the smallest margin is the least R5 robustness of the runs: the clearance kept
    values = [r["robustness"]["R5"] for r in doc["runs"]]
    best = doc["smallest"]["R5"]
    assert best["value"] == min(values) > 0
    assert "R5: smallest robustness" in res.output
    # and it is the clearance of that run, from an audit of the run redone here
    run = doc["runs"][best["run"] - 1]
    space = load_space(SPACES / "environment.toml")
    from fretc.sim.run import record_scenario
    path = tmp_path / "again.mcap"
    record_scenario(apply(space.scenario, run["parameters"]), space.seed, path)
    la = audit_log(plan, str(path))
    r5 = next(v for v in la.verdicts if v.requirement == "R5")
    assert r5.robustness == best["value"] and r5.robustness_at.tick == best["tick"]
    assert f"| R5 | {best['value']:+.4g} | {best['run']} | {best['tick']} |" in \
        (out / "falsify.md").read_text()
    assert (out / "falsify.svg").read_text().startswith("<?xml")


@pytest.mark.parametrize("body, where, words", [
    ("scenario = 'nominal'\n[parameters]\nwarp = [0, 1]\n", ":3", "unknown parameter 'warp'"),
    ("scenario = 'nominal'\n[parameters]\nobstacle_x = [2, 1]\nobstacle_y = [0, 1]\n",
     ":3", "low <= high"),
    ("scenario = 'nominal'\n[parameters]\nobstacle_x = [0, 1]\n", ":3", "needs obstacle_y"),
    ("scenario = 'moon'\n[parameters]\nstop_delay = [0, 1]\n", ":1", "is not one of"),
    ("scenario = 'nominal'\n[parameters]\nobstacle_speed = [0.1, 1]\n", ":3",
     "no moving obstacle"),
    ("scenario = 'nominal'\n[parameters\n", ":2", "not a TOML file"),
    # wrongly typed or out-of-range values are input errors, not exit 4
    ("scenario = ['nominal']\n[parameters]\nstop_delay = [0, 1]\n", ":1", "a TOML array"),
    ("scenario = {a = 1}\n[parameters]\nstop_delay = [0, 1]\n", ":1", "a TOML table"),
    ("scenario = 'nominal'\nmax_time = inf\n[parameters]\nstop_delay = [0, 1]\n", ":2",
     "finite number of seconds"),
    ("scenario = 'nominal'\nmax_time = 1e-300\n[parameters]\nstop_delay = [0, 1]\n", ":2",
     "at least one simulator step"),
    ("scenario = 'nominal'\nseed = 4294967296\n[parameters]\nstop_delay = [0, 1]\n", ":2",
     "2^32"),
    ("scenario = 'nominal'\n[parameters]\nobstacle_x = [-1.7e308, 1.7e308]\n"
     "obstacle_y = [0, 1]\n", ":3", "overflows"),
    ("scenario = 'nominal'\n[parameters]\nobstacle_x = [-1e300, 1e300]\nobstacle_y = [0, 1]\n",
     ":3", "goes beyond"),
])
def test_space_errors_name_file_and_line(tmp_path, body, where, words):
    p = tmp_path / "bad.toml"
    p.write_text(body)
    with pytest.raises(SpaceError) as exc:
        load_space(p)
    assert f"{p}{where}" in str(exc.value) and words in str(exc.value)


def test_cli_bad_space_and_unknown_target_exit_2(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("scenario = 'nominal'\n[parameters]\nwarp = [0, 1]\n")
    res = CliRunner().invoke(main, ["falsify", "-r", str(ROOT / "requirements"), "--space",
                                    str(p), "-o", str(tmp_path / "o")])
    assert res.exit_code == 2 and f"{p}:3" in res.output and "Traceback" not in res.output
    res = CliRunner().invoke(main, ["falsify", "-r", str(ROOT / "requirements"), "--space",
                                    str(SPACES / "environment.toml"), "-o",
                                    str(tmp_path / "o"), "--only", "R9"])
    assert res.exit_code == 2 and "no requirement R9" in res.output
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "falsify.json").write_text("{}")
    res = CliRunner().invoke(main, ["falsify", "-r", str(ROOT / "requirements"), "--space",
                                    str(SPACES / "environment.toml"), "-o",
                                    str(tmp_path / "used")])
    assert res.exit_code == 2 and "is not empty" in res.output


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_ray_gives_the_runs_of_a_run_without_ray(plan, delay_search, tmp_path):
    pytest.importorskip("ray")
    _out, search = delay_search
    space = load_space(SPACES / "interceptor_delay.toml")
    got = falsify(plan, space, budget=12, seed=1, out=tmp_path, targets=["R2"], first=True,
                  ray_address="local")
    assert [r.parameters for r in got.runs] == [r.parameters for r in search.runs]
    assert [r.robustness for r in got.runs] == [r.robustness for r in search.runs]


def test_cli_seed_of_32_bits_or_more_is_a_usage_error(tmp_path):
    res = CliRunner().invoke(main, ["falsify", "-r", str(ROOT / "requirements"), "--space",
                                    str(SPACES / "environment.toml"), "-o",
                                    str(tmp_path / "o"), "--seed", str(2**32)])
    assert res.exit_code == 2 and "--seed" in res.output, res.output


def test_ctrl_c_writes_the_runs_so_far_marked_interrupted(plan, tmp_path, monkeypatch):
    """Ctrl-C during the third run: the two runs made are the search, written as JSON and
    report, marked interrupted (exit 130); the third run's file is gone."""
    import fretc.sim.falsify as F

    made = []
    real = F.simulate

    def simulate(space, parameters, path):
        if len(made) == 2:
            open(path, "wb").close()  # a run half written
            raise KeyboardInterrupt
        made.append(path)
        return real(space, parameters, path)

    monkeypatch.setattr(F, "simulate", simulate)
    out = tmp_path / "o"
    res = CliRunner().invoke(main, ["falsify", "-r", str(ROOT / "requirements"), "--space",
                                    str(SPACES / "environment.toml"), "-o", str(out),
                                    "--budget", "5", "--only", "R5"])
    assert res.exit_code == 130, res.output
    doc = json.loads((out / "falsify.json").read_text())
    assert doc["interrupted"] is True and len(doc["runs"]) == 2 and doc["exit_code"] == 130
    assert "Interrupted" in (out / "falsify.md").read_text()
    assert not (out / "runs" / "run-0003.mcap").exists()
