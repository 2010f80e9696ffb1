"""Fleet statistics (audit/fleet/statistics.py): counts, scipy's Clopper-Pearson interval, the
statistical verdict of 'with probability' requirements, their exit code and JUnit cases,
locally and on Ray (the same JSON)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner
from scipy.stats import binomtest

from fretc.audit.fleet.statistics import (RequirementStatistics, clopper_pearson, decide,
                                          fleet_statistics, more_runs)
from fretc.audit.verdict import EXIT_UNDECIDED, LogAudit, Verdict, exit_code
from fretc.compiler.ir import ProbabilityBound
from fretc.cli import main

N, K = 1000, 630
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """1,000 CSV runs of which 630 keep ``ok`` true to the end (the others drop it)."""
    d = tmp_path_factory.mktemp("fleet")
    runs = d / "runs"
    runs.mkdir()
    for i in range(N):
        (runs / f"run{i:04d}.csv").write_text("ok\n1\n1\n" + ("1\n" if i < K else "0\n"))
    for p in ("0.5", "0.7"):
        (d / f"p{p}.fret").write_text(
            f"P1: the robot shall with probability >= {p} always satisfy ok\n")
    return d


def _audit(fleet, p, *extra):
    out = fleet / f"audit-{p}-{len(extra)}.json"
    res = CliRunner().invoke(main, ["audit", "-r", str(fleet / f"p{p}.fret"), str(fleet / "runs"),
                                    "--no-progress", "--json", str(out),
                                    "--junit", str(out.with_suffix(".xml")), *extra])
    return res, json.loads(out.read_text()), ET.parse(out.with_suffix(".xml")).getroot()


@pytest.mark.tor("TOR-VER-010")
def test_630_of_1000_holds_at_half_with_scipys_interval(fleet):
    res, doc, junit = _audit(fleet, "0.5")
    assert res.exit_code == 0, res.output  # 370 violated runs, yet the bound holds
    (st,) = doc["statistics"]
    ci = binomtest(K, N).proportion_ci(confidence_level=0.95, method="exact")
    assert st["estimate"] == pytest.approx(0.63, abs=1e-12)
    assert st["interval"] == pytest.approx([ci.low, ci.high], abs=1e-9)
    assert (st["runs"], st["satisfied"], st["violated"], st["vacuous"], st["unknown"]) == \
        (N, K, N - K, 0, 0)
    assert st["bound"] == {"op": ">=", "p": 0.5} and st["verdict"] == "holds"
    assert st["confidence"] == 0.95 and doc["summary"]["exit_code"] == 0
    suite = junit.find("testsuite[@name='statistics']")
    assert suite.get("failures") == "0" and suite.get("errors") == "0"
    assert junit.get("failures") == "0"  # violated runs of P1 are not failures
    import jsonschema
    schema = json.loads((ROOT / "docs" / "reference" / "audit.schema.json").read_text())
    jsonschema.validate(st, dict(schema["$defs"]["statistics"], **{"$defs": schema["$defs"]}))


def test_630_of_1000_fails_at_0_7(fleet):
    res, doc, junit = _audit(fleet, "0.7")
    assert res.exit_code == 1, res.output
    assert doc["statistics"][0]["verdict"] == "fails" and doc["summary"]["exit_code"] == 1
    suite = junit.find("testsuite[@name='statistics']")
    assert suite.find("testcase/failure").get("type") == "fails"


def test_confidence_option_changes_the_interval(fleet):
    _res, doc, _ = _audit(fleet, "0.5", "--confidence", "0.99")
    ci = binomtest(K, N).proportion_ci(confidence_level=0.99, method="exact")
    assert doc["statistics"][0]["interval"] == pytest.approx([ci.low, ci.high], abs=1e-9)


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_ray_gives_the_same_statistics(fleet):
    from fretc.audit.fleet import ray as fl
    started = fl.connect(num_cpus=2)
    try:
        a, da, _ = _audit(fleet, "0.7")
        b, db, _ = _audit(fleet, "0.7", "--ray")
    finally:
        if started:
            import ray
            ray.shutdown()
    assert a.exit_code == b.exit_code == 1
    assert da["statistics"] == db["statistics"]


# ------------------------------------------------------------------ the rules, on counts
def _logs(verdicts: list[str]) -> list[LogAudit]:
    return [LogAudit(f"l{i}", verdicts=[Verdict(f"l{i}", "P", verdict=v)])
            for i, v in enumerate(verdicts)]


@pytest.mark.tor("TOR-VER-010")
def test_unknown_runs_are_never_satisfied():
    logs = _logs(["satisfied"] * 18 + ["unknown"] * 2)
    b = {"P": ProbabilityBound(">=", "0.5")}
    worst, = fleet_statistics(logs, b, unknown="worst-case", trial="run")
    excl, = fleet_statistics(logs, b, unknown="exclude", trial="run")
    assert (worst.successes, worst.trials, worst.unknown_trials) == (18, 18, 2)
    assert (excl.successes, excl.trials, excl.unknown_trials) == (18, 18, 0)
    assert worst.estimate == excl.estimate == 1.0
    # worst case: the lower end as if both failed, the upper as if both succeeded
    assert worst.interval == (clopper_pearson(18, 20)[0], clopper_pearson(20, 20)[1])
    assert excl.interval == clopper_pearson(18, 18)
    assert worst.unknown == 2 and worst.to_json()["unknown_policy"] == "worst-case"
    old, = fleet_statistics(logs, b, unknown="fail", trial="run")  # the old name
    assert old.to_json() == worst.to_json()


@pytest.mark.parametrize("op,p,lo,hi,want", [
    (">=", 0.5, 0.6, 0.7, "holds"), (">=", 0.5, 0.3, 0.4, "fails"), (">=", 0.5, 0.4, 0.6, "undecided"),
    (">", 0.6, 0.6, 0.7, "undecided"), ("<=", 0.5, 0.3, 0.4, "holds"), ("<", 0.4, 0.3, 0.4, "undecided"),
    ("<=", 0.5, 0.6, 0.7, "fails"), ("=", 0.5, 0.4, 0.6, "undecided"), ("=", 0.5, 0.6, 0.7, "fails")])
def test_decide(op, p, lo, hi, want):
    assert decide(op, p, lo, hi) == want


def test_undecided_says_how_many_more_runs():
    st = RequirementStatistics("P", successes=19, trials=20)
    from fretc.audit.fleet.intervals import Counts
    from fretc.audit.fleet.statistics import judge_counts
    judge_counts(st, ">=", 0.9)
    assert st.verdict == "undecided" and st.more_runs is not None and "more runs" in st.why
    m = st.more_runs
    # at the observed rate, n + m runs decide and n + m - 1 do not
    k = lambda j: 19 + round(0.95 * j)  # noqa: E731
    assert decide(">=", 0.9, *clopper_pearson(k(m), 20 + m)) == "holds"
    assert decide(">=", 0.9, *clopper_pearson(k(m - 1), 19 + m)) == "undecided"
    half = Counts(5, 10, 0, 10, 10, 10)
    assert more_runs(">=", 0.5, half, 0.95) is None  # the rate is the bound: never


@pytest.mark.tor("TOR-VER-006", "TOR-VER-010")
def test_exit_codes_follow_the_statistical_verdict():
    logs = _logs(["satisfied"] * 3 + ["violated"])
    b = {"P": ProbabilityBound(">=", "0.5")}
    stats = fleet_statistics(logs, b, trial="run")
    assert stats[0].verdict == "undecided"
    assert exit_code(logs, statistics=stats) == EXIT_UNDECIDED == 5
    assert exit_code(logs, statistics=stats, allow_partial=True) == 5
    assert exit_code(logs) == 1  # without statistics: a plain requirement
    worse = _logs(["violated"] * 30)
    assert exit_code(worse, statistics=fleet_statistics(worse, b, trial="run")) == 1
    good = _logs(["satisfied"] * 30)
    assert exit_code(good, statistics=fleet_statistics(good, b, trial="run")) == 0


@pytest.mark.parametrize("p,clean,one", [(0.5, 6, 9), (0.9, 36, 54), (0.95, 72, 110),
                                         (0.99, 368, 555), (0.999, 3688, 5570)])
def test_the_guides_table_of_runs_needed(p, clean, one):
    """docs/guide/statistics.md "How many runs a bound needs"."""
    for fails, n in ((0, clean), (1, one)):
        assert decide(">=", p, *clopper_pearson(n - fails, n)) == "holds"
        assert decide(">=", p, *clopper_pearson(n - 1 - fails, n - 1)) != "holds"


def test_mixed_set_each_judged_its_own_way(fleet):
    """A probability requirement that holds beside a plain one violated on some runs: the
    plain one gives exit 1; the probability one stays 'holds' and its runs pass in JUnit."""
    (fleet / "mixed.fret").write_text(
        "P1: the robot shall with probability >= 0.5 always satisfy ok\n"
        "Q: the robot shall always satisfy ok\n")
    out = fleet / "mixed.json"
    res = CliRunner().invoke(main, ["audit", "-r", str(fleet / "mixed.fret"),
                                    str(fleet / "runs"), "--no-progress", "--json", str(out),
                                    "--junit", str(fleet / "mixed.xml")])
    assert res.exit_code == 1
    p1, q = json.loads(out.read_text())["statistics"]
    assert p1["verdict"] == "holds" and q["bound"] is None and q["verdict"] is None
    assert q["violated"] == N - K
    junit = ET.parse(fleet / "mixed.xml").getroot()
    failed = {c.get("name") for c in junit.iter("testcase") if c.find("failure") is not None}
    assert failed == {"Q"}


def test_a_probability_outside_0_1_is_refused_with_its_position(tmp_path):
    f = tmp_path / "bad.fret"
    f.write_text("P: the robot shall with probability >= 1.5 always satisfy ok\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "ltl"])
    assert res.exit_code == 1 and "outside [0, 1]" in res.output and f"{f}:1:" in res.output
