"""No silent roles: ``fretc check`` decides the realizability of a component only when every
variable its requirements read is declared an input or an output (FRET's rule: FRET checks
realizability only then). A variable declared neither is named with the requirements that
read them and how to declare it (``--inputs``/``--outputs``, ``@inputs``/``@outputs``, FRET's
glossary), the component is not decided, the exit code is 2 (an input error); the checks
that need no roles (satisfiability, vacuity, redundancy) and the declared components are
reported as ever. Before, an undeclared variable was taken as an output: the tour's
``--inputs too_close --outputs stopped`` gave the sensor reading ``clearance`` to the
controller and called R5 (``always clearance > 0``) realizable, "no findings"."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from fretc.check.analysis import check_requirements
from fretc.check.solver import SpotWorker
from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements

ROOT = Path(__file__).resolve().parents[2]
REQS = ROOT / "requirements"
#: the Safe-ROS requirements' variables: the environment's and the controller's
INPUTS = "too_close,clearance,scan_stale"
OUTPUTS = "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed"


def _check(*args: str):
    return CliRunner().invoke(main, ["check", *args, "--no-progress"])


def _components(doc: dict) -> dict:
    return {tuple(c["requirements"]): c for c in doc["realizability"]["groups"]}


def test_the_tours_undeclared_clearance_is_named_not_taken_as_an_output():
    """The tour's command as it was: ``clearance`` (R5), ``scan_stale``,
    ``stop_requested``, ``forwarded_zero`` (R3, R6) and the speeds (R4) are declared
    neither: those components are not decided (R5 is no longer "realizable", and there is
    no "no findings"), each variable named with its readers; R1, R2 (every variable
    declared) are decided realizable, and every requirement's satisfiability, vacuity and
    redundancy are reported. Exit 2."""
    res = _check(str(REQS), "--inputs", "too_close", "--outputs", "stopped", "--json")
    assert res.exit_code == 2, res.output
    doc = json.loads(res.output)
    assert doc["exit_code"] == 2
    comps = _components(doc)
    assert comps[("R1", "R2")]["realizable"] is True
    assert comps[("R5",)] == {"requirements": ["R5"], "realizable": None,
                              "undeclared": {"clearance": ["R5"]}}
    assert comps[("R4",)]["undeclared"] == {"linear_speed": ["R4"], "angular_speed": ["R4"]}
    assert comps[("R3", "R6")]["undeclared"] == {"stop_requested": ["R3", "R6"],
                                                 "forwarded_zero": ["R3"],
                                                 "scan_stale": ["R6"]}
    assert sorted(doc["realizability"]["undeclared"]) == sorted(
        ["clearance", "linear_speed", "angular_speed", "stop_requested", "forwarded_zero",
         "scan_stale"])
    undeclared = [f for f in doc["findings"] if f["kind"] == "undeclared"]
    assert [f["requirements"] for f in undeclared] == [["R3", "R6"], ["R4"], ["R5"]]
    assert all(f["severity"] == "input" for f in undeclared)
    assert [f["kind"] for f in doc["findings"]] == ["undeclared"] * 3
    r5 = undeclared[2]["message"]
    assert r5.startswith("realizability of R5 not checked: clearance (read by R5) is "
                         "declared neither input nor output"), r5
    for how in ("--inputs", "--outputs", "@inputs/@outputs", "FRET's glossary"):
        assert how in r5, (how, r5)
    # the checks that need no roles: as ever
    assert all(r["satisfiable"] is True and r["non_vacuous"] is True
               and r["redundant"] is False for r in doc["requirements"])
    # the finding is on R5's row (fretc report --check)
    r5_row = next(r for r in doc["requirements"] if r["id"] == "R5")
    assert [doc["findings"][k]["kind"] for k in r5_row["findings"]] == ["undeclared"]

    text = _check(str(REQS), "--inputs", "too_close", "--outputs", "stopped")
    assert text.exit_code == 2
    assert "  R5: not checked: clearance declared neither input nor output\n" in text.output
    assert "R5: realizable" not in text.output and "no findings" not in text.output
    assert "ERROR undeclared: realizability of R5 not checked" in text.output
    assert text.output.rstrip().endswith("exit 2")


def test_the_tours_set_declared_gives_the_honest_answer():
    """``clearance`` an input (a sensor reading): R5 over an input only is unrealizable,
    no controller keeps ``clearance > 0`` (the environment sets it to -1 at the first tick);
    the rest is realizable. Exit 1, the finding R5's."""
    res = _check(str(REQS), "--inputs", INPUTS, "--outputs", OUTPUTS, "--json")
    assert res.exit_code == 1, res.output
    doc = json.loads(res.output)
    assert [(f["kind"], f["requirements"]) for f in doc["findings"]] == [
        ("unrealizable", ["R5"])]
    assert doc["realizability"]["undeclared"] == []
    r5 = _components(doc)[("R5",)]
    assert r5["realizable"] is False and "undeclared" not in r5
    env = r5["environment"]
    rows = env["prefix"] + env["cycle"]
    assert rows and all(set(row) == {"clearance"} and row["clearance"] <= 0 for row in rows)
    assert "whatever the inputs (clearance) do" in doc["findings"][0]["message"]
    r5_row = next(r for r in doc["requirements"] if r["id"] == "R5")
    assert [doc["findings"][k]["kind"] for k in r5_row["findings"]] == ["unrealizable"]
    # what is checked is what must be declared: R1 and R2 alone need only their own
    res = _check(str(REQS), "--only", "R1,R2", "--inputs", "too_close", "--outputs",
                 "stopped")
    assert res.exit_code == 0 and "no findings" in res.output, res.output


