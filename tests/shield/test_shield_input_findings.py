"""The shield's findings on hostile inputs, each from its smallest input: a free-form requirement
(I1: an internal error), generated forms that did not load and exit 0 (I4: a constant
``1e309``, outputs named after ``<math.h>``'s macros, a group of one ``Bool`` output),
``--emit ros2`` with a message type that does not exist and its partial output (D2, D3),
a whole-number output given ``-inf`` (D8), and ``--explain``'s wording for ``whenever`` (D4)."""

from __future__ import annotations

import math
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import load_shield, render_python, tables
from fretc.shield.runtime import ShieldRuntime

from _c_monitors import build as build_c, needs_cc, write

REPO = Path(__file__).resolve().parents[2]
SAFE_ROS_B = REPO / "requirements" / "safe_ros.bindings.toml"


def _shield_cli(*args: str):
    return CliRunner().invoke(main, ["shield", *args])


def _file(tmp_path: Path, text: str, name: str = "r.fret") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_i1_a_free_form_requirement_is_an_input_error_naming_it(tmp_path):
    f = _file(tmp_path, 'R1: whenever a sw shall immediately satisfy x\n'
                        'R2: "the robot is kind to people"\n')
    got = _shield_cli(str(f), "--inputs", "a", "--outputs", "x")
    assert got.exit_code == 2, got.output
    assert "internal error" not in got.output
    assert f"{f}:2: R2 is free-form text" in got.output, got.output


def test_i4_a_constant_no_double_holds_gives_forms_that_load_and_build(tmp_path):
    """``v < 1e309``: the constant is infinite in doubles; the forms wrote a bare ``inf``
    (a NameError in Python, an undeclared name in C) and exited 0."""
    compiled = compile_entries(load_requirements([_file(
        tmp_path, "R1: whenever a sw shall immediately satisfy v < 1e309 & w > -1e309\n")]))
    shield = build_shield(compiled, ["a"], ["v", "w"], fork=False, name="big")
    sh = load_shield(render_python(shield))()
    assert not sh.step({"a": True}, {"v": 1e300, "w": -1e300}).overridden
    needs_cc()
    write(render_c(shield, "big"), tmp_path / "c")
    build_c(tmp_path / "c", ["big_shield.c", "big_shield_run.c"], "run")


def test_i4_outputs_named_after_c_macros_build(tmp_path):
    """Outputs named ``NAN``, ``INFINITY``, ``errno``, ``EOF``, ``MAX_ATOMS``: macros of the
    standard headers (and of the generated file) that a field of that name expands; the C
    fields are renamed, with the FRET name beside them."""
    needs_cc()
    names = ["NAN", "INFINITY", "errno", "EOF", "MAX_ATOMS", "stdout"]
    text = "".join(f"R{k}: whenever a sw shall immediately satisfy {n} > {k}\n"
                   for k, n in enumerate(names))
    compiled = compile_entries(load_requirements([_file(tmp_path, text)]))
    shield = build_shield(compiled, ["a"], names, fork=False, name="m")
    files = render_c(shield, "m")
    assert "double NAN_; /* FRET's NAN */" in files["m_shield.h"]
    write(files, tmp_path / "c")
    build_c(tmp_path / "c", ["m_shield.c", "m_shield_run.c"], "run")


def test_i4_a_group_of_one_boolean_output_builds_with_werror(tmp_path):
    """R6 alone with Safe-ROS's bindings: ``stop_requested`` is the only output of
    ``/gwendolen_control`` (a ``Bool``); its group's tables were written and never read,
    which ``-Werror`` refuses."""
    needs_cc()
    f = _file(tmp_path, "@tick_period 100 ms\nR6: whenever scan_stale safety_system shall "
                        "within 500 milliseconds satisfy stop_requested\n")
    out = tmp_path / "out"
    got = _shield_cli(str(f), "-b", str(SAFE_ROS_B), "--inputs", "scan_stale", "--outputs",
                      "stop_requested", "--emit", "c", "-o", str(out))
    assert got.exit_code == 0, got.output
    build_c(out, ["r_shield.c", "r_shield_run.c"], "run")


