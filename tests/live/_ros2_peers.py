"""ROS 2 peers for the live tests, each run in a process of its own with ROS 2 Jazzy's rclpy
on its default middleware (Fast DDS, default transports); nothing here imports fretc.

    python tests/live/_ros2_peers.py ROLE SECONDS [OUT]

Roles:

* ``talker``: ``/gwendolen_control`` (std_msgs/Bool) and ``/cmd_vel_filtered``
  (geometry_msgs/Twist) at 10 Hz, reliable; a stop requested from 4 s to 6 s, during which
  one command (at 5 s) is not zero; ``/scan`` (sensor_msgs/LaserScan, best effort, header
  stamps) and a latched ``/map`` (nav_msgs/OccupancyGrid, transient local) once.
* ``listen``: subscribes ``/scan``, ``/cmd_vel_filtered``, ``/gwendolen_control``,
  ``/diagnostics`` and writes each message received as a JSON line to OUT (topic, receipt
  time, fields).
* ``services``: a std_srvs/SetBool server ``/arm`` whose every fourth answer takes 0.7 s, and a
  client calling it every 200 ms, both with service introspection (contents) on.
* ``actions``: a test_msgs/Fibonacci action server ``/fib`` (each goal takes about 0.8 s) and a
  client sending a goal every second.
* ``controller``: the shield graph's controller and world, once the Safety System and the
  recorder subscribe to both its topics: ``/cmd_vel`` at 0.4 m/s every 100 ms (always
  proposing to drive on) and ``/scan`` (reliable) every 100 ms whose ranges read 0.5 m from
  2 s to 4 s (an obstacle within 0.9 m) and 3 m otherwise, with no scan from 5 s to 6 s.
* ``passthrough``: the unshielded graph's Safety System: forwards each ``/cmd_vel`` to
  ``/cmd_vel_filtered`` unchanged and publishes ``/gwendolen_control`` true while a scan reads
  under 0.9 m (a stop requested that nothing enforces), until the controller has gone.
* ``record``: an independent recorder: ``/scan``, ``/cmd_vel``, ``/cmd_vel_filtered``,
  ``/gwendolen_control`` as CDR into the MCAP file OUT (mcap's writer, the schemas of ROS 2
  Jazzy's definitions from rosbags), log time = the publisher's source timestamp (the order
  in which the node published: on a loaded machine two topics' messages can be received in
  the other order), until the controller has gone (``record_control``: until the
  ``control`` node has gone).
* ``lidar``: once three subscriptions match (the watch, the recorder, ``control``),
  ``/scan`` (best effort, header stamps) every 100 ms for SECONDS, then the node exits: a
  LiDAR that dies while the rest of the graph runs on.
* ``control``: ``/gwendolen_control`` (reliable) every 100 ms for SECONDS; with OUT
  ``stop``, the stop request raised once no scan came for 0.2 s after one did (a Safety
  System that keeps R6), else never.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

RELIABLE = QoSProfile(depth=10)
BEST_EFFORT = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
#: reliable, a history deep enough for a subscriber stalled for seconds on a loaded machine
DEEP = QoSProfile(depth=200)
LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def spin_for(node, seconds: float, step=None, period: float = 0.1) -> None:
    """Spin ``node`` for ``seconds``, calling ``step(k)`` every ``period`` s."""
    t0 = time.monotonic()
    k = 0
    nxt = t0
    while time.monotonic() - t0 < seconds:
        if step is not None and time.monotonic() >= nxt:
            step(k)
            k += 1
            nxt += period
        rclpy.spin_once(node, timeout_sec=max(0.0, min(0.01, nxt - time.monotonic())))


def wait_for_subscribers(node, publishers, count: int, limit: float = 60.0) -> None:
    """Spin ``node`` until each of ``publishers`` has ``count`` subscriptions matched (the
    graph's other peers discovered: a start that does not depend on how long they take to
    come up), at most ``limit`` s."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < limit:
        if all(p.get_subscription_count() >= count for p in publishers):
            return
        rclpy.spin_once(node, timeout_sec=0.05)
    raise SystemExit(f"the graph's peers were not discovered within {limit} s")


def spin_until_gone(node, topic: str, limit: float = 90.0) -> None:
    """Spin ``node`` until ``topic`` has had a publisher and has none left (the controller
    ended), then 0.5 s more for the last messages; at most ``limit`` s."""
    t0 = time.monotonic()
    seen = False
    while time.monotonic() - t0 < limit:
        n = node.count_publishers(topic)
        seen = seen or n > 0
        if seen and n == 0:
            break
        rclpy.spin_once(node, timeout_sec=0.05)
    spin_for(node, 0.5)


