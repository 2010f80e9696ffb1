"""fretc check: requirement sets whose answers are known by construction, and
witness CSVs audited by fretc audit giving the verdicts their headers promise."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from click.testing import CliRunner

from fretc.compiler.build import compile_entries
from fretc.check.analysis import check_requirements
from fretc.check.witness import read_expected
from fretc.cli import main
from fretc.fretish.files import load_requirements
from tests.check._replay import audit_verdicts

ROOT = Path(__file__).resolve().parents[2]


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def _check(path, **kw):
    return check_requirements(compile_entries(load_requirements([path])), **kw)


def _kinds(result):
    return sorted((f.kind, tuple(f.requirements)) for f in result.findings)


@pytest.mark.tor("TOR-CHK-002")
def test_consistent_set_has_no_finding(tmp_path):
    p = _write(tmp_path, "ok.fret",
               "C1: upon p the sw shall within 3 ticks satisfy q\n"
               "C2: whenever q the sw shall immediately satisfy r\n"
               "C3: in modeA the sw shall always satisfy a\n"
               "C4: in modeB the sw shall always satisfy !a\n")
    r = _check(p)
    assert r.findings == [] and r.exit_code == 0
    assert all(s["satisfiable"] is True and s["non_vacuous"] is True for s in r.requirements)
    assert r.groups == [["C1", "C2"], ["C3", "C4"]]


def test_fret_non_vacuity_example(tmp_path):
    # FRET passes this pair: modeA may never be entered. Both are vacuous together.
    p = _write(tmp_path, "modes.fret",
               "A1: in modeA the sw shall always satisfy a\n"
               "A2: in modeA the sw shall always satisfy !a\n")
    r = _check(p)
    assert _kinds(r) == [("vacuous", ("A1", "A2")), ("vacuous", ("A2", "A1"))]
    assert all(f.subsets == [["A1", "A2"]] for f in r.findings)
    assert r.exit_code == 1
    assert [s["satisfiable"] for s in r.requirements] == [True, True]


@pytest.mark.tor("TOR-CHK-002")
def test_conflict_only_in_a_mode(tmp_path):
    # the pair conflicts only inside modeA; a third requirement forces modeA
    p = _write(tmp_path, "modes.fret",
               "A1: in modeA the sw shall always satisfy a\n"
               "A2: in modeA the sw shall always satisfy !a\n"
               "A3: the sw shall eventually satisfy modeA\n"
               "A4: the sw shall always satisfy b\n")
    r = _check(p)
    conflicts = [f for f in r.findings if f.kind == "conflict"]
    assert len(conflicts) == 1 and conflicts[0].subsets == [["A1", "A2", "A3"]]
    assert not conflicts[0].cut


def test_bounded_timings_within_against_for(tmp_path):
    p = _write(tmp_path, "b.fret",
               "B1: upon p the sw shall within 3 ticks satisfy q\n"
               "B2: upon p the sw shall for 5 ticks satisfy !q\n")
    r = _check(p)
    assert {f.kind for f in r.findings} == {"vacuous"}
    # the other way round the windows leave room: q at ticks 4 or 5
    p2 = _write(tmp_path, "b2.fret",
                "B1: upon p the sw shall within 5 ticks satisfy q\n"
                "B2: upon p the sw shall for 3 ticks satisfy !q\n")
    assert _check(p2).findings == []


@pytest.mark.tor("TOR-CHK-002")
def test_numeric_thresholds_exclude_each_other(tmp_path):
    p = _write(tmp_path, "n.fret",
               "N1: the sw shall always satisfy speed <= 0.5\n"
               "N2: the sw shall always satisfy speed > 1.0\n"
               "N3: the sw shall always satisfy other > 1.0\n")
    r = _check(p)
    assert _kinds(r) == [("conflict", ("N1", "N2"))]
    assert r.abstractions == []


def test_numeric_implication_is_redundancy(tmp_path):
    p = _write(tmp_path, "n.fret",
               "N1: the sw shall always satisfy speed > 5\n"
               "N2: the sw shall always satisfy 3 < speed\n")
    r = _check(p)
    assert _kinds(r) == [("redundant", ("N2",))]
    assert r.exit_code == 0  # a warning


def test_uninterpreted_atoms_are_listed(tmp_path):
    p = _write(tmp_path, "u.fret", "U1: the sw shall always satisfy x + y > 2\n")
    r = _check(p)
    assert [a["atom"] for a in r.abstractions] == ["((x + y) > 2)"]


def test_self_vacuous_requirement(tmp_path):
    p = _write(tmp_path, "s.fret", "S1: upon p the sw shall immediately satisfy !p\n")
    r = _check(p)
    assert _kinds(r) == [("vacuous", ("S1",))] and r.findings[0].subsets == [["S1"]]


def test_satisfiable_but_unrealizable(tmp_path):
    p = _write(tmp_path, "u.fret",
               "@inputs too_close\n@outputs stopped\n"
               "U1: upon too_close the robot shall within 3 ticks satisfy stopped\n"
               "U2: the robot shall always satisfy too_close\n")
    entries = load_requirements([p])
    assert entries[0].inputs == ("too_close",) and entries[0].outputs == ("stopped",)
    r = check_requirements(compile_entries(entries), inputs=["too_close"],
                           outputs=["stopped"])
    assert _kinds(r) == [("unrealizable", ("U2",))]
    comp = r.realizability["groups"][0]
    assert comp["realizable"] is False and comp["minimal_unrealizable"] == [["U2"]]
    env = comp["environment"]
    assert any(row["too_close"] is False for row in env["prefix"] + env["cycle"])
    # the same set with too_close an output is realizable
    r2 = check_requirements(compile_entries(entries), inputs=[], outputs=["stopped",
                                                                          "too_close"])
    assert r2.findings == [] and r2.realizability["groups"][0]["strategy"][
        "state_bits"] >= 1
    r3 = check_requirements(compile_entries(entries), inputs=[], engine="spot",
                            outputs=["stopped", "too_close"])
    assert r3.findings == [] and r3.realizability["groups"][0]["mealy_states"] >= 1


def test_reactive_environment_needs_no_fixed_sequence(tmp_path):
    # the controller would have to predict the next input: unrealizable, but every fixed
    # input sequence has a matching output sequence
    p = _write(tmp_path, "p.fret", "P1: the robot shall always satisfy o <-> i2\n"
               "P2: the robot shall always satisfy i2 <-> i\n")
    r = _check(p, inputs=["i"], outputs=["o", "i2"])
    assert r.findings == []  # o can follow i within the same tick
    from fretc.check.solver import run_query
    ok, counter = run_query(("realizable", "G(o <-> X i)", ["o"]))
    assert ok is False and counter is None


def test_spot_past_its_bound_is_refused_as_unknown(tmp_path):
    """Spot's translation of a 40-tick bound may not end and cannot be stopped: the query
    is refused before Spot starts, unknown with the reason (the same on any machine)."""
    p = _write(tmp_path, "t.fret",
               "T1: in m upon p the sw shall within 40 ticks satisfy q\n"
               "T2: in m upon r the sw shall for 40 ticks satisfy !q\n")
    r = _check(p, engine="spot")
    assert r.unknown_queries >= 1
    assert any(f.kind == "unknown" for f in r.findings) and r.exit_code == 1
    assert any("Spot is given tick bounds up to 16" in n for n in r.notes), r.notes


def test_cli_json_and_exit_codes(tmp_path):
    p = _write(tmp_path, "n.fret", "N1: the sw shall always satisfy speed <= 0.5\n"
               "N2: the sw shall always satisfy speed > 1.0\n")
    res = CliRunner().invoke(main, ["check", str(p), "--json"])
    assert res.exit_code == 1
    doc = json.loads(res.output)
    assert doc["findings"][0]["kind"] == "conflict" and doc["exit_code"] == 1
    bad = _write(tmp_path, "bad.fret", "X1 the sw shall always satisfy a\n")
    assert CliRunner().invoke(main, ["check", str(bad)]).exit_code == 2
    both = _write(tmp_path, "both.fret", "@inputs a\n@outputs a\nX1: the sw shall always satisfy a\n")
    assert CliRunner().invoke(main, ["check", str(both)]).exit_code == 2


@pytest.mark.parametrize("text", [
    "A1: in modeA the sw shall always satisfy a\nA2: in modeA the sw shall always satisfy !a\n",
    "A1: in modeA the sw shall always satisfy a\nA2: in modeA the sw shall always satisfy !a\n"
    "A3: the sw shall eventually satisfy modeA\n",
    "B1: upon p the sw shall within 3 ticks satisfy q\n"
    "B2: upon p the sw shall for 5 ticks satisfy !q\nB3: whenever q the sw shall immediately "
    "satisfy speed > 2\n",
    "N1: the sw shall always satisfy speed <= 0.5\nN2: upon go the sw shall eventually satisfy "
    "speed > 1.0\nN3: the sw shall eventually satisfy go\n",
    "S1: upon p the sw shall immediately satisfy !p\n",
    "C1: upon p the sw shall within 3 ticks satisfy q\n"
    "C2: whenever q the sw shall immediately satisfy r & speed < 0.1\n"
    "C3: in m the sw shall always satisfy speed >= 0\n",
])
def test_witnesses_replay_through_the_audit(tmp_path, text):
    req = _write(tmp_path, "set.fret", text)
    wdir = tmp_path / "w"
    from fretc.monitors.interval import verdict_of

    r = _check(req, witness_dir=str(wdir), witness_judge=verdict_of)
    assert r.witnesses, "every finding here (or the consistent set) has a witness"
    for w in r.witnesses:
        promised = read_expected(w["path"])
        assert promised == w["expected"] and promised
        assert audit_verdicts(req, Path(w["path"]), tmp_path) == promised
    for f in r.findings:
        if f.witness:
            assert f.details["witness_shows_finding"] is True


def test_safe_ros_requirements(tmp_path):
    """Every variable declared (the sensor reading ``clearance`` an input): R5 alone is
    unrealizable, the others realizable (tests/check/test_undeclared.py: with ``clearance``
    undeclared R5 is not decided)."""
    files = sorted(str(p) for p in (ROOT / "requirements").glob("*.fret"))
    res = CliRunner().invoke(main, ["check", *files, "--inputs", "too_close,clearance,scan_stale",
                                    "--outputs", "stopped,stop_requested,forwarded_zero,"
                                    "linear_speed,angular_speed", "--json"])
    doc = json.loads(res.output)
    assert res.exit_code == 1, res.output
    assert [(f["kind"], f["requirements"]) for f in doc["findings"]] == [
        ("unrealizable", ["R5"])]
    assert {tuple(c["requirements"]): c["realizable"]
            for c in doc["realizability"]["groups"]} == {
        ("R1", "R2"): True, ("R3", "R6"): True, ("R4",): True, ("R5",): False}


def test_report_shows_check_findings(tmp_path):
    req = _write(tmp_path, "modes.fret",
                 "A1: in modeA the sw shall always satisfy a\n"
                 "A2: in modeA the sw shall always satisfy <b>!a</b>\n".replace("<b>", "")
                 .replace("</b>", ""))
    check_json = tmp_path / "check.json"
    wdir = tmp_path / "w"
    res = CliRunner().invoke(main, ["check", str(req), "-o", str(check_json),
                                    "--witness-dir", str(wdir)])
    assert res.exit_code == 1
    witness = sorted(wdir.glob("*.csv"))[0]
    out = tmp_path / "report"
    res = CliRunner().invoke(main, ["report", "-r", str(req), str(witness), "-o", str(out),
                                    "--check", str(check_json)])
    assert res.exit_code in (0, 1), res.output
    md = (out / "report.md").read_text()
    assert "## Check findings" in md and "| A1 |" in md and "vacuous:" in md
    assert 'id="check-findings"' in (out / "report.html").read_text()


_TEMPLATES = ["G(i -> F[0..{k}] o)", "G(o -> !p)", "G(i -> X o)", "G(o -> X i)",
              "G(i -> o)", "F o", "G(i -> F p)", "G(p -> X !p)", "G(j -> (o U i))",
              "G(!o | !j)", "G(o -> F[0..{k}] j)", "G((i & j) -> p)", "F G o", "G F i -> G F p"]


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(_TEMPLATES), st.integers(1, 4)), min_size=2,
                max_size=4))
def test_product_game_agrees_with_ltl_to_game(parts):
    """The per-conjunct product game and Spot's ltl_to_game on the conjunction decide
    realizability alike (inputs i, j; outputs o, p)."""
    import spot

    from fretc.check.solver import _conj, _product_game

    texts = [t.format(k=k) for t, k in parts]
    game = _product_game(texts, ["o", "p"])
    ref = spot.ltl_to_game(spot.formula(_conj(texts)), ["o", "p"], spot.synthesis_info())
    expected = spot.solve_game(ref)
    if game is not None:
        assert spot.solve_game(game) == expected, texts


def test_spot_errors_are_unknown_answers_not_crashes(tmp_path):
    """A bound beyond what Spot is given (16 ticks; Spot's own limit is 254) and a
    realizability query over numeric outputs (Spot cannot parse the comparison) give
    unknown answers with the reason, exit 1, no traceback."""
    from click.testing import CliRunner

    from fretc.cli import main

    big = tmp_path / "big.fret"
    big.write_text("C1: whenever p the sw shall within 300 ticks satisfy q\n")
    res = CliRunner().invoke(main, ["check", str(big), "--engine", "spot"])
    assert res.exit_code == 1, res.output
    assert "satisfiable=unknown" in res.output
    assert "Spot is given tick bounds up to 16, this query has 300" in res.output
    res = CliRunner().invoke(main, ["check", str(big)])  # auto: z3 past 16 ticks
    assert res.exit_code == 0 and "satisfiable=yes" in res.output, res.output
    ab = tmp_path / "ab.fret"
    ab.write_text("A: the r shall always satisfy s <= 0.5\n"
                  "B: whenever p the r shall immediately satisfy s > 0.6\n")
    res = CliRunner().invoke(main, ["check", str(ab), "--inputs", "p", "--outputs", "s",
                                    "--engine", "spot"])
    assert res.exit_code == 1 and "Traceback" not in res.output
    assert "realizability of A, B unknown" in res.output and "Spot could not take" in res.output
    # the safety game (auto) decides it: p at the first tick defeats every controller
    res = CliRunner().invoke(main, ["check", str(ab), "--inputs", "p", "--outputs", "s"])
    assert res.exit_code == 1 and "UNREALIZABLE (safety game)" in res.output, res.output
    assert "inputs that defeat every controller: {p=true}" in res.output


def test_progress_names_each_stage_and_query_in_order(tmp_path):
    """``progress`` is called before every query of each stage, component by component:
    each requirement alone, the set, non-vacuity and redundancy, counting 1..n; a component
    whose requirements conflict stops after the set (no vacuity, no redundancy)."""
    p = _write(tmp_path, "ok.fret",
               "C1: upon p the sw shall within 3 ticks satisfy q\n"
               "C2: whenever q the sw shall immediately satisfy r\n"
               "C3: whenever q the sw shall immediately satisfy r\n"
               "K1: the sw shall always satisfy k\n"
               "K2: the sw shall always satisfy !k\n")
    calls: list[tuple] = []
    r = _check(p, progress=lambda *a: calls.append(a))
    assert r.groups == [["C1", "C2", "C3"], ["K1", "K2"]]
    want = ([("alone", i, 3, 1, 2) for i in (1, 2, 3)] + [("set", 1, 1, 1, 2)]
            + [("vacuity", i, 3, 1, 2) for i in (1, 2, 3)]
            + [("redundancy", i, 3, 1, 2) for i in (1, 2, 3)]
            + [("alone", i, 2, 2, 2) for i in (1, 2)] + [("set", 1, 1, 2, 2)])
    assert calls == want
    # the same answers with and without it
    assert _kinds(r) == _kinds(_check(p)) and r.requirements == _check(p).requirements


def test_fretc_check_shows_its_progress_on_a_terminal_only(tmp_path):
    """On a terminal the standard error shows the stage being checked (rich's transient
    bar); ``--no-progress``, or a standard error that is not a terminal, shows none."""
    import os
    import pty
    import subprocess
    import sys

    p = _write(tmp_path, "ok.fret", "C1: upon p the sw shall within 3 ticks satisfy q\n"
                                    "C2: whenever q the sw shall immediately satisfy r\n")

    def stderr_on_a_terminal(*extra: str) -> str:
        main_fd, other_fd = pty.openpty()
        proc = subprocess.Popen([sys.executable, "-m", "fretc", "check", str(p), *extra],
                                stdout=subprocess.DEVNULL, stderr=other_fd)
        os.close(other_fd)
        got = b""
        while True:
            try:
                chunk = os.read(main_fd, 4096)
            except OSError:  # the terminal's other end closed
                break
            if not chunk:
                break
            got += chunk
        assert proc.wait(timeout=120) == 0
        os.close(main_fd)
        return got.decode("utf-8", "replace")

    # (the bar is drawn when it starts and then 10 times a second: which stage it shows
    # depends on the machine's speed)
    words = ("checking", "each requirement alone", "the set", "non-vacuity", "redundancy")
    assert any(w in stderr_on_a_terminal() for w in words)
    assert not any(w in stderr_on_a_terminal("--no-progress") for w in words)
    res = subprocess.run([sys.executable, "-m", "fretc", "check", str(p)], capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0 and res.stderr == ""
