"""The columnar CDR decoder (logs/ros/columnar.py) against the per-message selective
decoder, its reference: the same values wherever it reads a group, and no group read that the
selective fast path would not read.

* hypothesis: random messages of Bool, Twist, Odometry, LaserScan and a type built to stress
  the alignment rules (strings of every length mod 4 before 8-byte fields, empty and
  non-empty sequences before 8-byte fields, fixed arrays, nested messages), serialized by
  rosbags, laid one after another at random offsets in one buffer, random subsets of fields;
* the same groups with bytes flipped or cut: where the columnar decoder still reads a group,
  every message of it is read by the selective fast path with the same values;
* big-endian CDR, non-ASCII strings, LaserScans of different lengths: not read (None);
* the columnar MCAP pass (logs/mcap/columns.py) against the per-message pass, on
  every shipped trace, bit-flipped copies and a log with big-endian, malformed and odd-length
  scans: the same messages per topic in the same order, the same columns as the sampler
  builds from the messages, the same damage, problems and counts.
"""

from __future__ import annotations

import random
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from fretc.signals.bindings.extract import Valid
from fretc.signals.columns import SegmentList, _plain_column
from fretc.logs import open_log
from fretc.logs.ros.columnar import RANGES, columnar_decoder
from fretc.logs.ros.selective import selective_decoder

STRESS = """
string label
float64 a
uint8[] bytes_before
float64 b
float32[3] fixed
Inner inner
int16 small
bool flag
float64[] doubles
uint32 last
"""
INNER = """
string name
float64 x
bool on
"""

STORE = get_typestore(Stores.ROS2_HUMBLE)
STORE.register({**get_types_from_msg(INNER, "test_msgs/msg/Inner"),
                **get_types_from_msg(STRESS.replace("Inner", "test_msgs/Inner"),
                                     "test_msgs/msg/Stress")})
T = STORE.types
FLOATS = st.floats(width=32, allow_nan=True)
TEXT = st.text(alphabet="abcdefgh_/", max_size=9)


def _header(draw):
    stamp = T["builtin_interfaces/msg/Time"](draw(st.integers(0, 2**31 - 1)),
                                             draw(st.integers(0, 10**9 - 1)))
    return T["std_msgs/msg/Header"](stamp, draw(TEXT))


def _vec(draw, cls="geometry_msgs/msg/Vector3"):
    return T[cls](*(draw(FLOATS) for _ in range(3)))


@st.composite
def messages(draw, typename: str, beams: int):
    """One message of ``typename`` (LaserScan: ``beams`` ranges)."""
    if typename == "std_msgs/msg/Bool":
        return T[typename](draw(st.booleans()))
    if typename == "geometry_msgs/msg/Twist":
        return T[typename](_vec(draw), _vec(draw))
    if typename == "sensor_msgs/msg/LaserScan":
        arr = np.array(draw(st.lists(FLOATS, min_size=beams, max_size=beams)), np.float32)
        inten = np.array(draw(st.lists(FLOATS, max_size=3)), np.float32)
        return T[typename](_header(draw), *(draw(FLOATS) for _ in range(7)), arr, inten)
    if typename == "nav_msgs/msg/Odometry":
        pose = T["geometry_msgs/msg/Pose"](_vec(draw, "geometry_msgs/msg/Point"),
                                           T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0))
        cov = np.zeros(36)
        return T[typename](
            _header(draw), draw(TEXT), T["geometry_msgs/msg/PoseWithCovariance"](pose, cov),
            T["geometry_msgs/msg/TwistWithCovariance"](
                T["geometry_msgs/msg/Twist"](_vec(draw), _vec(draw)), cov))
    inner = T["test_msgs/msg/Inner"](draw(TEXT), draw(FLOATS), draw(st.booleans()))
    return T[typename](
        draw(TEXT), draw(FLOATS), np.array(draw(st.lists(st.integers(0, 255), max_size=5)),
                                           np.uint8),
        draw(FLOATS), np.array([draw(FLOATS) for _ in range(3)], np.float32), inner,
        draw(st.integers(-2**15, 2**15 - 1)), draw(st.booleans()),
        np.array(draw(st.lists(FLOATS, max_size=3)), np.float64), draw(st.integers(0, 2**32 - 1)))


