"""FRET's variable declarations in its exports (``{"requirements", "variables"}``, FRET 3.0's
requirements-and-variables export, as FRET's case studies ship): a component's Input and
Output variables are its requirements' ``@inputs``/``@outputs`` for ``fretc check`` and
``fretc shield``; what fretc does not use (an Internal variable's assignment, a whole-number
type) is said in a note, and the shield gives whole-number outputs whole numbers. They were
ignored: the shield said "no outputs" of an export that declares them."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.common.errors import FretishFileError
from fretc.fretish.files import load_requirements
from fretc.fretish.fret_variables import fret_variables

#: the shape of FRET's own export (FRET's FiniteStateMachine case study: a FRET variable per
#: component, and the imported Simulink model's ports, which are no FRET variables)
EXPORT = {
    "requirements": [
        {"reqid": "FSM-002", "parent_reqid": "", "project": "FSM", "rationale": "",
         "fulltext": "FSM shall always satisfy (standby & state = ap_transition_state) => "
                     "STATE = ap_standby_state"},
        {"reqid": "M-1", "project": "FSM", "fulltext": "monitor shall always satisfy ok"}],
    "variables": [
        {"project": "FSM", "component_name": "FSM", "variable_name": "STATE",
         "dataType": "double", "idType": "Output", "assignment": "", "reqs": ["x"]},
        {"project": "FSM", "component_name": "FSM", "variable_name": "ap_standby_state",
         "dataType": "double", "idType": "Internal", "assignment": "3.0"},
        {"project": "FSM", "component_name": "FSM", "variable_name": "ap_transition_state",
         "dataType": "double", "idType": "Internal", "assignment": "0.0"},
        {"project": "FSM", "component_name": "FSM", "variable_name": "standby",
         "dataType": "boolean", "idType": "Input", "assignment": ""},
        {"project": "FSM", "component_name": "FSM", "variable_name": "state",
         "dataType": "integer", "idType": "Input", "assignment": ""},
        {"project": "FSM", "component_name": "monitor", "variable_name": "ok",
         "dataType": "boolean", "idType": "Output", "assignment": ""},
        {"component_name": "fsm_12B/FiniteStateMachine", "dataType": ["boolean"],
         "modeldoc": True, "portType": "Inport", "variable_name": "standby"},
        {"Declarations": {"Enumerations": []}, "project": "FSM", "fretComponent": "FSM"}],
}


def _write(tmp_path, doc) -> str:
    path = tmp_path / "fsm_reqts_and_vars.json"
    path.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    return str(path)


def test_each_component_takes_its_input_and_output_variables(tmp_path):
    fsm, mon = load_requirements([_write(tmp_path, EXPORT)])
    assert fsm.inputs == ("standby", "state") and fsm.outputs == ("STATE",)
    assert [v.name for v in fsm.variables] == ["STATE", "ap_standby_state",
                                               "ap_transition_state", "standby", "state"]
    assert mon.inputs == () and mon.outputs == ("ok",)
    assert fret_variables({"requirements": []}, "x.json") == []


@pytest.mark.parametrize("bad, words", [
    ({"variables": {}}, "not a list"),
    ({"variables": [3]}, "variable #1 is not a JSON object"),
    ({"variables": [{"variable_name": "a", "idType": 1}]}, "\"idType\" is not a string"),
    ({"variables": [{"variable_name": "a", "idType": "Sensor"}]}, "none of FRET's"),
    ({"variables": [{"variable_name": " ", "idType": "Input"}]}, "empty \"variable_name\""),
])
def test_declarations_of_another_shape_are_refused_naming_the_entry(tmp_path, bad, words):
    with pytest.raises(FretishFileError, match=words):
        load_requirements([_write(tmp_path, {**EXPORT, **bad})])


def test_check_takes_the_declarations_and_says_what_it_does_not_use(tmp_path):
    got = CliRunner().invoke(main, ["check", _write(tmp_path, EXPORT), "--no-progress"])
    assert got.exit_code == 0, got.output
    # FRET checks each component with its own variables (the table at the end)
    assert "inputs standby, state; outputs STATE\n" in got.output, got.output
    assert "inputs -; outputs ok\n" in got.output
    assert "2 components: 2 realizable" in got.output
    # FRET's realizability reads an Internal variable's assignment: a literal is that
    # constant, so STATE = ap_standby_state is STATE = 3.0 (a comparison with a constant,
    # the safety game's), not a free proposition
    assert "note: ap_standby_state: FRET defines it (Internal) as 3.0; that constant in the " \
           "analysis (the emitted formulas keep its name)" in got.output
    assert "FSM-002: realizable by a controller over 1 state bit (safety game" in got.output
    assert "abstraction: (STATE = ap_standby_state)" not in got.output
    assert "note: state: declared integer in FRET; fretc's numbers are reals" in got.output


def test_the_shield_takes_the_outputs_and_their_whole_numbers(tmp_path):
    doc = {"requirements": [
        {"reqid": "R1", "fulltext": "whenever go ctrl shall immediately satisfy gear > 2"},
        {"reqid": "R2", "fulltext": "ctrl shall always satisfy gear < 6 & ready"}],
        "variables": [
        {"variable_name": "go", "dataType": "boolean", "idType": "Input"},
        {"variable_name": "gear", "dataType": "integer", "idType": "Output"},
        {"variable_name": "ready", "dataType": "boolean", "idType": "Output"}]}
    got = CliRunner().invoke(main, ["shield", _write(tmp_path, doc)])
    assert got.exit_code == 0, got.output  # (tests/shield/test_whole_numbers.py)
    assert "gear: declared integer in FRET; the shield gives it whole numbers" in got.output
    doc["variables"][1]["dataType"] = "double"
    got = CliRunner().invoke(main, ["shield", _write(tmp_path, doc)])
    assert got.exit_code == 0, got.output
    assert "inputs go; outputs gear, ready" in got.output
    doc["variables"][1]["idType"] = "Internal"
    got = CliRunner().invoke(main, ["shield", _write(tmp_path, doc)])
    assert got.exit_code == 2 and "gear is an Internal variable in FRET's export" in got.output


def test_a_literal_internal_assignment_is_that_constant_and_a_mode_its_requirement(tmp_path):
    from fretc.fretish.fret_variables import FretVariable, constant_of, with_fret_definitions

    def internal(a: str) -> FretVariable:
        return FretVariable("c", "k", "Internal", "double", a)

    assert [constant_of(internal(a)) is not None for a in
            ("3.0", "-2", "+1e3", ".5", "true", "false", "x + 1", "pre(k)", "")] == [
        True, True, True, True, True, True, False, False, False]
    doc = {"requirements": [{"reqid": "A", "fulltext":
                             "in m mode c shall always satisfy (k > x) & (flag | !on)"}],
           "variables": [{"variable_name": "k", "component_name": "c", "idType": "Internal",
                          "assignment": "2.5"},
                         {"variable_name": "flag", "component_name": "c",
                          "idType": "Internal", "assignment": "false"},
                         {"variable_name": "m", "component_name": "c", "idType": "Mode",
                          "modeRequirement": "on"}]}
    (entry,) = load_requirements([_write(tmp_path, doc)])
    from fretc.compiler.build import compile_entries

    (before,) = compile_entries([entry])
    (after,) = compile_entries([with_fret_definitions(entry)])
    assert set(before.formalization.variables) == {"m", "k", "x", "flag", "on"}
    # the mode is its mode requirement (on): in m mode is where on holds
    assert set(after.formalization.variables) == {"x", "on"}
    assert with_fret_definitions(entry).text == entry.text
