"""Every example of docs/bindings.md runs: each TOML block parses as a binding file (bare
``name = "expr"`` blocks as its ``[variables]``), and the section "Examples on a robot log"
audits logs written with rosbags (tests/_robot_logs.py: rosbag2 with MCAP storage and a ROS 1
bag) with verdicts and first violations equal to this test's own computation from the values
written."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.signals.bindings import parse_bindings

import _robot_logs as rl

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "bindings.md").read_text(encoding="utf-8")
ROBOT = DOC[DOC.index("## Examples on a robot log"):]
ROBOT = ROBOT[:ROBOT.find("\n## ", 5) if "\n## " in ROBOT[5:] else len(ROBOT)]


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


@pytest.mark.parametrize("k", range(len(_blocks(DOC, "toml"))))
def test_every_toml_example_parses_and_compiles(k):
    block = _blocks(DOC, "toml")[k]
    if not re.search(r"^\[", block, flags=re.M):  # bare variable lines
        block = "[variables]\n" + block
    if "[tick]" not in block:
        block = '[tick]\nperiod = "100 ms"\n' + block
    b = parse_bindings(block, f"docs/bindings.md block {k + 1}")
    if b.per_entity:  # one verdict per entity: they compile with an entity's value
        b = b.for_entity({name: "motor_left" for name in b.entities})
    assert b.variables or "[types]" in block or "[logs]" in block


def _expected(log: rl.RobotLog) -> dict[str, int | None]:
    """Requirement of the robot example -> time (ns) of its first violation, None when
    satisfied: computed from the values written, on the tick rules restated in
    :func:`_robot_logs.ticks`."""
    h = rl.held
    tf, diag = ["/tf", "/tf_static"], ["/diagnostics"]

    def level(t):
        return h(log, "/diagnostics", t)

    return {
        "B1": rl.first_false(log, ["/mode", "/battery"], lambda t: h(log, "/mode", t)
                             != "charging" or h(log, "/battery", t) == 1),
        "B2": rl.first_false(log, ["ORB-SLAM", "groundtruth"], lambda t: abs(
            h(log, "ORB-SLAM", t)[0] - h(log, "groundtruth", t)[0]) < 0.3),
        "B3": rl.first_false(log, tf, lambda t: rl.pose_in_map(log, t)[0] < 3.0),
        "B4": rl.first_false(log, tf, lambda t: rl.pose_in_map(log, t)[2] < 1.5),
        "B5": rl.first_false(log, tf, lambda t: rl.tf_age(log, t) <= 0.5),
        "B6": rl.first_false(log, ["/joint_states"],
                             lambda t: h(log, "/joint_states", t)["wheel_left_joint"] <= 6.0),
        "B7": rl.first_false(log, diag, lambda t: level(t) < 2),
        "B8": rl.first_false(log, diag, lambda t: level(t) < 3),
        "B9": rl.first_false(log, ["/mode"], lambda t: h(log, "/mode", t) != "charging"
                             or h(log, "/mode", t) not in ("navigating", "docking")),
    }


@pytest.mark.parametrize("ros1", [False, True], ids=["rosbag2-mcap", "ros1"])
def test_the_robot_log_example_audits_as_computed_independently(tmp_path, ros1):
    log = rl.write_robot_log(tmp_path, ros1=ros1)
    (bindings,) = _blocks(ROBOT, "toml")
    (fret,) = _blocks(ROBOT, "text")
    req = tmp_path / "req"
    req.mkdir()
    (req / "robot.fret").write_text(fret)
    (req / "robot.bindings.toml").write_text(bindings)
    res = CliRunner().invoke(main, ["audit", "--no-progress", "-r", str(req), str(log.path),
                                    "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 1, res.output
    assert "no requirement uses it" not in res.output  # every binding is exercised
    verdicts = {v["requirement"]: v for v in
                json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"]}
    want = _expected(log)
    assert sorted(verdicts) == sorted(want)  # every requirement has its computation
    for rid, first in want.items():
        v = verdicts[rid]
        assert v["verdict"] == ("satisfied" if first is None else "violated"), (rid, v["error"])
        if first is not None:
            assert v["first_violation"]["tick_time_ns"] == first, rid
    # the prose under the example says when each is violated
    said = dict(re.findall(r"(B\d) at ([\d.]+) s", ROBOT))
    assert len(said) == sum(t is not None for t in want.values())
    for rid, when in said.items():
        assert f"{(want[rid] - rl.T0) / rl.S:.1f}" == when, rid
