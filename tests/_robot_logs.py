"""A small robot log written with rosbags' writers, holding what real robots log and
bindings must reach: text (std_msgs/String ``/mode``), an enum
(BatteryState's ``power_supply_status``), topics named ``groundtruth`` and ``ORB-SLAM``, a
TF tree on ``/tf`` (two publishers: ``odom -> base_link`` at 20 Hz, ``map -> odom`` at
2 Hz) and ``/tf_static`` (``base_link -> laser``), a JointState whose joint order changes
between messages, and a DiagnosticArray whose statuses change order.

:func:`write_robot_log` writes it (rosbag2 with MCAP storage, or ROS 1) and returns
:class:`RobotLog`: what was written, message by message, so that a test computes the
expected verdicts on its own (:func:`held`, :func:`ticks`) and compares them with the audit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from collections.abc import Callable

from rosbags.typesys import Stores, get_typestore

S = 1_000_000_000
MS = 1_000_000
#: the log starts here (ns): a real epoch time, so stamps are 1.7e9 s
T0 = 1_700_000_000 * S
#: the log's length (ns)
SPAN = 10 * S


@dataclass
class RobotLog:
    """What :func:`write_robot_log` wrote: ``path`` (the file to audit) and, per topic, a
    list of (time ns, plain Python values of the message)."""

    path: Path
    data: dict[str, list[tuple[int, Any]]] = field(default_factory=dict)

    def add(self, topic: str, t: int, value: Any) -> None:
        self.data.setdefault(topic, []).append((t, value))


def mode_at(t: int) -> str:
    """``/mode``: navigating, charging from 3 s to 6 s, then navigating again."""
    s = (t - T0) / S
    return "charging" if 3.0 <= s < 6.0 else "navigating"


def status_at(t: int) -> int:
    """BatteryState.power_supply_status: CHARGING (1) from 2.9 s to 6.1 s (a little wider
    than the charging mode), except 4.2..4.5 s (DISCHARGING, 2: the fault the mode-scope
    requirement finds); else DISCHARGING."""
    s = (t - T0) / S
    if 2.9 <= s < 6.1:
        return 2 if 4.2 <= s < 4.5 else 1
    return 2


def odom_base(t: int) -> tuple[float, float, float]:
    """odom -> base_link at ``t``: x, y (m), yaw (rad)."""
    s = (t - T0) / S
    return 0.3 * s, 0.05 * s, 0.2 * s


def map_odom(t: int) -> tuple[float, float, float]:
    """map -> odom at ``t``: x, y (m), yaw (rad), drifting slowly."""
    s = (t - T0) / S
    return 1.0 + 0.01 * s, -2.0, 0.5 + 0.02 * s


#: base_link -> laser (static): x, y (m), yaw (rad)
BASE_LASER = (0.2, 0.0, math.pi / 2)
JOINTS = ("wheel_left_joint", "wheel_right_joint")


def wheel_velocity(t: int) -> tuple[float, float]:
    """(left, right) wheel velocities (rad/s): the left one over 6 rad/s from 7.0 s to 7.5 s."""
    s = (t - T0) / S
    left = 6.5 if 7.0 <= s < 7.5 else 4.0 + 0.1 * s
    return left, 4.0 - 0.1 * s


def battery_level(t: int) -> int:
    """Diagnostic level of the status named "battery": OK, WARN 5..8 s, ERROR 8.3..8.9 s."""
    s = (t - T0) / S
    return 2 if 8.3 <= s < 8.9 else 1 if 5.0 <= s < 8.0 else 0


def slam_error(t: int) -> float:
    """ORB-SLAM's x error against groundtruth (m): 0.02, 0.4 from 6.5 s to 7.2 s."""
    s = (t - T0) / S
    return 0.4 if 6.5 <= s < 7.2 else 0.02


def _quat(store: Any, yaw: float) -> Any:
    return store.types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                        w=math.cos(yaw / 2))


