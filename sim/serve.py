"""Run the simulator live: ``python -m fretc.sim serve --scenario S [--rate 10]`` publishes the
simulated robot's topics over the Foxglove WebSocket protocol (foxglove-sdk's server,
loopback by default) while it runs, paced at ``rate`` times real time, so the Foxglove app
and ``fretc watch`` can connect to it as to a robot running ``foxglove_bridge``.

Channels, schemas and bytes are those :class:`fretc.sim.recording.McapRecorder` writes (ROS 2:
``cdr`` / ``ros2msg``; ROS 1 with ``ros1=True``); log times are the simulation clock (from
1 700 000 000 s, as in the recorded traces), so a served run and the recorded run of the same
scenario and seed carry the same messages at the same log times.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from typing import Any, TYPE_CHECKING

from fretc.live.websocket.serve import FoxgloveServer, Pacer

from fretc.sim.recording import TOPICS, MessageFactory, schema_name
from fretc.sim.scenarios import get_scenario
from fretc.sim.simulation import Simulation

if TYPE_CHECKING:
    from fretc.sim.simulation import RunResult

__all__ = ["ServeRecorder", "serve"]


class ServeRecorder:
    """The recorder interface of :class:`fretc.sim.recording.McapRecorder` (``factory``,
    ``counts``, ``write``, ``finish``), publishing on a
    :class:`fretc.live.websocket.serve.FoxgloveServer` instead of writing a file.

    Raises ValueError for an unknown topic or a log time going backwards (as the MCAP
    recorder).
    """

    def __init__(self, server, rate: float = 1.0, ros1: bool = False,
                 topics: Iterable[tuple[str, str]] = TOPICS,
                 stop: threading.Event | None = None) -> None:
        self.server = server
        self.ros1 = ros1
        self.factory = MessageFactory(ros1)
        self.pacer = Pacer(rate)
        self.stop = stop
        self.counts: dict[str, int] = {}
        self.types: dict[str, str] = {}
        self.last_time = -1
        ts = self.factory.ts
        for topic, typename in topics:
            text, _md5 = ts.generate_msgdef(typename, ros_version=1 if ros1 else 2)
            server.channel(topic, "ros1" if ros1 else "cdr", schema_name(typename, ros1),
                           "ros1msg" if ros1 else "ros2msg", text.encode("utf-8"))
            self.types[topic] = typename
            self.counts[topic] = 0

    def write(self, topic: str, log_time_ns: int, msg: Any) -> None:
        """Serialize ``msg`` and publish it on ``topic`` when its log time is due."""
        # same checks as sim.recording.McapRecorder.write (kept: two small recorders, a live server
        # and a file)
        if topic not in self.types:
            raise ValueError(f"unknown topic {topic}")
        if log_time_ns < self.last_time:
            raise ValueError("log times must not decrease")
        if self.stop is not None and self.stop.is_set():
            raise KeyboardInterrupt
        self.last_time = log_time_ns
        data = self.factory.serialize(msg, self.types[topic])
        self.pacer.wait(log_time_ns)
        self.server.log(topic, data, log_time_ns)
        self.counts[topic] += 1

    def finish(self) -> None:
        """Nothing to flush (the server sends as messages are logged)."""


def serve(scenario: str, *, seed: int = 1, rate: float = 1.0, host: str = "127.0.0.1",
          port: int = 8765, ros1: bool = False, threshold: float = 0.9,
          stop_delay: float | None = None, wait: bool = True,
          server: FoxgloveServer | None = None,
          on_ready: Callable[[FoxgloveServer], None] | None = None,
          safety: str | None = None) -> RunResult:
    """Simulate ``scenario`` live on a foxglove-sdk server (a new one on ``host:port``
    unless ``server`` is given); with ``wait``, start once a client subscribed; ``safety``
    ``"shield:DIR"`` the shield generated in DIR in place of the hand-written SIF and
    interceptor (:mod:`fretc.sim.shielded`: a shielded run watched live). Returns the
    :class:`~fretc.sim.simulation.RunResult`.

    Raises KeyError for an unknown scenario, RuntimeError without foxglove-sdk, ValueError
    for a ``safety`` that names no shield folder (before the server starts).
    """
    from fretc.sim.run import shield_of

    shield = shield_of(safety)
    own = server is None
    if server is None:  # started once every channel exists: a client sees them all at once
        server = FoxgloveServer(host=host, port=port, name=f"fretc sim {scenario}",
                                start=False)
    try:
        rec = ServeRecorder(server, rate=rate, ros1=ros1)
        if own:
            server.start()
        if on_ready is not None:
            on_ready(server)
        if wait:
            server.wait_subscribed(timeout=1e9)
        sim = Simulation(get_scenario(scenario, stop_delay), seed=seed, threshold=threshold,
                         shield=shield)
        return sim.run(rec)
    finally:
        if own:
            time.sleep(0.5)  # let the last messages leave
            server.stop()
