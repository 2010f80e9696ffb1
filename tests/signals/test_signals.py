"""The tick clock: sample-and-hold, per-topic ticks, warm-up, header time, CSV, vectorized path."""

from __future__ import annotations

from pathlib import Path

import math

import numpy as np
import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from fretc.common import problems as P
from fretc.signals.bindings.files import parse_bindings
from fretc.signals.bindings.spec import TickSpec, make_bindings
from fretc.common.problems import SignalError
from fretc.signals.arrays import sample_arrays
from fretc.signals.clock import sample
from fretc.logs import open_log

from _shared import needs_shared
from _logs import (CMD_VEL_MCAP, MS, ROS2, S, STAGE_BAG, boolean, float64, scan, twist_stamped,
                   write_mcap)


def _ab_log(tmp_path: Path) -> Path:
    msgs = [
        ("/a", "std_msgs/msg/Float64", 1000 * MS, float64(1.0)),
        ("/b", "std_msgs/msg/Bool", 1100 * MS, boolean(False)),
        ("/a", "std_msgs/msg/Float64", 1250 * MS, float64(2.0)),
        ("/b", "std_msgs/msg/Bool", 1300 * MS, boolean(True)),
        ("/a", "std_msgs/msg/Float64", 1500 * MS, float64(3.0)),
    ]
    return write_mcap(tmp_path / "ab.mcap", msgs, chunk_size=64)


AB = {"av": "/a.data", "bv": "/b.data", "age_a": "age(/a)", "both": "/b.data & /a.data > 1.5"}


def _equal_paths(src, bindings):
    ticks = list(sample(src, bindings))
    arr = sample_arrays(src, bindings)
    times, cols = arr
    assert times.dtype == np.int64
    assert times.tolist() == [t.time for t in ticks]
    for name in bindings.variables:
        want = [t.values[name] for t in ticks]
        got = cols[name].tolist()
        assert len(got) == len(want)
        three_valued = cols[name].dtype.kind == "f" and any(type(w) is bool for w in want)
        for g, w in zip(got, want):
            if three_valued and type(w) is bool:  # (a boolean column with an unknown tick
                w = float(w)                      # holds 1.0, 0.0 and NaN)
            assert type(g) is type(w), name
            assert g == w or (g != g and w != w), (name, g, w)
    for topic, lts in arr.log_times.items():
        assert lts.tolist() == [t.log_times[topic] for t in ticks]
    return ticks, arr


@pytest.mark.tor("TOR-TCK-002", "TOR-TCK-003", "TOR-TCK-004")
def test_fixed_period_sample_and_hold_with_warmup(tmp_path):
    src = open_log(_ab_log(tmp_path))
    b = make_bindings(AB, TickSpec(period_ns=100 * MS))
    s = sample(src, b)
    ticks = list(s)
    assert s.warmup_ticks == 1 and s.waiting_for == ["/b"] and s.missing_topics == []
    assert s.start_time == 1000 * MS and s.first_time == 1100 * MS and s.end_time == 1500 * MS
    assert [t.index for t in ticks] == [0, 1, 2, 3, 4]
    assert [t.time for t in ticks] == [1100 * MS, 1200 * MS, 1300 * MS, 1400 * MS, 1500 * MS]
    # a message exactly at the tick time is used (≤), later ones are not
    assert [t.values["av"] for t in ticks] == [1.0, 1.0, 2.0, 2.0, 3.0]
    assert [t.values["bv"] for t in ticks] == [False, False, True, True, True]
    assert [t.values["both"] for t in ticks] == [False, False, True, True, True]
    assert [t.values["age_a"] for t in ticks] == [0.1, 0.2, 0.05, 0.15, 0.0]
    assert ticks[2].log_times == {"/a": 1250 * MS, "/b": 1300 * MS}
    _equal_paths(src, b)


