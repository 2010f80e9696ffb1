"""A shield's step is all or nothing, and no value it cannot read stops it.

Random requirement sets over the inputs ``a``, ``b`` (booleans), ``d`` (a number) and ``m``
(a mode) and the outputs ``x``, ``y`` (booleans) and ``v`` (a number), random runs, and at
random ticks a value the shield cannot read: an input or a proposal that is NaN, infinite
(a proposal), missing, of the wrong type, or an integer no double holds. Each faulty run is
judged against the fault-free run of a second shield (the reference):

* a tick whose input cannot be read leaves the state as it was (the reference skips the
  tick) and gives the fallback's outputs (none when the shield has none);
* a tick whose proposal cannot be read decides as the reference does on the proposal with
  the fallback's value in its place (without a fallback: outputs the shield's node table
  says are safe, the reference then given them); it is an override, never the value it
  could not read, never an exception;
* every other tick decides as the reference does;

and FRET's interval semantics finds no enforced requirement violated on the ticks whose
inputs were read. The C form is held to the Python form on the same faulty runs (NaN inputs;
NaN and infinite proposals: what a double can carry).
"""

from __future__ import annotations

import csv
import io
import math
import subprocess
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import load_shield, render_python, tables
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import ShieldRuntime

from _c_monitors import build as build_c, needs_cc, write
from _gen import (CONDITIONS, RESPONSES, SCOPES, TIMINGS, atoms_of, compile_text, safe,
                  verdicts)

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


def judged(shield, run) -> list:
    """The faulty run stepped by the Python form, each tick judged against the reference
    (module docstring); the decisions."""
    rt, ref = ShieldRuntime(tables(shield)), ShieldRuntime(tables(shield))
    fb = shield.fallback
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
        if read_in:
            assert rt.state == before and d.overridden and d.fault.startswith(f"input {var}")
            if fb is None:
                assert d.outputs == {}, d
            else:
                assert {v: d.outputs[v] for v in fb["outputs"]} == fb["outputs"], (d, fb)
            continue
        if read_out:
            assert d.overridden and d.fault.startswith(f"proposal {var}"), d
            for v in rt.output_kinds:
                assert v in d.outputs and d.outputs[v] is not None
                if rt.output_kinds[v] == "n":
                    assert math.isfinite(d.outputs[v]), d
            if fb is not None and var in fb["outputs"]:
                want = ref.step(ins, {**prop, var: fb["outputs"][var]})
                assert d.outputs == want.outputs and rt.state == ref.state, (d, want)
            else:
                for k, m in enumerate(shield.machines):
                    assert safe(m, before[k], ins, atoms_of(m, d.outputs)), d
                ref.step(ins, d.outputs)
                assert rt.state == ref.state
            continue
        # (no fault, or one in a value no enforced requirement reads: passed through)
        want = ref.step(got_ins, got_prop)
        assert _same(d.outputs, want.outputs) and d[1:4] == want[1:4] and not d.fault \
            and rt.state == ref.state, (d, want)
    return decisions


@SETTINGS
@given(text=requirement_sets(), run=faulty_runs())
def test_a_step_is_all_or_nothing_and_no_value_stops_it(text, run):
    compiled, shield = _shield(text)
    decisions = judged(shield, run)
    rt = ShieldRuntime(tables(shield))
    trace = [{**ins, **d.outputs} for (ins, _p, f), d in zip(run, decisions)
             if not (f and f[0] == "input" and f[1] in rt.input_kinds)]
    enforced = {r.id for r in shield.requirements}
    if trace and all(set(OUTPUTS) <= row.keys() and all(
            not isinstance(row[k], float) or math.isfinite(row[k]) for k in row)
            for row in trace):
        got = verdicts(compiled, trace)
        assert all(got[r] != "violated" for r in enforced), (text, got, trace)


def test_the_issue_example_nan_at_f1s_deadline_moves_no_machine(tmp_path):
    """F1/F2: ``a`` at tick 0, ``o`` proposed false throughout, ``x = NaN`` at F1's
    deadline. The step raised after F1's machine had moved, and F1 was violated on the next
    ticks; now the state stays, the fallback's ``o`` is true, and F1 is enforced after."""
    compiled = compile_text("F1: upon a ctrl shall within 2 ticks satisfy o\n"
                            "F2: whenever x > 2 ctrl shall immediately satisfy !p\n", tmp_path)
    shield = build_shield(compiled, ["a", "x"], ["o", "p"], fork=False)
    sh = load_shield(render_python(shield))()  # (the generated module, as a user runs it)
    ticks = [({"a": True, "x": 0.0}), ({"a": False, "x": 0.0}), ({"a": False, "x": math.nan}),
             ({"a": False, "x": 0.0}), ({"a": False, "x": 0.0})]
    rows = []
    for k, ins in enumerate(ticks):
        before = sh.state
        d = sh.step(ins, {"o": False, "p": False})
        if k == 2:
            assert sh.state == before and d.fault == "input x is NaN"
            assert d.outputs == {"o": True, "p": False}
        else:
            rows.append({**ins, **d.outputs})
    assert verdicts(compiled, rows)["F1"] == "satisfied", rows


def test_a_declared_fallback_is_used_and_one_that_is_not_safe_is_refused(tmp_path):
    compiled = compile_text("R1: whenever a sw shall immediately satisfy x\n"
                            "R2: the sw shall always satisfy v <= 1\n", tmp_path)
    shield = build_shield(compiled, ["a"], ["x", "v"], fork=False,
                          fallback={"x": True, "v": -2.0})
    assert shield.fallback is not None
    assert shield.fallback["outputs"] == {"x": True, "v": -2.0}
    d = ShieldRuntime(tables(shield)).step({"a": "?"}, {"x": False, "v": 0.0})
    assert d.outputs == {"x": True, "v": -2.0} and d.fault.startswith("input a")
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
def test_the_c_form_is_all_or_nothing_as_the_python_form(text, run):
    """The faulty runs a double can carry (NaN inputs; NaN and infinite proposals), each
    judged against the reference by :func:`judged`; the C runner gives the Python form's
    outputs, override, reasons and fault at every tick."""
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
            w.writerow([_cell(ins[v]) for v in INPUTS] + [_cell(prop[v]) for v in OUTPUTS])
        got = subprocess.run([str(exe)], input=text_in.getvalue(), capture_output=True,
                             text=True, timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    rows = list(csv.DictReader(io.StringIO(got.stdout)))
    for (_ins, _p, fault), d, c in zip(run, decisions, rows, strict=True):
        kind = d.fault.split(" ")[0] if d.fault else ""
        assert c["fault"] == kind, (fault, d, c)
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


def _cell(x) -> str:
    return ("true" if x else "false") if isinstance(x, bool) else repr(float(x))


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
