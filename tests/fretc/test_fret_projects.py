"""FRET projects end to end: a FRET export of the Safe-ROS requirements
(``requirements/fret/safe_ros.json``, its variables declared per component as FRET's Analysis
Portal declares them) through ``fretc check``, ``fretc shield`` (with ``--emit ros2``) and
``fretc audit``.

FRET declares a variable per component: the stop request is an Output of the safety system
and an Input of the interceptor. Both commands refused the export ("declared both input and
output", no component named); ``--component NAME`` takes one component's inputs and outputs,
the refusal without it names the variable and both components, an undeclared variable is
named with its component, ``--only``/``--exclude`` select requirements (R1, unbounded, is
left out of a shield), and ``--emit ros2`` works from the export with ``-b`` giving the
period.
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
    assert kinds[("cmd_vel_interceptor", "stop_requested")] == "Input"


def test_without_a_component_both_commands_name_the_variable_and_its_components():
    for cmd in (["check", EXPORT, "-b", BINDINGS], ["shield", EXPORT, "-b", BINDINGS]):
        got = _run(*cmd)
        assert got.exit_code == 2, got.output
        assert ("stop_requested is an Output of safety_system and an Input of "
                "cmd_vel_interceptor") in got.output and "--component" in got.output


def test_a_component_takes_its_inputs_and_outputs_and_r1_is_left_out(tmp_path):
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system")
    assert got.exit_code == 2 and "R1 is not a safety property" in got.output, got.output
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system",
               "--exclude", "R1", "--emit", "ros2", "-o", str(tmp_path / "out"))
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


def test_an_undeclared_variable_is_named_with_its_component():
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "agilex_agent",
               "--exclude", "R1")
    assert got.exit_code == 2, got.output
    assert "stop_requested is an Input variable of cmd_vel_interceptor in FRET's export" \
        in got.output


def test_the_audit_of_a_shielded_run_judges_the_export(tmp_path):
    from fretc.sim.run import record

    folder = tmp_path / "shield"
    got = _run("shield", EXPORT, "-b", BINDINGS, "--component", "safety_system",
               "--exclude", "R1", "--emit", "python", "-o", str(folder))
    assert got.exit_code == 0, got.output
    log = tmp_path / "run.mcap"
    record("sif_disabled", output=log, safety=f"shield:{folder}")
    got = _run("audit", "-r", EXPORT, "-b", BINDINGS, str(log), "--no-progress")
    assert got.exit_code == 0, got.output
    assert "0 violated" in got.output
