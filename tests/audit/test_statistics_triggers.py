"""Probability requirements judged per trigger (FRET's reading, audit/fleet/statistics.py): a fleet
of runs with several triggers each gives the per-trigger estimate and its interval (runs as
clusters), where the per-run reading decides otherwise; the interval's effective sample size
against an independent computation; a fleet whose triggers are perfectly correlated within
runs does not fool it; unknown and error runs or triggers never support a bound; one log
decides no per-trigger bound."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings, strategies as st
from scipy.stats import beta, binomtest

from fretc.audit.fleet.intervals import (Counts, clopper_pearson, cluster_interval,
                                         effective_clopper_pearson)
from fretc.audit.fleet.statistics import fleet_statistics
from fretc.audit.trials import Trials
from fretc.audit.verdict import LogAudit, Verdict, exit_code
from fretc.cli import main
from fretc.compiler.ir import ProbabilityBound

REQ = "P: upon c the robot shall with probability {op} {p} within 1 ticks satisfy r\n"


def _run_csv(results: list[bool]) -> str:
    """A CSV run with one trigger per result: ``c`` rises, ``r`` follows within one tick
    when the result is True; quiet ticks after each (no trigger is cut)."""
    rows = ["c,r", "0,0"]
    for ok in results:
        rows += ["1,0", f"0,{int(ok)}", "0,0"]
    return "\n".join(rows) + "\n"


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """60 runs of 5 triggers: 30 runs meet all 5, 30 miss exactly one (270 of 300)."""
    d = tmp_path_factory.mktemp("triggers")
    (d / "runs").mkdir()
    for i in range(60):
        results = [True] * 5 if i < 30 else [True, True, False, True, True]
        (d / "runs" / f"run{i:02d}.csv").write_text(_run_csv(results))
    (d / "p.fret").write_text(REQ.format(op=">=", p="0.75"))
    return d


def _audit(d, *extra):
    out = d / f"audit{len(extra)}.json"
    res = CliRunner().invoke(main, ["audit", "-r", str(d / "p.fret"), str(d / "runs"),
                                    "--no-progress", "--json", str(out), *extra])
    return res, json.loads(out.read_text())


@pytest.mark.tor("TOR-VER-010")
def test_per_trigger_and_per_run_readings_decide_differently(fleet):
    res, doc = _audit(fleet)
    (st,) = doc["statistics"]
    assert st["trial"] == "trigger" and (st["successes"], st["trials"]) == (270, 300)
    assert st["estimate"] == pytest.approx(0.9)
    assert st["triggers_per_run"] == {"min": 5, "mean": 5.0, "max": 5}
    assert st["triggers"] == {"satisfied": 270, "violated": 30, "cut": 0, "unknown": 0,
                              "hidden_runs": 0}
    # equal runs as clusters: Clopper-Pearson of 60 runs with 54 (= 0.9 x 60) successes
    assert st["effective_trials"] == pytest.approx(60)
    want = (beta.ppf(0.025, 54, 7), beta.ppf(0.975, 55, 6))
    assert st["interval"] == pytest.approx(want, abs=1e-9)
    assert st["verdict"] == "holds" and res.exit_code == 0, res.output
    v = doc["logs"][-1]["verdicts"][0]
    assert v["verdict"] == "violated" and v["trials"]["violated"] == 1  # the run, per trigger
    # the per-run reading: 30 of 60 runs meet every trigger; the stronger claim fails
    res, doc = _audit(fleet, "--trial", "run")
    (st,) = doc["statistics"]
    ci = binomtest(30, 60).proportion_ci(method="exact")
    assert st["trial"] == "run" and st["interval"] == pytest.approx([ci.low, ci.high])
    assert st["verdict"] == "fails" and res.exit_code == 1
    assert "triggers/run" in CliRunner().invoke(main, [
        "audit", "-r", str(fleet / "p.fret"), str(fleet / "runs"), "--no-progress"]).output


def _fleet(sizes_ok: list[tuple[int, int]], **trials) -> list[LogAudit]:
    """Logs whose requirement ``P`` had ``ok`` of ``n`` triggers met in each run."""
    logs = []
    for i, (ok, n) in enumerate(sizes_ok):
        t = Trials(satisfied=ok, violated=n - ok, **trials)
        verdict = "satisfied" if ok == n else "violated"
        logs.append(LogAudit(f"l{i}", verdicts=[Verdict(f"l{i}", "P", verdict=verdict,
                                                        trials=t)]))
    return logs


def test_unequal_runs_take_kish_effective_sample_size():
    runs = [(1, 1), (2, 3), (9, 10), (0, 2), (20, 20), (4, 4)]
    (st,) = fleet_statistics(_fleet(runs), {"P": ProbabilityBound(">=", "0.5")})
    m = np.array([n for _, n in runs], float)
    ne = m.sum() ** 2 / (m ** 2).sum()
    k = sum(ok for ok, _ in runs) / m.sum() * ne
    assert st.effective_trials == pytest.approx(ne)
    assert st.interval == pytest.approx((beta.ppf(0.025, k, ne - k + 1),
                                         beta.ppf(0.975, k + 1, ne - k)))
    assert st.estimate == pytest.approx(36 / 40)


def test_perfectly_correlated_triggers_do_not_fool_the_interval():
    """Each run's 20 triggers all succeed or all fail, with P = 0.88: the bound >= 0.9 is
    false. Counting triggers as independent says 'holds' in many fleets of 40 runs; runs as
    clusters keep it within the 2.5 % the interval allows."""
    rng = np.random.default_rng(5)
    naive = clustered = 0
    fleets = 400
    for _ in range(fleets):
        ok = rng.random(40) < 0.88
        c = Counts()
        for x in ok:
            c.add(20 * int(x), 20)
        lo, _ = cluster_interval(c, 0.95)
        clustered += lo >= 0.9
        naive += binomtest(c.successes, c.trials).proportion_ci(method="exact").low >= 0.9
    assert naive / fleets > 0.2  # what an interval over independent triggers would say
    assert clustered / fleets <= 0.025 + 3 * (0.025 * 0.975 / fleets) ** 0.5


def test_effective_clopper_pearson_is_scipys_at_integer_counts():
    for k, n in ((0, 5), (3, 7), (7, 7), (40, 100)):
        ci = binomtest(k, n).proportion_ci(confidence_level=0.9, method="exact")
        assert effective_clopper_pearson(float(k), float(n), 0.9) == pytest.approx(
            (ci.low, ci.high))


@settings(max_examples=300, deadline=None)
@given(n=st.integers(1, 50_000), share=st.floats(0, 1),
       confidence=st.sampled_from([0.5, 0.8, 0.9, 0.95, 0.99, 0.999, 0.999999]))
def test_the_beta_quantile_interval_is_scipys_root_searched_one(n, share, confidence):
    """clopper_pearson's beta quantiles against scipy's exact interval by root search
    (binomtest; its tolerance 2e-12), on counts up to 50,000 trials and tail confidences;
    effective_clopper_pearson at integer counts is clopper_pearson's interval."""
    k = round(share * n)
    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="exact")
    lo, hi = clopper_pearson(k, n, confidence)
    assert abs(lo - ci.low) <= 1e-9 and abs(hi - ci.high) <= 1e-9, (k, n, confidence)
    assert (k == 0) == (lo == 0.0) and (k == n) == (hi == 1.0)
    assert effective_clopper_pearson(float(k), float(n), confidence) == (lo, hi)


