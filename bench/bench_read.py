"""Reading speed and memory of the signal layer on a long synthetic MCAP.

Writes a ROS 2 MCAP to a temporary folder: /scan (sensor_msgs/LaserScan, 720 beams, 10 Hz),
/cmd_vel (geometry_msgs/Twist, 10 Hz), /odom (nav_msgs/Odometry, 20 Hz), then in one run
times

* plain:  ``mcap.reader.make_reader(f).iter_messages()`` + rosbags ``deserialize_cdr`` of
  every message (types built from the file's schemas) — the floor for any Python reader;
* sample: ``signals.sample(open_log(path), bindings)`` with 6 bindings on a 100 ms
  tick (CRC checks, decoding, sample-and-hold, evaluation);

and prints both times and their ratio, plus each run's peak resident memory (each measured
in a fresh child process) and the tracemalloc peak of ``sample()`` for every log length
given, to show memory does not grow with the log.

    python bench/bench_read.py                 # 10 minutes
    python bench/bench_read.py --minutes 10 60 # memory at 10 vs 60 minutes
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

BINDINGS = """
[tick]
period = "100 ms"
time = "log"

[variables]
too_close = "min(/scan.ranges) < 0.9"
n_close = "count(/scan.ranges < 1.5)"
stopped = "abs(/cmd_vel.linear.x) < 1e-3 & abs(/cmd_vel.angular.z) < 1e-3"
linear_speed = "abs(/cmd_vel.linear.x)"
odom_speed = "norm(/odom.twist.twist.linear.x, /odom.twist.twist.linear.y)"
scan_stale = "age(/scan) > 0.3"
"""

MS = 1_000_000
T0 = 1_700_000_000 * 1_000_000_000


def write_log(path: Path, minutes: float, compression: str) -> int:
    """Write the synthetic log; returns the number of messages."""
    from mcap.writer import CompressionType, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]
    V3, Twist = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Twist"]
    rng = np.random.default_rng(0)
    beams = 720
    angles = np.linspace(-np.pi, np.pi, beams, dtype=np.float32)
    end = int(minutes * 60 * 1000) * MS
    comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[compression]
    n = 0
    with open(path, "wb") as f:
        w = Writer(f, compression=comp, enable_data_crcs=True)
        w.start(profile="ros2", library="fretc-bench")
        chans = {}
        for topic, typ in [("/scan", "sensor_msgs/msg/LaserScan"), ("/cmd_vel", "geometry_msgs/msg/Twist"),
                           ("/odom", "nav_msgs/msg/Odometry")]:
            sid = w.register_schema(typ, "ros2msg", ts.generate_msgdef(typ, ros_version=2)[0].encode())
            chans[topic] = (w.register_channel(topic, "cdr", sid), typ)

        def put(topic: str, t: int, msg: object) -> None:
            nonlocal n
            cid, typ = chans[topic]
            w.add_message(cid, log_time=T0 + t, publish_time=T0 + t, data=bytes(ts.serialize_cdr(msg, typ)))
            n += 1

        def hdr(t: int, frame: str) -> object:
            return Header(stamp=Time(sec=(T0 + t) // 10**9, nanosec=(T0 + t) % 10**9), frame_id=frame)

        odom_t = T["nav_msgs/msg/Odometry"]
        pose_cov = T["geometry_msgs/msg/PoseWithCovariance"]
        twist_cov = T["geometry_msgs/msg/TwistWithCovariance"]
        Pose, Point, Quat = T["geometry_msgs/msg/Pose"], T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
        cov = np.zeros(36)
        for t in range(0, end, 50 * MS):  # 20 Hz base
            phase = t / 1e9
            if t % (100 * MS) == 0:
                dist = 1.5 + np.sin(phase / 7.0) + 0.3 * np.cos(angles * 3 + phase)
                ranges = (dist + rng.normal(0, 0.01, beams)).astype(np.float32)
                ranges[rng.integers(0, beams, 5)] = np.inf
                put("/scan", t + 3 * MS, T["sensor_msgs/msg/LaserScan"](
                    header=hdr(t + 3 * MS, "laser"), angle_min=-np.pi, angle_max=np.pi,
                    angle_increment=float(2 * np.pi / beams), time_increment=0.0, scan_time=0.1,
                    range_min=0.05, range_max=12.0, ranges=ranges, intensities=np.zeros(0, np.float32)))
                vx = max(0.0, 0.5 * np.sin(phase / 5.0))
                put("/cmd_vel", t + 50 * MS - 1, Twist(linear=V3(x=vx, y=0.0, z=0.0),
                                                       angular=V3(x=0.0, y=0.0, z=0.2 * np.cos(phase))))
            put("/odom", t + 7 * MS, odom_t(
                header=hdr(t + 7 * MS, "odom"), child_frame_id="base_link",
                pose=pose_cov(pose=Pose(position=Point(x=phase, y=0.0, z=0.0),
                                        orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0)), covariance=cov),
                twist=twist_cov(twist=Twist(linear=V3(x=0.4, y=0.1 * np.sin(phase), z=0.0),
                                            angular=V3(x=0.0, y=0.0, z=0.0)), covariance=cov)))
        w.finish()
    return n


def run_plain(path: str) -> tuple[float, int, int]:
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    t = time.perf_counter()
    n = 0
    # same decode loop as _decode_mcap in tests/audit/test_audit.py (kept: the bench times it,
    # the test keeps the messages)
    stores = {}
    with open(path, "rb") as f:
        for schema, _channel, m in make_reader(f).iter_messages(log_time_order=True):
            if schema.id not in stores:
                store = get_typestore(Stores.EMPTY)
                store.register(get_types_from_msg(schema.data.decode(), schema.name))
                stores[schema.id] = store
            stores[schema.id].deserialize_cdr(m.data, schema.name)
            n += 1
    return time.perf_counter() - t, n, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def run_sample(path: str) -> tuple[float, int, int]:
    from fretc.signals.bindings import parse_bindings
    from fretc.signals import sample
    from fretc.logs import open_log

    t = time.perf_counter()
    s = sample(open_log(path), parse_bindings(BINDINGS, "bench"))
    n = 0
    for _tick in s:
        n += 1
    assert not s.problems, s.problems
    return time.perf_counter() - t, n, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def run_arrays(path: str) -> tuple[float, int, int]:
    from fretc.signals.bindings import parse_bindings
    from fretc.signals import sample_arrays
    from fretc.logs import open_log

    t = time.perf_counter()
    times, _cols = sample_arrays(open_log(path), parse_bindings(BINDINGS, "bench"))
    return time.perf_counter() - t, len(times), resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def run_traced(path: str) -> tuple[float, int, int]:
    from fretc.signals.bindings import parse_bindings
    from fretc.signals import sample
    from fretc.logs import open_log

    tracemalloc.start()
    n = sum(1 for _ in sample(open_log(path), parse_bindings(BINDINGS, "bench")))
    _cur, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return 0.0, n, peak


def _child(fn, path, q):
    q.put(fn(path))


def in_child(fn, path: str) -> tuple[float, int, int]:
    """Run ``fn(path)`` in a fresh process so its peak RSS is its own."""
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=_child, args=(fn, path, q))
    p.start()
    out = q.get()
    p.join()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--minutes", type=float, nargs="+", default=[10.0],
                    help="log lengths to write and read (default: 10)")
    ap.add_argument("--compression", choices=["zstd", "lz4", "none"], default="zstd")
    ap.add_argument("--arrays", action="store_true", help="also time sample_arrays() (holds the log in memory)")
    args = ap.parse_args()
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}; 6 bindings, 100 ms tick")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for minutes in args.minutes:
            path = Path(tmp) / f"synthetic_{minutes:g}min.mcap"
            t = time.perf_counter()
            n = write_log(path, minutes, args.compression)
            size = path.stat().st_size
            print(f"\n{minutes:g} min: wrote {n} messages, {size / 2**20:.1f} MiB ({args.compression}) "
                  f"in {time.perf_counter() - t:.1f} s")
            plain_s, plain_n, plain_rss = in_child(run_plain, str(path))
            samp_s, ticks, samp_rss = in_child(run_sample, str(path))
            _, _, traced = in_child(run_traced, str(path))
            assert plain_n == n
            print(f"  plain mcap iter_messages + deserialize_cdr: {plain_s:7.2f} s "
                  f"({n / plain_s:8.0f} msg/s)  peak RSS {plain_rss / 1024:6.1f} MiB")
            print(f"  sample() with 6 bindings:                  {samp_s:7.2f} s "
                  f"({n / samp_s:8.0f} msg/s)  peak RSS {samp_rss / 1024:6.1f} MiB  "
                  f"tracemalloc peak {traced / 2**20:.2f} MiB  ({ticks} ticks)")
            print(f"  ratio sample / plain: {samp_s / plain_s:.2f}")
            if args.arrays:
                arr_s, arr_ticks, arr_rss = in_child(run_arrays, str(path))
                assert arr_ticks == ticks
                print(f"  sample_arrays():                           {arr_s:7.2f} s "
                      f"({n / arr_s:8.0f} msg/s)  peak RSS {arr_rss / 1024:6.1f} MiB")
            rows.append((minutes, size, plain_s, samp_s, samp_rss, traced))
    if len(rows) > 1:
        print("\nminutes  MiB     plain s  sample s  ratio  sample RSS MiB  tracemalloc MiB")
        for minutes, size, p, s, rss, tr in rows:
            print(f"{minutes:7g}  {size / 2**20:6.1f}  {p:7.2f}  {s:8.2f}  {s / p:5.2f}  {rss / 1024:14.1f}  "
                  f"{tr / 2**20:15.2f}")


if __name__ == "__main__":
    main()