@pytest.mark.tor("TOR-TCK-002")
def test_period_not_dividing_the_log(tmp_path):
    src = open_log(_ab_log(tmp_path))
    b = make_bindings({"av": "/a.data"}, TickSpec(period_ns=300 * MS))
    ticks = list(sample(src, b))
    # the multiples of 300 ms from the first message on (1200, 1500 ms), not 1000 + k * 300
    assert [(t.time, t.values["av"]) for t in ticks] == [(1200 * MS, 1.0), (1500 * MS, 3.0)]
    _equal_paths(src, b)


@pytest.mark.tor("TOR-TCK-005")
def test_per_topic_tick(tmp_path):
    src = open_log(_ab_log(tmp_path))
    b = make_bindings(AB, TickSpec(topic="/b"))
    ticks = list(sample(src, b))
    assert [t.time for t in ticks] == [1100 * MS, 1300 * MS]
    assert [t.values["av"] for t in ticks] == [1.0, 2.0]
    assert [t.values["age_a"] for t in ticks] == [0.1, 0.05]
    _equal_paths(src, b)
    # Ticking on /a: its first message comes before any /b: one warm-up tick.
    b = make_bindings(AB, TickSpec(topic="/a"))
    s = sample(src, b)
    ticks = list(s)
    assert s.warmup_ticks == 1 and [t.time for t in ticks] == [1250 * MS, 1500 * MS]
    _equal_paths(src, b)


def test_tick_topic_need_not_be_bound(tmp_path):
    src = open_log(_ab_log(tmp_path))
    b = make_bindings({"bv": "/b.data"}, TickSpec(topic="/a"))
    ticks = list(sample(src, b))
    # /a at 1.0 s is before the first /b: warm-up; then /a at 1.25 and 1.5.
    assert [(t.time, t.values["bv"]) for t in ticks] == [(1250 * MS, False), (1500 * MS, True)]
    assert set(ticks[0].log_times) == {"/a", "/b"}
    _equal_paths(src, b)


@pytest.mark.tor("TOR-TCK-003")
def test_simultaneous_messages(tmp_path):
    msgs = [("/a", "std_msgs/msg/Float64", 0, float64(1.0)),
            ("/a", "std_msgs/msg/Float64", 10 * MS, float64(2.0)),
            ("/a", "std_msgs/msg/Float64", 10 * MS, float64(3.0)),
            ("/b", "std_msgs/msg/Bool", 10 * MS, boolean(True))]
    src = open_log(write_mcap(tmp_path / "tie.mcap", msgs))
    b = make_bindings({"av": "/a.data", "bv": "/b.data"}, TickSpec(topic="/a"))
    ticks = list(sample(src, b))
    # Both /a messages at 10 ms tick, each with its own /a message; /b at 10 ms is held by both.
    assert [(t.time, t.values["av"], t.values["bv"]) for t in ticks] == [(10 * MS, 2.0, True), (10 * MS, 3.0, True)]
    # A fixed period holds the last of the simultaneous messages.
    b = make_bindings({"av": "/a.data", "bv": "/b.data"}, TickSpec(period_ns=10 * MS))
    assert [(t.time, t.values["av"]) for t in sample(src, b)] == [(10 * MS, 3.0)]
    _equal_paths(src, b)
    _equal_paths(src, b)


def test_missing_topic_and_missing_field_are_clear_errors(tmp_path):
    src = open_log(_ab_log(tmp_path))
    with pytest.raises(SignalError, match=r"ab\.mcap: the log has no topic /scan \(used by close\)"):
        sample(src, make_bindings({"close": "min(/scan.ranges) < 1"}, TickSpec(period_ns=S)))
    b = parse_bindings('[tick]\nperiod = "100 ms"\n[variables]\nbad = "/a.date > 1"\n', "r1.toml")
    with pytest.raises(SignalError, match=r"r1\.toml:4:8: variable 'bad': /a\.date: a std_msgs/msg/Float64 "
                                          r"message has no field 'date' \(tick at 1000000000 ns; held: "
                                          r"/a @ log time 1000000000\)"):
        list(sample(src, b))
    with pytest.raises(SignalError):
        sample_arrays(src, b)
    with pytest.raises(SignalError, match="needs bindings"):
        sample(src)


