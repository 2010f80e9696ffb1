"""``fretc shield-replay`` on a real robot's recording (``../shared/data/foreign_logs/
fuse_tb3/turtlebot3.bag``: a TurtleBot3 with ``/scan`` and ``/cmd_vel``, ROS 1): the
corrected outputs written are those of the generated Python form stepped by hand over the
same messages (read by ``rosbags``, not by fretc's readers; the inputs computed here from
the ranges, REP 117); every recorded message is in the shielded MCAP unchanged (the
``mcap`` library's reading); the shielded run audits satisfied where the recorded one
(the controller's commands as driven) is violated."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from _replay import python_shield
from fretc.cli import main

BAG = "data/foreign_logs/fuse_tb3/turtlebot3.bag"
PERIOD = 100_000_000  # ns: the requirements' tick (@tick_period 100 ms)

REQUIREMENTS = """@tick_period 100 ms
@inputs too_close, scan_stale, obstacle_ahead
@outputs stopped, stop_requested, forwarded_zero, linear_speed, angular_speed, linear_velocity

R2: upon too_close turtlebot shall within 1 second satisfy stopped
R3: whenever stop_requested turtlebot shall immediately satisfy forwarded_zero
R4: the turtlebot shall always satisfy linear_speed <= 0.22 & angular_speed <= 0.3
R6: whenever scan_stale turtlebot shall within 500 milliseconds satisfy stop_requested
R9: whenever obstacle_ahead turtlebot shall immediately satisfy linear_velocity <= 0
"""

# The TurtleBot3's LiDAR: 360 beams from 0 rad (ahead) counter-clockwise; ahead is the
# 90-degree sector of beams 315..359 and 0..45.
INPUTS = """too_close = "min(/scan.ranges) < 0.25"
obstacle_ahead = "min(/scan.ranges[:46]) < 0.5 | min(/scan.ranges[315:]) < 0.5"
scan_stale = "age(/scan) > 0.3"
"""


def outputs_on(topic: str, stop: str) -> str:
    """The output variables bound to the Twist ``topic`` and the Bool ``stop``."""
    return f"""stopped = "abs({topic}.linear.x) < 1e-3 & abs({topic}.angular.z) < 1e-3"
