"""fretc estimate (sim/estimate.py, sim/rare.py, reports/estimate.py) on a small simulator
space: the SPRT decides, violating runs are kept with their audits, the same seed gives a
byte-identical report (locally and on Ray), a budget too small is 'undecided' (exit 5),
and bad spaces and boolean --rare targets are refused (exit 2). Space distributions
(sim/distributions.py): sampling, truncation, faults, degenerate ones refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import truncnorm
from click.testing import CliRunner

from fretc.cli import main
from fretc.sim.distributions import DistributionError, parse_distribution
from fretc.sim.estimate import sample_point
from fretc.sim.space import SpaceError, load_space

ROOT = Path(__file__).resolve().parents[2]
BINDINGS = str(ROOT / "requirements" / "safe_ros.bindings.toml")
pytestmark = pytest.mark.xdist_group("sim")

SPACE = """scenario = "nominal"
seed = 1
max_time = 20.0
[parameters]
interceptor_delay = {dist = "choice", values = [0.2, 1.6], weights = [0.4, 0.6]}
obstacle_x = {dist = "uniform", low = 1.2, high = 1.4}
obstacle_y = [-0.7, -0.5]
"""
REQS = """@tick_period 100 ms
R2p: upon too_close agilex_agent shall with probability >= 0.9 within 1 second satisfy stopped
R5: the scout_mini shall always satisfy clearance > 0
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("estimate")
    (d / "space.toml").write_text(SPACE)
    (d / "r.fret").write_text(REQS)
    return d


def _run(files, out, *extra):
    return CliRunner().invoke(main, ["estimate", "-r", str(files / "r.fret"), "-b", BINDINGS,
                                     "--space", str(files / "space.toml"), "-o", str(out),
                                     *extra])


@pytest.fixture(scope="module")
def campaign(files):
    out = files / "c1"
    return out, _run(files, out, "--seed", "3", "--budget", "40")


def test_sprt_decides_fails_and_keeps_the_violating_runs(campaign):
    out, res = campaign
    assert res.exit_code == 1, res.output
    doc = json.loads((out / "estimate.json").read_text())
    r2, r5 = doc["statistics"]
    assert r2["verdict"] == "fails" and r2["bound"] == {"op": ">=", "p": 0.9}
    assert r2["sequential"]["decision"] == "fails" and r2["sequential"]["at"] == doc["runs_used"]
    assert doc["runs_used"] < 40 and "decided" in doc["stopped"]
    assert r5["bound"] is None and r5["verdict"] is None  # plain: counted, judged per run
    assert r2["satisfied"] + r2["violated"] + r2["vacuous"] == doc["runs_used"]
    kept = [r for r in doc["runs"] if r["mcap"]]
    assert kept and all(r["verdicts"]["R2p"] == "violated" for r in kept)
    for r in kept:  # MCAP + audit of each violating run
        assert (out / r["mcap"]).exists()
        audit = json.loads((out / r["mcap"].replace(".mcap", ".audit.json")).read_text())
        assert audit["logs"][0]["verdicts"][0]["verdict"] == "violated"
    assert len(list((out / "runs").glob("*.mcap"))) == len(kept)
    assert (out / "R2p.svg").read_text().startswith("<?xml")
    assert "fails" in (out / "estimate.md").read_text()


def test_same_seed_byte_identical_report(files, campaign):
    out, _ = campaign
    again = files / "c2"
    _run(files, again, "--seed", "3", "--budget", "40")
    assert (again / "estimate.json").read_bytes() == (out / "estimate.json").read_bytes()


def test_budget_too_small_is_undecided_exit_5(files):
    out = files / "small"
    res = _run(files, out, "--seed", "3", "--budget", "2", "--test", "cp")
    assert res.exit_code == 5, res.output
    st = json.loads((out / "estimate.json").read_text())["statistics"][0]
    assert st["verdict"] == "undecided" and "budget of 2 runs ended" in st["why"]


def test_rare_refuses_a_boolean_requirement(files):
    res = _run(files, files / "rare", "--rare", "--target", "R2p", "--particles", "4",
               "--kill", "1", "--budget", "4")
    assert res.exit_code == 2, res.output
    assert "boolean" in res.output


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_ray_gives_the_same_report(files, campaign):
    out, _ = campaign
    ray_out = files / "ray"
    res = _run(files, ray_out, "--seed", "3", "--budget", "40", "--ray")
    assert res.exit_code == 1, res.output
    assert (ray_out / "estimate.json").read_bytes() == (out / "estimate.json").read_bytes()