def test_sampling_is_iterated_once(tmp_path):
    s = sample(open_log(_ab_log(tmp_path)), make_bindings({"av": "/a.data"}, TickSpec(period_ns=S)))
    list(s)
    with pytest.raises(RuntimeError):
        list(s)


# -- header time base -----------------------------------------------------------------------------


def _stamped_log(tmp_path):
    #            log time   header stamp   x
    rows = [(1000, 900, 1.0), (1100, 1050, 2.0), (1200, 1000, 3.0),  # 1000 goes backwards
            (5000, 4900, 4.0), (5100, 1020, 5.0),  # 1020 arrives after 1050 was used: late
            (5200, 5150, 6.0)]
    msgs = [("/cmd", "geometry_msgs/msg/TwistStamped", lt * MS, twist_stamped(hs * MS, x=x)) for lt, hs, x in rows]
    return write_mcap(tmp_path / "stamped.mcap", msgs)


@pytest.mark.tor("TOR-TCK-008")
def test_header_time_base_reorders_and_reports(tmp_path):
    src = open_log(_stamped_log(tmp_path))
    b = parse_bindings('[tick]\ntopic = "/cmd"\ntime = "header"\nheader_lag = "100 ms"\n'
                       '[variables]\nx = "/cmd.twist.linear.x"\n')
    s = sample(src, b)
    ticks = list(s)
    assert [(t.time, t.values["x"]) for t in ticks] == [
        (900 * MS, 1.0), (1000 * MS, 3.0), (1050 * MS, 2.0), (4900 * MS, 4.0), (5150 * MS, 6.0)]
    assert [t.log_times["/cmd"] for t in ticks] == [1000 * MS, 1200 * MS, 1100 * MS, 5000 * MS, 5200 * MS]
    kinds = [(p.kind, p.log_time) for p in s.signal_problems]
    assert kinds == [(P.HEADER_BACKWARDS, 1200 * MS), (P.HEADER_BACKWARDS, 5100 * MS),
                     (P.HEADER_LATE, 5100 * MS)]
    # the late stamp (1020 ms) against the newest one used (1050 ms)
    assert s.signal_problems[-1].detail.startswith(
        "header.stamp 1020000000 is 30000000 ns older than a message already used")
    assert s.problems == src.problems + s.signal_problems
    _equal_paths(src, b)
    # The same log on log time: no reordering, no problems.
    b_log = parse_bindings('[tick]\ntopic = "/cmd"\n[variables]\nx = "/cmd.twist.linear.x"\n')
    s = sample(src, b_log)
    assert [t.values["x"] for t in s] == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    assert s.signal_problems == []


@pytest.mark.tor("TOR-TCK-009")
def test_the_tick_bound_counts_the_ticks_already_made(tmp_path):
    """A header stamp that jumps 10^8 periods after a tick was made gives more than 10^8
    ticks in all: an error raised before the grid's ticks are made, though the jump alone
    is at the limit (the log times, 2 ns apart, let it through)."""
    from itertools import islice

    msgs = [("/cmd", "geometry_msgs/msg/TwistStamped", lt, twist_stamped(hs, x=1.0))
            for lt, hs in ((0, 0), (1, 1), (2, 1 + 10**8))]
    log = write_mcap(tmp_path / "jump.mcap", msgs)
    b = parse_bindings('[tick]\nperiod = "1 ns"\ntime = "header"\nheader_lag = "1 ns"\n'
                       '[variables]\nx = "/cmd.twist.linear.x > 0"\n')
    with pytest.raises(SignalError, match=r"more than 100,000,000 ticks .* header\.stamp jump"):
        list(islice(sample(open_log(log), b), 100))


def test_header_time_base_needs_headers(tmp_path):
    src = open_log(_ab_log(tmp_path))
    b = parse_bindings('[tick]\nperiod = "1 s"\ntime = "header"\n[variables]\nav = "/a.data"\n', "h.toml")
    with pytest.raises(SignalError, match=r"/a messages .* have no header\.stamp .* in h\.toml"):
        list(sample(src, b))