def test_a_fret_export_with_glossary_roles_is_unaffected():
    """The shipped FRET export with ``--component safety_system``: every variable of the
    requirements has its role in FRET's glossary, so nothing is undeclared and the answers
    are those of the declared flags (R5 unrealizable, exit 1)."""
    res = _check(str(REQS / "fret" / "safe_ros.json"), "-b",
                 str(REQS / "shield" / "safe_ros_shield.bindings.toml"),
                 "--component", "safety_system", "--json")
    assert res.exit_code == 1, res.output
    doc = json.loads(res.output)
    assert doc["realizability"]["undeclared"] == []
    assert [(f["kind"], f["requirements"]) for f in doc["findings"]] == [
        ("unrealizable", ["R5"])]
    assert all(c["realizable"] is True for k, c in _components(doc).items() if k != ("R5",))
    assert "R1" not in [r["id"] for r in doc["requirements"]]  # (agilex_agent's)


def _export(kind_of_b: str, assignment: str = "") -> dict:
    return {"requirements": [
        {"reqid": "E1", "project": "P", "fulltext": "whenever a ctrl shall immediately satisfy b"},
        {"reqid": "E2", "project": "P", "fulltext": "ctrl shall always satisfy c | !a"}],
        "variables": [
        {"project": "P", "component_name": "ctrl", "variable_name": "a", "idType": "Input",
         "dataType": "boolean"},
        {"project": "P", "component_name": "ctrl", "variable_name": "b", "idType": kind_of_b,
         "dataType": "boolean", "assignment": assignment},
        {"project": "P", "component_name": "ctrl", "variable_name": "c", "idType": "Output",
         "dataType": "boolean"}]}