def talker(seconds: float, _out: str) -> None:
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import OccupancyGrid
    from sensor_msgs.msg import LaserScan
    from std_msgs.msg import Bool

    n = rclpy.create_node("talker")
    c = n.create_publisher(Bool, "/gwendolen_control", RELIABLE)
    f = n.create_publisher(Twist, "/cmd_vel_filtered", RELIABLE)
    s = n.create_publisher(LaserScan, "/scan", BEST_EFFORT)
    m = n.create_publisher(OccupancyGrid, "/map", LATCHED)
    grid = OccupancyGrid()
    grid.info.width, grid.info.height, grid.info.resolution = 2, 2, 0.5
    grid.data = [0, 100, 0, 0]
    m.publish(grid)
    # the steps start when the watch's subscriptions are matched (the one non-zero command
    # during a stop, k = 30..32, then falls inside the watch whatever the start-up took)
    wait_for_subscribers(n, [c, f], 1)

    def step(k: int) -> None:
        stop = 20 <= k < 40
        c.publish(Bool(data=stop))
        tw = Twist()
        # three steps, not one: a 100 ms pulse between two 100 ms ticks can fall between
        # them when the messages jitter (neither the watch nor the audit would sample it)
        tw.linear.x = 0.3 if (not stop or 30 <= k <= 32) else 0.0
        f.publish(tw)
        scan = LaserScan(range_min=0.1, range_max=10.0, ranges=[2.0] * 8)
        scan.header.stamp = n.get_clock().now().to_msg()
        scan.header.frame_id = "base_link"
        s.publish(scan)

    spin_for(n, seconds, step)


def listen(seconds: float, out: str) -> None:
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import LaserScan
    from std_msgs.msg import Bool

    n = rclpy.create_node("listener")
    rows = []

    def keep(topic, fields):
        return lambda msg: rows.append({"topic": topic, "t": time.time_ns(), **fields(msg)})

    n.create_subscription(LaserScan, "/scan", keep("/scan", lambda m: {
        "stamp": m.header.stamp.sec * 10**9 + m.header.stamp.nanosec,
        "n": len(m.ranges)}), BEST_EFFORT)
    n.create_subscription(Twist, "/cmd_vel_filtered", keep("/cmd_vel_filtered", lambda m: {
        "x": m.linear.x, "z": m.angular.z}), BEST_EFFORT)
    n.create_subscription(Bool, "/gwendolen_control", keep("/gwendolen_control", lambda m: {
        "data": bool(m.data)}), BEST_EFFORT)
    n.create_subscription(DiagnosticArray, "/diagnostics", keep("/diagnostics", lambda m: {
        "status": [(s.name, int.from_bytes(s.level, "little") if isinstance(s.level, bytes)
                    else int(s.level), s.message) for s in m.status]}), BEST_EFFORT)
    spin_for(n, seconds)
    with open(out, "w", encoding="utf-8") as fh:
        for r in rows:
            fh.write(json.dumps(r) + "\n")


def services(seconds: float, _out: str) -> None:
    from rclpy.service_introspection import ServiceIntrospectionState
    from std_srvs.srv import SetBool

    n = rclpy.create_node("arm_server")
    count = [0]

    def serve(req, resp):
        count[0] += 1
        if count[0] % 4 == 0:
            time.sleep(0.7)
        resp.success = bool(req.data)
        return resp

    srv = n.create_service(SetBool, "/arm", serve)
    cli = n.create_client(SetBool, "/arm")
    qos = QoSProfile(depth=10)
    srv.configure_introspection(n.get_clock(), qos, ServiceIntrospectionState.CONTENTS)
    cli.configure_introspection(n.get_clock(), qos, ServiceIntrospectionState.CONTENTS)
    client_node = rclpy.create_node("arm_client")
    cli2 = client_node.create_client(SetBool, "/arm")
    cli2.configure_introspection(client_node.get_clock(), qos,
                                 ServiceIntrospectionState.CONTENTS)
    from rclpy.executors import MultiThreadedExecutor

    ex = MultiThreadedExecutor(num_threads=3)
    ex.add_node(n)
    ex.add_node(client_node)
    time.sleep(1.0)
    t0 = time.monotonic()
    nxt = t0
    k = 0
    while time.monotonic() - t0 < seconds:
        if time.monotonic() >= nxt:
            cli2.call_async(SetBool.Request(data=bool(k % 2)))
            k += 1
            nxt += 0.2
        ex.spin_once(timeout_sec=0.01)


def actions(seconds: float, _out: str) -> None:
    from rclpy.action import ActionClient, ActionServer
    from rclpy.executors import MultiThreadedExecutor
    from test_msgs.action import Fibonacci

    n = rclpy.create_node("fib_server")

    def execute(handle):
        time.sleep(0.8)
        handle.succeed()
        result = Fibonacci.Result()
        result.sequence = [0, 1, 1]
        return result

    ActionServer(n, Fibonacci, "/fib", execute)
    c = rclpy.create_node("fib_client")
    client = ActionClient(c, Fibonacci, "/fib")
    ex = MultiThreadedExecutor(num_threads=3)
    ex.add_node(n)
    ex.add_node(c)
    time.sleep(1.0)
    t0 = time.monotonic()
    nxt = t0
    while time.monotonic() - t0 < seconds:
        if time.monotonic() >= nxt:
            client.send_goal_async(Fibonacci.Goal(order=3))
            nxt += 1.0
        ex.spin_once(timeout_sec=0.01)


