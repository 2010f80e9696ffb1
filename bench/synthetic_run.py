"""A synthetic but faithful recorded Safe-ROS run, for the audit benchmark.

``write_run(path, minutes)`` writes a ROS 2 MCAP (``ros2`` profile, ``ros2msg`` schemas, CDR
messages, zstd chunks of 1 MiB, as ``ros2 bag record -s mcap`` does) with the topics and rates
of the Safe-ROS AgileX Scout Mini stack:

=======================  =================================  =======
topic                    type                               rate
=======================  =================================  =======
``/scan``                sensor_msgs/msg/LaserScan, 722      10 Hz
                         beams (REP 117: some inf / NaN)
``/odom``                nav_msgs/msg/Odometry               20 Hz
``/cmd_vel``             geometry_msgs/msg/Twist             10 Hz
``/cmd_vel_filtered``    geometry_msgs/msg/Twist             10 Hz
``/gwendolen_control``   std_msgs/msg/Bool                   on change (+ one at start)
=======================  =================================  =======

The robot drives back and forth along a corridor; when the minimum range falls below 0.9 m
the SIF publishes ``true`` on ``/gwendolen_control`` and the interceptor forwards zero
velocity until the range clears, as in Safe-ROS. Deterministic: a fixed seed, no wall clock.
Times are ns from 1_700_000_000 s.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

EPOCH_NS = 1_700_000_000 * 1_000_000_000
MS = 1_000_000
BEAMS = 722
TOPICS = (
    ("/scan", "sensor_msgs/msg/LaserScan"),
    ("/odom", "nav_msgs/msg/Odometry"),
    ("/cmd_vel", "geometry_msgs/msg/Twist"),
    ("/gwendolen_control", "std_msgs/msg/Bool"),
    ("/cmd_vel_filtered", "geometry_msgs/msg/Twist"),
)


class _Writer:
    """The MCAP writer of one synthetic run: channels, messages and their constructors."""

    def __init__(self, w: Writer):
        self.ts = get_typestore(Stores.ROS2_HUMBLE)
        self.T = self.ts.types
        self.w = w
        self.counts = {t: 0 for t, _ in TOPICS}
        self.chan = {}
        schemas = {}
        for topic, typ in TOPICS:
            if typ not in schemas:
                text = self.ts.generate_msgdef(typ, ros_version=2)[0]
                schemas[typ] = w.register_schema(typ, "ros2msg", text.encode())
            self.chan[topic] = (w.register_channel(topic, "cdr", schemas[typ]), typ)

    def put(self, topic, t_ns, msg):
        cid, typ = self.chan[topic]
        self.w.add_message(cid, log_time=t_ns, publish_time=t_ns,
                           data=bytes(self.ts.serialize_cdr(msg, typ)),
                           sequence=self.counts[topic])
        self.counts[topic] += 1

    def header(self, t_ns, frame):
        stamp = self.T["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        return self.T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def twist(self, v, w_):
        V3 = self.T["geometry_msgs/msg/Vector3"]
        return self.T["geometry_msgs/msg/Twist"](linear=V3(x=float(v), y=0.0, z=0.0),
                                                  angular=V3(x=0.0, y=0.0, z=float(w_)))

    def odom(self, t_ns, x, v, w_cmd, rng, cov):
        T = self.T
        pose = T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=x, y=0.0, z=0.0),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))
        self.put("/odom", t_ns, T["nav_msgs/msg/Odometry"](
            header=self.header(t_ns, "odom"), child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=self.twist(v + rng.normal(0, 0.002), w_cmd), covariance=cov)))

    def scan(self, t_ns, x, direction, rng, angles) -> float:
        """/scan: a corridor 0.6 m wide, walls ahead at the corridor ends (0 .. 20 m); the
        smallest finite range."""
        ahead = (20.0 - x) if direction > 0 else x
        ranges = np.where(np.abs(np.cos(angles)) > 0.2,
                          np.abs(np.where(np.cos(angles) * direction > 0, ahead, 30.0)
                                 / np.cos(angles)),
                          1.5 / np.maximum(np.abs(np.sin(angles)), 1e-3))
        ranges = ranges + rng.normal(0, 0.01, BEAMS)
        ranges[rng.integers(0, BEAMS, 8)] = np.inf
        ranges[rng.integers(0, BEAMS, 2)] = np.nan
        ranges = np.clip(ranges, 0.05, 12.0).astype(np.float32)
        self.put("/scan", t_ns, self.T["sensor_msgs/msg/LaserScan"](
            header=self.header(t_ns, "laser"), angle_min=-math.pi, angle_max=math.pi,
            angle_increment=2 * math.pi / (BEAMS - 1), time_increment=0.0,
            scan_time=0.1, range_min=0.1, range_max=12.0, ranges=ranges,
            intensities=np.zeros(0, dtype=np.float32)))
        finite = ranges[np.isfinite(ranges)]
        return float(finite.min()) if finite.size else math.inf


def write_run(path: str | Path, minutes: float, seed: int = 7) -> dict:
    """Write ``minutes`` of recording to ``path``; returns messages per topic.

    Raises ``OSError`` if the file cannot be written.
    """
    rng = np.random.default_rng(seed)
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression=CompressionType.ZSTD)
        w.start(profile="ros2", library="fretc-bench")
        out = _Writer(w)
        Bool = out.T["std_msgs/msg/Bool"]
        cov = np.zeros(36)
        angles = np.linspace(-math.pi, math.pi, BEAMS, dtype=np.float64)
        end_ms = int(minutes * 60_000)
        x, v, w_cmd = 0.0, 0.0, 0.0
        direction = 1.0
        stop = False
        out.put("/gwendolen_control", EPOCH_NS, Bool(data=False))
        v_cmd = 0.0
        for t_ms in range(0, end_ms, 50):
            t_ns = EPOCH_NS + t_ms * MS
            # physics at 20 Hz: the base follows the filtered command
            v_f = 0.0 if stop else v_cmd
            v += 0.5 * (v_f - v)
            x += v * 0.05
            out.odom(t_ns, x, v, w_cmd, rng, cov)
            if t_ms % 100 == 0:
                too_close = out.scan(t_ns, x, direction, rng, angles) < 0.9
                if too_close != stop:
                    stop = too_close
                    out.put("/gwendolen_control", t_ns, Bool(data=stop))
                    if stop:
                        out.put("/cmd_vel_filtered", t_ns, out.twist(0.0, 0.0))
                        direction = -direction  # turn round: the SRAS replans
            elif t_ms % 100 == 50:
                # SRAS at 10 Hz, 50 ms after the scan; the interceptor forwards it
                v_cmd = 0.4 * direction
                w_cmd = 0.1 * math.sin(t_ms / 5000.0)
                out.put("/cmd_vel", t_ns, out.twist(v_cmd, w_cmd))
                out.put("/cmd_vel_filtered", t_ns,
                        out.twist(0.0, 0.0) if stop else out.twist(v_cmd, w_cmd))
        w.finish()
    return out.counts
