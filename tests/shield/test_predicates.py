"""Comparisons of several variables in the shield (:mod:`fretc.shield.predicates`): z3's
invariant allows every valuation some numbers give and no other, its numbers give their
valuation in doubles; shields of random sets over such comparisons keep their requirements
(FRET's interval semantics on the corrected trace), let safe proposals through, decide alike
in Python and C, and are proved; the FRET case studies that compare two variables give
shields (or are refused for another, named reason)."""

from __future__ import annotations

import csv
import io
import itertools
import json
import math
import random
import re
import subprocess
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.compiler import ir
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import tables
from fretc.shield.plan import ShieldError
from fretc.shield.predicates import clusters, term
from fretc.shield.prove import prove_shield
from fretc.shield.runtime import ShieldRuntime, term_value

from _c_monitors import build, needs_cc, write
from _gen import atoms_of, compile_text, safe, shield_or_assume, verdicts, unscoped_sets

INPUTS = ["a", "b"]
OUTPUTS = ["x", "p", "q", "r"]
CONDITIONS = ["", "whenever a ", "upon a ", "upon b | x ", "whenever p < q "]
RESPONSES = ["p < q", "p + q > 3", "p <= 1 & q < p", "q = p", "!(p < q) | x", "p = r | q = r",
             "2 * p - q >= 1", "absReal(p - q) <= 1", "x -> maxReal(p, q) > 2"]
TIMINGS = ["immediately ", "at the next timepoint ", "within 2 ticks ", "for 2 ticks ",
           "always ", "never ", "until b "]
NUMBERS = [-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.5]
SETTINGS = settings(max_examples=30, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@st.composite
def sets(draw) -> str:
    """1 .. 3 requirements over comparisons of several variables (module docstring)."""
    return draw(unscoped_sets(CONDITIONS, TIMINGS, RESPONSES))


@st.composite
def runs(draw, length: int = 30) -> list[tuple[dict, dict]]:
    out = []
    for _ in range(draw(st.integers(1, length))):
        out.append(({"a": draw(st.booleans()), "b": draw(st.booleans())},
                    {"x": draw(st.booleans()), **{v: draw(st.sampled_from(NUMBERS))
                                                  for v in ("p", "q", "r")}}))
    return out


def _shield(text: str):
    return shield_or_assume(text, INPUTS, OUTPUTS)


def _pred(text: str):
    with tempfile.TemporaryDirectory() as tmp:
        (c,) = compile_text(f"@inputs a\n@outputs p, q, r\nR: sw shall always satisfy {text}\n",
                            Path(tmp))
    return c.formalization.ft_inf


@pytest.mark.parametrize("formula", ["p < q & q < r & p <= 1 & r > 2",
                                     "p + q > 3 | q = r | 2 * p <= r",
                                     "absReal(p - q) <= 1 & p > 5 & q < 4.5 | minReal(p, r) = q"])
def test_the_invariant_allows_exactly_the_valuations_numbers_give(formula):
    (cl,) = clusters([_pred(formula)], INPUTS)
    atoms = [term(a) for a in cl.atoms]
    rnd = random.Random(0)
    seen = set()
    for _ in range(3000):  # numbers drawn at random: every valuation they give is allowed
        values = {v: rnd.choice([-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.5, 5.5, 7.0]) for v in cl.variables}
        seen.add(tuple(bool(term_value(t, values)) for t in atoms))
    names = {a: ir.ap(f"_a{k}") for k, a in enumerate(cl.atoms)}
    for valuation in itertools.product((False, True), repeat=len(atoms)):
        allowed = _holds(cl.invariant, dict(zip(cl.atoms, valuation)))
        assert allowed == (valuation in cl.witnesses), valuation
        if valuation in seen:
            assert allowed, valuation
    for valuation, numbers in cl.witnesses.items():  # the recorded numbers give it
        assert tuple(bool(term_value(t, numbers)) for t in atoms) == valuation
    assert names  # the cluster has atoms


def _holds(f, truth: dict) -> bool:
    if f in truth:
        return truth[f]
    if f.op in ("true", "false"):
        return f.op == "true"
    args = [_holds(a, truth) for a in f.args]
    return {"!": lambda: not args[0], "&": lambda: all(args), "|": lambda: any(args)}[f.op]()


def test_a_comparison_of_an_input_with_an_output_is_enforced_as_a_bound(tmp_path):
    """``p < a`` (a the environment's) was refused ("which its game does not see"): it is a
    bound of p by the input (fretc.check.bounds), enforced: p the proposal where it is below
    a, else the largest double below a."""
    compiled = compile_text("R: sw shall always satisfy p < a\n", tmp_path)
    shield = build_shield(compiled, ["a"], ["p"], fork=False)
    rt = ShieldRuntime(tables(shield))
    assert rt.step({"a": 1.0}, {"p": 0.5}).outputs == {"p": 0.5}
    d = rt.step({"a": 1.0}, {"p": 3.0})
    assert d.outputs == {"p": math.nextafter(1.0, 0.0)} and d.reasons == ("R",)


@pytest.mark.parametrize("response, why", [
    ("p * a < 1", "multiplies the output p by a, which is no constant"),
    ("p + q < a", "a bound reads one output"),
    ("p = a", "by =: the shield bounds an output"),
    ("absReal(p) < a", "reads the output p inside absReal(p)"),
    ("p + p < a", "reads the output p 2 times"),
    ("a / p < 1", "divides by the output p"),
])
def test_a_comparison_of_inputs_and_outputs_that_is_no_bound_is_refused_with_why(
        tmp_path, response, why):
    compiled = compile_text(f"R: sw shall always satisfy {response}\n", tmp_path)
    with pytest.raises(ShieldError, match=re.escape(why)):
        build_shield(compiled, ["a"], ["p", "q"], fork=False)


def test_a_past_number_is_refused_with_why(tmp_path):
    compiled = compile_text("R: sw shall always satisfy absReal(preReal(0.0, p) - p) <= 1\n",
                            tmp_path)
    with pytest.raises(ShieldError, match="previous value of a number"):
        build_shield(compiled, ["a"], ["p"], fork=False)


def test_inputs_compared_together_are_the_environments(tmp_path):
    """``a < b`` over inputs: the environment's; the shield reads its truth each tick."""
    compiled = compile_text("R: whenever a < b sw shall immediately satisfy x\n", tmp_path)
    shield = build_shield(compiled, ["a", "b"], ["x"], fork=False)
    rt = ShieldRuntime(tables(shield))
    assert rt.step({"a": 1.0, "b": 2.0}, {"x": False}).outputs == {"x": True}
    assert rt.step({"a": 2.0, "b": 1.0}, {"x": False}).outputs == {"x": False}


@pytest.mark.tor("TOR-SHD-001")
@SETTINGS
@given(text=sets(), run=runs())
def test_a_shield_over_comparisons_keeps_its_requirements(text, run):
    compiled, shield = _shield(text)
    rt = ShieldRuntime(tables(shield))
    trace = []
    for ins, prop in run:
        before = [m.state for m in rt.machines]
        d = rt.step(ins, prop)
        for k, m in enumerate(shield.machines):
            p, o = atoms_of(m, prop), atoms_of(m, d.outputs)  # the numbers give the atoms
            assert safe(m, before[k], ins, o), (text, ins, prop, d)
            if safe(m, before[k], ins, p):
                assert o == p
        if not d.overridden:
            assert d.outputs == prop
        trace.append({**ins, **d.outputs})
    got = verdicts(compiled, trace)
    enforced = {r.id for r in shield.requirements}
    assert all(got[r] != "violated" for r in enforced), (text, got, trace)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=sets())
