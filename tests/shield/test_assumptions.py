"""The plant in the proof: assumptions of the environment (``fretc shield
--assume``) as the shield's game's assumptions.

A requirement over inputs only (``d > 0``) is monitored without them; with assumptions that
relate ``d`` to the output ``go`` it is enforced: the environment loses a play in which it
breaks one. ``--prove`` proves it under them and says so; the Python and C forms report an
assumption that breaks (``Decision.broken``, the C state's ``broken``, the runner's column)
and give their fallback from then on. An assumption that reads an output at the tick it is
judged (the controller could break it) is refused. On random runs that keep the
assumptions, FRET's interval semantics finds the enforced requirement never violated. Safe-ROS:
R5 (``clearance > 0``) enforced under ``requirements/shield/environment.fret``, proved under
it, and unrealizable without the braking assumption.
"""

from __future__ import annotations

import csv
import io
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import tables
from fretc.shield.plan import ShieldError
from fretc.shield.prove import prove_shield
from fretc.shield.runtime import ShieldRuntime

from _c_monitors import build as build_c, needs_cc, write
from _gen import verdicts

REPO = Path(__file__).resolve().parents[2]
REQ = "R1: the sw shall always satisfy d > 0\nR2: whenever b sw shall immediately satisfy !go\n"
ASSUME = ("A0: env shall immediately satisfy d > 1\n"
          "A1: whenever d > 1 env shall at the next timepoint satisfy d > 0.5\n"
          "A2: whenever d <= 1 & !go env shall at the next timepoint satisfy d > 0\n")


def _compiled(folder: Path, name: str, text: str):
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return compile_entries(load_requirements([path]))


@pytest.fixture(scope="module")
def under(tmp_path_factory):
    folder = tmp_path_factory.mktemp("assume")
    reqs = _compiled(folder, "r.fret", REQ)
    assumed = _compiled(folder, "a.fret", ASSUME)
    return reqs, assumed, build_shield(reqs, ["b", "d"], ["go"], fork=False,
                                       assumptions=assumed)


@pytest.mark.tor("TOR-SHD-002")
def test_a_requirement_over_inputs_is_enforced_only_under_assumptions(tmp_path, under):
    reqs, assumed, shield = under
    alone = build_shield(reqs, ["b", "d"], ["go"], fork=False)
    assert list(alone.monitored) == ["R1"]
    assert [r.id for r in shield.requirements] == ["R1", "R2"] and not shield.monitored
    assert [a.id for a in shield.assumptions] == ["A0", "A1", "A2"]
    proof = prove_shield(shield, [*reqs, *assumed])
    assert proof.holds and proof.under["R1"] == ("A0", "A1", "A2"), proof.text()
    assert "R1: holds under A0, A1, A2" in proof.text()
    assert "while the environment keeps its assumptions" in proof.text()


def test_the_forms_report_a_broken_assumption_and_give_the_fallback(tmp_path, under):
    _reqs, _assumed, shield = under
    rt = ShieldRuntime(tables(shield))
    assert shield.fallback is not None and shield.fallback["outputs"] == {"go": False}
    rows = [(False, 2.0, True), (False, 1.5, True), (False, 0.8, True), (False, 0.9, True),
            (True, 2.0, True), (False, 2.0, True), (False, 0.1, True), (False, 3.0, True)]
    got = []
    for b, d, go in rows:
        got.append(rt.step({"b": b, "d": d}, {"go": go}))
    assert [g.outputs["go"] for g in got[:6]] == [True, True, False, False, False, True]
    assert all(not g.broken for g in got[:6])
    # d from 2.0 to 0.1: A1 (at most 0.5 a tick) broken, for good: the fallback
    assert got[6].broken == ("A1",) and got[6].outputs == {"go": False} and got[6].overridden
    assert got[7].broken == ("A1",) and got[7].outputs == {"go": False}
    needs_cc()
    write(render_c(shield, "a"), tmp_path / "c")
    exe = build_c(tmp_path / "c", ["a_shield.c", "a_shield_run.c"], "run")
    text = "b,d,go\n" + "".join(f"{str(b).lower()},{d},{str(go).lower()}\n"
                                for b, d, go in rows)
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    c = list(csv.DictReader(io.StringIO(out.stdout)))
    assert [r["go"] for r in c] == [str(int(g.outputs["go"])) for g in got]
    assert [r["broken"] for r in c] == ["|".join(g.broken) for g in got]


def test_an_assumption_that_reads_an_output_now_is_refused(tmp_path):
    reqs = _compiled(tmp_path, "r.fret", REQ)
    bad = _compiled(tmp_path, "a.fret", "A9: whenever go env shall immediately satisfy d > 1\n")
    with pytest.raises(ShieldError, match="reads the output.s. go at the tick it is judged"):
        build_shield(reqs, ["b", "d"], ["go"], fork=False, assumptions=bad)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.floats(-0.4, 0.6), st.booleans()),
                min_size=1, max_size=40))
