"""``fretc check`` reads a FRET stream variable (an Internal variable whose Lustre definition
reads itself through ``pre``, as LMCPS's ``psiAtZero``) as FRET's realizability does: a value
computed each tick from the variables its definition reads. A comparison reading it is an
independent proposition, as a comparison reading a previous value (``preReal``) is, with an
abstraction note naming the stream, and its role in realizability is that of the variables
its definition reads (the controller's when one is an output); a variable the definition
reads that is declared neither is named with the stream (FRET's rule). Before, the stream was
a free variable declared neither input nor output: exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

LMCPS = (Path(__file__).resolve().parents[3] / "shared" / "corpora" / "fret_projects"
         / "LMCPS" / "LM_requirements.json")


def _var(name: str, kind: str, data_type: str, assignment: str = "") -> dict:
    return {"project": "P", "component_name": "ctrl", "variable_name": name, "idType": kind,
            "dataType": data_type, "assignment": assignment}


def _check(path: Path, *args: str) -> tuple[int, dict]:
    got = CliRunner().invoke(main, ["check", str(path), "--no-progress", "--json", *args])
    return got.exit_code, json.loads(got.output)


def _write(tmp_path: Path, texts: list[str], variables: list[dict]) -> Path:
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"requirements": [
        {"reqid": f"R{k + 1}", "project": "P", "fulltext": t} for k, t in enumerate(texts)],
        "variables": variables}), encoding="utf-8")
    return path


#: a boolean stream reading a previous number (tests/check/test_stream_bits.py: one reading
#: booleans and the tick's comparisons only is no stream for check)
_NUMERIC = "b -> (b xor (pre latched and x > pre x))"


def test_a_stream_read_by_one_requirement_takes_its_definitions_role(tmp_path):
    """Three variables, ``b``, ``x`` (Inputs) and ``o`` (Output), and ``latched`` := ``b ->
    (b xor (pre latched and x > pre x))`` (a boolean stream reading a previous number: a
    stream for check; one reading booleans and the tick's comparisons only is read by its
    state bit, tests/check/
    test_stream_bits.py, a monotone one as a past-time formula, tests/check/
    test_check_since.py): R1 is checked (not "declared neither"), ``latched`` is the
    environment's (its definition reads the inputs b and x), the controller answers it (o
    true), and the notes name the stream."""
    path = _write(tmp_path, ["whenever latched ctrl shall immediately satisfy o"], [
        _var("b", "Input", "boolean"), _var("x", "Input", "double"),
        _var("o", "Output", "boolean"), _var("latched", "Internal", "boolean", _NUMERIC)])
    code, doc = _check(path)
    rz = doc["realizability"]
    assert code == 0, doc
    assert rz["undeclared"] == [] and rz["inputs"] == ["b", "x"] and rz["outputs"] == ["o"]
    assert rz["streams"] == {"latched": {"reads": ["b", "x"], "role": "input"}}
    assert [g["realizable"] for g in rz["groups"]] == [True]
    assert not [f for f in doc["findings"] if f["kind"] == "undeclared"]
    [note] = [a for a in doc["abstractions"] if a["atom"] == "latched"]
    assert "stream variable latched" in note["why"] and "reads b" in note["why"]
    assert any(n.startswith(f"latched: FRET defines it (Internal) as {_NUMERIC}; "
                            "that definition is a stream with state (it reads itself "
                            "through pre): fretc check reads") for n in doc["notes"])


def test_a_stream_reading_an_output_is_the_controllers_and_its_win_proves_nothing(tmp_path):
    """``held`` := ``y -> if b then y else pre held`` reads the output y: the controller's.
    A controller that sets ``held`` freely wins ``always held > 1``, which proves nothing
    (its definition fixes it): unknown, saying why, exit 1."""
    path = _write(tmp_path, ["ctrl shall always satisfy held > 1.0"], [
        _var("b", "Input", "boolean"), _var("y", "Output", "double"),
        _var("held", "Internal", "double", "y -> if b then y else pre held")])
    code, doc = _check(path)
    rz = doc["realizability"]
    assert rz["streams"] == {"held": {"reads": ["b", "y"], "role": "output"}}
    [group] = rz["groups"]
    assert code == 1 and group["realizable"] == "unknown", doc
    assert "held given to the controller" in group["why"]


def test_a_streams_undeclared_input_is_named_with_the_stream(tmp_path):
    """A variable the definition reads that is declared neither (FRET's rule) is named with
    the stream reading it and the requirement reading the stream: exit 2."""
    path = _write(tmp_path, ["whenever latched ctrl shall immediately satisfy o"], [
        _var("z", "", "boolean"), _var("x", "Input", "double"), _var("o", "Output", "boolean"),
        _var("latched", "Internal", "boolean", _NUMERIC.replace("b", "z"))])
    code, doc = _check(path)
    assert code == 2, doc
    [found] = [f for f in doc["findings"] if f["kind"] == "undeclared"]
    assert found["details"]["undeclared"] == {"z": ["R1"]}
    assert found["details"]["through_streams"] == {"z": ["latched"]}
    assert "z (read by R1 through the stream variable latched)" in found["message"]
    assert doc["realizability"]["streams"]["latched"]["role"] is None


#: requirements reading ``{S}``: the stream ``s`` (``x -> if x > pre x then x else pre s``,
#: reading x now and through pre), or ``preReal(0.0, x)`` (a comparison over the variable
#: its definition reads, through pre)
_FORMS = ["ctrl shall always satisfy {S} <= 1.0",
          "ctrl shall always satisfy y - {S} <= 1.0",
          "whenever {S} > 1.0 ctrl shall immediately satisfy o",
          "whenever o ctrl shall immediately satisfy {S} > 2.0",
          "ctrl shall always satisfy {S} > 0.0 | y > 2.0"]


@pytest.mark.parametrize("form", _FORMS)
@pytest.mark.parametrize("x_role", ["Input", "Output"])
def test_a_stream_reads_as_a_comparison_over_its_definitions_variables(tmp_path, form,
                                                                         x_role):
    """Differential: the requirement reading the stream ``s`` and the same requirement with
    ``s`` replaced by a comparison of the variable its definition reads through pre
    (``preReal(0.0, x)``) give the same realizability answers, and the stream's role is
    the one that comparison's variable has."""
    base = [_var("x", x_role, "double"), _var("y", "Output", "double"),
            _var("o", "Output", "boolean")]
    stream = _var("s", "Internal", "double", "x -> if x > pre x then x else pre s")
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    code_s, with_stream = _check(_write(tmp_path / "a", [form.format(S="s")], base + [stream]))
    code_p, with_pre = _check(_write(tmp_path / "b", [form.format(S="preReal(0.0, x)")],
                                     base))
    answers = [[g["realizable"] for g in d["realizability"]["groups"]]
               for d in (with_stream, with_pre)]
    assert answers[0] == answers[1] and code_s == code_p, (with_stream, with_pre)
    assert with_stream["realizability"]["streams"]["s"]["role"] == x_role.lower()
    assert any("stream variable s" in a["why"] for a in with_stream["abstractions"])


@pytest.mark.skipif(not LMCPS.is_file(), reason="FRET's LMCPS export (../shared/corpora/"
                    "fret_projects/LMCPS) is not on this machine")
def test_lmcps_autopilot_is_checked_with_its_stream_variables():
    """FRET's LMCPS export: the Autopilot component, whose AP-010bv2, AP-010b and AP-004b
    read psiAtZero and rollAtZero, is checked (no ``undeclared``, exit not 2); both are the
    controller's (their definitions read the outputs Psi, roll_angle) and the answer says
    why it is not exact; the whole project (FRET's table) names neither as undeclared."""
    code, doc = _check(LMCPS, "--component", "Autopilot")
    rz = doc["realizability"]
    assert code != 2 and rz["undeclared"] == [], doc
    assert rz["streams"] == {
        "psiAtZero": {"reads": ["Psi", "hdg"], "role": "output"},
        "rollAtZero": {"reads": ["autopilot_engaged", "hdg", "roll_angle"], "role": "output"}}
    [group] = [g for g in rz["groups"] if "AP-010bv2" in g["requirements"]]
    assert group["realizable"] == "unknown" and "psiAtZero" in group["why"]
    assert {"psiAtZero", "rollAtZero"} <= {n for a in doc["abstractions"]
                                          for n in ("psiAtZero", "rollAtZero")
                                          if f"stream variable {n}" in a["why"]}
    got = CliRunner().invoke(main, ["check", str(LMCPS), "--no-progress", "--json",
                                    "--tick-period", "1s"])
    project = json.loads(got.output)
    words = json.dumps([f for c in project["fret_components"] for f in c["check"]["findings"]
                        if f["kind"] == "undeclared"])
    assert "psiAtZero" not in words and "rollAtZero" not in words
    [auto] = [c for c in project["fret_components"] if c["component"] == "Autopilot"]
    assert auto["realizability"] == "unknown" and auto["exit_code"] == 1, auto


def test_witnesses_of_a_stream_say_its_column_is_computed(tmp_path):
    """The witness of a set reading a stream carries the stream's column computed from its
    inputs' (:mod:`fretc.check.stream_rows`); a note says so."""
    path = _write(tmp_path, ["whenever latched ctrl shall immediately satisfy o"], [
        _var("b", "Input", "boolean"), _var("x", "Input", "double"),
        _var("o", "Output", "boolean"), _var("latched", "Internal", "boolean", _NUMERIC)])
    code, doc = _check(path, "--witness-dir", str(tmp_path / "w"))
    assert code == 0 and doc["witnesses"], doc
    assert any(n.startswith("the witnesses' columns of the stream variable latched are "
                            "computed from the columns") for n in doc["notes"]), doc["notes"]


def test_a_stream_declared_an_input_is_that_input(tmp_path):
    """``--inputs`` naming the stream itself (read from the system, as the shield's refusal
    suggests): it is the environment's variable as declared, not its definition's."""
    path = _write(tmp_path, ["ctrl shall always satisfy held > 1.0"], [
        _var("b", "Input", "boolean"), _var("y", "Output", "double"),
        _var("held", "Internal", "double", "y -> if b then y else pre held")])
    code, doc = _check(path, "--inputs", "b,held", "--outputs", "y")
    rz = doc["realizability"]
    assert "streams" not in rz and rz["undeclared"] == [], rz
    assert code == 1 and [g["realizable"] for g in rz["groups"]] == [False], doc
