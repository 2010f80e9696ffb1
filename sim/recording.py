"""ROS messages and MCAP recording.

Messages are built and serialized with ``rosbags`` (``rosbags.typesys``): the ROS 2 Humble
store and CDR by default, the ROS 1 Noetic store and the ROS 1 wire format with ``ros1=True``.
Files are written with ``mcap``'s writer, following the MCAP well-known profiles
(mcap.dev/spec/registry):

Design notes: ARCHITECTURE.md, `sim/recording.py`."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any, BinaryIO, Protocol, TYPE_CHECKING

import numpy as np
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

#: Topics recorded, with their message types (ROS 2 names), in channel order.
TOPICS: tuple[tuple[str, str], ...] = (
    ("/map", "nav_msgs/msg/OccupancyGrid"),
    ("/tf", "tf2_msgs/msg/TFMessage"),
    ("/odom", "nav_msgs/msg/Odometry"),
    ("/scan", "sensor_msgs/msg/LaserScan"),
    ("/goal", "geometry_msgs/msg/PoseStamped"),
    ("/cmd_vel", "geometry_msgs/msg/Twist"),
    ("/gwendolen_control", "std_msgs/msg/Bool"),
    ("/cmd_vel_filtered", "geometry_msgs/msg/Twist"),
    ("/ground_truth/pose", "geometry_msgs/msg/PoseStamped"),
    ("/ground_truth/clearance", "std_msgs/msg/Float64"),
)

#: Publishing node of each topic (ROS 1 ``callerid`` metadata).
CALLERS = {
    "/map": "/map_server", "/tf": "/sim", "/odom": "/scout_base",
    "/scan": "/pointcloud_to_laserscan",
    "/goal": "/inspection_navigation", "/cmd_vel": "/move_base",
    "/gwendolen_control": "/gwendolen_agent", "/cmd_vel_filtered": "/cmd_vel_interceptor_node",
    "/ground_truth/pose": "/sim", "/ground_truth/clearance": "/sim",
}

_TF_MSG = "geometry_msgs/TransformStamped[] transforms"


def make_typestore(ros1: bool) -> Typestore:
    """The rosbags typestore for ROS 1 Noetic (``ros1=True``) or ROS 2 Humble, with
    ``tf2_msgs/msg/TFMessage`` registered where the store lacks it (Noetic)."""
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    if "tf2_msgs/msg/TFMessage" not in ts.types:
        ts.register(get_types_from_msg(_TF_MSG, "tf2_msgs/msg/TFMessage"))
    return ts


def yaw_to_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion ``(x, y, z, w)`` of a rotation by ``yaw`` rad about z (REP 103)."""
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


