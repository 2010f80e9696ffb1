"""The Gwendolen form's machine (``N_shield.java``) decides an input it cannot read as any
value, as the Python and C forms do: its ``main`` reads an input atom ``x`` (the atom reads a
variable that could not be read) and a state that is a belief (states separated by ``|``, one
part per machine separated by ``/``, or ``lost``), and prints the next belief in the same
notation.

* Differential: seeded random runs of the docs' Safe-ROS shield with unreadable inputs (at
  every tick of some runs, at random ticks, at the tick a trigger rises), the Python form
  stepped with ``None``, NaN or a missing value, the Java form with ``x`` atoms; every tick's
  output atoms, next belief and broken flag equal. A Java machine that keeps its state on an
  unknown tick is caught.
* Judged against the requirements: G1/G2 (``upon a`` for 3 ticks, ``whenever x > 2``
  immediately) with ``a`` true and ``x`` unreadable at tick 0: the Java form's outputs keep
  G1 (``o`` from tick 0 to 3) and G2 whatever ``x`` was (FRET's semantics on the trace with
  each value). Random requirement sets and faulty runs (tests/shield/test_faults.py's
  strategies, long) through the Java form: the Python form's decisions, which that file's
  brute force and FRET's verdicts judge.
"""

from __future__ import annotations

import math
import random
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, assume, given, settings

from fretc.shield.build import build_shield
from fretc.shield.emit_gwendolen import render_gwendolen
from fretc.shield.emit_python import load_shield, tables
from fretc.shield.machine import evaluate
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import ShieldRuntime

from _gen import compile_text, verdicts
from test_faults import MISSING, _shield, faulty_runs, judged, requirement_sets
from test_faults import OUTPUTS as FAULT_OUTPUTS
from test_gwendolen import NO_JAVAC, _random_runs, write_docs_forms

#: the values of a boolean input the shield cannot read (MISSING: the key left out)
BAD = [None, math.nan, MISSING]
#: the docs' shield's boolean inputs that its machine reads
DOCS_INPUTS = ["too_close", "scan_stale", "obstacle_ahead", "obstacle_behind"]


def _javac() -> str:
    javac = shutil.which("javac")
    if javac is None:
        pytest.skip(NO_JAVAC)
    return javac


def compile_java(files: list[Path], classes: Path) -> Path:
    """``files`` compiled by javac into ``classes`` (a skip without javac)."""
    subprocess.run([_javac(), "-nowarn", "-d", str(classes), *map(str, files)], check=True,
                   capture_output=True, timeout=300)
    return classes


def run_java(classes: Path, main_class: str, lines: list[str]) -> list[str]:
    """``main_class``'s ``main`` over ``lines`` ("INPUTS PROPOSAL STATE"), one JVM."""
    java = Path(_javac()).with_name("java")
    got = subprocess.run([str(java), "-cp", str(classes), main_class],
                         input="\n".join(lines) + "\n", capture_output=True, text=True,
                         timeout=300)
    assert got.returncode == 0, got.stderr[-3000:]
    return got.stdout.splitlines()


def _bits(values) -> str:
    """0/1 text (``-`` when empty: ``N_shield.java``'s empty field)."""
    return "".join(str(int(b)) for b in values) or "-"


def belief_text(machines) -> str:
    """The machines' states in ``N_shield.java``'s notation (its header): the bits one after
    the other while each knows its one state, else one part per machine (``lost``, or its
    belief's states separated by ``|``) separated by ``/``."""
    if all(not m.lost and not m.others for m in machines):
        return _bits(b for m in machines for b in m.state)
    return "/".join("lost" if m.lost else "|".join("".join(map(str, s)) for s in m.belief)
                    for m in machines)


def _unread_value(ins: dict, var: str, bad: Any) -> dict:
    out = dict(ins)
    if bad is MISSING:
        del out[var]
    else:
        out[var] = bad
    return out