# ------------------------------------------------------------------ never support a bound
def test_unknown_triggers_widen_the_interval_both_ways():
    logs = _fleet([(5, 5)] * 20, unknown=2)
    b = {"P": ProbabilityBound(">=", "0.7")}
    (worst,) = fleet_statistics(logs, b)
    (excl,) = fleet_statistics(logs, b, unknown="exclude")
    assert worst.unknown_trials == 40 and excl.unknown_trials == 0
    assert worst.interval[0] < excl.interval[0] and worst.interval[1] == excl.interval[1] == 1
    lo_alone = cluster_interval(Counts(100, 140, 0, 20, 140, 20 * 49), 0.95)[0]
    assert worst.interval[0] == pytest.approx(lo_alone)  # as if every unknown one failed


@pytest.mark.parametrize("trial", ["trigger", "run"])
def test_unknown_and_error_runs_do_not_help_an_upper_bound(trial):
    """The hostile round: two judged runs against a <= bound, the rest unknown or errors:
    counted as failures they made '<= 0.5 holds'. Now never."""
    logs = _fleet([(1, 1), (1, 1)])
    for i in range(30):
        la = LogAudit(f"u{i}", verdicts=[Verdict(f"u{i}", "P", verdict="unknown",
                                                 trials=Trials(unknown=1))])
        logs.append(la)
    logs += [LogAudit(f"e{i}", error="cannot read", verdicts=[]) for i in range(10)]
    b = {"P": ProbabilityBound("<=", "0.5")}
    for policy in ("worst-case", "fail", "exclude"):
        (st,) = fleet_statistics(logs, b, unknown=policy, trial=trial)
        assert st.verdict != "holds", (policy, st)
    (st,) = fleet_statistics(logs, b, trial=trial)
    assert st.verdict == "undecided" and st.why
    assert exit_code(logs, statistics=[st], allow_partial=True) != 0
    if trial == "trigger":
        assert "could not be judged" in st.why  # error runs hide any number of triggers