#: type -> the field paths a binding may read
FIELDS = {
    "std_msgs/msg/Bool": [("data",)],
    "geometry_msgs/msg/Twist": [("linear", "x"), ("linear", "y"), ("angular", "z")],
    "sensor_msgs/msg/LaserScan": [RANGES, ("angle_min",), ("header", "stamp", "sec")],
    "nav_msgs/msg/Odometry": [("twist", "twist", "linear", "x"), ("pose", "pose", "position", "y")],
    "test_msgs/msg/Stress": [("a",), ("b",), ("inner", "x"), ("inner", "on"), ("small",),
                             ("flag",), ("last",), ("fixed",), ("doubles",)],
}


def _layout(raws: list[bytes], gaps: list[int]):
    """The messages one after another in one buffer, ``gaps`` bytes of junk before each."""
    parts, starts, at = [], [], 0
    for raw, gap in zip(raws, gaps):
        parts.append(b"\xa5" * gap)
        at += gap
        starts.append(at)
        parts.append(raw)
        at += len(raw)
    buf = np.frombuffer(b"".join(parts), np.uint8)
    return buf, np.array(starts, np.int64), np.array([len(r) for r in raws], np.int64)


def _reference(typename, paths, raws):
    """Per message: the selective fast path's object (None: the fast path does not read it)."""
    dec = selective_decoder(STORE, typename, "cdr", paths,
                            lambda raw: STORE.deserialize_cdr(raw, typename))
    out = []
    for raw in raws:
        try:
            out.append(dec.fast(raw))
        except Exception:  # noqa: BLE001 - any failure of the fast path
            out.append(None)
    return out


def _value(obj, path):
    for p in path:
        obj = getattr(obj, p)
    return obj


def _assert_same(typename, paths, raws, cols):
    """``cols`` (not None) holds, for every gathered path, the selective decoder's values."""
    ref = _reference(typename, paths, raws)
    assert all(r is not None for r in ref), "a group read that the fast path does not read"
    for path, col in cols.items():
        values = [_value(r, path) for r in ref]
        if path == RANGES:
            want = np.array(values, dtype=np.float32).reshape(len(raws), -1)
            assert col.shape == want.shape
            assert np.array_equal(col, want, equal_nan=True)
            continue
        want = np.array(values)
        want = want if want.dtype == np.bool_ else want.astype(np.float64)
        assert col.dtype == want.dtype
        assert np.array_equal(col, want, equal_nan=True), path


@st.composite
def groups(draw):
    typename = draw(st.sampled_from(sorted(FIELDS)))
    beams = draw(st.integers(0, 6))
    msgs = draw(st.lists(messages(typename, beams), min_size=1, max_size=6))
    paths = draw(st.sets(st.sampled_from(FIELDS[typename]), min_size=1))
    gaps = draw(st.lists(st.integers(0, 7), min_size=len(msgs), max_size=len(msgs)))
    return typename, msgs, paths, gaps


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(groups())
def test_columns_equal_the_selective_decoder(group):
    typename, msgs, paths, gaps = group
    raws = [bytes(STORE.serialize_cdr(m, typename)) for m in msgs]
    dec = columnar_decoder(STORE, typename, "cdr", paths)
    assert dec is not None
    cols = dec.decode(*_layout(raws, gaps))
    assert cols is not None, "a well-formed group (ASCII, one scan length) is read"
    _assert_same(typename, paths, raws, cols)
    # every bound number is gathered (fixed arrays and sequences other than ranges are read
    # from the messages)
    assert set(cols) >= set(paths) - {("fixed",), ("doubles",)}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(groups(), st.data())
def test_damaged_groups_are_read_only_as_the_fast_path_reads_them(group, data):
    typename, msgs, paths, gaps = group
    raws = [bytearray(STORE.serialize_cdr(m, typename)) for m in msgs]
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(raws) - 1))
        if data.draw(st.booleans()) and len(raws[i]) > 1:
            del raws[i][data.draw(st.integers(1, len(raws[i]) - 1)):]
        else:
            k = data.draw(st.integers(0, len(raws[i]) - 1))
            raws[i][k] ^= 1 << data.draw(st.integers(0, 7))
    raws = [bytes(r) for r in raws]
    cols = columnar_decoder(STORE, typename, "cdr", paths).decode(*_layout(raws, gaps))
    if cols is not None:
        _assert_same(typename, paths, raws, cols)