def python_lines(rt: Any, runs: list[list[tuple[dict, dict, dict]]]
                 ) -> tuple[list[str], list[str]]:
    """The Python form ``rt`` (a ShieldRuntime, reset before each run) stepped over ``runs``
    (per tick the true inputs, the proposal, the unreadable inputs -> the value given
    instead): per tick the line ``N_shield.java`` reads (``x`` for each input atom reading an
    unreadable input, the belief before) and the line it must print (``none``: no outputs)."""
    machines = rt.machines
    lines, want = [], []
    for run in runs:
        rt.reset()
        for ins, prop, unread in run:
            before = belief_text(machines)
            atoms: dict[str, str] = {}
            for m in machines:  # (an input atom read by several machines is one percept)
                free = {j for v in unread for j in m.reading_in.get(v, ())}
                for j, (spec, f) in enumerate(zip(m.ins, m.in_tests)):
                    atoms[repr(spec)] = "x" if j in free else str(int(f(ins)))
            given_ins = dict(ins)
            for var, bad in unread.items():
                given_ins = _unread_value(given_ins, var, bad)
            d = rt.step(given_ins, prop)
            outs = ("none" if not d.outputs else
                    _bits(int(f(d.outputs)) for m in machines for f in m.out_tests))
            prop_atoms = _bits(int(f(prop)) for m in machines for f in m.out_tests)
            lines.append(f"{''.join(atoms.values()) or '-'} {prop_atoms} {before}")
            want.append(f"{outs} {belief_text(machines)} {int(bool(d.broken))}")
    return lines, want


def unreadable_runs(seed: int, runs: int, ticks: int) -> list[list[tuple[dict, dict, dict]]]:
    """The docs' random runs (test_gwendolen) with unreadable inputs: every third run one or
    two inputs unreadable at every tick; the others an input unreadable at a tick with
    probability 0.15, and always at a tick ``too_close`` or ``obstacle_ahead`` rises (another
    input then, the trigger read)."""
    rng = random.Random(seed)
    out = []
    for k, run in enumerate(_random_runs(seed, runs, ticks)):
        every = k % 3 == 0
        ticks_out = []
        was: dict = {}
        for ins, prop in run:
            rises = [v for v in ("too_close", "obstacle_ahead") if ins[v] and not was.get(v)]
            unread: dict = {}
            if every:
                for v in rng.sample(DOCS_INPUTS, rng.choice((1, 1, 2))):
                    unread[v] = rng.choice(BAD)
            elif rises:
                v = rng.choice([v for v in DOCS_INPUTS if v not in rises])
                unread[v] = rng.choice(BAD)
            elif rng.random() < 0.15:
                unread[rng.choice(DOCS_INPUTS)] = rng.choice(BAD)
            ticks_out.append((ins, prop, unread))
            was = ins
        out.append(ticks_out)
    return out


@pytest.fixture(scope="module")
def docs_java(tmp_path_factory) -> tuple[Path, Path]:
    """The docs' forms and their Java machine compiled once: ``(folder, classes)`` (a skip
    without javac, before the forms are written)."""
    _javac()
    folder = write_docs_forms(tmp_path_factory.mktemp("gwendolen-unreadable"))
    return folder, compile_java([folder / "safe_ros_shield.java"], folder / "classes")


def _docs_runtime(folder: Path) -> Any:
    return load_shield((folder / "safe_ros_shield.py").read_text(encoding="utf-8"),
                       "gwendolen_unreadable_shield")()


#: the differential's runs: 60 runs of 40 ticks
RUNS, TICKS = 60, 40


@pytest.fixture(scope="module")
def docs_lines(docs_java) -> tuple[list[str], list[str]]:
    """The Python form over the differential's runs (:func:`python_lines`), once."""
    return python_lines(_docs_runtime(docs_java[0]), unreadable_runs(5, RUNS, TICKS))