class MessageFactory:
    """Builds rosbags message objects for one ROS version and serializes them.

    All ``stamp_ns`` arguments are int ns since the epoch; poses are ``(x, y, yaw)`` in m, rad.
    """

    def __init__(self, ros1: bool = False):
        self.ros1 = ros1
        self.ts = make_typestore(ros1)
        self.T = self.ts.types
        self._seq: dict[str, int] = {}

    # ---------------------------------------------------------------- primitives
    def time(self, stamp_ns: int) -> Any:
        """``builtin_interfaces/Time`` (ROS 1 ``time``) for ``stamp_ns``."""
        return self.T["builtin_interfaces/msg/Time"](sec=int(stamp_ns // 1_000_000_000),
                                                      nanosec=int(stamp_ns % 1_000_000_000))

    def header(self, stamp_ns: int, frame_id: str, seq_key: str = "") -> Any:
        """``std_msgs/Header``; in ROS 1 ``seq`` counts up per ``seq_key`` (per publisher)."""
        H = self.T["std_msgs/msg/Header"]
        if self.ros1:
            seq = self._seq.get(seq_key, 0)
            self._seq[seq_key] = seq + 1
            return H(seq=seq, stamp=self.time(stamp_ns), frame_id=frame_id)
        return H(stamp=self.time(stamp_ns), frame_id=frame_id)

    def vector3(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
        """``geometry_msgs/Vector3``."""
        return self.T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def pose(self, x: float, y: float, yaw: float) -> Any:
        """``geometry_msgs/Pose`` in the plane."""
        qx, qy, qz, qw = yaw_to_quaternion(yaw)
        return self.T["geometry_msgs/msg/Pose"](
            position=self.T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0),
            orientation=self.T["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw))

    # ---------------------------------------------------------------- messages
    def twist(self, v: float, w: float) -> Any:
        """``geometry_msgs/Twist`` with ``linear.x = v`` m/s and ``angular.z = w`` rad/s."""
        return self.T["geometry_msgs/msg/Twist"](linear=self.vector3(v),
                                                  angular=self.vector3(0, 0, w))

    def bool(self, value: bool) -> Any:
        """``std_msgs/Bool``."""
        return self.T["std_msgs/msg/Bool"](data=bool(value))

    def float64(self, value: float) -> Any:
        """``std_msgs/Float64``."""
        return self.T["std_msgs/msg/Float64"](data=float(value))

    def pose_stamped(self, stamp_ns: int, frame_id: str, x: float, y: float, yaw: float,
                     seq_key: str) -> Any:
        """``geometry_msgs/PoseStamped``."""
        return self.T["geometry_msgs/msg/PoseStamped"](
            header=self.header(stamp_ns, frame_id, seq_key), pose=self.pose(x, y, yaw))

    def transform(self, stamp_ns: int, parent: str, child: str, x: float, y: float, yaw: float) -> Any:
        """``geometry_msgs/TransformStamped`` of ``child`` in ``parent``."""
        qx, qy, qz, qw = yaw_to_quaternion(yaw)
        return self.T["geometry_msgs/msg/TransformStamped"](
            header=self.header(stamp_ns, parent, "tf:" + child),
            child_frame_id=child,
            transform=self.T["geometry_msgs/msg/Transform"](
                translation=self.vector3(x, y, 0.0),
                rotation=self.T["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw)))

    def tf(self, transforms: Sequence) -> Any:
        """``tf2_msgs/TFMessage``."""
        return self.T["tf2_msgs/msg/TFMessage"](transforms=list(transforms))

    def odometry(self, stamp_ns: int, x: float, y: float, yaw: float, v: float, w: float,
                 pose_cov: Sequence[float] | np.ndarray, twist_cov: Sequence[float] | np.ndarray
                 ) -> Any:
        """``nav_msgs/Odometry`` (``odom`` -> ``base_link``; twist in ``base_link``);
        covariances are 36-element row-major 6x6 matrices (x, y, z, roll, pitch, yaw)."""
        T = self.T
        return T["nav_msgs/msg/Odometry"](
            header=self.header(stamp_ns, "odom", "/odom"), child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](
                pose=self.pose(x, y, yaw), covariance=np.asarray(pose_cov, dtype=np.float64)),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=self.twist(v, w), covariance=np.asarray(twist_cov, dtype=np.float64)))

    def laser_scan(self, stamp_ns: int, frame_id: str, angle_min: float, angle_max: float,
                   angle_increment: float, scan_time: float, range_min: float,
                   range_max: float, ranges: np.ndarray) -> Any:
        """``sensor_msgs/LaserScan`` with float32 ``ranges`` and no intensities."""
        return self.T["sensor_msgs/msg/LaserScan"](
            header=self.header(stamp_ns, frame_id, "/scan"),
            angle_min=float(angle_min), angle_max=float(angle_max),
            angle_increment=float(angle_increment), time_increment=0.0,
            scan_time=float(scan_time), range_min=float(range_min), range_max=float(range_max),
            ranges=np.asarray(ranges, dtype=np.float32),
            intensities=np.zeros(0, dtype=np.float32))

    def occupancy_grid(self, stamp_ns: int, resolution: float, width: int, height: int,
                       origin_x: float, origin_y: float, data: np.ndarray) -> Any:
        """``nav_msgs/OccupancyGrid`` in ``map`` (``data``: int8, row-major, row 0 at
        ``origin_y``)."""
        T = self.T
        info = T["nav_msgs/msg/MapMetaData"](
            map_load_time=self.time(stamp_ns), resolution=float(resolution), width=int(width),
            height=int(height), origin=self.pose(origin_x, origin_y, 0.0))
        return T["nav_msgs/msg/OccupancyGrid"](
            header=self.header(stamp_ns, "map", "/map"), info=info,
            data=np.ascontiguousarray(data, dtype=np.int8).ravel())

    def serialize(self, msg: Any, typename: str) -> bytes:  # a rosbags message
        """Wire bytes of ``msg`` (CDR for ROS 2, ROS 1 serialization for ROS 1)."""
        if self.ros1:
            return bytes(self.ts.serialize_ros1(msg, typename))
        return bytes(self.ts.serialize_cdr(msg, typename))


def schema_name(typename: str, ros1: bool) -> str:
    """MCAP schema name: ``pkg/msg/Type`` (ROS 2) or ``pkg/Type`` (ROS 1)."""
    return typename.replace("/msg/", "/") if ros1 else typename


class Recorder(Protocol):
    """What a simulation writes its messages to (:class:`McapRecorder`, or
    :class:`fretc.sim.serve.ServeRecorder` live): its ``factory`` and :meth:`write`."""

    factory: MessageFactory
    counts: dict[str, int]  # messages per topic

    def write(self, topic: str, log_time_ns: int, msg: Any) -> None:
        """Add the message ``msg`` on ``topic`` at ``log_time_ns``."""


class McapRecorder:
    """Writes messages to an MCAP file (see the module docstring).

    ``compression`` is ``"zstd"`` (default) or ``"lz4"``. Messages must be written in
    non-decreasing ``log_time`` (the simulation produces them so).
    Raises ``ValueError`` for an unknown topic or compression, or for a time going backwards.
    """

    def __init__(self, stream: BinaryIO, ros1: bool = False, compression: str = "zstd",
                 topics: Iterable[tuple[str, str]] = TOPICS, chunk_size: int = 1 << 20):
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                "none": CompressionType.NONE}.get(compression)
        if comp is None:
            raise ValueError(f"unknown compression {compression!r}")
        self.ros1 = ros1
        self.factory = MessageFactory(ros1)
        self.writer = Writer(stream, chunk_size=chunk_size, compression=comp)
        self.writer.start(profile="ros1" if ros1 else "ros2", library="fretc-sim")
        self.channels: dict[str, tuple[int, str]] = {}
        self.counts: dict[str, int] = {}
        self.last_time = -1
        ts = self.factory.ts
        schemas: dict[str, int] = {}
        for topic, typename in topics:
            if typename not in schemas:
                text, md5 = ts.generate_msgdef(typename, ros_version=1 if ros1 else 2)
                schemas[typename] = self.writer.register_schema(
                    name=schema_name(typename, ros1),
                    encoding="ros1msg" if ros1 else "ros2msg",
                    data=text.encode("utf-8"))
            if ros1:
                md5 = ts.generate_msgdef(typename, ros_version=1)[1]
                meta = {"md5sum": md5, "callerid": CALLERS.get(topic, "/sim")}
                if topic == "/map":
                    meta["latching"] = "1"
            else:
                meta = {}
            cid = self.writer.register_channel(
                topic=topic, message_encoding="ros1" if ros1 else "cdr",
                schema_id=schemas[typename], metadata=meta)
            self.channels[topic] = (cid, typename)
            self.counts[topic] = 0

    def write(self, topic: str, log_time_ns: int, msg: Any) -> None:
        """Serialize ``msg`` and add it on ``topic`` at ``log_time_ns`` (= publish time)."""
        # same checks as sim.serve.ServeRecorder.write (kept: two small recorders, a file and a
        # live server)
        if topic not in self.channels:
            raise ValueError(f"unknown topic {topic}")
        if log_time_ns < self.last_time:
            raise ValueError("log times must not decrease")
        self.last_time = log_time_ns
        cid, typename = self.channels[topic]
        data = self.factory.serialize(msg, typename)
        self.writer.add_message(channel_id=cid, log_time=int(log_time_ns), data=data,
                                publish_time=int(log_time_ns), sequence=self.counts[topic])
        self.counts[topic] += 1

    def metadata(self, name: str, data: dict[str, str]) -> None:
        """Add an MCAP Metadata record ``name`` with the string map ``data`` (MCAP spec:
        Metadata, name and key/value strings), where the run describes its fault injections
        (:mod:`fretc.sim.simulation`)."""
        self.writer.add_metadata(name, dict(data))

    def finish(self) -> None:
        """Write the summary and footer."""
        self.writer.finish()
