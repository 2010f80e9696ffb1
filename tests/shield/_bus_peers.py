"""ROS 2 peers of the shield's bus test (tests/shield/test_ros2_bus.py), each run in a process
of its own with ROS 2 Jazzy's rclpy on its default middleware; nothing here imports fretc.

    python tests/shield/_bus_peers.py ROLE SECONDS [OUT]

Roles:

* ``lidar``: once its two readers match (the Safety System and the checker), ``/scan``
  (sensor_msgs/LaserScan, 720 beams over 360 degrees as the simulated Scout Mini's, best
  effort) every 100 ms: every range 0.5 m from 3 s to 6 s (an obstacle around the robot),
  3 m otherwise, each with up to 5 mm of noise, and none from 8 s on (the LiDAR falls
  silent); it exits after SECONDS.
* ``sector_lidar``, with OUT ``SCENARIO:BEAMS:FOV``: a LiDAR of another beam count and field
  of view than the simulator's (``near:360:270``: 360 beams over 270 degrees from -135
  degrees, REP 103: 0 ahead, counter-clockwise), once its two readers match, ``/scan`` every
  100 ms until it exits after SECONDS, 3 m on every beam but: ``near``, an obstacle on the
  beams within 30 degrees of ahead closing from 2 m at 2 s to 0.5 m at 3 s and staying there;
  ``blind``, every range NaN from 3 s on (a LiDAR that fails while it keeps publishing).
  Every valid range has up to 5 mm of noise (no frame repeats the one before).
* ``controller``: once its two readers match (the Safety System and the checker),
  ``/cmd_vel`` (geometry_msgs/Twist, reliable) every 100 ms proposing to drive on at
  0.3 m/s, for SECONDS.
* ``controller20``, with OUT the number of its readers (default 2: the Safety System and the
  checker; a recorder makes 3): once they match,
  ``/cmd_vel`` (reliable) every 50 ms, Nav2's controller rate, each proposal its own number
  (``linear.x`` 0.2 m/s plus 0.1 mm/s a message: every answer tells which proposal it
  answers), for SECONDS; then it exits (a controller that dies).
* ``recorder``: an independent recorder beside the node: ``/scan``, ``/cmd_vel`` and
  ``/cmd_vel_filtered`` as CDR into the MCAP file OUT, each message's log time its receipt
  time (the middleware's ``received_timestamp``), for SECONDS.
* ``checker``: an independent node that writes, as JSON lines into OUT, each message it
  receives on ``/scan`` (its least range), ``/cmd_vel_filtered`` (linear.x, angular.z),
  ``/gwendolen_control`` (data), ``/cmd_vel`` (linear.x) and ``/diagnostics`` (level, message, values) with its
  receipt time: the middleware's ``received_timestamp`` (ns), when the message reached this
  node (its callbacks run later, in the executor's order, not the messages'), for SECONDS.
"""

from __future__ import annotations

import json
import math
import random
import sys
import time

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy

RELIABLE = QoSProfile(depth=10)
BEST_EFFORT = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)


def _spin(node, seconds: float, step=None, period: float = 0.1) -> None:
    """Spin ``node`` for ``seconds``, calling ``step(t)`` every ``period`` s (``t`` the
    seconds since the start)."""
    t0 = time.monotonic()
    nxt = t0
    while time.monotonic() - t0 < seconds:
        now = time.monotonic()
        if step is not None and now >= nxt:
            step(now - t0)
            nxt += period
        rclpy.spin_once(node, timeout_sec=max(0.0, min(0.01, nxt - time.monotonic())))


def _wait_for(node, publisher, count: int, limit: float = 60.0) -> None:
    t0 = time.monotonic()
    while publisher.get_subscription_count() < count and time.monotonic() - t0 < limit:
        rclpy.spin_once(node, timeout_sec=0.05)


def lidar(seconds: float, _out: str) -> None:
    from sensor_msgs.msg import LaserScan

    n = rclpy.create_node("lidar")
    pub = n.create_publisher(LaserScan, "/scan", BEST_EFFORT)
    _wait_for(n, pub, 2)
    _spin(n, 1.0)

    noise = random.Random(3)

    def step(t: float) -> None:
        if t >= 8.0:
            return
        r = 0.5 if 3.0 <= t < 6.0 else 3.0
        # (a real LiDAR's noise: no frame repeats the one before, no frozen frame, R13)
        s = LaserScan(angle_min=-3.141592653589793, angle_increment=3.141592653589793 / 360,
                      range_min=0.1, range_max=30.0,
                      ranges=[r + noise.uniform(-0.005, 0.005) for _ in range(720)])
        s.header.stamp = n.get_clock().now().to_msg()
        pub.publish(s)

    _spin(n, seconds, step)


