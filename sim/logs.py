"""Read a recorded run back, and evaluate the Safe-ROS requirements on it.

Reading uses only the file: ``mcap``'s reader, and ``rosbags`` deserializers whose types are
built from the schemas embedded in the log (``get_types_from_msg``), so ROS 1 and ROS 2
recordings from any tool decode the same way.

Design notes: ARCHITECTURE.md, `sim/logs.py`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

#: Requirement texts (requirements/safe_ros.fret).
REQUIREMENTS = {
    "R1": "whenever too_close agilex_agent shall eventually satisfy stopped",
    "R2": "upon too_close agilex_agent shall within 1 second satisfy stopped",
    "R3": "whenever stop_requested cmd_vel_interceptor shall immediately satisfy forwarded_zero",
    "R4": "the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5",
    "R5": "the scout_mini shall always satisfy clearance > 0",
    "R6": "whenever scan_stale safety_system shall within 500 milliseconds satisfy "
          "stop_requested",
}


@dataclass
class RecordedLog:
    """A decoded log: ``profile`` (``ros1``/``ros2``), ``messages[topic]`` = list of
    ``(log_time_ns, publish_time_ns, msg)`` in file order, ``schemas[topic]`` = schema name,
    and the raw log times in file order (``order``: list of ``(topic, log_time_ns)``)."""

    profile: str
    messages: dict[str, list[tuple[int, int, object]]]
    schemas: dict[str, str]
    encodings: dict[str, tuple[str, str]]
    order: list[tuple[str, int]]

    def times(self, topic: str) -> np.ndarray:
        """Log times (s since the epoch, float64) of ``topic``."""
        return np.array([m[0] for m in self.messages.get(topic, [])], dtype=np.int64) / 1e9

    @property
    def start_ns(self) -> int:
        """First log time (ns)."""
        return min(t for _, t in self.order)

    @property
    def end_ns(self) -> int:
        """Last log time (ns)."""
        return max(t for _, t in self.order)


def read_log(path: str | Path) -> RecordedLog:
    """Decode every message of the MCAP file at ``path``.

    Raises ``ValueError`` for a profile other than ``ros1``/``ros2`` or an unknown schema
    encoding, and whatever ``mcap`` raises for a corrupt file."""
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        header = reader.get_header()
        profile = header.profile
        if profile not in ("ros1", "ros2"):
            raise ValueError(f"unsupported MCAP profile {profile!r}")
        ts = get_typestore(Stores.EMPTY)
        registered = {}
        messages: dict[str, list] = {}
        schemas: dict[str, str] = {}
        encodings: dict[str, tuple[str, str]] = {}
        order = []
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema is not None  # (the simulator's channels have their schemas)
            if schema.id not in registered:
                if schema.encoding not in ("ros1msg", "ros2msg"):
                    raise ValueError(f"unsupported schema encoding {schema.encoding!r}")
                name = schema.name
                typename = name if "/msg/" in name else name.replace("/", "/msg/", 1)
                ts.register(get_types_from_msg(schema.data.decode("utf-8"), typename))
                registered[schema.id] = typename
            typename = registered[schema.id]
            if channel.message_encoding == "cdr":
                msg = ts.deserialize_cdr(message.data, typename)
            elif channel.message_encoding == "ros1":
                msg = ts.deserialize_ros1(message.data, typename)
            else:
                raise ValueError(f"unsupported message encoding {channel.message_encoding!r}")
            messages.setdefault(channel.topic, []).append(
                (message.log_time, message.publish_time, msg))
            schemas[channel.topic] = schema.name
            encodings[channel.topic] = (schema.encoding, channel.message_encoding)
            order.append((channel.topic, message.log_time))
    return RecordedLog(profile, messages, schemas, encodings, order)


def min_valid(ranges: Sequence[float] | np.ndarray, range_min: float, range_max: float) -> float:
    """Minimum valid LaserScan range (m) under REP 117 (see module docstring); ``inf`` if
    none is valid."""
    r = np.asarray(ranges, dtype=np.float64)
    ok = np.isfinite(r) & (r >= range_min) & (r <= range_max)
    m = float(r[ok].min()) if ok.any() else math.inf
    if np.isneginf(r).any():
        m = min(m, float(range_min))
    return m


def _hold(times_ns: np.ndarray, values: np.ndarray, ticks_ns: np.ndarray, default):
    idx = np.searchsorted(times_ns, ticks_ns, side="right") - 1
    out = np.empty(len(ticks_ns), dtype=np.asarray(values).dtype if len(values) else float)
    vals = np.asarray(values)
    has = idx >= 0
    if len(vals):
        out[has] = vals[idx[has]]
    out[~has] = default
    return out


def signals(log: RecordedLog, threshold: float = 0.9, tick_s: float = 0.1,
            stale_s: float = 0.3) -> dict[str, np.ndarray]:
    """The requirement variables sampled at every tick (see module docstring): arrays of
    equal length keyed ``t`` (s from the first message), ``too_close``, ``stopped``,
    ``stop_requested``, ``forwarded_zero``, ``linear_speed``, ``angular_speed``,
    ``clearance``, ``scan_stale``, ``min_range``."""
    t0, t1 = log.start_ns, log.end_ns
    step = int(round(tick_s * 1e9))
    ticks = np.arange(t0, t1 + 1, step, dtype=np.int64)

    def series(topic, fn):
        ms = log.messages.get(topic, [])
        return (np.array([m[0] for m in ms], dtype=np.int64), np.array([fn(m[2]) for m in ms]))

    st, smin = series("/scan", lambda s: min_valid(s.ranges, s.range_min, s.range_max))
    ft, fv = series("/cmd_vel_filtered", lambda m: (m.linear.x, m.linear.y, m.linear.z,
                                                     m.angular.x, m.angular.y, m.angular.z))
    gt, gv = series("/gwendolen_control", lambda m: bool(m.data))
    ct, cv = series("/ground_truth/clearance", lambda m: float(m.data))
    min_range = _hold(st, smin, ticks, math.inf)
    fv = fv.reshape(-1, 6) if fv.size else np.zeros((0, 6))
    lin = np.abs(_hold(ft, fv[:, 0], ticks, 0.0)) if len(ft) else np.zeros(len(ticks))
    ang = np.abs(_hold(ft, fv[:, 5], ticks, 0.0)) if len(ft) else np.zeros(len(ticks))
    allzero = (np.all(fv == 0.0, axis=1) if len(ft) else np.zeros(0, bool))
    fz = _hold(ft, allzero, ticks, True).astype(bool) if len(ft) else np.ones(len(ticks), bool)
    sr = _hold(gt, gv, ticks, False).astype(bool) if len(gt) else np.zeros(len(ticks), bool)
    clr = _hold(ct, cv, ticks, math.inf) if len(ct) else np.full(len(ticks), math.inf)
    if len(st):
        idx = np.searchsorted(st, ticks, side="right") - 1
        stale = (idx < 0) | ((ticks - st[np.maximum(idx, 0)]) > int(round(stale_s * 1e9)))
    else:
        stale = np.ones(len(ticks), bool)
    return {
        "t": (ticks - t0) / 1e9, "too_close": min_range < threshold,
        "stopped": (lin < 1e-3) & (ang < 1e-3), "stop_requested": sr, "forwarded_zero": fz,
        "linear_speed": lin, "angular_speed": ang, "clearance": clr, "scan_stale": stale,
        "min_range": min_range,
    }


@dataclass
class Verdict:
    """``ok`` (satisfied on the whole log), ``vacuous`` (the trigger never held), the first
    violating tick time ``t_fail`` (s from the start) and the number of triggering ticks."""

    ok: bool
    vacuous: bool
    t_fail: float
    triggers: int

    def text(self) -> str:
        """Short cell text for a table."""
        if not self.ok:
            return f"violated (t={self.t_fail:.1f} s)"
        return "satisfied (vacuous)" if self.vacuous else "satisfied"


def _whenever_within(trig, resp, n, t):
    """Every tick with ``trig`` has ``resp`` within ``n`` ticks (``n=None``: before the end)."""
    N = len(trig)
    if n is None:
        # suffix-or: is there a resp at or after i?
        later = np.flip(np.logical_or.accumulate(np.flip(resp)))
        bad = trig & ~later
    else:
        cs = np.concatenate([[0], np.cumsum(resp.astype(np.int64))])
        hi = np.minimum(np.arange(N) + n + 1, N)
        bad = trig & ((cs[hi] - cs[np.arange(N)]) == 0)
    fail = np.nonzero(bad)[0]
    return Verdict(ok=fail.size == 0, vacuous=not trig.any(),
                   t_fail=float(t[fail[0]]) if fail.size else math.nan,
                   triggers=int(trig.sum()))


def expected_verdicts(log: RecordedLog, threshold: float = 0.9) -> dict[str, Verdict]:
    """R1-R6 on ``log`` under the reference conventions of the module docstring."""
    s = signals(log, threshold)
    t = s["t"]
    tc = s["too_close"]
    rise = tc & ~np.concatenate([[False], tc[:-1]])
    always = np.ones(len(t), bool)
    return {
        "R1": _whenever_within(tc, s["stopped"], None, t),
        "R2": _whenever_within(rise, s["stopped"], 10, t),
        "R3": _whenever_within(s["stop_requested"], s["forwarded_zero"], 0, t),
        "R4": _whenever_within(always, (s["linear_speed"] <= 0.5) & (s["angular_speed"] <= 0.5),
                               0, t),
        "R5": _whenever_within(always, s["clearance"] > 0, 0, t),
        "R6": _whenever_within(s["scan_stale"], s["stop_requested"], 5, t),
    }


def counts(path: str | Path) -> dict[str, int]:
    """Messages per topic from the MCAP summary (statistics record)."""
    with open(path, "rb") as fh:
        summ = make_reader(fh).get_summary()
    assert summ is not None and summ.statistics is not None  # (the simulator writes them)
    by_id = {cid: ch.topic for cid, ch in summ.channels.items()}
    return {by_id[cid]: n for cid, n in summ.statistics.channel_message_counts.items()}
