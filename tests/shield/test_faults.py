"""A shield's step never raises, an input it cannot read is any value, and no value it cannot
read costs a trigger it can.

Random requirement sets over the inputs ``a``, ``b`` (booleans), ``d`` (a number) and ``m``
(a mode) and the outputs ``x``, ``y`` (booleans) and ``v`` (a number), random runs, and at
random ticks a value the shield cannot read: an input or a proposal that is NaN, infinite
(a proposal), missing, of the wrong type, or an integer no double holds. Each faulty run is
judged by brute force over the node table and by FRET's semantics, not against the
fault-free run ("an unreadable input is any value"):

* a tick whose input cannot be read gives outputs that are safe (the node table's ``safe``)
  from every state the shield may be in with every valuation of the unread input's atoms
  that real numbers give (``env_ok``): the belief the brute force keeps itself, every state
  the decided outputs lead to from every case;
* a tick whose proposal cannot be read, the belief one state, decides as the reference does
  on the proposal with the fallback's value in its place (without a fallback: outputs the
  node table says are safe); it is an override, never the value it could not read;
* every other tick with the belief one state decides as the reference does from that state;

and FRET's interval semantics finds no enforced requirement violated on the run **with the
values the shield could not read** (the true inputs): a NaN in ``d`` at the tick ``a``
rises loses nothing. The C form is held to the Python form on the same faulty runs (NaN
inputs; NaN and infinite proposals: what a double can carry).
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import subprocess
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import load_shield, render_python, tables
from fretc.shield.plan import ShieldError
from fretc.shield.machine import evaluate
from fretc.shield.runtime import ShieldRuntime

from _c_monitors import build as build_c, needs_cc, write
from _gen import (CONDITIONS, RESPONSES, SCOPES, TIMINGS, atoms_of, compile_text, csv_cell,
                  fault_kind, verdicts)

INPUTS = ["a", "b", "d", "m"]
OUTPUTS = ["x", "y", "v"]
MISSING = object()
#: the values a shield cannot read, per variable kind and side
BAD_INPUT = {"b": [None, 2, "true", math.nan, 1.5, MISSING],
             "n": [math.nan, 10**400, "1.0", True, None, MISSING]}
BAD_PROPOSAL = {"b": [None, 2, "yes", math.nan, MISSING],
                "n": [math.nan, math.inf, -math.inf, 10**400, "0.5", None, False, MISSING]}
SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@st.composite
def requirement_sets(draw) -> str:
    """1 to 3 requirements (tests/shield/_gen.py's parts, and conditions on ``d``)."""
    lines = []
    for k in range(draw(st.integers(1, 3))):
        scope = draw(st.sampled_from(SCOPES))
        cond = draw(st.sampled_from([*CONDITIONS, "whenever d > 1 ", "upon d <= 0 "]))
        timing = draw(st.sampled_from(TIMINGS))
        resp = draw(st.sampled_from(RESPONSES))
        lines.append(f"R{k + 1}: {scope}{cond}sw shall {timing}satisfy {resp}")
    return "\n".join(lines) + "\n"


@st.composite
def faulty_runs(draw, length: int = 30) -> list[tuple[dict, dict, tuple | None]]:
    """Ticks of random inputs and proposals, each with a fault or None: ``("input" or
    "proposal", variable, bad value)``."""
    out = []
    for _ in range(draw(st.integers(1, length))):
        ins = {"a": draw(st.booleans()), "b": draw(st.booleans()),
               "d": draw(st.sampled_from([-1.0, 0.0, 0.5, 1.0, 2.0, math.inf])),
               "m": draw(st.booleans())}
        prop = {"x": draw(st.booleans()), "y": draw(st.booleans()),
                "v": draw(st.sampled_from([0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0]))}
        fault = None
        if draw(st.integers(0, 2)) == 0:
            side = draw(st.sampled_from(["input", "proposal"]))
            var = draw(st.sampled_from(INPUTS if side == "input" else OUTPUTS))
            kind = "n" if var in ("d", "v") else "b"
            bad = draw(st.sampled_from((BAD_INPUT if side == "input" else BAD_PROPOSAL)[kind]))
            fault = (side, var, bad)
        out.append((ins, prop, fault))
    return out


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(
        a[k] == b[k] or (isinstance(a[k], float) and isinstance(b[k], float)
                         and math.isnan(a[k]) and math.isnan(b[k])) for k in a)


def _with(values: dict, var: str, bad) -> dict:
    out = dict(values)
    if bad is MISSING:
        del out[var]
    else:
        out[var] = bad
    return out


def _shield(text: str):
    with tempfile.TemporaryDirectory() as tmp:
        compiled = compile_text(text, Path(tmp))
        try:
            return compiled, build_shield(compiled, INPUTS, OUTPUTS, fork=False)
        except ShieldError:
            assume(False)
            raise


def input_cases(m, ins: dict, unread: set) -> list[list[int]]:
    """Brute force: the valuations of machine ``m``'s input atoms with the values ``ins``,
    every atom reading a variable of ``unread`` free, those ``env_ok`` allows."""
    free = [j for j, a in enumerate(m.inputs)
            if ((_term_vars(a.term) if a.op == "pred" else {a.variable}) & unread)]
    fixed = [0 if j in free else int(a.value(ins if a.op == "pred" else ins[a.variable]))
             for j, a in enumerate(m.inputs)]
    out = []
    for bits in itertools.product((0, 1), repeat=len(free)):
        v = list(fixed)
        for j, b in zip(free, bits):
            v[j] = b
        if evaluate(m.nodes, m.env_ok, v + [0] * (len(m.outputs) + len(m.init))):
            out.append(v)
    return out


def _term_vars(t) -> set:
    if t[0] == "var":
        return {t[1]}
    return set().union(*(_term_vars(x) for x in t[1:] if isinstance(x, tuple)))


def judged(shield, run) -> list:
    """The faulty run stepped by the Python form, each tick judged (module docstring) with
    a belief per machine kept by brute force; the decisions."""
    rt, ref = ShieldRuntime(tables(shield)), ShieldRuntime(tables(shield))
    fb = shield.fallback
    beliefs = [{tuple(int(b) for b in m.init)} for m in shield.machines]
    decisions = []
    for ins, prop, fault in run:
        side, var, bad = fault or ("", "", None)
        read_in = side == "input" and var in rt.input_kinds
        read_out = side == "proposal" and var in rt.output_kinds
        before = rt.state
        got_ins = _with(ins, var, bad) if side == "input" else ins
        got_prop = _with(prop, var, bad) if side == "proposal" else prop
        d = rt.step(got_ins, got_prop)
        decisions.append(d)
        if d.lost or not all(beliefs):  # (past the bounds: the fallback's, none without one)
            assert fb is None or {v: d.outputs[v] for v in fb["outputs"]} == fb["outputs"]
            beliefs = [set() for _ in shield.machines]  # (no longer checked)
            continue
        if read_in:
            assert d.fault.startswith(f"input {var}"), d
        if read_out:
            assert d.overridden and f"proposal {var}" in d.fault, d
            for v in rt.output_kinds:
                assert v in d.outputs and d.outputs[v] is not None
                if rt.output_kinds[v] == "n":
                    assert math.isfinite(d.outputs[v]), d
        if not read_in and all(len(b) == 1 for b in beliefs):
            ref.restore(before)
            if read_out and fb is not None and var in fb["outputs"]:
                want = ref.step(ins, {**prop, var: fb["outputs"][var]})
                assert d.outputs == want.outputs and rt.state == ref.state, (d, want)
            elif not read_out:
                # (no fault, or one in a value no enforced requirement reads: passed through)
                want = ref.step(got_ins, got_prop)
                assert _same(d.outputs, want.outputs) and d[1:4] == want[1:4] \
                    and not d.fault and rt.state == ref.state, (d, want)
        # the outputs safe in every case, and the belief every state they lead to
        unread = {var} if read_in else set()
        seen = dict(ins)
        if read_in:
            seen[var] = 0.0 if var == "d" else False  # (any value: its atoms are free)
        for k, m in enumerate(shield.machines):
            if not d.outputs:
                assert fb is None, d
                beliefs[k] = set()
                continue
            outs = atoms_of(m, d.outputs)
            nxt = set()
            for state in beliefs[k]:
                for i in input_cases(m, seen, unread):
                    values = i + outs + list(state)
                    assert evaluate(m.nodes, m.safe, values), (d, state, i)
                    nxt.add(tuple(int(evaluate(m.nodes, r, values)) for r in m.next))
            beliefs[k] = nxt
            got = rt.state[k]
            want_belief = sorted(nxt)
            assert (tuple(got) == want_belief[0] if len(nxt) == 1
                    else list(got[1:]) == want_belief), (got, want_belief)
    return decisions


@SETTINGS
@given(text=requirement_sets(), run=faulty_runs())
@pytest.mark.tor("TOR-SHD-003")
def test_an_unread_input_is_any_value_and_no_trigger_is_lost(text, run):
    compiled, shield = _shield(text)
    decisions = judged(shield, run)
    # the run with the values the shield could not read: FRET's verdicts
    trace = [{**ins, **d.outputs} for (ins, _p, _f), d in zip(run, decisions)]
    enforced = {r.id for r in shield.requirements}
    if trace and all(set(OUTPUTS) <= row.keys() and all(
            not isinstance(row[k], float) or math.isfinite(row[k]) for k in row)
            for row in trace):
        got = verdicts(compiled, trace)
        assert all(got[r] != "violated" for r in enforced), (text, got, trace)


def test_the_issue_example_nan_at_f1s_deadline_moves_no_machine(tmp_path):
    """F1/F2: ``a`` at tick 0, ``o`` proposed false throughout, ``x = NaN`` at F1's
    deadline. The step raised after F1's machine had moved, and F1 was violated on the next
    ticks; the NaN is now any value of ``x``: F1's machine moves (it reads no ``x``), ``o``
    is true by F1's deadline, and ``p`` false (safe whatever ``x`` was)."""
    compiled = compile_text("F1: upon a ctrl shall within 2 ticks satisfy o\n"
                            "F2: whenever x > 2 ctrl shall immediately satisfy !p\n", tmp_path)
    shield = build_shield(compiled, ["a", "x"], ["o", "p"], fork=False)
    sh = load_shield(render_python(shield))()  # (the generated module, as a user runs it)
    ticks = [({"a": True, "x": 0.0}), ({"a": False, "x": 0.0}), ({"a": False, "x": math.nan}),
             ({"a": False, "x": 0.0}), ({"a": False, "x": 0.0})]
    rows = []
    for k, ins in enumerate(ticks):
        d = sh.step(ins, {"o": False, "p": False})
        if k == 2:
            assert d.fault == "input x is NaN" and d.outputs == {"o": True, "p": False}, d
        rows.append({**ins, "x": 3.0 if k == 2 else ins["x"], **d.outputs})
    assert verdicts(compiled, rows) == {"F1": "satisfied", "F2": "satisfied"}, rows


@pytest.mark.tor("TOR-SHD-003")
def test_a_nan_in_another_requirements_input_loses_no_trigger(tmp_path):
    """The Safety System round's case: ``G1: upon a ctrl shall for 3 ticks satisfy o``, ``G2: whenever x >
    2 ctrl shall immediately satisfy !p``; ``a = true, x = NaN`` at tick 0, proposals false.
    The tick was not counted, ``a``'s trigger lost and G1 violated at tick 1; every value of
    ``x`` is now decided for: G1's three ticks of ``o`` start at tick 0, and G2 holds
    whether ``x`` was 3 or 0."""
    compiled = compile_text("G1: upon a ctrl shall for 3 ticks satisfy o\n"
                            "G2: whenever x > 2 ctrl shall immediately satisfy !p\n", tmp_path)
    shield = build_shield(compiled, ["a", "x"], ["o", "p"], fork=False)
    for x_true in (3.0, 0.0):
        sh = load_shield(render_python(shield))()
        rows = []
        for k in range(6):
            d = sh.step({"a": k == 0, "x": math.nan if k == 0 else 0.0},
                        {"o": False, "p": k == 0})
            rows.append({"a": k == 0, "x": x_true if k == 0 else 0.0, **d.outputs})
        assert [r["o"] for r in rows[:3]] == [True] * 3, rows
        assert rows[0]["p"] is False and rows[0]["x"] == x_true
        got = verdicts(compiled, rows)
        assert got["G1"] == "satisfied" and got["G2"] == (
            "satisfied" if x_true > 2 else "vacuous"), (got, rows)


def test_a_declared_fallback_is_used_and_one_that_is_not_safe_is_refused(tmp_path):
    compiled = compile_text("R1: whenever a sw shall immediately satisfy x\n"
                            "R2: the sw shall always satisfy v <= 1\n", tmp_path)
    shield = build_shield(compiled, ["a"], ["x", "v"], fork=False,
                          fallback={"x": True, "v": -2.0})
    assert shield.fallback is not None
    assert shield.fallback["outputs"] == {"x": True, "v": -2.0}
    # (an unreadable ``a`` is any value: ``x`` must be true; ``v`` = 0 is safe, kept)
    d = ShieldRuntime(tables(shield)).step({"a": "?"}, {"x": False, "v": 0.0})
    assert d.outputs == {"x": True, "v": 0.0} and d.fault.startswith("input a")
    # (a machine that no longer knows its state: the declared fallback)
    rt = ShieldRuntime(tables(shield))
    rt.restore((("lost",),) * len(rt.machines))
    d = rt.step({"a": False}, {"x": False, "v": 0.0})
    assert d.outputs == {"x": True, "v": -2.0} and d.lost, d
    for bad, why in (({"x": False}, "x must be true"), ({"v": 3.0}, "(v <= 1) must be true"),
                     ({"w": True}, "names w, not an output"),
                     ({"x": 1.0}, "x is a boolean")):
        try:
            build_shield(compiled, ["a"], ["x", "v"], fork=False, fallback=bad)
        except ShieldError as exc:
            assert why in str(exc), (bad, str(exc))
        else:
            raise AssertionError(f"{bad} was taken")


@settings(max_examples=10, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(text=requirement_sets(), run=faulty_runs(length=40))
@pytest.mark.tor("TOR-SHD-003", "TOR-SHD-004")
def test_the_c_form_is_all_or_nothing_as_the_python_form(text, run):
    """The faulty runs a double can carry (NaN inputs; NaN and infinite proposals), each
    judged by :func:`judged`; the C runner gives the Python form's outputs, override, reasons
    and fault at every tick: a NaN input is any value in both forms, each machine keeping a
    belief of states (the C form in arrays of fixed capacity), and a machine that no longer
    knows its state gives the fallback's outputs (none, empty cells, without one) in both."""
    needs_cc()
    run = [(i, p, f) for i, p, f in run
           if f is None or (isinstance(f[2], float) and f[1] in ("d", "v"))]
    assume(run)
    _compiled, shield = _shield(text)
    decisions = judged(shield, run)
    rt = ShieldRuntime(tables(shield))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(render_c(shield, "t"), folder)
        exe = build_c(folder, ["t_shield.c", "t_shield_run.c"], "run")
        text_in = io.StringIO()
        w = csv.writer(text_in, lineterminator="\n")
        w.writerow(INPUTS + OUTPUTS)
        for ins, prop, fault in run:
            ins = _with(ins, fault[1], fault[2]) if fault and fault[0] == "input" else ins
            prop = _with(prop, fault[1], fault[2]) if fault and fault[0] == "proposal" else prop
            w.writerow([csv_cell(ins[v]) for v in INPUTS] + [csv_cell(prop[v]) for v in OUTPUTS])
        got = subprocess.run([str(exe)], input=text_in.getvalue(), capture_output=True,
                             text=True, timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    rows = list(csv.DictReader(io.StringIO(got.stdout)))
    for (_ins, _p, fault), d, c in zip(run, decisions, rows, strict=True):
        assert c["fault"] == fault_kind(d), (fault, d, c)
        assert c["overridden"] == str(int(d.overridden)), (fault, d, c)
        assert set(filter(None, c["reasons"].split("|"))) == set(d.reasons), (d, c)
        for v in OUTPUTS:
            if v not in shield.read:
                continue
            if v not in d.outputs:
                assert c[v] == "", (v, d, c)
            elif v in rt.output_kinds and rt.output_kinds[v] == "n" or isinstance(
                    d.outputs[v], float):
                assert float(c[v]) == d.outputs[v] or (
                    math.isnan(d.outputs[v]) and math.isnan(float(c[v]))), (v, d, c)
            else:
                assert c[v] == str(int(d.outputs[v])), (v, d, c)


def test_a_message_shield_whose_messages_fail_takes_no_step(tmp_path, monkeypatch):
    """All or nothing between messages: a tick whose messages cannot be made (here made to
    fail) puts the shield's state back as it was, so a host that publishes the fallback
    instead has not half stepped; the next tick is decided from the state before."""
    from rosbags.typesys import Stores, get_typestore

    from fretc.fretish.files import load_requirements
    from fretc.compiler.build import compile_entries
    from fretc.shield.messages import MessageShield, default_message
    from fretc.signals.bindings.files import load_bindings

    reqs = Path(__file__).resolve().parents[2] / "requirements"
    bindings = load_bindings(reqs / "safe_ros.bindings.toml")
    shield = build_shield(compile_entries(load_requirements([reqs / "safe_ros.fret"])),
                          ["too_close", "scan_stale", "clearance"],
                          ["stopped", "stop_requested", "forwarded_zero", "linear_speed",
                           "angular_speed"], bindings=bindings, fork=False, name="safe_ros")
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {"/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
             "/cmd_vel_filtered": "geometry_msgs/msg/Twist",
             "/gwendolen_control": "std_msgs/msg/Bool"}
    ms = MessageShield(ShieldRuntime(tables(shield)), bindings,
                       {"/cmd_vel_filtered": "/cmd_vel"},
                       lambda t: default_message(store, types[t]))
    import numpy as np

    def hear(k: int, r: float) -> None:
        scan = default_message(store, types["/scan"])
        scan.range_min, scan.range_max = 0.1, 10.0
        scan.ranges = np.full(8, r, dtype="float32")
        ms.hear("/scan", scan, k * 100_000_000)
        cmd = default_message(store, types["/cmd_vel"])
        cmd.linear.x = 0.3
        ms.hear("/cmd_vel", cmd, k * 100_000_000)

    hear(1, 3.0)
    ms.tick(100_000_000)
    hear(2, 0.5)  # (an obstacle: R2's deadline starts)
    before = ms.runtime.state
    real = MessageShield._messages

    def fail(*args, **kwargs):
        raise RuntimeError("made to fail")

    monkeypatch.setattr(MessageShield, "_messages", fail)
    try:
        ms.tick(200_000_000)
    except RuntimeError:
        pass
    else:
        raise AssertionError("the made failure did not reach the host")
    assert ms.runtime.state == before
    monkeypatch.setattr(MessageShield, "_messages", real)
    stop = ms.fallback_messages(200_000_000)
    assert [(t, getattr(m, "data", None)) for t, m in stop][1] == ("/gwendolen_control", True)
    assert stop[0][1].linear.x == 0.0 and ms.runtime.state == before


def test_the_fallback_is_rest_where_its_atoms_allow_it(tmp_path):
    """The Safety System round: a shield whose output is bound to ``/cmd_vel.linear.x`` with ``R1: whenever
    too_close ctrl shall immediately satisfy cmd_linear < 0.01 & cmd_linear > -0.01``: its
    fallback commanded 0.009 m/s (the message the bindings solved for the valuation), not
    rest; rest (0) now, as the summary prints."""
    from click.testing import CliRunner

    from fretc.cli import main

    (tmp_path / "r.fret").write_text(
        "@inputs too_close\n@outputs cmd_linear\nR1: whenever too_close ctrl shall immediately "
        "satisfy cmd_linear < 0.01 & cmd_linear > -0.01\n", encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\ntoo_close = "min(/scan.ranges) < 0.5"\n'
        'cmd_linear = "/cmd_vel.linear.x"\n', encoding="utf-8")
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "r.bindings.toml")])
    assert got.exit_code == 0, got.output
    assert "fallback (a tick whose inputs cannot be read): cmd_linear=0\n" in got.output, \
        got.output