def test_the_closed_loop_of_a_shield_over_comparisons_is_proved(text):
    compiled, shield = _shield(text)
    proof = prove_shield(shield, compiled)
    assert all(v in ("holds", "unknown") for v in proof.results.values()), proof.results
    assert "holds" in proof.results.values() or not shield.requirements


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=sets(), rows=runs(length=40))
def test_c_and_python_shields_over_comparisons_decide_alike(text, rows):
    needs_cc()
    _compiled, shield = _shield(text)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(render_c(shield, "t"), folder)
        exe = build(folder, ["t_shield.c", "t_shield_run.c"], "run")
        lines = [",".join(INPUTS + OUTPUTS)]
        for ins, prop in rows:
            lines.append(",".join(str(ins[v]).lower() for v in INPUTS) + ","
                         + ",".join(str(prop[v]).lower() if v == "x" else repr(prop[v])
                                    for v in OUTPUTS))
        got = subprocess.run([str(exe)], input="\n".join(lines) + "\n", capture_output=True,
                             text=True, timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    rt = ShieldRuntime(tables(shield))
    for (ins, prop), c in zip(rows, csv.DictReader(io.StringIO(got.stdout)), strict=True):
        d = rt.step(ins, prop)
        for v in OUTPUTS:
            if v not in shield.read:
                continue
            want = d.outputs[v]
            assert (c[v] == str(int(want))) if isinstance(want, bool) else float(c[v]) == want, \
                (v, d, c)
        assert c["overridden"] == str(int(d.overridden)), (d, c)


def _case_study(shared: Path, group: str):
    from fretc.compiler.build import compile_entry
    from fretc.fretish.files import RequirementEntry
    from fretc.fretish.parser import parse

    entries = []
    path = shared / "corpora" / "fret_casestudies.jsonl"
    for n, line in enumerate(path.read_text().splitlines(), start=1):
        d = json.loads(line)
        g, _, rid = d["id"].partition("#")
        if g == group:
            e = RequirementEntry(id=rid, text=d["text"], source=path.name, line=n, column=1)
            e.requirement = parse(d["text"], source=path.name, line=n, column=1)
            entries.append(e)
    compiled = [c for c in (compile_entry(e) for e in entries) if c.formalization]
    return compiled, sorted({v for c in compiled for v in c.formalization.variables})


def _drive(shield, names: list[str], ticks: int) -> int:
    """Random proposals (numbers 0 .. 3 and the case studies' constants) through the shield:
    the corrected numbers give safe truth values, a safe proposal is kept. Returns the
    number of overrides."""
    rt = ShieldRuntime(tables(shield))
    rnd = random.Random(1)
    overridden = 0
    for _ in range(ticks):
        prop = {v: (rnd.choice([0.0, 1.0, 2.0, 3.0, 20.0, 35.0, 95.0, 120.0])
                    if v in shield.numbers else rnd.random() < 0.5) for v in names}
        before = [m.state for m in rt.machines]
        d = rt.step({}, prop)
        overridden += d.overridden
        for k, m in enumerate(shield.machines):
            assert safe(m, before[k], {}, atoms_of(m, d.outputs)), (prop, d)
        if not d.overridden:
            assert d.outputs == prop
    return overridden


def test_the_fsm_case_study_gives_a_shield(shared):
    """Every variable the controller's (as the case-study bench declares them): its
    ``state = ap_standby_state`` comparisons are predicates; overrides give numbers that
    realize safe truth values."""
    compiled, names = _case_study(shared, "FiniteStateMachine/fsm_reqts_and_vars.json")
    shield = build_shield(compiled, [], names, fork=False, name="fsm")
    assert sum(a.op == "pred" for m in shield.machines for a in m.outputs) >= 12
    assert _drive(shield, names, 300) > 0


def test_lift_plus_cruise_without_its_past_number_gives_a_shield(shared):
    """The LPC mini set without LPC_KIAS_DERIVATIVE (its ``preReal``): ``kias = kgs`` and
    the ``lift_mode = thrust_borne`` enumerations are predicates."""
    compiled, names = _case_study(shared, "LiftPlusCruise/LPC_mini_reqts_and_vars.json")
    compiled = [c for c in compiled if c.id != "LPC_KIAS_DERIVATIVE"]
    shield = build_shield(compiled, [], names, fork=False, name="lpc")
    assert any(a.text == "(kias = kgs)" for m in shield.machines for a in m.outputs)
    assert _drive(shield, names, 200) > 0


@pytest.mark.parametrize("group", ["LiftPlusCruise/LPC_mini_reqts_and_vars.json",
                                   "LiftPlusCruise/LPC_full_reqts_and_vars.json"])
def test_the_lift_plus_cruise_sets_are_refused_for_their_past_numbers(shared, group):
    compiled, names = _case_study(shared, group)
    with pytest.raises(ShieldError, match=r"LPC_KIAS_DERIVATIVE.*previous value of a number"):
        build_shield(compiled, [], names, fork=False)


def test_the_ros2_form_refuses_comparisons_of_several_outputs_with_why(tmp_path):
    from fretc.shield.emit_ros2 import render_ros2

    compiled = compile_text("R: sw shall always satisfy p < q\n", tmp_path)
    shield = build_shield(compiled, [], ["p", "q"], fork=False)
    with pytest.raises(ShieldError, match=r"cannot publish the outputs of \(p < q\)"):
        render_ros2(shield, "t", None, None)


def test_the_command_proves_a_shield_over_comparisons_of_two_variables(tmp_path):
    from click.testing import CliRunner

    from fretc.cli import main

    path = tmp_path / "two.fret"
    path.write_text("@inputs go\n@outputs x, y, lmode, cruise, hover\n"
                    "P1: the ctl shall always satisfy x < y\n"
                    "P2: upon go the ctl shall within 2 ticks satisfy x + y > 10 & x <= 4\n"
                    "P3: the ctl shall always satisfy lmode = cruise | lmode = hover\n"
                    "P4: upon go the ctl shall at the next timepoint satisfy lmode = hover & "
                    "!(lmode = cruise)\n")
    got = CliRunner().invoke(main, ["shield", str(path), "--prove", "--emit", "python",
                                    "--emit", "c", "-o", str(tmp_path / "out")])
    assert got.exit_code == 0, got.output
    for rid in ("P1", "P2", "P3", "P4"):
        assert f"{rid}: holds" in got.output
    assert "the shield satisfies every enforced requirement" in got.output


def test_a_clusters_numbers_do_not_depend_on_what_z3_was_asked_before(tmp_path):
    """The numbers z3 gives a cluster (written by the shield) and the valuations whose
    numbers hold in doubles (the others are never chosen) came out of z3's one global
    context: after other z3 work in the same process, the same requirements gave other
    numbers and another set of valuations. Each cluster has a context of its own."""
    import z3

    text = ("A: whenever i1 c shall immediately satisfy y / z > 2\n"
            "B: whenever i2 c shall immediately satisfy z = 0\n"
            "C: whenever i1 c shall immediately satisfy y + z > 0.3 & y - z < 4\n")

    def decided():
        shield = build_shield(compile_text(text, tmp_path), ["i1", "i2"], ["y", "z"],
                              fork=False)
        return ([c["numbers"] for m in shield.machines for c in m.clusters],
                [m.nodes for m in shield.machines], shield.notes)

    first = decided()
    for k in range(50):  # other work in z3's main context
        a, b, c = z3.Reals(f"a{k} b{k} c{k}")
        s = z3.Solver()
        s.add(a / b > 2, b > 0.001 * k, c == a + b, a < 100 + k)
        assert s.check() == z3.sat
        s.model()
    assert decided() == first