class _Msgs:
    """Message builders for one typestore (ROS 1 headers carry ``seq``)."""

    def __init__(self, store: Any, ros1: bool) -> None:
        self.s, self.ros1 = store, ros1

    def T(self, name: str) -> Any:
        return self.s.types[name]

    def header(self, t: int, frame: str) -> Any:
        stamp = self.T("builtin_interfaces/msg/Time")(sec=t // S, nanosec=t % S)
        if self.ros1:
            return self.T("std_msgs/msg/Header")(seq=0, stamp=stamp, frame_id=frame)
        return self.T("std_msgs/msg/Header")(stamp=stamp, frame_id=frame)

    def transform(self, t: int, parent: str, child: str, x: float, y: float, yaw: float) -> Any:
        V = self.T("geometry_msgs/msg/Vector3")
        tr = self.T("geometry_msgs/msg/Transform")(translation=V(x=x, y=y, z=0.0),
                                                   rotation=_quat(self.s, yaw))
        return self.T("geometry_msgs/msg/TransformStamped")(
            header=self.header(t, parent), child_frame_id=child, transform=tr)

    def pose(self, t: int, x: float, y: float) -> Any:
        P = self.T("geometry_msgs/msg/Point")
        pose = self.T("geometry_msgs/msg/Pose")(position=P(x=x, y=y, z=0.0),
                                                orientation=_quat(self.s, 0.0))
        return self.T("geometry_msgs/msg/PoseStamped")(header=self.header(t, "map"), pose=pose)

    def battery(self, t: int, status: int) -> Any:
        import numpy as np
        B = self.T("sensor_msgs/msg/BatteryState")
        kw = dict(header=self.header(t, "base_link"), voltage=24.0, current=-1.0,
                  charge=float("nan"), capacity=float("nan"), design_capacity=float("nan"),
                  percentage=0.8, power_supply_status=status, power_supply_health=1,
                  power_supply_technology=2, present=True,
                  cell_voltage=np.zeros(0, np.float32), location="base", serial_number="x1",
                  temperature=30.0, cell_temperature=np.zeros(0, np.float32))
        return B(**kw)

    def joints(self, t: int, k: int) -> Any:
        import numpy as np
        left, right = wheel_velocity(t)
        names, vel = list(JOINTS), [left, right]
        if k % 2:  # the order changes: a binding must pick by name, not by index
            names, vel = names[::-1], vel[::-1]
        return self.T("sensor_msgs/msg/JointState")(
            header=self.header(t, ""), name=names, position=np.array([0.1 * k, 0.2 * k]),
            velocity=np.array(vel, dtype=np.float64), effort=np.zeros(0, np.float64))

    def diagnostics(self, t: int, k: int) -> Any:
        St = self.T("diagnostic_msgs/msg/DiagnosticStatus")
        KV = self.T("diagnostic_msgs/msg/KeyValue")
        motor = St(level=0, name="motor", message="ok", hardware_id="m1",
                   values=[KV(key="temp", value="40")])
        battery = St(level=battery_level(t), name="battery", message="", hardware_id="b1",
                     values=[])
        statuses = [motor, battery] if k % 2 else [battery, motor]
        return self.T("diagnostic_msgs/msg/DiagnosticArray")(header=self.header(t, ""),
                                                            status=statuses)


#: topic -> (message type, period ns, first time offset ns): the log's schedule; offsets
#: keep messages off the 100 ms tick grid, so "at or before the tick" is never a tie.
SCHEDULE = {
    "/mode": ("std_msgs/msg/String", 200 * MS, 7 * MS),
    "/battery": ("sensor_msgs/msg/BatteryState", 100 * MS, 13 * MS),
    "groundtruth": ("geometry_msgs/msg/PoseStamped", 100 * MS, 21 * MS),
    "ORB-SLAM": ("geometry_msgs/msg/PoseStamped", 100 * MS, 33 * MS),
    "/tf": ("tf2_msgs/msg/TFMessage", 50 * MS, 3 * MS),
    "/joint_states": ("sensor_msgs/msg/JointState", 100 * MS, 41 * MS),
    "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", 500 * MS, 47 * MS),
}


def _messages(m: _Msgs, log: RobotLog) -> list[tuple[str, int, Any]]:
    """Every message of the log in time order: (topic, time ns, message); ``log`` gets the
    plain values."""
    out: list[tuple[str, int, Any]] = []
    tr = m.transform(T0, "base_link", "laser", *BASE_LASER)
    out.append(("/tf_static", T0, m.T("tf2_msgs/msg/TFMessage")(transforms=[tr])))
    log.add("/tf_static", T0, [("base_link", "laser", BASE_LASER)])
    for topic, (_type, period, offset) in SCHEDULE.items():
        k = 0
        while offset + k * period < SPAN:
            t = T0 + offset + k * period
            out.append((topic, t, _one(m, log, topic, t, k)))
            k += 1
    out.sort(key=lambda x: x[1])
    return out


