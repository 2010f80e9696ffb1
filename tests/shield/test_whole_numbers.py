"""Outputs FRET's export declares whole numbers (``dataType`` integer): the shield corrects
them to whole numbers, the one nearest the proposal among those that give the corrected
truths (it gave the real 2.0000000000000004 for ``gear > 2``, which an integer actuator
takes as 2, so it refused such outputs), and its game never chooses truths no whole number
gives (``gear > 2 & gear < 3``). Python against brute force over the integers, C against
Python; comparisons with other variables stay refused."""

from __future__ import annotations

import csv
import io
import json
import math
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
from fretc.shield.runtime import ShieldRuntime, nearest, truth

from _c_monitors import build, needs_cc, write

OPS = ["<", "<=", ">", ">=", "=", "!="]
VARIABLES = [{"variable_name": "go", "dataType": "boolean", "idType": "Input"},
             {"variable_name": "slow", "dataType": "boolean", "idType": "Input"},
             {"variable_name": "gear", "dataType": "integer", "idType": "Output"},
             {"variable_name": "ready", "dataType": "boolean", "idType": "Output"}]
GEAR = [("R1", "whenever go ctrl shall immediately satisfy gear > 2"),
        ("R2", "ctrl shall always satisfy gear < 6 & ready"),
        ("R3", "whenever slow ctrl shall immediately satisfy gear < 3.5"),
        ("R4", "ctrl shall always satisfy gear != 4")]


def _export(folder: Path, requirements, variables=VARIABLES) -> Path:
    path = folder / "gear.json"
    path.write_text(json.dumps({"requirements": [{"reqid": i, "fulltext": t}
                                                 for i, t in requirements],
                                "variables": variables}), encoding="utf-8")
    return path


def _shield(folder: Path, requirements=GEAR):
    compiled = compile_entries(load_requirements([_export(folder, requirements)]))
    return build_shield(compiled, ["go", "slow"], ["gear", "ready"], fork=False)


specs = st.lists(st.tuples(st.sampled_from(OPS), st.one_of(
    st.integers(-5, 5).map(float), st.sampled_from([0.5, -1.5, 2.25, 3.75, math.inf]))),
    min_size=1, max_size=4)


@settings(max_examples=300, deadline=None)
@given(specs, st.data(), st.one_of(st.floats(-9, 9), st.sampled_from([math.nan, math.inf,
                                                                      -math.inf])))
def test_the_nearest_whole_number_is_the_brute_forces(comparisons, data, x):
    """Against every whole number from -20 to 20 (the constants are within 6): ``x`` when
    it gives the truths and is whole or infinite, else the whole number nearest ``x``
    giving them, the smaller of two as near; for a NaN or infinite ``x``, the one nearest
    the end of the region that real numbers give."""
    spec = [("g", op, c) for op, c in comparisons]
    truths = data.draw(st.lists(st.integers(0, 1), min_size=len(spec), max_size=len(spec)))
    if not math.isnan(x) and all(truth(s, x) == bool(t) for s, t in zip(spec, truths)) \
            and (math.isinf(x) or x == int(x)):
        assert nearest(spec, truths, x, True) == x
        return
    whole = [float(w) for w in range(-20, 21)
             if all(truth(s, float(w)) == bool(t) for s, t in zip(spec, truths))]
    if not whole:
        with pytest.raises(ValueError):
            nearest(spec, truths, x, True)
        return
    ref = x if math.isfinite(x) else nearest(spec, truths, x)
    want = min(whole, key=lambda w: (abs(w - ref), w))
    got = nearest(spec, truths, x, True)
    assert got == want and got == int(got), (spec, truths, x, got, want)


def test_the_shield_corrects_a_whole_number_output_to_whole_numbers(tmp_path):
    shield = _shield(tmp_path)
    assert shield.integers == ("gear",)
    rt = ShieldRuntime(tables(shield))
    cases = [({"go": True, "slow": False}, 1.0, 3.0),   # the real answer: 2.0000000000000004
             ({"go": True, "slow": True}, 5.5, 3.0),    # 2 < gear < 3.5
             # != 4 made true, gear < 3.5 kept false (the fewest changes): 5, not 3
             ({"go": False, "slow": False}, 4.0, 5.0),
             # no truth changed: a whole proposal kept, another the nearest whole number
             # with its truths (4.4 is not left for an integer actuator to make 4)
             ({"go": False, "slow": False}, 3.0, 3.0),
             ({"go": False, "slow": False}, 4.4, 5.0),
             ({"go": False, "slow": False}, 2.5, 3.0)]
    for ins, proposed, want in cases:
        got = rt.step(ins, {"gear": proposed, "ready": True}).outputs["gear"]
        assert got == want, (ins, proposed, got)


