"""``fretc shield-replay`` with bindings that tick once per message of a topic (``[tick]
topic``, docs/guide/shield-replay.md "How the shield is stepped"), on a shipped trace:
the simulator's ``lidar_dropout`` run, ticking on the controller's ``/cmd_vel`` (10 Hz, 50 ms
off the period's grid) while ``/scan`` drops out for up to 3.1 s.

Differential: the corrected outputs written at each tick are those of the generated Python
form stepped by hand over the same messages (read by the ``mcap`` library and
``rosbags``, not by fretc's readers; the inputs computed here from the ranges, REP 117),
one tick per ``/cmd_vel`` message at its log time, a tick hearing every message of its log
time or earlier, as ``tests/shield/test_replay_tb3.py`` does for the period's grid."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from test_replay_tb3 import REQUIREMENTS, atoms, outputs_on, published, twist_values, valid_min

from _replay import python_shield
from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
TRACE = REPO / "traces" / "lidar_dropout.mcap"

# The simulated Scout Mini's LiDAR: 720 beams from -pi; ahead is beams 270..450 (-45..+45
# degrees), as requirements/shield/safe_ros_shield.bindings.toml reads it.
INPUTS = """too_close = "min(/scan.ranges) < 0.25"
obstacle_ahead = "min(/scan.ranges[270:451]) < 0.5"
scan_stale = "age(/scan) > 0.3"
"""

BINDINGS = ("[tick]\ntopic = \"/cmd_vel\"\nnominal_rate = \"10 Hz\"\ntime = \"log\"\n\n"
            "[variables]\n" + INPUTS + outputs_on("/cmd_vel_filtered", "/stop_request")
            + "\n[shield]\nproposals = { \"/cmd_vel_filtered\" = \"/cmd_vel\" }\n"
            "originates = [\"/stop_request\"]\n"
            "types = { \"/stop_request\" = \"std_msgs/msg/Bool\" }\n")


@pytest.fixture(scope="module")
def replayed(tmp_path_factory):
    """(the shield folder, the output folder, the replay's JSON run)."""
    tmp = tmp_path_factory.mktemp("tick_topic")
    python_shield(tmp, "r", REQUIREMENTS, BINDINGS)
    got = CliRunner().invoke(main, ["shield-replay", str(tmp / "shield"), str(TRACE), "-o",
                                    str(tmp / "out"), "-r", str(tmp / "r.fret"), "--json",
                                    str(tmp / "replay.json")])
    assert got.exit_code in (0, 1), got.output
    return tmp / "shield", tmp / "out", json.loads((tmp / "replay.json").read_text())["runs"][0]


def trace_messages(path: Path):
    """(topic, log time ns, message or None) of an MCAP file in log-time order, by the mcap
    library; /scan and /cmd_vel deserialized by rosbags."""
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    with open(path, "rb") as f:
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            data = (store.deserialize_cdr(m.data, schema.name)
                    if channel.topic in ("/scan", "/cmd_vel") else None)
            yield channel.topic, m.log_time, data


def stepped_by_hand(shield_dir: Path) -> tuple[dict, int]:
    """(tick time -> the Python form's decided outputs as a message gives them, the ticks
    whose scan was stale): one tick per /cmd_vel message, stepped once every message of
    its log time or earlier was heard."""
    module = next(shield_dir.glob("*_shield.py"))
    spec = importlib.util.spec_from_file_location(module.stem, module)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    shield = mod.Shield()
    state: dict = {"scan": None, "scan_time": None, "twist": None}
    decided: dict[int, dict] = {}
    stale = 0

    def step(t: int) -> None:
        nonlocal stale
        scan = state["scan"]
        if scan is None:
            decided[t] = published(shield.fault("input too_close: no /scan yet", {}),
                                   (0.0,) * 6)
            return
        inputs = {"too_close": valid_min(scan, 0, len(scan.ranges)) < 0.25,
                  "obstacle_ahead": valid_min(scan, 270, 451) < 0.5,
                  "scan_stale": (t - state["scan_time"]) / 1e9 > 0.3}
        stale += inputs["scan_stale"]
        proposal = state["twist"]
        proposed = twist_values(*proposal)
        proposed["stop_requested"] = False  # (no proposal topic: the default Bool)
        decided[t] = published(shield.step(inputs, proposed), proposal)

    pending: list[int] = []
    for topic, t, data in trace_messages(TRACE):
        while pending and pending[0] < t:
            step(pending.pop(0))
        if topic == "/scan":
            state["scan"], state["scan_time"] = data, t
        elif topic == "/cmd_vel":
            state["twist"] = (data.linear.x, data.linear.y, data.linear.z, data.angular.x,
                              data.angular.y, data.angular.z)
            pending.append(t)
    for t in pending:
        step(t)
    return decided, stale


def test_one_tick_per_message_of_the_tick_topic_is_the_python_form_stepped_by_hand(
        replayed):
    from rosbags.typesys import Stores, get_typestore

    shield_dir, out, doc = replayed
    store = get_typestore(Stores.ROS2_JAZZY)
    want, stale = stepped_by_hand(shield_dir)
    commands = [t for topic, t, _d in trace_messages(TRACE) if topic == "/cmd_vel"]
    # one tick per /cmd_vel message, at its log time: off the 100 ms grid
    assert sorted(want) == commands and doc["ticks"] == len(commands) > 700
    assert all(t % 100_000_000 == 50_000_000 for t in commands)
    assert stale > 10  # (the LiDAR's dropouts: R6's input true at some ticks)
    from mcap.reader import make_reader

    got: dict[int, dict] = {}
    with open(out / "lidar_dropout.shielded.mcap", "rb") as f:
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            if channel.topic == "/cmd_vel_filtered":
                x = store.deserialize_cdr(m.data, schema.name)
                got.setdefault(m.log_time, {}).update(twist_values(
                    x.linear.x, x.linear.y, x.linear.z, x.angular.x, x.angular.y,
                    x.angular.z))
            elif channel.topic == "/stop_request":
                got.setdefault(m.log_time, {})["stop_requested"] = bool(
                    store.deserialize_cdr(m.data, schema.name).data)
    assert sorted(got) == sorted(want)  # one message of each output topic a tick
    witnessed = {t for t in want if want[t].get("witness")}
    differ = {t: (got[t], want[t]) for t in want
              if (atoms(got[t]) if t in witnessed else got[t])
              != {k: v for k, v in want[t].items() if k != "witness"}}
    assert not differ, list(differ.items())[:3]
    assert len(witnessed) < len(want) // 10  # (the numbers of the others compared exactly)
    # the shield corrected the controller on this run (it drives past 0.22 m/s)
    assert doc["overridden"]["ticks"] > 100