def _one(m: _Msgs, log: RobotLog, topic: str, t: int, k: int) -> Any:
    if topic == "/mode":
        log.add(topic, t, mode_at(t))
        return m.T("std_msgs/msg/String")(data=mode_at(t))
    if topic == "/battery":
        log.add(topic, t, status_at(t))
        return m.battery(t, status_at(t))
    if topic in ("groundtruth", "ORB-SLAM"):
        x, y, _ = odom_base(t)
        x += slam_error(t) if topic == "ORB-SLAM" else 0.0
        log.add(topic, t, (x, y))
        return m.pose(t, x, y)
    if topic == "/tf":
        edges = [("odom", "base_link", odom_base(t))]
        if k % 10 == 0:  # map -> odom from another publisher, at 2 Hz, in its own messages
            edges = [("map", "odom", map_odom(t))]
        log.add(topic, t, edges)
        return m.T("tf2_msgs/msg/TFMessage")(
            transforms=[m.transform(t, p, c, *v) for p, c, v in edges])
    if topic == "/joint_states":
        log.add(topic, t, dict(zip(JOINTS, wheel_velocity(t))))
        return m.joints(t, k)
    log.add(topic, t, battery_level(t))
    return m.diagnostics(t, k)


def write_robot_log(folder: Path, ros1: bool = False) -> RobotLog:
    """Write the log into ``folder`` with rosbags' writers: a rosbag2 with MCAP storage
    (``RobotLog.path`` is its ``.mcap`` file) or, with ``ros1``, a ROS 1 bag
    (``robot.bag``), where topics without a leading ``/`` are as legal."""
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    if ros1:  # Noetic's store has no tf2_msgs: its one-line definition, as ROS 1 has it
        from rosbags.typesys import get_types_from_msg
        store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                          "tf2_msgs/msg/TFMessage"))
    m = _Msgs(store, ros1)
    if ros1:
        from rosbags.rosbag1 import Writer as Writer1
        log = RobotLog(folder / "robot.bag")
        msgs = _messages(m, log)
        with Writer1(log.path) as w:
            conns = {t: w.add_connection(t, SCHEDULE.get(t, ("tf2_msgs/msg/TFMessage",))[0],
                                         typestore=store) for t in {x[0] for x in msgs}}
            for topic, t, msg in msgs:
                w.write(conns[topic], t, store.serialize_ros1(msg, conns[topic].msgtype))
        return log
    from rosbags.rosbag2 import StoragePlugin, Writer
    bag = folder / "robot_bag"
    log = RobotLog(bag)
    msgs = _messages(m, log)
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {t: w.add_connection(t, SCHEDULE.get(t, ("tf2_msgs/msg/TFMessage",))[0],
                                     typestore=store) for t in sorted({x[0] for x in msgs})}
        for topic, t, msg in msgs:
            w.write(conns[topic], t, store.serialize_cdr(msg, conns[topic].msgtype))
    log.path = next(bag.glob("*.mcap"))
    return log


def held(log: RobotLog, topic: str, t: int) -> Any:
    """The value of the newest message of ``topic`` at or before ``t`` (None: none yet)."""
    out = None
    for tm, v in log.data[topic]:
        if tm > t:
            break
        out = v
    return out


def ticks(log: RobotLog, topics: list[str], period: int = 100 * MS) -> list[int]:
    """The evaluated ticks of a requirement reading ``topics`` on a fixed period (the tick
    rules of docs/guide/ticks.md, restated): the multiples of ``period`` from the first at or
    after the first message of those topics to the first at or after their last message,
    skipping the ticks before each topic has one."""
    first = min(log.data[t][0][0] for t in topics)
    last = max(log.data[t][-1][0] for t in topics)
    ready = max(log.data[t][0][0] for t in topics)
    out, t = [], -(-first // period) * period
    while t < last + period:
        if t >= ready:
            out.append(t)
        t += period
    return out


def first_false(log: RobotLog, topics: list[str], holds: Callable[[int], bool]) -> int | None:
    """The first evaluated tick (ns) where ``holds`` is false, None if it holds at every one:
    FRET's ``always`` on a finite trace is violated exactly there."""
    for t in ticks(log, topics):
        if not holds(t):
            return t
    return None


def pose_in_map(log: RobotLog, t: int) -> tuple[float, float, float]:
    """base_link in map at ``t`` (x, y in m, yaw in rad, not wrapped) from the newest edges
    written at or before ``t``: an independent 2-D composition with complex numbers."""
    edges = {}
    for tm, es in log.data["/tf"]:
        if tm > t:
            break
        for parent, child, v in es:
            edges[(parent, child)] = v
    mx, my, myaw = edges[("map", "odom")]
    ox, oy, oyaw = edges[("odom", "base_link")]
    p = complex(mx, my) + complex(ox, oy) * complex(math.cos(myaw), math.sin(myaw))
    return p.real, p.imag, myaw + oyaw


def tf_age(log: RobotLog, t: int) -> float:
    """Seconds since the older of the newest map -> odom and odom -> base_link edges."""
    newest = {}
    for tm, es in log.data["/tf"]:
        if tm <= t:
            for p, c, _ in es:
                newest[(p, c)] = tm
    return (t - min(newest.values())) / S