def test_no_whole_number_between_the_constants_is_unrealizable_and_says_why(tmp_path):
    got = CliRunner().invoke(main, ["shield", str(_export(tmp_path, [
        ("R1", "whenever go ctrl shall immediately satisfy gear > 2 & gear < 3")]))])
    assert got.exit_code == 2, got.output
    assert "in whole numbers as FRET's export declares gear" in got.output, got.output
    variables = [dict(v, dataType="double") if v["variable_name"] == "gear" else v
                 for v in VARIABLES]
    got = CliRunner().invoke(main, ["shield", str(_export(tmp_path, [
        ("R1", "whenever go ctrl shall immediately satisfy gear > 2 & gear < 3")],
        variables))])
    assert got.exit_code == 0, got.output


def test_a_whole_number_output_compared_with_another_variable_is_refused(tmp_path):
    variables = VARIABLES + [{"variable_name": "top", "dataType": "double",
                              "idType": "Output"}]
    got = CliRunner().invoke(main, ["shield", str(_export(tmp_path, [
        ("R1", "ctrl shall always satisfy gear < top & ready")], variables))])
    assert got.exit_code == 2, got.output
    assert "compared with other variables or in arithmetic: gear (integer)" in got.output
    got = CliRunner().invoke(main, ["shield", str(_export(tmp_path, GEAR))])
    assert got.exit_code == 0, got.output
    assert "gear: declared integer in FRET; the shield gives it whole numbers" in got.output
    unsigned = [dict(v, dataType="unsigned integer") if v["variable_name"] == "gear" else v
                for v in VARIABLES]
    got = CliRunner().invoke(main, ["shield", str(_export(tmp_path, GEAR, unsigned))])
    assert got.exit_code == 2, got.output
    assert "unsigned whole numbers in the FRET export and compared with numbers: gear " \
           "(unsigned integer)" in got.output


@settings(max_examples=4, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.booleans(), st.sampled_from(
    [-3.0, 0.0, 1.0, 2.5, 3.0, 3.4, 4.0, 4.5, 5.9, 7.0, 1e300, math.inf, -math.inf])),
    min_size=1, max_size=40))