@pytest.mark.tor("TOR-SHD-003", "TOR-SHD-006")
def test_the_java_machine_decides_an_unreadable_input_as_the_python_form(docs_java,
                                                                         docs_lines):
    """Differential: 60 seeded runs of 40 ticks with unreadable inputs (module docstring):
    every tick's decided output atoms, next belief and broken flag equal; and each tick of
    the Java form judged by brute force over the node table (:func:`judge_by_the_table`:
    outputs safe for every value the unreadable input could have had). The runs reach
    beliefs of several states and unknown atoms at the tick a trigger rises (checked below;
    past the bounds: :func:`test_past_the_bounds_both_forms_lose_the_state`)."""
    lines, want = docs_lines
    got = run_java(docs_java[1], "safe_ros_shield", lines)
    assert len(got) == len(want)
    diff = [(k, lines[k], want[k], got[k]) for k in range(len(want)) if got[k] != want[k]]
    assert not diff, diff[:5]
    judge_by_the_table(_docs_runtime(docs_java[0]).machines[0], lines, got)
    unknown = [line for line in lines if "x" in line.split()[0]]
    several = [w for w in want if "|" in w.split()[1]]
    assert len(unknown) > 500 and len(several) > 100, (len(unknown), len(several))
    assert any(w.split()[1].isdigit() for w in want)  # (and back to one state)
    # (a trigger read at a tick another input is not: too_close rises, another atom x)
    assert any(a.split()[0][0] == "1" and "x" in a.split()[0][1:] for a in lines)


def judge_by_the_table(m: Any, lines: list[str], got: list[str]) -> None:
    """The Java form's ticks of a one-machine shield judged by brute force over the node
    table ``m`` (not by the Python form's rule): every tick the machine decides (not lost)
    gives outputs ``safe`` from every state of the belief before with every valuation of
    the unknown atoms ``env_ok`` allows, and its next belief is every state they lead to
    from those cases, sorted."""
    pad = [0] * (len(m.outs) + len(m.init))
    for line, out in zip(lines, got, strict=True):
        ins, _prop, before = line.split()
        outs, nxt, _broken = out.split()
        if before == "lost" or nxt == "lost":
            continue
        free = [j for j, c in enumerate(ins) if c == "x"]
        cases = []
        for k in range(1 << len(free)):
            v = [0 if c == "x" else int(c) for c in ins]
            for b, j in enumerate(free):
                v[j] = (k >> b) & 1
            if not free or evaluate(m.nodes, m.env_ok, v + pad):
                cases.append(v)
        after = set()
        for st in before.split("|"):
            for v in cases:
                values = v + [int(c) for c in outs] + [int(c) for c in st]
                assert evaluate(m.nodes, m.safe, values), (line, out, st, v)
                after.add("".join(str(int(evaluate(m.nodes, r, values))) for r in m.next))
        assert nxt.split("|") == sorted(after), (line, out)


def test_a_machine_that_keeps_its_state_on_an_unknown_tick_is_caught(docs_java, docs_lines,
                                                                     tmp_path):
    """The comparison can fail: a Java machine whose belief stays as it was on a tick it
    decides for several cases (an input it cannot read: the old behaviour, the tick not
    counted) differs from the Python form."""
    folder, _classes = docs_java
    java = (folder / "safe_ros_shield.java").read_text(encoding="utf-8")
    kept = java.replace("                next[k] = d.next;", "                next[k] = belief[k];")
    assert kept != java
    mutant = tmp_path / "safe_ros_shield.java"
    mutant.write_text(kept, encoding="utf-8")
    classes = compile_java([mutant], tmp_path / "classes")
    lines, want = (x[:10 * TICKS] for x in docs_lines)  # (the first 10 runs)
    got = run_java(classes, "safe_ros_shield", lines)
    assert len(got) == len(want) and got != want


def test_the_plain_lines_are_read_and_printed_as_before(docs_java):
    """Backward compatible: a line of 0/1 strings gives a line of 0/1 strings (the single
    state path), and the same tick written as a belief of one state gives the same answer."""
    folder, classes = docs_java
    rt = _docs_runtime(folder)
    init = belief_text(rt.machines)
    got = run_java(classes, "safe_ros_shield", [f"1000 00000001 {init}",
                                                f"1000 00000001 {init}|{init}"])
    outs, nxt, broken = got[0].split()
    assert set(outs + nxt + broken) <= {"0", "1"} and len(nxt) == len(init)
    assert got[1] == got[0]