# ------------------------------------------------------------------ distributions
def test_degenerate_distributions_are_refused_with_file_and_line(files, tmp_path):
    for spec, words in (('{dist = "normal", mean = 1.0, sd = 0.0}', "degenerate"),
                        ('{dist = "uniform", low = 1.0, high = 1.0}', "degenerate"),
                        ('{dist = "choice", values = [1.0, 2.0], weights = [1, 0]}', "one value"),
                        ('{dist = "gamma", low = 1.0}', "dist must be")):
        p = tmp_path / "bad.toml"
        p.write_text(SPACE.replace('{dist = "uniform", low = 1.2, high = 1.4}', spec))
        with pytest.raises(SpaceError, match=words) as e:
            load_space(p)
        assert f"{p}:6:" in str(e.value)
    p = tmp_path / "point.toml"
    p.write_text(SPACE.replace("[-0.7, -0.5]", "[-0.6, -0.6]"))
    res = CliRunner().invoke(main, ["estimate", "-r", str(files / "r.fret"), "-b", BINDINGS,
                                    "--space", str(p), "-o", str(tmp_path / "o")])
    assert res.exit_code == 2 and "degenerate" in res.output and f"{p}:7:" in res.output


def test_sampling_follows_the_distributions_and_the_seed():
    space = load_space(ROOT / "sim" / "spaces" / "interceptor_delay.toml")
    pts = [sample_point(space, 1, i)[1] for i in range(1, 2001)]
    d = np.array([p["interceptor_delay"] for p in pts])
    # a normal(0.3, 0.4) truncated to [0, 2]: scipy's median of it
    median = truncnorm(-0.3 / 0.4, 1.7 / 0.4, loc=0.3, scale=0.4).median()
    assert d.min() >= 0 and d.max() <= 2.0 and abs(np.median(d) - median) < 0.03
    x = np.array([p["obstacle_x"] for p in pts])
    assert 0.7 <= x.min() and x.max() <= 1.8 and abs(x.mean() - 1.25) < 0.03
    assert sample_point(space, 1, 7) == sample_point(space, 1, 7)
    assert sample_point(space, 2, 7)[1] != sample_point(space, 1, 7)[1]


def test_a_fault_happens_in_its_share_of_runs():
    def fail(msg):
        raise DistributionError(msg)
    d = parse_distribution("dropout_start", {"dist": "uniform", "low": 2.0, "high": 8.0,
                                             "fault": 0.1}, True, fail)
    rng = np.random.default_rng(0)
    vals = [d.value(rng.standard_normal(2)) for _ in range(5000)]
    share = sum(v is not None for v in vals) / 5000
    assert abs(share - 0.1) < 0.015
    assert all(2.0 <= v <= 8.0 for v in vals if v is not None)
    with pytest.raises(DistributionError, match="share"):
        parse_distribution("x", {"dist": "uniform", "low": 0, "high": 1, "fault": 1.5}, True,
                           fail)


def test_estimate_runs_with_the_shield_of_safety(files, tmp_path, monkeypatch):
    """``fretc estimate --safety shield:DIR`` (the contact probability with the generated
    Safety System, beside the hand-written SIF): every run is simulated with the
    shield in DIR in place of the SIF; a folder without a shield is a usage error."""
    from fretc.shield.build import build_shield
    from fretc.shield.emit import write_forms
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.signals.bindings.files import load_bindings
    from fretc.sim import estimate as est

    reqs = ROOT / "requirements"
    shield = build_shield(compile_entries(load_requirements([reqs / "safe_ros.fret"])),
                          ["too_close", "scan_stale", "clearance"],
                          ["stopped", "stop_requested", "forwarded_zero", "linear_speed",
                           "angular_speed"], bindings=load_bindings(BINDINGS), fork=False,
                          name="safe_ros")
    folder = tmp_path / "shield"
    write_forms(shield, ["python"], folder, bindings_file=BINDINGS)
    seen = []
    real = est.record_scenario

    def spy(*args, **kwargs):
        seen.append(kwargs.get("shield"))
        return real(*args, **kwargs)

    monkeypatch.setattr(est, "record_scenario", spy)
    res = _run(files, tmp_path / "out", "--seed", "3", "--budget", "2", "--test", "cp",
               "--safety", f"shield:{folder}")
    assert res.exit_code in (0, 1, 5), res.output
    assert len(seen) == 2 and all(s is not None and s.path.parent == folder for s in seen)
    res = _run(files, tmp_path / "out2", "--budget", "2", "--safety", f"shield:{tmp_path}")
    assert res.exit_code == 2 and "one *_shield.py" in res.output, res.output
