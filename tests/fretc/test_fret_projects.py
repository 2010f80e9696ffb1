"""FRET projects end to end: a FRET export of the Safe-ROS requirements
(``requirements/fret/safe_ros.json``, its variables declared per component as FRET's Analysis
Portal declares them) through ``fretc check``, ``fretc shield`` (with ``--emit ros2``) and
``fretc audit``, and small exports built here.

FRET checks a project one component at a time: ``--component NAME`` judges that component's
requirements (those whose text names it) with its Inputs and Outputs; without it, ``fretc
check`` on a project of several components gives FRET's table (each component realizable,
unrealizable with its conflicts, unknown or not checked, with the reason), and an Output of
one component read as an Input of another is no conflict. A shield is one component's: without
``--component`` it is refused naming the components. ``--only``/``--exclude`` select inside the
component, a variable declared for another component is named with it, and ``--emit ros2``
works from the export with ``-b`` giving the period.
"""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
EXPORT = str(REPO / "requirements" / "fret" / "safe_ros.json")
BINDINGS = str(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml")


def _run(*args: str):
    return CliRunner().invoke(main, list(args))


def test_the_export_holds_the_shipped_requirements_and_their_components():
    doc = json.loads(Path(EXPORT).read_text(encoding="utf-8"))
    ids = [r["reqid"] for r in doc["requirements"]]
    assert ids == ["R1", "R2", "R3", "R4", "R5", "R6", "R8", "R9", "R10", "R11"]
    kinds = {(v["component_name"], v["variable_name"]): v["idType"] for v in doc["variables"]}
    assert kinds[("safety_system", "stop_requested")] == "Output"
    assert kinds[("agilex_agent", "too_close")] == "Input"


def _project(tmp_path: Path) -> str:
    """A project of two components: ``ctrl`` sets ``o`` from ``a``; ``mon`` reads ``o`` (an
    Input there) and sets ``w``; ``mon``'s two requirements conflict (``w`` and ``!w``
    whenever ``o``, which the environment sets for ``mon``)."""
    def var(comp: str, name: str, kind: str) -> dict:
        return {"project": "P", "component_name": comp, "variable_name": name,
                "idType": kind, "dataType": "boolean"}
    doc = {"requirements": [
        {"reqid": "C1", "project": "P", "fulltext": "whenever a ctrl shall immediately satisfy o"},
        {"reqid": "M1", "project": "P", "fulltext": "whenever o mon shall immediately satisfy w"},
        {"reqid": "M2", "project": "P", "fulltext": "whenever o mon shall immediately satisfy !w"},
        {"reqid": "M3", "project": "P", "fulltext": "mon shall always satisfy w | !w"}],
        "variables": [var("ctrl", "a", "Input"), var("ctrl", "o", "Output"),
                      var("mon", "o", "Input"), var("mon", "w", "Output")]}
    path = tmp_path / "project.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return str(path)


def test_the_whole_project_is_fret_s_table_one_component_at_a_time(tmp_path):
    path = _project(tmp_path)
    got = _run("check", path, "--json", "--no-redundancy")
    assert got.exit_code == 1, got.output
    doc = json.loads(got.output)
    rows = {r["component"]: r for r in doc["fret_components"]}
    assert list(rows) == ["ctrl", "mon"]
    assert rows["ctrl"]["requirements"] == ["C1"]
    assert rows["ctrl"]["realizability"] == "realizable" and rows["ctrl"]["exit_code"] == 0
    assert rows["mon"]["requirements"] == ["M1", "M2", "M3"]
    assert rows["mon"]["realizability"] == "unrealizable"
    assert rows["mon"]["conflicts"] == [["M1", "M2"]]
    # each component with its own inputs and outputs (o: ctrl's output, mon's input)
    assert rows["ctrl"]["check"]["realizability"]["outputs"] == ["o"]
    assert rows["mon"]["check"]["realizability"]["inputs"] == ["o"]
    text = _run("check", path, "--no-redundancy").output
    assert "== component ctrl: C1" in text and "== component mon: M1, M2, M3" in text
    assert "conflict {M1, M2}" in text and "2 components: 1 realizable, 1 unrealizable" in text


def test_a_component_is_judged_alone_whatever_else_the_project_holds(tmp_path):
    """``--component mon`` checks M1..M3 only (FRET's component), with mon's interface: the
    same answer as mon's row of the whole project, and ctrl's requirement never in it."""
    path = _project(tmp_path)
    got = _run("check", path, "--component", "mon", "--json", "--no-redundancy")
    doc = json.loads(got.output)
    assert got.exit_code == 1 and [r["id"] for r in doc["requirements"]] == ["M1", "M2", "M3"]
    whole = json.loads(_run("check", path, "--json", "--no-redundancy").output)
    mon = next(r for r in whole["fret_components"] if r["component"] == "mon")
    assert doc["findings"] == mon["check"]["findings"]
    got = _run("check", path, "--component", "ctrl")
    assert got.exit_code == 0 and "M1" not in got.output, got.output


def test_a_shield_is_one_component_s(tmp_path):
    got = _run("shield", _project(tmp_path))
    assert got.exit_code == 2, got.output
    assert "--component" in got.output and "ctrl, mon" in got.output
    got = _run("shield", EXPORT, "-b", BINDINGS)
    assert got.exit_code == 2 and "agilex_agent, safety_system" in got.output, got.output


def test_a_component_takes_its_inputs_and_outputs(tmp_path):
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system",
               "--emit", "ros2", "-o", str(tmp_path / "out"))
    assert got.exit_code == 0, got.output
    assert ("inputs too_close, scan_stale, clearance, obstacle_ahead, obstacle_behind; outputs "
            "stopped, stop_requested, forwarded_zero, linear_speed, angular_speed, "
            "linear_velocity") in got.output
    node = (tmp_path / "out" / "safe_ros_shield_ros2" / "safe_ros_shield_ros2" /
            "shield_node.py").read_text()
    assert "PERIOD_NS = 100000000" in node  # (the period of -b: the export declares none)
    got = _run("check", EXPORT, "-b", BINDINGS, "--component", "safety_system", "--json")
    doc = json.loads(got.output)
    assert got.exit_code == 1 and doc["realizability"]["outputs"][:2] == ["stopped",
                                                                         "stop_requested"]
    assert "R1" not in [r["id"] for r in doc["requirements"]]