def test_past_the_bounds_both_forms_lose_the_state(docs_java, docs_lines):
    """A belief of 257 states the runs reached (their union): with every input unreadable,
    16 valuations a state, more than CASES_LIMIT cases: the machine is lost in both forms
    (the fallback's outputs, ``lost``), and stays lost on the next tick whatever it reads;
    with every input read, 257 cases, both forms decide alike."""
    folder, classes = docs_java
    rt = _docs_runtime(folder)
    want = docs_lines[1]
    seen = sorted({s for w in want for s in w.split()[1].split("|") if s.isdigit()})
    assert len(seen) > 256, len(seen)
    belief = [tuple(int(c) for c in s) for s in seen[:257]]
    ins = {"too_close": True, "scan_stale": False, "obstacle_ahead": False,
           "obstacle_behind": True, "clearance": 1.0}
    prop = {"stopped": False, "stop_requested": False, "forwarded_zero": False,
            "linear_speed": 0.7, "angular_speed": 0.7, "linear_velocity": 0.3}
    lines, expect = [], []
    for unread in (DOCS_INPUTS, ["scan_stale"], []):
        rt.restore((("belief", *belief),))
        before = belief_text(rt.machines)
        d = rt.step({**ins, **{v: None for v in unread}}, prop)
        m = rt.machines[0]
        atoms = "".join("x" if any(j in m.reading_in.get(v, ()) for v in unread)
                        else str(int(f(ins))) for j, f in enumerate(m.in_tests))
        lines.append(f"{atoms} {_bits(int(f(prop)) for f in m.out_tests)} {before}")
        expect.append(f"{_bits(int(f(d.outputs)) for f in m.out_tests)} "
                      f"{belief_text(rt.machines)} {int(bool(d.broken))}")
        if unread == DOCS_INPUTS:
            assert d.lost and expect[-1].split()[1] == "lost", d
            lines.append("1001 00000001 lost")
            d = rt.step(ins, prop)
            expect.append(f"{_bits(int(f(d.outputs)) for f in m.out_tests)} lost 0")
            assert d.lost, d
    assert run_java(classes, "safe_ros_shield", lines) == expect


def _g1_g2(tmp: Path) -> tuple[Any, Any, Path]:
    """G1/G2 (module docstring): compiled, shield, and its Java machine compiled."""
    compiled = compile_text("G1: upon a ctrl shall for 3 ticks satisfy o\n"
                            "G2: whenever x > 2 ctrl shall immediately satisfy !p\n", tmp)
    shield = build_shield(compiled, ["a", "x"], ["o", "p"], fork=False)
    files = render_gwendolen(shield, compiled, "g")
    (tmp / "g_shield.java").write_text(files["g_shield.java"], encoding="utf-8")
    return compiled, shield, compile_java([tmp / "g_shield.java"], tmp / "classes")


