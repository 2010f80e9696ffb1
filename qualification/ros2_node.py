"""The ROS 2 node ``fretc shield --emit ros2`` wrote, driven message by message in a process
of its own: ``python -m fretc.qualification.ros2_node PACKAGE MODULE`` reads runs from
standard input and prints, as one JSON line, what the node sent and reported for each
message.

The node is built with ROS 2 Jazzy's rclpy (its subscriptions, services and publishers
made as on the robot); its publishers are replaced by recorders, and its clock by each
message's time, so the run is the same on every machine and nothing is sent on a graph.
Each message is given as its subscription gives it, CDR bytes, through the node's own
``hear`` (a message of its tick topic ticks it). The ``shield-ros2`` check of
:mod:`fretc.qualification.checks_shield` holds what it prints against the shield's Python
form.

Input (JSON): ``[[event, ...], ...]``, one list a run (a fresh node each), an event
``[kind, topic, value, time_ns]``: ``kind`` ``"message"`` (``value`` set as the message's
``data`` field: a number, NaN and infinities as Python's ``json`` writes them, or a
boolean) or ``"garbage"`` (bytes that are no message of the topic's type). Output: per
run, per event ``{"sent": [[topic, data], ...], "diagnostics": [[level, message], ...]}``
(level 0 OK, 1 WARN, 2 ERROR, REP 107).

With ``--graph`` the node runs on a ROS 2 graph instead (:func:`on_graph`): its messages go
through rclpy's middleware to a probe node in the same process.
"""

from __future__ import annotations

import json
import sys
from typing import Any

#: bytes that are no CDR message of a Float64 or a Bool (a representation header cut short)
GARBAGE = b"\x00\x01"


def _level(status: Any) -> int:
    """A DiagnosticStatus's level as a number (rclpy gives it as one byte)."""
    level = status.level
    return int.from_bytes(level, "little") if isinstance(level, bytes) else int(level)


def drive(package: str, module: str, runs: list[list[list[Any]]]) -> list[list[dict[str, Any]]]:
    """Drive the node of ``module`` (its package folder ``package`` put first on
    ``sys.path``) over ``runs`` (module docstring); rclpy is initialized and shut down
    here. Raises ImportError when rclpy or the package cannot be imported; an exception
    the node lets escape ends the drive (the node must never let one)."""
    import rclpy

    sys.path.insert(0, package)
    node_module = __import__(module + ".shield_node", fromlist=["ShieldNode"])
    from fretc.shield.messages import default_message

    rclpy.init()
    out = []
    try:
        for events in runs:
            node = node_module.ShieldNode()
            store, types = node.store, node_module.TYPES
            sent: list[list[Any]] = []
            diagnostics: list[list[Any]] = []
            for topic, pub in node.pubs.items():
                pub.publish = (lambda raw, topic=topic, sent=sent, store=store, types=types: sent.append(
                    [topic, store.deserialize_cdr(bytes(raw), types[topic]).data]))
            node.diagnostics.publish = (lambda m, diagnostics=diagnostics: diagnostics.extend(
                [_level(s), s.message] for s in m.status))
            got = []
            for kind, topic, value, time_ns in events:
                sent.clear()
                diagnostics.clear()
                node.now = (lambda now: lambda: now)(int(time_ns))
                if kind == "garbage":
                    raw = GARBAGE
                else:
                    msg = default_message(store, types[topic])
                    msg.data = value
                    raw = bytes(store.serialize_cdr(msg, types[topic]))
                node.hear(topic, raw)
                got.append({"sent": list(sent), "diagnostics": list(diagnostics)})
            node.destroy_node()
            out.append(got)
    finally:
        rclpy.shutdown()
    return out


#: seconds the graph run waits for each answer of the node
GRAPH_WAIT = 20.0


def on_graph(package: str, module: str, steps: list[list[Any]]) -> list[dict[str, Any]]:
    """The node of ``module`` on a ROS 2 graph, as on the robot: its own publishers,
    subscriptions and timer, spun with a probe node that publishes each step's ``/x`` and
    ``/o_proposed`` (``[x, proposed]``) ten times a second until the node's ``/o`` and
    ``/diagnostics`` have answered at least three times, or :data:`GRAPH_WAIT` seconds
    passed. Returns per step ``{"o": [data, ...], "levels": [level, ...]}``, what the probe
    heard in its last three periods. Raises ImportError without rclpy."""
    import time

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import Bool, Float64

    sys.path.insert(0, package)
    node_module = __import__(module + ".shield_node", fromlist=["ShieldNode"])
    rclpy.init()
    out = []
    try:
        node = node_module.ShieldNode()
        probe = rclpy.create_node("fretc_qualify_probe")
        heard: dict[str, list[Any]] = {"o": [], "levels": []}

        def on_o(m: Any) -> None:
            heard["o"].append(bool(m.data))

        def on_diagnostics(m: Any) -> None:
            heard["levels"].extend(_level(s) for s in m.status)

        probe.create_subscription(Bool, "/o", on_o, 10)
        probe.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 10)
        xs = probe.create_publisher(Float64, "/x", 10)
        proposals = probe.create_publisher(Bool, "/o_proposed", 10)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        executor.add_node(probe)
        for x, proposed in steps:
            heard["o"].clear()
            heard["levels"].clear()
            end = time.monotonic() + GRAPH_WAIT
            while time.monotonic() < end and min(len(heard["o"]), len(heard["levels"])) < 3:
                proposals.publish(Bool(data=bool(proposed)))
                xs.publish(Float64(data=float(x)))
                stop = time.monotonic() + 0.1
                while time.monotonic() < stop:
                    executor.spin_once(timeout_sec=0.02)
            out.append({"o": heard["o"][-3:], "levels": heard["levels"][-3:]})
        executor.shutdown()
        probe.destroy_node()
        node.destroy_node()
    finally:
        rclpy.shutdown()
    return out


def main(argv: list[str] | None = None) -> None:
    """The command line (module docstring): PACKAGE MODULE, runs on standard input; with
    ``--graph`` after them, :func:`on_graph`'s steps instead."""
    args = sys.argv[1:] if argv is None else argv
    given = json.loads(sys.stdin.read())
    if args[2:] == ["--graph"]:
        print(json.dumps(on_graph(args[0], args[1], given)))
    else:
        print(json.dumps(drive(args[0], args[1], given)))


if __name__ == "__main__":
    main()