def test_one_log_decides_no_per_trigger_bound(tmp_path):
    (tmp_path / "p.fret").write_text(REQ.format(op=">=", p="0.01"))
    (tmp_path / "one.csv").write_text(_run_csv([True] * 40))
    out = tmp_path / "a.json"
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "p.fret"),
                                    str(tmp_path / "one.csv"), "--no-progress", "--json",
                                    str(out)])
    doc = json.loads(out.read_text())
    (st,) = doc["statistics"]
    assert (st["successes"], st["trials"]) == (40, 40)
    assert doc["logs"][0]["verdicts"][0]["trials"]["satisfied"] == 40
    assert st["verdict"] == "undecided" and "one run" in st["why"]
    assert res.exit_code == 5 and "one run" in res.output


@pytest.mark.parametrize("option,value", [("--confidence", "nan"), ("--confidence", "1e-9"),
                                          ("--confidence", "inf"), ("--confidence", "1")])
def test_statistics_options_are_validated(fleet, option, value):
    res = CliRunner().invoke(main, ["audit", "-r", str(fleet / "p.fret"), str(fleet / "runs"),
                                    "--no-progress", option, value])
    # fretc's refusal, not click's wording of it (which changes between click releases)
    assert res.exit_code == 2 and "'--confidence'" in res.output, res.output
    assert "Traceback" not in res.output


@pytest.mark.parametrize("trial", ["trigger", "run"])
@pytest.mark.parametrize("op,p", [("<=", "1"), (">=", "0")])
def test_a_bound_every_probability_meets_is_not_decided_without_trials(trial, op, p):
    """Found by bench/fuzz_statistics.py: '<= 1' was 'holds' over no judged run at all.
    A bound is decided by trials; with none it is undecided, saying so."""
    logs = [LogAudit(f"e{i}", error="cannot read", verdicts=[]) for i in range(3)]
    for policy in ("worst-case", "exclude"):
        (st,) = fleet_statistics(logs, {"P": ProbabilityBound(op, p)}, unknown=policy,
                                 trial=trial)
        assert st.verdict == "undecided" and st.why, (policy, st)
    (st,) = fleet_statistics([], {"P": ProbabilityBound(op, p)}, trial=trial)
    assert st.verdict == "undecided" and "no trial" in st.why