@pytest.mark.tor("TOR-SHD-003")
def test_a_trigger_read_at_a_tick_of_an_unreadable_input_is_kept_by_the_java_form(tmp_path):
    """G1 and G2 with ``a = true, x`` unreadable at tick 0, the proposals false every tick:
    the Java form gives ``o`` on ticks 0 to 3 (G1 from its trigger, not lost) and ``p``
    false at tick 0; FRET's semantics on the trace with ``x`` 3 or 0 at tick 0 finds both
    requirements kept. The Python form decides the same."""
    compiled, shield, classes = _g1_g2(tmp_path)
    assert len(shield.machines) == 2
    order = [a.text for m in shield.machines for a in m.inputs]
    assert order == ["a", "(x > 2)"], order
    py_lines, want = python_lines(ShieldRuntime(tables(shield)), [
        [({"a": k == 0, "x": 0.0}, {"o": False, "p": False},
          {"x": math.nan} if k == 0 else {}) for k in range(6)]])
    assert py_lines[0] == f"1x 00 {_bits(b for m in shield.machines for b in m.init)}"
    got = run_java(classes, "g_shield", py_lines)
    # (the Java form's own run: each tick's line holds the state the tick before printed)
    assert [g.split()[1] for g in got[:-1]] == [line.split()[2] for line in py_lines[1:]]
    o = [int(g.split()[0][0]) for g in got]
    p = [int(g.split()[0][1]) for g in got]
    assert o[:4] == [1, 1, 1, 1] and p[0] == 0, got
    for x_true in (3.0, 0.0):
        rows = [{"a": k == 0, "x": x_true if k == 0 else 0.0, "o": bool(o[k]),
                 "p": bool(p[k])} for k in range(6)]
        v = verdicts(compiled, rows)
        assert v["G1"] == "satisfied" and v["G2"] == (
            "satisfied" if x_true > 2 else "vacuous"), (v, rows)
    assert want == got, (py_lines, want, got)


@settings(max_examples=8, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(text=requirement_sets(), run=faulty_runs(length=30))
@pytest.mark.tor("TOR-SHD-003")
def test_random_requirements_with_unreadable_inputs_through_the_java_form(text, run):
    """test_faults.py's random requirement sets and faulty runs (input faults only: the Java
    form reads no proposal it cannot read), judged there (brute force over the node table,
    FRET's verdicts on the true values: no enforced requirement violated); the Java form
    gives the Python form's output atoms, next belief and broken flag at every tick."""
    run = [(i, p, f) for i, p, f in run if f is None or f[0] == "input"]
    assume(run)
    compiled, shield = _shield(text)
    decisions = judged(shield, run)
    trace = [{**ins, **d.outputs} for (ins, _p, _f), d in zip(run, decisions)]
    if trace and all(set(FAULT_OUTPUTS) <= row.keys() for row in trace) and all(
            not isinstance(x, float) or math.isfinite(x) for row in trace for x in row.values()):
        got_v = verdicts(compiled, trace)
        assert all(got_v[r.id] != "violated" for r in shield.requirements), (text, got_v)
    try:
        files = render_gwendolen(shield, compiled, "t")
    except ShieldError:
        assume(False)
        raise
    rt = ShieldRuntime(tables(shield))
    steps = [(i, p, {} if f is None else {f[1]: f[2]}) for i, p, f in run]
    lines, want = python_lines(rt, [steps])
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "t_shield.java"
        src.write_text(files["t_shield.java"], encoding="utf-8")
        got = run_java(compile_java([src], Path(tmp) / "classes"), "t_shield", lines)
    assert got == want, [(a, b, c) for a, b, c in zip(lines, want, got) if b != c][:3]


def test_without_a_fallback_a_machine_that_cannot_decide_gives_no_outputs(tmp_path):
    """``x`` follows ``a`` exactly: no outputs are safe for both values of an unreadable
    ``a``, and there is no fallback. The Python form gives no outputs and loses the machine's
    state; the Java form prints ``none`` and ``lost``, and keeps giving none."""
    compiled = compile_text("R1: whenever a sw shall immediately satisfy x\n"
                            "R2: whenever !a sw shall immediately satisfy !x\n", tmp_path)
    shield = build_shield(compiled, ["a"], ["x"], fork=False)
    assert shield.fallback is None
    files = render_gwendolen(shield, compiled, "n")
    (tmp_path / "n_shield.java").write_text(files["n_shield.java"], encoding="utf-8")
    classes = compile_java([tmp_path / "n_shield.java"], tmp_path / "classes")
    lines, want = python_lines(ShieldRuntime(tables(shield)), [[
        ({"a": True}, {"x": True}, {}), ({"a": True}, {"x": True}, {"a": None}),
        ({"a": False}, {"x": True}, {})]])
    assert [w.split()[:2] for w in want[1:]] == [["none", "lost"], ["none", "lost"]], want
    assert run_java(classes, "n_shield", lines) == want