stop_requested = "{stop}.data"
forwarded_zero = "{topic}.linear.x = 0 & {topic}.linear.y = 0 & {topic}.linear.z = 0 & {topic}.angular.x = 0 & {topic}.angular.y = 0 & {topic}.angular.z = 0"
linear_speed = "abs({topic}.linear.x)"
angular_speed = "abs({topic}.angular.z)"
linear_velocity = "{topic}.linear.x"
"""


BINDINGS = ("[tick]\nperiod = \"100 ms\"\ntime = \"log\"\n\n[variables]\n" + INPUTS
            + outputs_on("/cmd_vel_filtered", "/stop_request")
            + "\n[shield]\nproposals = { \"/cmd_vel_filtered\" = \"/cmd_vel\" }\n"
            "originates = [\"/stop_request\"]\n"
            "types = { \"/stop_request\" = \"std_msgs/msg/Bool\" }\n")


@pytest.fixture(scope="module")
def replayed(tmp_path_factory):
    """(the recording, the shield folder, the output folder, the replay's JSON)."""
    from _shared import PRESENT, REASON, SHARED

    if not PRESENT:
        pytest.skip(REASON)
    tmp = tmp_path_factory.mktemp("tb3")
    python_shield(tmp, "tb3", REQUIREMENTS, BINDINGS)
    bag = SHARED / BAG
    got = CliRunner().invoke(main, ["shield-replay", str(tmp / "shield"), str(bag), "-o",
                                    str(tmp / "out"), "-r", str(tmp / "tb3.fret"), "--json",
                                    str(tmp / "replay.json")])
    assert got.exit_code == 0, got.output
    return bag, tmp / "shield", tmp / "out", json.loads((tmp / "replay.json").read_text())


def bag_messages(bag: Path):
    """(topic, log time ns, raw bytes, message) of the bag in time order, by rosbags."""
    from rosbags.rosbag1 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    with Reader(bag) as reader:
        for c, t, raw in reader.messages():
            data = (store.deserialize_ros1(raw, c.msgtype)
                    if c.topic in ("/scan", "/cmd_vel") else None)
            yield c.topic, int(t), bytes(raw), data


def mcap_messages(path: Path):
    """(topic, log time ns, bytes, schema) of an MCAP file, by the mcap library."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            yield channel.topic, message.log_time, bytes(message.data), schema


def valid_min(scan, lo: int, hi: int) -> float:
    """The least valid range of beams [lo, hi) (REP 117: finite, within range_min and
    range_max), +inf when none is valid."""
    r = np.asarray(scan.ranges[lo:hi], dtype=float)
    ok = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    return float(r[ok].min()) if ok.any() else math.inf


def twist_values(lx: float, ly: float, lz: float, ax: float, ay: float, az: float) -> dict:
    return {"stopped": abs(lx) < 1e-3 and abs(az) < 1e-3,
            "forwarded_zero": lx == 0 and ly == 0 and lz == 0 and ax == 0 and ay == 0
            and az == 0, "linear_speed": abs(lx), "angular_speed": abs(az),
            "linear_velocity": lx}


def published(d, proposal: tuple) -> dict:
    """The outputs the message of decision ``d`` on the proposed Twist ``proposal`` gives
    (docs/guide/shield.md, "The ROS 2 node"): the decided booleans; each number set through
    its binding, the proposal's sign kept (``abs(angular.z)``); where two outputs read one
    field (``linear_speed = abs(linear.x)``, ``linear_velocity = linear.x``) the one whose
    atom the decision changed decides it, so both give the decided atoms (asserted)."""
    out = d.outputs
    az = proposal[5]
    if abs(out["linear_velocity"]) == out["linear_speed"] or \
            any(c.lstrip("(").startswith("linear_velocity") for c in d.changed):
        x = out["linear_velocity"]
    else:
        x = math.copysign(out["linear_speed"], out["linear_velocity"])
    values = {"stopped": out["stopped"], "forwarded_zero": out["forwarded_zero"],
              "stop_requested": out["stop_requested"], "linear_speed": abs(x),
              "angular_speed": abs(math.copysign(out["angular_speed"], az)),
              "linear_velocity": x}
    for v, c in (("linear_speed", 0.22), ("angular_speed", 0.3), ("linear_velocity", 0)):
        assert (values[v] <= c) == (out[v] <= c), (v, d)
    made = twist_values(x, *proposal[1:5], math.copysign(out["angular_speed"], az))
    if (made["stopped"], made["forwarded_zero"]) != (out["stopped"], out["forwarded_zero"]):
        # no Twist with these numbers gives the decided booleans (stopped false with both
        # speeds zero): the message is the one the bindings' inversion gives for the
        # valuation (its own numbers), so only the atoms are the decision's
        return {**atoms(values), "witness": True}
    return values


def atoms(values: dict) -> dict:
    """The truth of each output atom of the requirements for the outputs ``values``."""
    return {"stopped": values["stopped"], "forwarded_zero": values["forwarded_zero"],
            "stop_requested": values["stop_requested"],
            "linear_speed <= 0.22": values["linear_speed"] <= 0.22,
            "angular_speed <= 0.3": values["angular_speed"] <= 0.3,
            "linear_velocity <= 0": values["linear_velocity"] <= 0}


def stepped_by_hand(bag: Path, shield_dir: Path):
    """tick time -> the Python form's decided outputs (as a message gives them:
    :func:`published`), stepped over the bag's messages on
    the 100 ms grid (a tick hears every message of its time or earlier), from the first
    /scan or /cmd_vel to the bag's last message."""
    module = next(shield_dir.glob("*_shield.py"))
    spec = importlib.util.spec_from_file_location(module.stem, module)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    shield = mod.Shield()
    scan = scan_time = twist = None
    decided = {}
    tick = None
    last = 0

    def step(t):
        if scan is None:  # (no scan yet: the inputs cannot be read, the fallback's)
            d = shield.fault("input too_close: no /scan yet", {})
            decided[t] = published(d, (0.0,) * 6)
            return
        inputs = {"too_close": valid_min(scan, 0, len(scan.ranges)) < 0.25,
                  "obstacle_ahead": valid_min(scan, 0, 46) < 0.5
                  or valid_min(scan, 315, len(scan.ranges)) < 0.5,
                  "scan_stale": (t - scan_time) / 1e9 > 0.3}
        proposal = twist if twist is not None else (0.0,) * 6
        proposed = twist_values(*proposal)
        proposed["stop_requested"] = False  # (no proposal topic: the default Bool)
        decided[t] = published(shield.step(inputs, proposed), proposal)

    for topic, t, _raw, data in bag_messages(bag):
        last = t
        if topic not in ("/scan", "/cmd_vel"):
            continue
        if tick is None:
            tick = -(-t // PERIOD) * PERIOD
        while tick < t:
            step(tick)
            tick += PERIOD
        if topic == "/scan":
            scan, scan_time = data, t
        else:
            twist = (data.linear.x, data.linear.y, data.linear.z, data.angular.x,
                     data.angular.y, data.angular.z)
    end = -(-last // PERIOD) * PERIOD
    while tick <= end:
        step(tick)
        tick += PERIOD
    return decided


def test_written_outputs_are_the_python_form_stepped_by_hand(replayed):
    from rosbags.typesys import Stores, get_typestore

    bag, shield_dir, out, doc = replayed
    store = get_typestore(Stores.ROS2_JAZZY)
    want = stepped_by_hand(bag, shield_dir)
    got: dict[int, dict] = {}
    for topic, t, data, schema in mcap_messages(out / "turtlebot3.shielded.mcap"):
        if topic == "/cmd_vel_filtered":
            m = store.deserialize_cdr(data, schema.name)
            got.setdefault(t, {}).update(twist_values(m.linear.x, m.linear.y, m.linear.z,
                                                      m.angular.x, m.angular.y, m.angular.z))
        elif topic == "/stop_request":
            got.setdefault(t, {})["stop_requested"] = bool(
                store.deserialize_cdr(data, schema.name).data)
    assert sorted(got) == sorted(want)  # one message of each output topic a tick
    assert len(want) == doc["runs"][0]["ticks"] > 900
    witnessed = {t for t in want if want[t].get("witness")}
    differ = {t: (got[t], want[t]) for t in want
              if (atoms(got[t]) if t in witnessed else got[t])
              != ({k: v for k, v in want[t].items() if k != "witness"})}
    assert not differ, list(differ.items())[:3]
    assert len(witnessed) < 10  # (the numbers of all other ticks compared exactly)
    # the shield did correct the controller: the run's proposals broke R4 and R9
    overrides = doc["runs"][0]["overrides"]
    assert overrides["R4"]["ticks"] > 100 and overrides["R9"]["ticks"] > 10


def test_every_recorded_message_is_kept_unchanged(replayed):
    bag, _shield, out, doc = replayed
    recorded: dict[str, list] = {}
    for topic, t, raw, _data in bag_messages(bag):
        recorded.setdefault(topic, []).append((t, raw))
    written: dict[str, list] = {}
    schemas: dict[str, tuple] = {}
    for topic, t, data, schema in mcap_messages(out / "turtlebot3.shielded.mcap"):
        written.setdefault(topic, []).append((t, data))
        schemas[topic] = (schema.name, schema.encoding)
    for topic, messages in recorded.items():
        assert written[topic] == messages, topic  # count, log times and bytes
    assert set(written) - set(recorded) == {"/cmd_vel_filtered", "/stop_request"}
    assert schemas["/scan"] == ("sensor_msgs/LaserScan", "ros1msg")
    assert schemas["/cmd_vel_filtered"] == ("geometry_msgs/msg/Twist", "ros2msg")
    assert doc["runs"][0]["published"] == {"/cmd_vel_filtered": len(written["/cmd_vel_filtered"]),
                                           "/stop_request": len(written["/stop_request"])}


def test_the_shielded_run_audits_satisfied_where_the_recorded_run_is_violated(replayed,
                                                                              tmp_path):
    bag, _shield, out, doc = replayed
    shielded = {v["requirement"]: v["verdict"] for v in doc["runs"][0]["audit"]["verdicts"]}
    assert shielded == {"R2": "satisfied", "R3": "vacuous", "R4": "satisfied",
                        "R6": "vacuous", "R9": "satisfied"}
    # the recorded run: the controller's commands as the robot drove them (no shield)
    (tmp_path / "r.fret").write_text(
        "\n".join(line for line in REQUIREMENTS.splitlines() if not line.startswith(("R3",
                                                                                     "R6"))))
    (tmp_path / "unshielded.bindings.toml").write_text(
        "[tick]\nperiod = \"100 ms\"\ntime = \"log\"\n\n[variables]\n" + INPUTS
        + outputs_on("/cmd_vel", "/none").replace('stop_requested = "/none.data"\n', ""))
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "unshielded.bindings.toml"), str(bag),
                                    "--no-progress", "--json", str(tmp_path / "a.json")])
    assert got.exit_code == 1, got.output
    verdicts = {v["requirement"]: v["verdict"]
                for v in json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"]}
    assert verdicts == {"R2": "violated", "R4": "violated", "R9": "violated"}


def test_a_replay_without_proposals_is_never_a_silent_all_clear(tmp_path):
    """Hostile round 9: bindings as a user writes them, the outputs bound to the recorded
    ``/cmd_vel`` and no ``[shield] proposals``: the replay proposed the default Twist at
    every tick, published zeros, reported "0 overridden", an all-satisfied audit and exit
    0 (569 overridden ticks with the table). The recorded ``/cmd_vel`` is now its own
    proposal, and said; an output topic the recording does not hold and no table names is
    an input error naming it and the tables."""
    from _shared import PRESENT, REASON, SHARED

    if not PRESENT:
        pytest.skip(REASON)
    bag = SHARED / BAG
    (tmp_path / "tb3.fret").write_text(REQUIREMENTS)
    for name, stop, table, want in (
            ("own", "/stop_request", 'originates = ["/stop_request"]\n', 0),
            ("none", "/stop_request", "", 2)):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "b.toml").write_text(
            "[tick]\nperiod = \"100 ms\"\ntime = \"log\"\n\n[variables]\n" + INPUTS
            + outputs_on("/cmd_vel", stop) + "\n[shield]\n" + table
            + "types = { \"/stop_request\" = \"std_msgs/msg/Bool\" }\n")
        got = CliRunner().invoke(main, ["shield", str(tmp_path / "tb3.fret"), "-b",
                                        str(folder / "b.toml"), "--emit", "python", "-o",
                                        str(folder / "shield")])
        assert got.exit_code == 0, got.output
        got = CliRunner().invoke(main, ["shield-replay", str(folder / "shield"), str(bag),
                                        "-o", str(folder / "out"), "--json",
                                        str(folder / "r.json")])
        if want == 2:
            assert got.exit_code == 2, got.output
            assert "no proposal for /stop_request" in got.output
            assert "[shield] proposals" in got.output and "[shield] originates" in got.output
            assert not (folder / "out").exists() or not any((folder / "out").iterdir())
            continue
        assert got.exit_code in (0, 1), got.output
        doc = json.loads((folder / "r.json").read_text())["runs"][0]
        assert doc["own_proposals"] == ["/cmd_vel"], doc["own_proposals"]
        assert "proposals of /cmd_vel: its recorded messages" in got.output
        assert doc["overridden"]["ticks"] > 100, doc["overridden"]