@pytest.mark.tor("TOR-SHD-002")
def test_runs_that_keep_the_assumptions_keep_the_requirements(under, steps):
    """Random runs whose ``d`` keeps A0..A2 (each tick's change drawn, then cut to what the
    assumptions allow given the shield's last output), random proposals: R1 and R2 are
    never violated on the corrected trace, and no assumption is reported broken."""
    reqs, _assumed, shield = under
    rt = ShieldRuntime(tables(shield))
    d, last_go, trace = 2.0, None, []
    for b, step, go in steps:
        if trace:
            floor = 0.5 if d > 1 else (0.0 if not last_go else -1.0)
            d = max(d - abs(step), floor + 1e-3) if step < 0 else d + step
        dec = rt.step({"b": b, "d": d}, {"go": go})
        assert not dec.broken, (trace, dec)
        assert not (b and dec.outputs["go"]), dec
        last_go = dec.outputs["go"]
        trace.append({"b": b, "d": d, "go": last_go})
    got = verdicts(reqs, trace)
    assert got["R1"] != "violated" and got["R2"] != "violated", (got, trace)


def _safe_ros(*extra: str):
    return CliRunner().invoke(main, [
        "shield", str(REPO / "requirements" / "safe_ros.fret"),
        str(REPO / "requirements" / "shield" / "release.fret"), "-b",
        str(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml"), "--inputs",
        "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind", "--outputs",
        "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,linear_velocity",
        *extra])


def test_safe_ros_r5_is_enforced_and_proved_under_the_shipped_assumptions(tmp_path):
    env = REPO / "requirements" / "shield" / "environment.fret"
    got = _safe_ros("--assume", str(env), "--prove")
    assert got.exit_code == 0, got.output
    assert "enforces R2, R3, R4, R5, R6, R8, R9, R10, R11" in got.output
    assert "R5: holds under E0, E1, E2, E3, E4" in got.output
    assert "monitored only" not in got.output
    # without the assumption of braking ahead (E3) no controller keeps the clearance: the
    # environment brings an obstacle ahead within 5 cm and the clearance to 0
    text = env.read_text()
    no_brake = tmp_path / "env.fret"
    no_brake.write_text(text.split("\nE3:")[0] + "\nE4:" + text.split("\nE4:")[1])
    got = _safe_ros("--assume", str(no_brake))
    assert got.exit_code == 2 and "unrealizable" in got.output, got.output


def _ab(tmp_path: Path, assumption: str):
    """The Safety System round's set: ``R1: always p``, ``R2: whenever a immediately o``, under one
    assumption of the environment: (compiled requirements, assumption, shield)."""
    (tmp_path / "r.fret").write_text("R1: ctrl shall always satisfy p\n"
                                     "R2: whenever a ctrl shall immediately satisfy o\n")
    (tmp_path / "a.fret").write_text(assumption + "\n")
    compiled = compile_entries(load_requirements([tmp_path / "r.fret"]))
    assumed = compile_entries(load_requirements([tmp_path / "a.fret"]))
    return compiled, assumed, build_shield(compiled, ["a"], ["p", "o"], fork=False,
                                           assumptions=assumed)


def test_a_broken_assumption_never_turns_the_shield_against_a_correct_controller(tmp_path):
    """The Safety System round: under ``A5: environment shall always satisfy !a`` the fallback was ``p,
    !o`` (robust only while A5 holds), and once ``a`` came the shield overrode a correct
    controller with ``o = false`` at every tick (R2 failed 101 of 200 ticks). The fallback
    now keeps the requirements without the assumptions: R2 kept after A5 breaks."""
    compiled, _assumed, shield = _ab(tmp_path, "A5: environment shall always satisfy !a")
    assert shield.fallback is not None and shield.fallback["outputs"] == {"p": True, "o": True}
    rt = ShieldRuntime(tables(shield))
    rows = []
    for k in range(200):
        a = k >= 99
        d = rt.step({"a": a}, {"p": True, "o": a})  # (a correct controller)
        rows.append({"a": a, **d.outputs})
        assert d.broken == (("A5",) if a else ()), d
    assert verdicts(compiled, rows) == {"R1": "satisfied", "R2": "satisfied"}


@pytest.mark.parametrize("assumption,why", [
    ("A5: environment shall always satisfy !a",
     "under A5 no run of the closed loop fires its trigger"),
    ("A1: environment shall always satisfy a & !a",
     "no run of the closed loop keeps the assumptions A1: nothing is proved")])
@pytest.mark.tor("TOR-SHD-002")
def test_prove_never_calls_an_impossible_or_vacuous_assumption_proved(tmp_path, assumption,
                                                                      why):
    """The Safety System round: an assumption no run can keep (A1) was "proved" without a word, and one that
    makes R2 vacuous (A5) "proved" R2: both are "vacuous" with the reason, NOT PROVED."""
    compiled, assumed, shield = _ab(tmp_path, assumption)
    proof = prove_shield(shield, [*compiled, *assumed])
    assert proof.results["R2"] == "vacuous" and why in proof.why["R2"], proof.text()
    assert not proof.holds and "NOT PROVED" in proof.text()
    # (an assumption every run keeps proves both)
    compiled, assumed, shield = _ab(tmp_path, "A2: environment shall always satisfy a | !a")
    proof = prove_shield(shield, [*compiled, *assumed])
    assert proof.results == {"R1": "holds", "R2": "holds"} and proof.holds, proof.text()