def _scan(frame_id: str, beams: int):
    h = T["std_msgs/msg/Header"](T["builtin_interfaces/msg/Time"](1, 2), frame_id)
    return T["sensor_msgs/msg/LaserScan"](h, 0.0, 1.0, 0.1, 0.0, 0.1, 0.05, 10.0,
                                         np.arange(beams, dtype=np.float32),
                                         np.zeros(0, np.float32))


@pytest.mark.parametrize("case", ["big_endian", "non_ascii", "ragged_ranges", "padding",
                                  "no_nul"])
def test_unexpected_groups_are_left_to_the_per_message_decoder(case):
    typename = "sensor_msgs/msg/LaserScan"
    msgs = [_scan("laser", 4), _scan("laser", 4)]
    if case == "non_ascii":
        msgs[1] = _scan("läser", 4)
    if case == "ragged_ranges":
        msgs[1] = _scan("laser", 5)
    raws = [bytes(STORE.serialize_cdr(m, typename, little_endian=case != "big_endian"))
            for m in msgs]
    if case == "padding":  # 4 bytes past the last field: more than CDR's 3 of padding
        raws[1] += b"\0\0\0\0"
    if case == "no_nul":  # frame_id "laser" without its terminator (at 4 + 8 + 4 + 5)
        raws[1] = raws[1][:21] + b"x" + raws[1][22:]
    dec = columnar_decoder(STORE, typename, "cdr", [RANGES])
    assert dec.decode(*_layout(raws, [0, 3])) is None
    # the selective decoder reads them (through rosbags where its fast path does not)
    sel = selective_decoder(STORE, typename, "cdr", [RANGES],
                            lambda raw: STORE.deserialize_cdr(raw, typename))
    if case not in ("padding", "no_nul"):
        assert [list(sel(r).ranges) for r in raws] == [list(m.ranges) for m in msgs]


def test_not_covered_types_give_no_columnar_decoder():
    # a sequence of messages (TFMessage's transforms), ROS 1 messages, the header time base
    assert columnar_decoder(STORE, "tf2_msgs/msg/TFMessage", "cdr", [("transforms",)]) is None
    assert columnar_decoder(STORE, "std_msgs/msg/Bool", "ros1", [("data",)]) is None
    assert columnar_decoder(STORE, "std_msgs/msg/Bool", "cdr", None) is None


# --------------------------------------------------------------------------- the MCAP pass
ROOT = Path(__file__).resolve().parents[2]
TRACES = sorted((ROOT / "traces").glob("*.mcap"))
#: the Safe-ROS bindings' fields (the audit's wanted fields of the shipped traces)
TRACE_FIELDS = {"/scan": {RANGES}, "/gwendolen_control": {("data",)},
                "/cmd_vel_filtered": {("linear", "x"), ("angular", "z")},
                "/ground_truth/clearance": {("data",)},
                "/odom": {("twist", "twist", "linear", "x")}}


def _passes(path: Path, fields: dict):
    """(per-message pass, columnar pass) of ``path`` reading ``fields``: per topic the log
    times and messages, and the source's damage record; the columnar one None when that pass
    does not apply."""
    wanted = {t: frozenset(p) for t, p in fields.items()}
    out = []
    for columnar in (False, True):
        src = open_log(str(path))
        src._wanted_fields = wanted
        got: dict[str, tuple[list, list]] = {}
        lists: dict[str, SegmentList] = {}
        if columnar:
            released = src.message_blocks(set(fields))
            if released is None:
                return out[0], None
            for blocks in released:
                for topic, log_times, seg in blocks:
                    got.setdefault(topic, ([], []))[0].extend(log_times)
                    lists.setdefault(topic, SegmentList()).add(seg)
            for topic, msgs in lists.items():
                got[topic][1].extend(msgs)
        else:
            for m in src.messages(set(fields)):
                times, data = got.setdefault(m.topic, ([], []))
                times.append(m.log_time)
                data.append(m.data)
        record = (src.problems, src.counts, src.records, src.partial, src.damage_time,
                  src.gaps, src.intact_end)
        out.append((got, lists, record))
    return out[0], out[1]