def sector_lidar(seconds: float, spec: str) -> None:
    from sensor_msgs.msg import LaserScan

    scenario, beams, fov = spec.split(":")
    count, width = int(beams), math.radians(float(fov))
    angle_min, step_angle = -width / 2, width / (int(beams) - 1)
    ahead = [i for i in range(count) if abs(angle_min + i * step_angle) <= math.radians(30)]
    n = rclpy.create_node("lidar")
    pub = n.create_publisher(LaserScan, "/scan", BEST_EFFORT)
    _wait_for(n, pub, 2)
    _spin(n, 1.0)

    noise = random.Random(7)

    def step(t: float) -> None:
        ranges = [3.0] * count
        if scenario == "near" and t >= 2.0:
            for i in ahead:
                ranges[i] = max(0.5, 2.0 - 1.5 * (t - 2.0))
        # a real LiDAR's noise (no two frames alike: no frozen frame, R13)
        ranges = [r + noise.uniform(-0.005, 0.005) for r in ranges]
        if scenario == "blind" and t >= 3.0:
            ranges = [math.nan] * count
        s = LaserScan(angle_min=angle_min, angle_max=angle_min + (count - 1) * step_angle,
                      angle_increment=step_angle, range_min=0.1, range_max=30.0,
                      ranges=ranges)
        s.header.stamp = n.get_clock().now().to_msg()
        pub.publish(s)

    _spin(n, seconds, step)


def controller(seconds: float, _out: str) -> None:
    from geometry_msgs.msg import Twist

    n = rclpy.create_node("controller")
    pub = n.create_publisher(Twist, "/cmd_vel", RELIABLE)
    _wait_for(n, pub, 2)  # (the Safety System and the checker)
    _spin(n, 1.0)

    def step(_t: float) -> None:
        tw = Twist()
        tw.linear.x = 0.3
        pub.publish(tw)

    _spin(n, seconds, step)


def controller20(seconds: float, out: str) -> None:
    from geometry_msgs.msg import Twist

    n = rclpy.create_node("controller")
    pub = n.create_publisher(Twist, "/cmd_vel", RELIABLE)
    _wait_for(n, pub, int(out or 2))
    _spin(n, 1.0)
    sent = [0]

    def step(_t: float) -> None:
        tw = Twist()
        tw.linear.x = 0.2 + 1e-4 * sent[0]
        sent[0] += 1
        pub.publish(tw)

    _spin(n, seconds, step, 0.05)


def recorder(seconds: float, out: str) -> None:
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = {"/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
             "/cmd_vel_filtered": "geometry_msgs/msg/Twist"}
    import importlib

    n = rclpy.create_node("recorder")
    with open(out, "wb") as fh:
        w = Writer(fh)
        w.start(profile="ros2", library="fretc-test-recorder")
        channels = {}
        for topic, typ in types.items():
            text, _ = store.generate_msgdef(typ, ros_version=2)
            sid = w.register_schema(name=typ, encoding="ros2msg", data=text.encode())
            channels[topic] = w.register_channel(topic=topic, message_encoding="cdr",
                                                 schema_id=sid)
            pkg, _m, name = typ.split("/")
            cls = getattr(importlib.import_module(pkg + ".msg"), name)

            def cb(raw, info, topic=topic):
                t = info["received_timestamp"]
                w.add_message(channels[topic], log_time=t, publish_time=t, data=raw)

            n.create_subscription(cls, topic, cb, BEST_EFFORT, raw=True)
        _spin(n, seconds)
        w.finish()


def checker(seconds: float, out: str) -> None:
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import LaserScan
    from std_msgs.msg import Bool

    n = rclpy.create_node("checker")
    # line-buffered: each receipt is in OUT once written, should the node be ended early
    with open(out, "w", encoding="utf-8", buffering=1) as fh:
        def keep(topic: str, info, fields: dict) -> None:
            fh.write(json.dumps({"topic": topic, "t": info["received_timestamp"],
                                 **fields}) + "\n")

        n.create_subscription(LaserScan, "/scan", lambda m, i: keep(
            "/scan", i, {"min": min(m.ranges)}), BEST_EFFORT)
        n.create_subscription(Twist, "/cmd_vel_filtered", lambda m, i: keep(
            "/cmd_vel_filtered", i, {"x": m.linear.x, "z": m.angular.z}), BEST_EFFORT)
        n.create_subscription(Twist, "/cmd_vel", lambda m, i: keep(
            "/cmd_vel", i, {"x": m.linear.x}), RELIABLE)
        n.create_subscription(Bool, "/gwendolen_control", lambda m, i: keep(
            "/gwendolen_control", i, {"data": bool(m.data)}), BEST_EFFORT)
        n.create_subscription(DiagnosticArray, "/diagnostics", lambda m, i: keep(
            "/diagnostics", i, {"level": int.from_bytes(m.status[0].level, "little")
                                if isinstance(m.status[0].level, bytes)
                                else int(m.status[0].level), "message": m.status[0].message,
                                "values": {v.key: v.value for v in m.status[0].values}}),
            BEST_EFFORT)
        _spin(n, seconds)


def main() -> None:
    role, seconds = sys.argv[1], float(sys.argv[2])
    out = sys.argv[3] if len(sys.argv) > 3 else ""
    rclpy.init()
    try:
        {"lidar": lidar, "sector_lidar": sector_lidar, "controller": controller,
         "controller20": controller20, "checker": checker,
         "recorder": recorder}[role](seconds, out)
    finally:
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