def test_c_and_python_give_the_same_whole_numbers(tmp_path_factory, rows):
    needs_cc()
    folder = tmp_path_factory.mktemp("whole")
    shield = _shield(folder)
    write(render_c(shield, "g"), folder / "c")
    exe = build(folder / "c", ["g_shield.c", "g_shield_run.c"], "run")
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(["go", "slow", "gear", "ready"])
    for go, slow, gear in rows:
        w.writerow([str(go).lower(), str(slow).lower(), repr(gear), "true"])
    got = subprocess.run([str(exe)], input=text.getvalue(), capture_output=True, text=True,
                         timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    rt = ShieldRuntime(tables(shield))
    for (go, slow, gear), c in zip(rows, csv.DictReader(io.StringIO(got.stdout)), strict=True):
        want = rt.step({"go": go, "slow": slow}, {"gear": gear, "ready": True}).outputs["gear"]
        assert float(c["gear"]) == want, (go, slow, gear, c, want)


def test_the_shield_refuses_no_whole_number_output_it_cannot_take(tmp_path):
    """A build without declarations keeps reals (no integers)."""
    path = tmp_path / "r.fret"
    path.write_text("R1: whenever go ctrl shall immediately satisfy gear > 2\n")
    shield = build_shield(compile_entries(load_requirements([path])), ["go"], ["gear"],
                          fork=False)
    assert shield.integers == ()
    with pytest.raises(ShieldError):
        build_shield(compile_entries(load_requirements([_export(tmp_path, [
            ("R1", "ctrl shall always satisfy absInt(gear) > 2 & ready")])])),
            ["go", "slow"], ["gear", "ready"], fork=False)


def _gear_shield(tmp_path, variables: str):
    """(the bindings, the shield) of GEAR over inputs go, slow and outputs gear, ready, bound
    by ``go = "/go.data"`` and ``variables`` (gear.bindings.toml)."""
    from fretc.signals.bindings.files import load_bindings

    b = tmp_path / "gear.bindings.toml"
    b.write_text('[tick]\nperiod = "100 ms"\n[variables]\ngo = "/go.data"\n' + variables,
                 encoding="utf-8")
    bindings = load_bindings(b)
    compiled = compile_entries(load_requirements([_export(tmp_path, GEAR)]))
    return bindings, build_shield(compiled, ["go", "slow"], ["gear", "ready"],
                                  bindings=bindings, fork=False)


def test_the_ros_2_node_publishes_the_whole_number_of_a_kept_proposal(tmp_path):
    """The node forwarded a proposal whose atoms the shield kept as it came: the whole
    number the shield made of 4.4 never reached the topic."""
    from types import SimpleNamespace

    from fretc.shield.messages import MessageShield

    bindings, shield = _gear_shield(tmp_path, 'slow = "/slow.data"\ngear = "/gear_cmd.data"\n'
                                              'ready = "/ready_cmd.data"\n')
    node = MessageShield(ShieldRuntime(tables(shield)), bindings,
                         {"/gear_cmd": "/gear_prop", "/ready_cmd": "/ready_prop"},
                         lambda topic: SimpleNamespace(data=0))
    for k, (gear, want) in enumerate([(3.0, 3.0), (4.4, 5.0), (1.0, 3.0), (2.5, 3.0)]):
        t = (k + 1) * 100_000_000
        node.hear("/go.data".split(".")[0], SimpleNamespace(data=k == 2), t)
        node.hear("/slow", SimpleNamespace(data=False), t)
        node.hear("/gear_prop", SimpleNamespace(data=gear), t)
        node.hear("/ready_prop", SimpleNamespace(data=True), t)
        d, msgs = node.tick(t)
        assert d.outputs["gear"] == want and dict(msgs)["/gear_cmd"].data == want, (gear, d)


def test_a_whole_number_output_beside_a_corrected_boolean_of_its_message_stays_whole(tmp_path):
    """``gear`` and ``ready`` in one message: an override of ``ready`` takes the group's
    message numbers (a real witness such as 3.15); a whole-number output takes them only
    when whole, else the nearest whole number (Python and C alike)."""
    from types import SimpleNamespace

    from fretc.shield.messages import MessageShield

    bindings, shield = _gear_shield(tmp_path, 'slow = "/slow.data"\ngear = "/cmd.gear"\n'
                                              'ready = "/cmd.ready"\n')
    node = MessageShield(ShieldRuntime(tables(shield)), bindings, {"/cmd": "/prop"},
                         lambda topic: SimpleNamespace(gear=0.0, ready=False))
    rows = [(True, True, 1.0, False), (False, True, 3.3, False), (False, False, 4.0, False),
            (True, False, 2.5, True), (False, True, 9.0, False)]
    got = []
    for k, (go, slow, gear, ready) in enumerate(rows):
        t = (k + 1) * 100_000_000
        node.hear("/go", SimpleNamespace(data=go), t)
        node.hear("/slow", SimpleNamespace(data=slow), t)
        node.hear("/prop", SimpleNamespace(gear=gear, ready=ready), t)
        d, msgs = node.tick(t)
        out = dict(msgs)["/cmd"]
        assert out.gear == d.outputs["gear"] == int(out.gear) and out.ready, (k, d, out)
        got.append(d.outputs["gear"])
    if not _has_cc():
        return
    write(render_c(shield, "g"), tmp_path / "c")
    exe = build(tmp_path / "c", ["g_shield.c", "g_shield_run.c"], "run")
    text = "go,slow,gear,ready\n" + "".join(f"{str(g).lower()},{str(s).lower()},{x!r},"
                                             f"{str(r).lower()}\n" for g, s, x, r in rows)
    run = subprocess.run([str(exe)], input=text, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert [float(c["gear"]) for c in csv.DictReader(io.StringIO(run.stdout))] == got


def _has_cc() -> bool:
    try:
        needs_cc()
    except pytest.skip.Exception:
        return False
    return True