def _safe_ros_with_types(tmp_path: Path, scan_type: str) -> Path:
    text = SAFE_ROS_B.read_text(encoding="utf-8").replace(
        '"/scan" = "sensor_msgs/msg/LaserScan", "/cmd_vel"',
        f'"/scan" = "{scan_type}", "/cmd_vel"')
    return _file(tmp_path, text, "b.bindings.toml")


def test_d2_d3_a_message_type_that_does_not_exist_is_refused_and_nothing_is_written(tmp_path):
    b = _safe_ros_with_types(tmp_path, "sensor_msgs/msg/LaserScann")
    out = tmp_path / "out"
    got = _shield_cli(str(REPO / "requirements" / "safe_ros.fret"), "-b", str(b), "--inputs",
                      "too_close,scan_stale,clearance", "--outputs",
                      "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed",
                      "--emit", "python", "--emit", "c", "--emit", "ros2", "-o", str(out))
    assert got.exit_code == 2, got.output
    assert "sensor_msgs/msg/LaserScann" in got.output and "/scan" in got.output, got.output
    assert not out.exists() or not any(out.iterdir()), sorted(out.rglob("*"))


def test_d8_a_whole_number_output_never_passes_minus_infinity(tmp_path):
    """A FRET export's ``integer`` output compared with a constant: ``-inf`` kept its truths
    (``gear < 3``) and went out as it came (Python and C); it is a proposal no actuator
    takes: replaced by a whole number that keeps them."""
    import json

    export = _file(tmp_path, json.dumps({
        "requirements": [{"reqid": "R1", "fulltext": "whenever go sw shall immediately "
                                                     "satisfy gear < 3"}],
        "variables": [{"variable_name": "go", "dataType": "boolean", "idType": "Input"},
                      {"variable_name": "gear", "dataType": "integer",
                       "idType": "Output"}]}), "gear.json")
    shield = build_shield(compile_entries(load_requirements([export])), ["go"], ["gear"],
                          fork=False)
    assert shield.integers == ("gear",)
    rt = ShieldRuntime(tables(shield))
    for x in (-math.inf, math.inf):
        d = rt.step({"go": True}, {"gear": x})
        g = d.outputs["gear"]
        assert math.isfinite(g) and g == math.floor(g) and g < 3 and d.overridden, d
    needs_cc()
    write(render_c(shield, "g"), tmp_path / "c")
    exe = build_c(tmp_path / "c", ["g_shield.c", "g_shield_run.c"], "run")
    import subprocess

    got = subprocess.run([str(exe)], input="go,gear\ntrue,-inf\nfalse,-inf\n",
                         capture_output=True, text=True, timeout=60)
    rows = got.stdout.splitlines()[1:]
    assert got.returncode == 0 and all(",-inf" not in r for r in rows), got.stdout
    assert all(r.endswith(",proposal") for r in rows), got.stdout


def test_d4_explain_of_whenever_says_what_it_means(tmp_path):
    f = _file(tmp_path, "A: whenever i1 c shall immediately satisfy o1\n"
                        "B: whenever i2 c shall within 3 ticks satisfy o2\n"
                        "C: upon i1 c shall within 2 ticks satisfy o3\n")
    got = _shield_cli(str(f), "--inputs", "i1,i2", "--outputs", "o1,o2,o3", "--explain")
    assert got.exit_code == 0, got.output
    assert "A: o1 must hold at every tick at which i1 holds" in got.output, got.output
    assert ("B: o2 may wait up to 3 ticks after each tick at which i2 holds"
            in got.output), got.output
    assert "C: o3 may wait up to 2 ticks after i1 becomes true" in got.output, got.output
    assert "after i1 becomes true" not in got.output.split("C: ")[0]
    assert "after i2 becomes true" not in got.output