def controller(seconds: float, _out: str) -> None:
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import LaserScan

    n = rclpy.create_node("controller")
    cmd = n.create_publisher(Twist, "/cmd_vel", DEEP)
    # reliable, so that the recorder hears every scan the Safety System could (its
    # best-effort subscription matches); a scan the recorder alone lost on a loaded machine
    # read as a dropout the shield never saw (R6 broken in the recording only)
    scan = n.create_publisher(LaserScan, "/scan", DEEP)
    # the Safety System (shield or passthrough) and the recorder read both topics
    wait_for_subscribers(n, [cmd, scan], 2)
    spin_for(n, 0.5)
    t0 = time.monotonic()

    def step(k: int) -> None:
        t = time.monotonic() - t0
        close = 2.0 <= t < 4.0
        s = LaserScan(range_min=0.1, range_max=10.0, ranges=[0.5 if close else 3.0] * 8)
        s.header.stamp = n.get_clock().now().to_msg()
        if not 5.0 <= t < 6.0:  # the LiDAR drops out for a second
            scan.publish(s)
        tw = Twist()
        tw.linear.x = 0.4
        cmd.publish(tw)

    spin_for(n, seconds, step)


def passthrough(seconds: float, _out: str) -> None:
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import LaserScan
    from std_msgs.msg import Bool

    n = rclpy.create_node("passthrough")
    out = n.create_publisher(Twist, "/cmd_vel_filtered", RELIABLE)
    ctl = n.create_publisher(Bool, "/gwendolen_control", RELIABLE)
    n.create_subscription(Twist, "/cmd_vel", out.publish, RELIABLE)
    n.create_subscription(LaserScan, "/scan", lambda s: ctl.publish(
        Bool(data=min(s.ranges) < 0.9)), BEST_EFFORT)
    spin_until_gone(n, "/cmd_vel")


def record(seconds: float, out: str, until: str = "/cmd_vel", scan_qos: Any = None) -> None:
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = {"/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
             "/cmd_vel_filtered": "geometry_msgs/msg/Twist",
             "/gwendolen_control": "std_msgs/msg/Bool"}
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
            # the publishers' reliability (as rosbag2 adapts its QoS): a loaded machine
            # drops no message a reliable publisher sent
            qos = (scan_qos or DEEP) if topic == "/scan" else DEEP

            def cb(raw, info, topic=topic):
                t = info["source_timestamp"]
                w.add_message(channels[topic], log_time=t, publish_time=t, data=raw)

            n.create_subscription(cls, topic, cb, qos, raw=True)
        spin_until_gone(n, until)
        w.finish()


def record_control(seconds: float, out: str) -> None:
    record(seconds, out, until="/gwendolen_control", scan_qos=BEST_EFFORT)  # (the lidar's)


def lidar(seconds: float, _out: str) -> None:
    from sensor_msgs.msg import LaserScan

    n = rclpy.create_node("lidar")
    scan = n.create_publisher(LaserScan, "/scan", BEST_EFFORT)
    # its readers (the watch, the recorder, the control node) matched first: all of its
    # scans are theirs, whatever their start-up took
    wait_for_subscribers(n, [scan], 3)

    def step(k: int) -> None:
        s = LaserScan(range_min=0.1, range_max=10.0, ranges=[3.0] * 8)
        s.header.stamp = n.get_clock().now().to_msg()
        scan.publish(s)

    spin_for(n, seconds, step)
    n.destroy_node()  # the publisher leaves with the node


def control(seconds: float, out: str) -> None:
    from sensor_msgs.msg import LaserScan
    from std_msgs.msg import Bool

    n = rclpy.create_node("control")
    ctl = n.create_publisher(Bool, "/gwendolen_control", RELIABLE)
    last = [None]
    n.create_subscription(LaserScan, "/scan", lambda s: last.__setitem__(0, time.monotonic()),
                          BEST_EFFORT)

    def step(k: int) -> None:
        stale = last[0] is not None and time.monotonic() - last[0] > 0.2
        ctl.publish(Bool(data=out == "stop" and stale))

    spin_for(n, seconds, step)


ROLES = {"talker": talker, "listen": listen, "services": services, "actions": actions,
         "controller": controller, "passthrough": passthrough, "record": record,
         "record_control": record_control, "lidar": lidar, "control": control}


if __name__ == "__main__":
    role, secs = sys.argv[1], float(sys.argv[2])
    rclpy.init()
    try:
        ROLES[role](secs, sys.argv[3] if len(sys.argv) > 3 else "")
    finally:
        rclpy.try_shutdown()
