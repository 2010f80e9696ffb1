"""``fretc shield --emit ros2``: an ament_python package whose node reads the bound topics,
takes the proposal topic of ``[shield] proposals`` and publishes the corrected outputs and
its diagnostics (the live graph test is tests/live/test_ros2_graph.py); the form needs the
binding file's ``[types]``."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
ARGS = [str(REPO / "requirements" / "safe_ros.fret"), "--inputs",
        "too_close,scan_stale,clearance", "--outputs",
        "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed"]


def test_the_package_holds_the_node_the_shield_and_the_bindings(tmp_path):
    got = CliRunner().invoke(main, ["shield", *ARGS, "-b",
                                    str(REPO / "requirements" / "safe_ros.bindings.toml"),
                                    "--emit", "ros2", "-o", str(tmp_path)])
    assert got.exit_code == 0, got.output
    pkg = tmp_path / "safe_ros_shield_ros2"
    names = sorted(str(p.relative_to(pkg)) for p in pkg.rglob("*") if p.is_file())
    assert names == ["launch/safe_ros_shield_ros2.launch.py", "package.xml",
                     "resource/safe_ros_shield_ros2", "safe_ros_shield_ros2/__init__.py",
                     "safe_ros_shield_ros2/__main__.py",
                     "safe_ros_shield_ros2/safe_ros.bindings.toml",
                     "safe_ros_shield_ros2/safe_ros_shield.py",
                     "safe_ros_shield_ros2/shield_node.py", "setup.cfg", "setup.py"]
    node = (pkg / "safe_ros_shield_ros2" / "shield_node.py").read_text()
    tree = ast.parse(node)
    consts = {t.id: ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign)
              for t in n.targets if isinstance(t, ast.Name) and t.id.isupper()}
    assert consts["PROPOSALS"] == {"/cmd_vel_filtered": "/cmd_vel"}
    assert consts["INPUT_TOPICS"] == ["/scan"] and consts["TICK_TOPIC"] == "/scan"
    assert consts["OUTPUT_TOPICS"] == ["/cmd_vel_filtered", "/gwendolen_control"]
    assert consts["PERIOD_NS"] == 100_000_000
    xml = (pkg / "package.xml").read_text()
    for dep in ("rclpy", "sensor_msgs", "geometry_msgs", "std_msgs", "diagnostic_msgs"):
        assert f"<exec_depend>{dep}</exec_depend>" in xml
    # setup.py is a plain setuptools script: its name and entry point read back
    out = subprocess.run([sys.executable, "setup.py", "--name"], cwd=pkg, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip().splitlines()[-1] == "safe_ros_shield_ros2"


def test_without_types_the_form_is_refused(tmp_path):
    b = tmp_path / "b.bindings.toml"
    text = (REPO / "requirements" / "safe_ros.bindings.toml").read_text()
    b.write_text(text.split("types = {")[0], encoding="utf-8")
    got = CliRunner().invoke(main, ["shield", *ARGS, "-b", str(b), "--emit", "ros2", "-o",
                                    str(tmp_path / "out")])
    assert got.exit_code == 2 and "gives no ROS 2 type for" in got.output, got.output
    got = CliRunner().invoke(main, ["shield", *ARGS, "--emit", "ros2", "-o",
                                    str(tmp_path / "out2")])
    assert got.exit_code == 2 and "needs the binding file" in got.output, got.output


def test_the_node_meets_each_deadline_early_by_its_period_phase_and_latency(tmp_path):
    """On a bus the node's answers reach a reader up to a tick late (its sampling phase)
    plus the node's latency: the package's shield meets each deadline that many ticks
    early without a flag (100 ms ticks and the 20 ms budget: 2 ticks; a budget of 250 ms
    in [shield] latency_budget: 4), the node carries its margin and budget, and --prove
    states the timing and proves the node's shield too."""
    import fractions

    from fretc.shield.emit_ros2 import node_margin

    assert node_margin(fractions.Fraction(1, 10)) == 2
    assert node_margin(fractions.Fraction(1, 10), fractions.Fraction(1, 4)) == 4
    got = CliRunner().invoke(main, ["shield", *ARGS, "-b",
                                    str(REPO / "requirements" / "safe_ros.bindings.toml"),
                                    "--prove", "--emit", "ros2", "-o", str(tmp_path / "a")])
    assert got.exit_code == 0, got.output
    assert "each 'within' deadline is met 2 tick(s) early" in got.output
    assert "the ROS 2 node's shield (deadlines 2 tick(s) early): every enforced " \
           "requirement holds" in got.output
    pkg = tmp_path / "a" / "safe_ros_shield_ros2" / "safe_ros_shield_ros2"
    node = (pkg / "shield_node.py").read_text()
    assert "MARGIN_TICKS = 2" in node and "LATENCY_BUDGET_NS = 20000000" in node
    assert "upon too_close agilex_agent shall within 1 second satisfy stopped " \
           "[a deadline 2 tick(s) early: 8 ticks]" in (pkg / "safe_ros_shield.py").read_text()
    b = tmp_path / "b.bindings.toml"
    b.write_text((REPO / "requirements" / "safe_ros.bindings.toml").read_text().replace(
        "[shield]\n", '[shield]\nlatency_budget = "250 ms"\n'), encoding="utf-8")
    got = CliRunner().invoke(main, ["shield", *ARGS, "-b", str(b), "--emit", "ros2", "-o",
                                    str(tmp_path / "b")])
    assert got.exit_code == 0, got.output
    node = (tmp_path / "b" / "safe_ros_shield_ros2" / "safe_ros_shield_ros2" /
            "shield_node.py").read_text()
    assert "MARGIN_TICKS = 4" in node and "LATENCY_BUDGET_NS = 250000000" in node