def _assert_same_pass(path: Path, fields: dict) -> bool:
    ref, col = _passes(path, fields)
    if col is None:
        return False
    assert col[2] == ref[2], "damage, problems and counts"
    assert set(col[0]) == set(ref[0])
    for topic, (times, data) in ref[0].items():
        ctimes, cdata = col[0][topic]
        assert ctimes == times, topic
        for path_ in fields[topic]:
            want = [_value(d, path_) for d in data]
            got = [_value(d, path_) for d in cdata]
            assert len(got) == len(want)
            assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(got, want)), path_
            column = col[1][topic].column(path_)
            if column is not None:  # what the sampler reads: the columns of the messages
                plain = _plain_column(data, path_)
                if isinstance(plain, Valid):
                    assert np.array_equal(column.data, plain.data, equal_nan=True)
                    assert np.array_equal(column.mask, plain.mask)
                else:
                    assert np.array_equal(column, plain, equal_nan=True)
    return True


@pytest.mark.parametrize("log", TRACES, ids=lambda p: p.name)
def test_the_columnar_pass_gives_the_messages_of_the_per_message_pass(log):
    fields = {t: p for t, p in TRACE_FIELDS.items() if t in open_log(str(log)).topics()}
    applies = _assert_same_pass(log, fields)
    assert applies == (log.name != "nominal_ros1.mcap")  # ROS 1 messages: one by one


@pytest.mark.parametrize("seed", range(12))
def test_damaged_copies_give_the_same_damage_and_messages(tmp_path, seed):
    rng = random.Random(seed)
    log = TRACES[seed % len(TRACES)]
    data = bytearray(log.read_bytes())
    for _ in range(1 + seed % 4):  # bit flips, mostly in chunks (a gap each)
        i = rng.randrange(len(data) * 9 // 10)
        data[i] ^= 1 << rng.randrange(8)
    copy = tmp_path / log.name
    copy.write_bytes(bytes(data))
    fields = {t: p for t, p in TRACE_FIELDS.items() if t in open_log(str(log)).topics()}
    _assert_same_pass(copy, fields)


def _scans_log(path: Path, odd: dict[int, bytes]) -> None:
    """An MCAP file of 40 LaserScans on /scan and 40 Bools on /b in chunks of ~1 kB, where
    message ``k`` of /scan is replaced by ``odd[k]``."""
    schema = ("std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n"
              "float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n"
              "float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n"
              "================================================================================\n"
              "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
              "================================================================================\n"
              "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1024, compression=CompressionType.ZSTD)
        w.start("ros2", "fretc-test")
        sid = w.register_schema("sensor_msgs/msg/LaserScan", "ros2msg", schema.encode())
        bid = w.register_schema("std_msgs/msg/Bool", "ros2msg", b"bool data")
        scan = w.register_channel("/scan", "cdr", sid)
        flag = w.register_channel("/b", "cdr", bid)
        for k in range(40):
            t = 10**9 + k * 10**8
            raw = odd.get(k, bytes(STORE.serialize_cdr(_scan("laser", 3), _LASER)))
            w.add_message(scan, log_time=t, data=raw, publish_time=t, sequence=k)
            w.add_message(flag, log_time=t + (k % 3 - 1) * 10**8 // 2, data=bytes(
                STORE.serialize_cdr(T["std_msgs/msg/Bool"](k % 2 == 0), "std_msgs/msg/Bool")),
                publish_time=t)
        w.finish()


_LASER = "sensor_msgs/msg/LaserScan"


def test_groups_the_columnar_decoder_leaves_are_decoded_one_by_one(tmp_path):
    big = bytes(STORE.serialize_cdr(_scan("laser", 3), _LASER, little_endian=False))
    odd = {5: big, 17: b"\x00\x01\x00\x00\x01", 30: bytes(STORE.serialize_cdr(_scan("l", 4),
                                                                              _LASER))}
    path = tmp_path / "odd.mcap"
    _scans_log(path, odd)
    fields = {"/scan": {RANGES, ("angle_max",)}, "/b": {("data",)}}
    assert _assert_same_pass(path, fields)
    ref, _col = _passes(path, fields)
    assert [p.kind for p in ref[2][0]] == ["undecodable"]  # message 17; 5 is rosbags'
    assert len(ref[0]["/scan"][0]) == 39
