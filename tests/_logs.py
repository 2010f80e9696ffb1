"""Helpers for the signal-layer tests: small logs written with mcap + rosbags serialization."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any
from collections.abc import Iterable

import numpy as np
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

from _shared import SHARED  # the real logs below: their tests are marked needs_shared

ROS2 = get_typestore(Stores.ROS2_HUMBLE)
ROS1 = get_typestore(Stores.ROS1_NOETIC)
LOGS = SHARED / "data" / "logs"
CMD_VEL_MCAP = LOGS / "cmd_vel_scaled.mcap"
STAGE_BAG = LOGS / "stage_mapping1.bag"
MS = 1_000_000
S = 1_000_000_000


def T(store: Any, name: str) -> Any:
    return store.types[name]


def stamp(ns: int, store: Any = ROS2) -> Any:
    return T(store, "builtin_interfaces/msg/Time")(sec=ns // S, nanosec=ns % S)


def header(ns: int, store: Any = ROS2, frame: str = "base") -> Any:
    H = T(store, "std_msgs/msg/Header")
    if store is ROS1:
        return H(seq=0, stamp=stamp(ns, store), frame_id=frame)
    return H(stamp=stamp(ns, store), frame_id=frame)


def vec3(x: float = 0.0, y: float = 0.0, z: float = 0.0, store: Any = ROS2) -> Any:
    return T(store, "geometry_msgs/msg/Vector3")(x=float(x), y=float(y), z=float(z))


def twist(x: float = 0.0, z: float = 0.0, store: Any = ROS2) -> Any:
    return T(store, "geometry_msgs/msg/Twist")(linear=vec3(x, store=store), angular=vec3(z=z, store=store))


def twist_stamped(ns: int, x: float = 0.0, z: float = 0.0, store: Any = ROS2) -> Any:
    return T(store, "geometry_msgs/msg/TwistStamped")(header=header(ns, store), twist=twist(x, z, store))


def boolean(v: bool, store: Any = ROS2) -> Any:
    return T(store, "std_msgs/msg/Bool")(data=bool(v))


def float64(v: float, store: Any = ROS2) -> Any:
    return T(store, "std_msgs/msg/Float64")(data=float(v))


def scan(ranges: Iterable[float], ns: int = 0, range_min: float = 0.1, range_max: float = 10.0,
         store: Any = ROS2) -> Any:
    r = np.asarray(list(ranges), dtype=np.float32)
    return T(store, "sensor_msgs/msg/LaserScan")(
        header=header(ns, store, "laser"), angle_min=-1.0, angle_max=1.0,
        angle_increment=2.0 / max(len(r) - 1, 1), time_increment=0.0, scan_time=0.1,
        range_min=range_min, range_max=range_max, ranges=r,
        intensities=np.zeros(len(r), dtype=np.float32))


def write_mcap(path: Path, messages: list[tuple[str, str, int, Any]], *, ros1: bool = False,
               chunk_size: int = 1024 * 1024, compression: CompressionType = CompressionType.ZSTD,
               use_chunking: bool = True, schema_override: dict[str, tuple[str, bytes]] | None = None,
               encoding_override: dict[str, str] | None = None, raw_override: dict[int, bytes] | None = None,
               publish_offset: int = 0) -> Path:
    """Write ``messages`` = [(topic, typename, log_time, msg), ...] in the given order.

    ``schema_override[topic] = (schema_encoding, data)`` and ``encoding_override[topic] =
    message_encoding`` make a channel with a bad schema; ``raw_override[i]`` replaces the
    serialized bytes of message i.
    """
    store = ROS1 if ros1 else ROS2
    schema_override = schema_override or {}
    encoding_override = encoding_override or {}
    raw_override = raw_override or {}
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=compression, use_chunking=use_chunking,
                   enable_crcs=True, enable_data_crcs=True)
        w.start(profile="ros1" if ros1 else "ros2", library="fretc-tests")
        schemas: dict[tuple, int] = {}
        channels: dict[str, int] = {}
        for i, (topic, typename, log_time, msg) in enumerate(messages):
            if topic not in channels:
                if topic in schema_override:
                    enc, data = schema_override[topic]
                    key = (topic, enc)
                else:
                    text = store.generate_msgdef(typename, ros_version=1 if ros1 else 2)[0]
                    enc, data = ("ros1msg" if ros1 else "ros2msg"), text.encode()
                    key = (typename,)
                if key not in schemas:
                    name = typename.replace("/msg/", "/") if ros1 else typename
                    schemas[key] = w.register_schema(name, enc, data)
                menc = encoding_override.get(topic, "ros1" if ros1 else "cdr")
                channels[topic] = w.register_channel(topic, menc, schemas[key])
            if i in raw_override:
                raw = raw_override[i]
            elif ros1:
                raw = bytes(store.serialize_ros1(msg, typename))
            else:
                raw = bytes(store.serialize_cdr(msg, typename))
            w.add_message(channels[topic], log_time=log_time, data=raw,
                          publish_time=log_time + publish_offset, sequence=i)
        w.finish()
    return path


#: bindings of one verdict per tracked object: ``dist`` and ``present`` of the track ``$track``
TRACK_BINDINGS = '''[tick]
period = "100 ms"
[entities]
track = "/tracks.tracks[:].id"
[variables]
dist = 'min(/tracks.tracks[:]{id==$track}.distance)'
present = 'count(/tracks.tracks[:]{id==$track}.distance >= 0) = 1'
'''

#: bindings of one verdict per motor of ``/diagnostics``: ``motor_level`` and ``present``
DIAG_BINDINGS = '''[tick]
period = "100 ms"
[entities]
motor = { key = "/diagnostics.status[:].name", matching = "motor*" }
[variables]
motor_level = 'max(/diagnostics.status[:]{name==$motor}.level)'
present = 'count(/diagnostics.status[:]{name==$motor}.level >= 0) = 1'
'''


def track_types() -> tuple[Any, Any]:
    """The message classes (Track, TrackArray) of ``tracking_msgs``, registered once in ROS2."""
    from rosbags.typesys import get_types_from_msg

    if "tracking_msgs/msg/TrackArray" not in ROS2.types:
        ROS2.register(get_types_from_msg("uint32 id\nfloat64 distance", "tracking_msgs/msg/Track"))
        ROS2.register(get_types_from_msg("tracking_msgs/Track[] tracks",
                                         "tracking_msgs/msg/TrackArray"))
    return ROS2.types["tracking_msgs/msg/Track"], ROS2.types["tracking_msgs/msg/TrackArray"]


def diag_array(statuses: Iterable[tuple[str, int]], hdr: Any = None) -> Any:
    """A ``diagnostic_msgs/DiagnosticArray`` of (name, level) statuses; header stamped 0
    unless ``hdr`` is given."""
    St = T(ROS2, "diagnostic_msgs/msg/DiagnosticStatus")
    Arr = T(ROS2, "diagnostic_msgs/msg/DiagnosticArray")
    return Arr(header=header(0, frame="") if hdr is None else hdr,
               status=[St(level=lvl, name=n, message="", hardware_id="", values=[])
                       for n, lvl in statuses])


@functools.lru_cache(maxsize=8)
def written_plan(folder: str, name: str, requirements: str) -> Any:
    """The audit's plan of ``requirements`` written to ``folder/name`` (cached: a module's
    hypothesis examples share it)."""
    from fretc.audit import AuditConfig, load_plan

    fret = Path(folder) / name
    fret.write_text(requirements, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(fret),)))


def audit_written(tmp_path: Path, name: str, fret: str, bindings: str, log: Any) -> Any:
    """The audit of ``log`` by ``fret`` written to ``tmp_path/name.fret`` beside its
    ``bindings`` (``name.bindings.toml``)."""
    from fretc.audit import AuditConfig, audit_log, load_plan

    (tmp_path / f"{name}.fret").write_text(fret)
    (tmp_path / f"{name}.bindings.toml").write_text(bindings)
    return audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / f"{name}.fret"),))),
                     str(log))


def both_clocks(path: Path, bindings: Any) -> list:
    """The ticks of the watch's clock over the log at ``path``, checked equal to the audit's
    block sampler (NaN equal to NaN)."""
    from fretc.logs import open_log
    from fretc.signals.arrays import sample_arrays
    from fretc.signals.clock import sample

    src = open_log(path)
    ticks = list(sample(src, bindings))
    arr = sample_arrays(src, bindings)
    assert arr.times.tolist() == [t.time for t in ticks]
    for name in bindings.variables:
        got, want = arr.columns[name].tolist(), [t.values[name] for t in ticks]
        assert all((g != g and w != w) or g == w for g, w in zip(got, want)), (name, got, want)
    return ticks


#: the bindings of the synthetic run (/scan, /cmd, /flag) that the audit and report tests share
SYN_BINDINGS = """[tick]
period = "100 ms"
[variables]
near = "min(/scan.ranges) < 0.5"
halted = "abs(/cmd.linear.x) < 1e-3"
speed = "abs(/cmd.linear.x)"
flag = "/flag.data"
"""