def test_only_and_exclude_select_and_name_what_they_do_not_know():
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system",
               "--only", "R2,R3")
    assert got.exit_code == 0 and "enforces R2, R3:" in got.output, got.output
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system",
               "--only", "R2,R7")
    assert got.exit_code == 2 and "--only/--exclude name R7: no requirement" in got.output
    got = _run("check", EXPORT, "-b", BINDINGS, "--component", "nobody")
    assert got.exit_code == 2 and "no requirement of that component" in got.output
    assert "safety_system" in got.output


def test_an_undeclared_variable_is_named_with_its_component(tmp_path):
    doc = json.loads(Path(_project(tmp_path)).read_text(encoding="utf-8"))
    doc["requirements"].append({"reqid": "C2", "project": "P",
                                "fulltext": "ctrl shall always satisfy k | o"})
    doc["variables"].append({"project": "P", "component_name": "ctrl", "variable_name": "k",
                             "idType": "Internal", "dataType": "boolean"})
    path = tmp_path / "p2.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    got = _run("shield", str(path), "--component", "ctrl")
    assert got.exit_code == 2, got.output
    assert "k is an Internal variable of ctrl in FRET's export" in got.output


def test_the_audit_of_a_shielded_run_judges_the_export(tmp_path):
    from fretc.sim.run import record

    folder = tmp_path / "shield"
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system",
               "--emit", "python", "-o", str(folder))
    assert got.exit_code == 0, got.output
    log = tmp_path / "run.mcap"
    record("sif_disabled", output=log, safety=f"shield:{folder}")
    got = _run("audit", "-r", EXPORT, "-b", BINDINGS, str(log), "--no-progress")
    assert got.exit_code == 0, got.output
    assert "0 violated" in got.output


def test_a_component_not_checked_counts_as_unknown_and_names_the_cause(tmp_path):
    """A component whose Internal variable fretc cannot read (a definition outside FRET's
    Lustre subset) is not checked, its row naming that cause; the project exits with the
    worst result of the others, the component counted as unknown (1), never 2."""
    doc = json.loads(Path(_project(tmp_path)).read_text(encoding="utf-8"))
    doc["requirements"] = [r for r in doc["requirements"] if r["reqid"] in ("C1", "M3")]
    doc["requirements"].append({"reqid": "M4", "project": "P",
                                "fulltext": "mon shall always satisfy k | w"})
    doc["variables"].append({"project": "P", "component_name": "mon", "variable_name": "k",
                             "idType": "Internal", "dataType": "boolean",
                             "assignment": "current o"})
    path = tmp_path / "p3.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    got = _run("check", str(path), "--json", "--no-redundancy")
    rows = {r["component"]: r for r in json.loads(got.output)["fret_components"]}
    assert rows["ctrl"]["realizability"] == "realizable"
    assert rows["mon"]["realizability"] == "not checked" and rows["mon"]["exit_code"] == 2
    assert "k: FRET defines it, but its definition is outside FRET's Lustre subset" in \
        rows["mon"]["reason"], rows["mon"]["reason"]
    assert got.exit_code == 1, got.output