# -- real logs against numpy computed here ---------------------------------------------------------


@needs_shared
def test_real_mcap_bindings_against_numpy():
    # same arrange as test_real_bag_laserscan_against_numpy (kept: another log and other
    # expressions)
    src = open_log(CMD_VEL_MCAP)
    b = make_bindings({
        "cmd": "/vehicle/cmd_vel.twist.linear.x",
        "scaled": "/scaled/cmd_vel.twist.linear.x",
        "slowed": "/scaled/cmd_vel.twist.linear.x <= /vehicle/cmd_vel.twist.linear.x + 1e-9",
        "stopped": "abs(/scaled/cmd_vel.twist.linear.x) < 1e-3 & abs(/scaled/cmd_vel.twist.angular.z) < 1e-3",
        "stale": "age(/vehicle/cmd_vel) > 0.05",
    }, TickSpec(period_ns=50 * MS))
    s = sample(src, b)
    ticks = list(s)
    # Independent: mcap reader + bundled types, sample-and-hold by searchsorted.
    per = {"/vehicle/cmd_vel": ([], [], []), "/scaled/cmd_vel": ([], [], [])}
    with open(CMD_VEL_MCAP, "rb") as f:
        for _s, ch, m in make_reader(f).iter_messages(log_time_order=True):
            d = ROS2.deserialize_cdr(m.data, "geometry_msgs/msg/TwistStamped")
            per[ch.topic][0].append(m.log_time)
            per[ch.topic][1].append(d.twist.linear.x)
            per[ch.topic][2].append(d.twist.angular.z)
    t0 = min(v[0][0] for v in per.values())
    t1 = max(v[0][-1] for v in per.values())
    t0 = -(-t0 // (50 * MS)) * (50 * MS)  # the grid: multiples of the period, from the
    t1 = -(-t1 // (50 * MS)) * (50 * MS)  # first at or after the first message to the last
    grid = np.arange(t0, t1 + 1, 50 * MS, dtype=np.int64)
    idx = {k: np.searchsorted(np.array(v[0]), grid, side="right") - 1 for k, v in per.items()}
    ok = (idx["/vehicle/cmd_vel"] >= 0) & (idx["/scaled/cmd_vel"] >= 0)
    assert s.warmup_ticks == int((~ok).sum())
    grid = grid[ok]
    iv, isc = idx["/vehicle/cmd_vel"][ok], idx["/scaled/cmd_vel"][ok]
    cmd = np.array(per["/vehicle/cmd_vel"][1])[iv]
    scaled = np.array(per["/scaled/cmd_vel"][1])[isc]
    az = np.array(per["/scaled/cmd_vel"][2])[isc]
    age = (grid - np.array(per["/vehicle/cmd_vel"][0])[iv]) / 1e9
    assert [t.time for t in ticks] == grid.tolist()
    assert [t.values["cmd"] for t in ticks] == cmd.tolist()
    assert [t.values["scaled"] for t in ticks] == scaled.tolist()
    assert [t.values["slowed"] for t in ticks] == (scaled <= cmd + 1e-9).tolist()
    assert [t.values["stopped"] for t in ticks] == ((np.abs(scaled) < 1e-3) & (np.abs(az) < 1e-3)).tolist()
    assert [t.values["stale"] for t in ticks] == (age > 0.05).tolist()
    assert any(t.values["cmd"] > 0 for t in ticks) and any(t.values["stopped"] for t in ticks)
    _equal_paths(src, b)


@needs_shared
def test_real_bag_laserscan_against_numpy():
    # same arrange as test_real_mcap_bindings_against_numpy (kept: another log and other
    # expressions)
    src = open_log(STAGE_BAG)
    b = make_bindings({
        "too_close": "min(/base_scan.ranges) < 0.9",
        "n_close": "count(/base_scan.ranges < 0.9)",
        "nearest": "min(/base_scan.ranges)",
        "speed": "norm(/base_pose_ground_truth.twist.twist.linear.x, /base_pose_ground_truth.twist.twist.linear.y)",
    }, TickSpec(topic="/base_scan"))
    s = sample(src, b)
    ticks = list(s)
    assert len(ticks) + s.warmup_ticks == 1727
    with AnyReader([STAGE_BAG]) as reader:
        scans, odom = [], []
        for c, t, raw in reader.messages():
            d = reader.deserialize(raw, c.msgtype)
            (scans if c.topic == "/base_scan" else odom).append((t, d))
    odom_t = np.array([t for t, _ in odom])
    want_close, want_n, want_near, want_speed = [], [], [], []
    for t, d in scans:
        i = np.searchsorted(odom_t, t, side="right") - 1
        if i < 0:
            continue
        r = d.ranges.astype(np.float64)
        v = r[(r >= d.range_min) & (r <= d.range_max) & ~np.isnan(r)]
        near = v.min() if v.size else np.inf
        want_near.append(near)
        want_close.append(bool(near < 0.9))
        want_n.append(float((v < 0.9).sum()))
        tw = odom[i][1].twist.twist.linear
        want_speed.append(float(np.sqrt(tw.x * tw.x + tw.y * tw.y)))
    assert [t.values["too_close"] for t in ticks] == want_close
    assert [t.values["n_close"] for t in ticks] == want_n
    assert [t.values["nearest"] for t in ticks] == want_near
    assert [t.values["speed"] for t in ticks] == pytest.approx(want_speed, abs=0, rel=1e-15)
    assert any(want_close) and not all(want_close)
    _equal_paths(src, b)


def test_rep117_through_the_clock(tmp_path):
    frames = [[np.nan, 5.0, 0.01], [np.inf, -np.inf, 0.5], [np.nan, np.nan, np.nan], [20.0, 1.0, 0.95]]
    msgs = [("/scan", "sensor_msgs/msg/LaserScan", i * 100 * MS, scan(r, ns=i * 100 * MS, range_min=0.05, range_max=10.0))
            for i, r in enumerate(frames)]
    src = open_log(write_mcap(tmp_path / "rep117.mcap", msgs))
    b = make_bindings({"near": "min(/scan.ranges)", "far": "max(/scan.ranges)", "close": "min(/scan.ranges) < 0.9",
                       "valid": "len(/scan.ranges)"}, TickSpec(topic="/scan"))
    ticks, _arr = _equal_paths(src, b)
    # frame 1's -inf (REP 117: closer than range_min) reads as range_min = 0.05
    # frame 2, every beam NaN (a blind LiDAR): unknown (NaN), never the clear +inf
    near = [t.values["near"] for t in ticks]
    assert near[0] == 5.0 and near[1] == pytest.approx(0.05) and math.isnan(near[2]) \
        and near[3] == pytest.approx(0.95)
    far = [t.values["far"] for t in ticks]
    assert far[:2] == [5.0, 0.5] and math.isnan(far[2]) and far[3] == 1.0
    close = [t.values["close"] for t in ticks]
    assert close[:2] == [False, True] and math.isnan(close[2]) and close[3] is False
    assert [t.values["valid"] for t in ticks] == [1.0, 2.0, 0.0, 2.0]


def test_ragged_arrays_reduced_per_message_or_evaluated_per_tick(tmp_path):
    """Arrays whose length changes: a reduction of one topic's fields is still computed per
    message by numpy; an array mixed with another topic's value is evaluated tick by tick.
    Both equal the streaming clock."""
    msgs = [("/scan", "sensor_msgs/msg/LaserScan", i * MS, scan([1.0 + i] * (3 + i), ns=i * MS))
            for i in range(4)]
    msgs += [("/a", "std_msgs/msg/Float64", i * MS, float64(2.5)) for i in range(4)]
    msgs.sort(key=lambda m: m[2])
    src = open_log(write_mcap(tmp_path / "ragged.mcap", msgs))
    b = make_bindings({"n": "len(/scan.ranges)"}, TickSpec(topic="/scan"))
    ticks, arr = _equal_paths(src, b)
    assert arr.vectorized and arr.columns["n"].tolist() == [3.0, 4.0, 5.0, 6.0]
    b = make_bindings({"n": "count(/scan.ranges > /a.data)"}, TickSpec(topic="/scan"))
    ticks, arr = _equal_paths(src, b)
    assert not arr.vectorized and arr.columns["n"].tolist() == [0.0, 0.0, 5.0, 6.0]


def test_truncated_log_samples_up_to_the_damage(tmp_path):
    msgs = [("/a", "std_msgs/msg/Float64", i * 10 * MS, float64(i)) for i in range(400)]
    path = write_mcap(tmp_path / "full.mcap", msgs, chunk_size=512)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    src = open_log(cut)
    s = sample(src, make_bindings({"v": "/a.data"}, TickSpec(period_ns=10 * MS)))
    ticks = list(s)
    assert src.partial and ticks and ticks[-1].time == src.damage_time
    assert [t.values["v"] for t in ticks] == [float(i) for i in range(len(ticks))]
    assert [p.kind for p in s.problems] == [P.TRUNCATED]


# -- CSV -----------------------------------------------------------------------------------------


@pytest.mark.tor("TOR-TCK-007")
def test_csv_rows_are_ticks(tmp_path):
    p = tmp_path / "trace.csv"
    p.write_text("time,too_close,stopped,speed\n0.0,0,1,0\n0.5,1,1,0\n# note\n1.0,1,0,0.7\n")
    src = open_log(p)
    s = sample(src)
    ticks = list(s)
    assert [(t.index, t.time, t.line) for t in ticks] == [(0, 0, 2), (1, 500 * MS, 3), (2, S, 5)]
    assert ticks[2].values == {"too_close": True, "stopped": False, "speed": 0.7}
    assert s.warmup_ticks == 0 and s.first_time == 0
    times, cols = sample_arrays(src)
    assert times.tolist() == [0, 500 * MS, S]
    assert cols["too_close"].dtype == np.bool_ and cols["speed"].tolist() == [0.0, 0.0, 0.7]


@pytest.mark.tor("TOR-TCK-007")
def test_csv_times_are_exact_ns_and_a_column_is_boolean_or_numeric(tmp_path, monkeypatch):
    """A time column's seconds are read to the ns (whole, negative, the largest an int64 of
    ns holds); a time past that bound is refused at its line; a column mixing true/false and
    numbers is refused, also when they come in different chunks of rows."""
    from fretc.common.problems import CsvError
    from fretc.logs.csv import read as csv_read

    p = tmp_path / "t.csv"
    p.write_text("time,ok\n-1.5,1\n0,1\n2,0\n9223372036.854775807,1\n")
    times, cols = sample_arrays(open_log(p))
    assert times.tolist() == [-1500 * MS, 0, 2 * S, (1 << 63) - 1]
    assert cols["ok"].tolist() == [True, True, False, True]
    for rows in ("0,1\n9223372036.854775808,1\n", "-9223372036.854775809,1\n0,1\n"):
        p.write_text("time,ok\n" + rows)
        with pytest.raises(CsvError, match=r"t\.csv:\d.*time .* s is out of range"):
            sample_arrays(open_log(p))
    monkeypatch.setattr(csv_read, "CHUNK_ROWS", 1)
    for rows in ("0,0.5\n1,true\n", "0,true\n1,0.5\n"):
        p.write_text("time,x\n" + rows)
        with pytest.raises(CsvError, match="column mixes true/false .* with numbers"):
            sample_arrays(open_log(p))


@pytest.mark.tor("TOR-TCK-007")
def test_csv_cells_padded_with_white_space_are_read_as_their_values(tmp_path, monkeypatch):
    """Cells are read stripped of white space, also in a chunk of rows read at once: a column
    of 1/0 cells, one of them padded, is boolean, and a true/false later in it is no mix."""
    from fretc.logs.csv import read as csv_read

    p = tmp_path / "t.csv"
    p.write_text("time,ok\n0,1 \n1,0\n2,1\n")
    _times, cols = sample_arrays(open_log(p))
    assert cols["ok"].dtype == np.bool_ and cols["ok"].tolist() == [True, False, True]
    monkeypatch.setattr(csv_read, "CHUNK_ROWS", 1)
    p.write_text("time,ok\n0,1 \n1,true\n2, false\n")
    _times, cols = sample_arrays(open_log(p))
    assert cols["ok"].tolist() == [True, True, False]


@pytest.mark.tor("TOR-TCK-007")
def test_csv_with_bindings_and_period(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("speed,stop\n0.2,false\n0.9,false\n0.0,true\n")
    src = open_log(p)
    b = parse_bindings('[tick]\nperiod = "100 ms"\n[variables]\nfast = "/csv.speed > 0.5"\n'
                       'ok = "/csv.stop -> /csv.speed < 0.1"\n')
    ticks, _ = _equal_paths(src, b)
    assert [(t.time, t.values["fast"], t.values["ok"]) for t in ticks] == [
        (0, False, True), (100 * MS, True, True), (200 * MS, False, True)]
    with pytest.raises(SignalError, match="pseudo-topic /csv"):
        list(sample(src, make_bindings({"x": "/scan.range_max"}, TickSpec(period_ns=S))))


# -- property: the vectorized path equals the streaming one --------------------------------------

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_times = st.lists(st.integers(0, 2000), min_size=1, max_size=25)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a_times=_times, s_times=_times, period=st.integers(1, 400), per_topic=st.booleans(),
       seed=st.integers(0, 2**16))
def test_sample_arrays_equals_sample(tmp_path_factory, a_times, s_times, period, per_topic, seed):
    rng = np.random.default_rng(seed)
    msgs = [("/a", "std_msgs/msg/Float64", t * MS, float64(rng.normal())) for t in a_times]
    msgs += [("/scan", "sensor_msgs/msg/LaserScan", t * MS,
              scan(rng.choice([0.01, 0.5, 1.0, 3.0, np.nan, np.inf, 20.0], size=6), ns=t * MS,
                   range_min=0.05, range_max=10.0)) for t in s_times]
    path = write_mcap(tmp_path_factory.mktemp("prop") / "p.mcap", sorted(msgs, key=lambda m: m[2]),
                      chunk_size=256)
    tick = TickSpec(topic="/scan") if per_topic else TickSpec(period_ns=period * MS)
    b = make_bindings({
        "close": "min(/scan.ranges) < 0.9",
        "mean": "mean(/scan.ranges) * /a.data",
        "n": "count(/scan.ranges > 0.9) + len(/scan.ranges)",
        "mix": "/a.data > 0 -> any(/scan.ranges < 1) | age(/a) > 0.5",
        "q": "/a.data / (/scan.ranges[0] - 1)",
    }, tick)
    src = open_log(path)
    s = sample(src, b)
    n = sum(1 for _ in s)
    arr = sample_arrays(src, b)
    assert arr.vectorized and arr.warmup_ticks == s.warmup_ticks and len(arr.times) == n
    _equal_paths(src, b)


def test_a_header_stamp_jump_of_decades_is_an_error_before_any_tick_is_made(tmp_path):
    """One stamp 63 years ahead at a 10 ms period would need 2e11 ticks: the clock says so at
    once (the audit then makes its requirements errors) instead of making 10^8 of them."""
    import time
    rows = [(1000, 900, 1.0), (1100, 1000, 2.0), (1200, 2 * 10**12, 3.0), (1300, 1100, 4.0)]
    msgs = [("/cmd", "geometry_msgs/msg/TwistStamped", lt * MS, twist_stamped(hs * MS, x=x))
            for lt, hs, x in rows]
    src = open_log(write_mcap(tmp_path / "jump.mcap", msgs))
    b = parse_bindings('[tick]\nperiod = "10 ms"\ntime = "header"\nheader_lag = "50 ms"\n'
                       '[variables]\nx = "/cmd.twist.linear.x"\n')
    t0 = time.process_time()
    with pytest.raises(SignalError, match=r"more than 100,000,000 ticks .*header\.stamp jump"):
        sample_arrays(src, b)
    assert time.process_time() - t0 < 5