@pytest.mark.parametrize("kind, assignment, words", [
    ("Output", "", None),
    ("Internal", "a and b", "b an Internal of ctrl, a free variable to fretc"),
    ("Mode", "", "b a Mode of ctrl, a free variable to fretc"),
    ("", "", None),
])
def test_a_fret_export_variable_without_a_role_is_named_with_its_fret_kind(
        tmp_path, kind, assignment, words):
    """A FRET export whose glossary gives every variable Input or Output is decided as
    before; a variable FRET declares Internal whose definition fretc keeps free (it reads
    itself without pre, a cycle Lustre gives no value; a definition fretc reads is expanded:
    tests/fretish/test_lustre_definitions.py, one reading itself through pre is a stream:
    tests/check/test_check_streams.py), Mode or not at all is undeclared for
    realizability, named with FRET's kind."""
    f = tmp_path / "p.json"
    f.write_text(json.dumps(_export(kind, assignment)), encoding="utf-8")
    res = _check(str(f), "--json")
    doc = json.loads(res.output)
    if kind == "Output":
        assert res.exit_code == 0 and doc["findings"] == [], res.output
        assert doc["realizability"]["inputs"] == ["a"]
        return
    assert res.exit_code == 2, res.output
    [found] = [x for x in doc["findings"] if x["kind"] == "undeclared"]
    assert found["requirements"] == ["E1"] and found["details"]["undeclared"] == {"b": ["E1"]}
    assert "b (read by E1) is declared neither input nor output" in found["message"]
    if words:
        assert words in found["message"], found["message"]
    else:
        assert "FRET's export:" not in found["message"]


_FORMS = ["whenever {a} the sw shall within 2 ticks satisfy {b}",
          "the sw shall always satisfy {a} | {b}",
          "upon {a} the sw shall eventually satisfy {b}",
          "the sw shall always satisfy x > 1.0 | {a}",
          "in m mode the sw shall always satisfy {b}"]
_VARS = ["a", "b", "c", "d"]
_ROLES = st.sampled_from(["input", "output", "none"])


@pytest.fixture(scope="module")
def worker():
    with SpotWorker(fork=False) as w:
        yield w


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(_FORMS), st.sampled_from(_VARS),
                          st.sampled_from(_VARS)), min_size=1, max_size=4),
       st.fixed_dictionaries({v: _ROLES for v in _VARS + ["x", "m"]}))
def test_every_undeclared_variable_is_named_with_its_readers(tmp_path, worker, parts, roles):
    """Random sets and random roles (each variable an input, an output or neither): a
    component is decided exactly when every variable it reads is declared; otherwise its
    entry and an ``undeclared`` finding name each undeclared variable with exactly the
    requirements reading it, and the exit code is 2 exactly when there is one."""
    f = tmp_path / "r.fret"
    f.write_text("".join(f"R{k}: " + form.format(a=a, b=b) + "\n"
                         for k, (form, a, b) in enumerate(parts)), encoding="utf-8")
    compiled = compile_entries(load_requirements([f]))
    ins = [v for v, r in roles.items() if r == "input"]
    outs = [v for v, r in roles.items() if r == "output"]
    res = check_requirements(compiled, inputs=ins, outputs=outs, vacuity=False,
                             redundancy=False, worker=worker)
    reads = {c.id: list(c.formalization.variables) for c in compiled}
    found = {tuple(x.details["group"]): x for x in res.findings if x.kind == "undeclared"}
    every = set()
    for comp in res.realizability["groups"]:
        ids = comp["requirements"]
        want: dict[str, list[str]] = {}
        for rid in ids:
            for v in reads[rid]:
                if roles[v] == "none" and rid not in want.setdefault(v, []):
                    want[v].append(rid)
        every |= set(want)
        event("decided" if not want else "not decided")
        if not want:
            assert "undeclared" not in comp and tuple(ids) not in found
            assert comp["realizable"] in (True, False, "unknown"), comp
            continue
        assert comp["realizable"] is None and comp["undeclared"] == want, (comp, want)
        finding = found[tuple(ids)]
        assert finding.severity == "input" and finding.details["undeclared"] == want
        assert set(finding.requirements) == {r for rs in want.values() for r in rs}
        for v, readers in want.items():
            assert f"{v} (read by {', '.join(readers)})" in finding.message, finding.message
    assert set(res.realizability["undeclared"]) == every
    assert len(found) == sum("undeclared" in c for c in res.realizability["groups"])
    assert (res.exit_code == 2) == bool(every)
