"""Peak memory of ``fretc audit`` over a long MCAP log: flat from one hour to a day.

    python bench/bench_log_memory.py                    # 1 h and 24 h
    python bench/bench_log_memory.py --hours 1 6        # other lengths

Writes, in a temporary folder, a synthetic ROS 2 MCAP of each length (``ros2`` profile,
``ros2msg`` schemas, CDR messages, zstd chunks of 1 MiB): ``/cmd_vel``
(geometry_msgs/msg/Twist) and ``/range`` (std_msgs/msg/Float64) at 10 Hz, ``/sif``
(std_msgs/msg/Bool) at 1 Hz; every minute an obstacle comes within 0.9 m for 2 s and the
robot stops 0.3 s after it, so the four requirements (:data:`REQUIREMENTS`, a 100 ms tick)
hold on every tick and are judged to the last one (``--violation`` adds a fifth, violated at
every peak of the speed: its evidence is read again). Then, in one run:

1. each log audited in a fresh process (``audit_log`` after the plan is loaded): the peak of
   the Python heap the audit allocated (tracemalloc, numpy's arrays included) and the
   process's peak resident set (``VmHWM``), with the clocks judged as they are read (the
   default) and with every clock's columns kept (``KEEP_TICKS`` past the log: the whole
   clock judged as one chunk, as before);
2. the CPU time of the audit of the one-hour log against a plain decode of the same file
   (the ``mcap`` reader and rosbags' CDR deserializer over every message, best of
   ``--repeat``), and their ratio.

Prints one line per log and mode, and the ratio.
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

EPOCH_NS = 1_700_000_000 * 1_000_000_000
MS = 1_000_000

REQUIREMENTS = """\
@tick_period 100 ms
M1: the robot shall always satisfy speed <= 0.5
M2: upon too_close the robot shall within 1 second satisfy stopped
M3: whenever sif_on the robot shall immediately satisfy turn <= 0.5
M4: the robot shall always satisfy range >= 0.2
"""
#: with ``--violation``: violated at the speed's every peak (its evidence read again)
VIOLATED = "M5: the robot shall always satisfy speed <= 0.39\n"
BINDINGS = """\
[tick]
period = "100 ms"
[variables]
speed = "abs(/cmd_vel.linear.x)"
turn = "abs(/cmd_vel.angular.z)"
stopped = "abs(/cmd_vel.linear.x) < 0.01"
too_close = "/range.data < 0.9"
range = "/range.data"
sif_on = "/sif.data"
"""
TYPES = (("/cmd_vel", "geometry_msgs/msg/Twist"), ("/range", "std_msgs/msg/Float64"),
         ("/sif", "std_msgs/msg/Bool"))
CDR = b"\x00\x01\x00\x00"  # little-endian CDR's encapsulation header


def write_log(path: Path, hours: float) -> int:
    """The synthetic run of ``hours`` hours (module docstring) at ``path``; its messages."""
    from mcap.writer import CompressionType, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    n = 0
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression=CompressionType.ZSTD)
        w.start(profile="ros2", library="fretc-bench")
        chan = {}
        for topic, typ in TYPES:
            text = ts.generate_msgdef(typ, ros_version=2)[0]
            chan[topic] = w.register_channel(topic, "cdr", w.register_schema(
                typ, "ros2msg", text.encode()))
        twist, f64, boolean = struct.Struct("<6d"), struct.Struct("<d"), struct.Struct("<?")
        for k in range(int(hours * 36_000)):
            t = EPOCH_NS + k * 100 * MS
            phase = k % 600  # one minute of 100 ms ticks
            close = 100 <= phase < 120  # 2 s within 0.9 m
            stopped = 103 <= phase < 140
            rng = 0.6 if close else 2.0 + math.sin(k / 50.0)
            v = 0.0 if stopped else 0.3 + 0.1 * math.sin(k / 30.0)
            w.add_message(chan["/range"], log_time=t, publish_time=t,
                          data=CDR + f64.pack(rng))
            w.add_message(chan["/cmd_vel"], log_time=t + 5 * MS, publish_time=t + 5 * MS,
                          data=CDR + twist.pack(v, 0.0, 0.0, 0.0, 0.0, 0.2 * math.sin(k / 70)))
            n += 2
            if k % 10 == 0:
                w.add_message(chan["/sif"], log_time=t + 7 * MS, publish_time=t + 7 * MS,
                              data=CDR + boolean.pack(close))
                n += 1
        w.finish()
    return n


def _child(log: str, fret: str, whole: bool) -> None:
    """In a fresh process: the audit's heap peak, resident peak, verdicts, CPU time."""
    import tracemalloc

    import fretc.audit.streamed_log as streamed_log
    from fretc.audit import AuditConfig, audit_log, load_plan

    if whole:
        streamed_log.KEEP_TICKS = 1 << 40
    plan = load_plan(AuditConfig(requirements=(fret,)))
    tracemalloc.start()
    t = time.process_time()
    la = audit_log(plan, log)
    cpu = time.process_time() - t
    heap = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    rss = 0
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                rss = int(line.split()[1])
    print(json.dumps({"heap_mb": heap / 2**20, "rss_mb": rss / 1024, "cpu": cpu,
                      "ticks": la.ticks_evaluated,
                      "verdicts": [v.verdict for v in la.verdicts]}))


def audit_child(log: Path, fret: Path, whole: bool = False) -> dict:
    """:func:`_child` in a fresh process: its figures."""
    cmd = [sys.executable, __file__, "--child", str(log), str(fret)] + (
        ["--whole"] if whole else [])
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def plain_decode(path: Path) -> float:
    """CPU seconds to read and decode every message with mcap + rosbags."""
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    t = time.process_time()
    stores: dict = {}
    with open(path, "rb") as f:
        for schema, _channel, message in make_reader(f).iter_messages(log_time_order=True):
            st = stores.get(schema.id)
            if st is None:
                st = stores[schema.id] = get_typestore(Stores.EMPTY)
                st.register(get_types_from_msg(schema.data.decode(), schema.name))
            st.deserialize_cdr(message.data, schema.name)
    return time.process_time() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hours", type=float, nargs="+", default=[1.0, 24.0])
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each (best kept)")
    ap.add_argument("--no-whole", action="store_true",
                    help="skip the audits keeping every clock's columns")
    ap.add_argument("--violation", action="store_true",
                    help="a fifth requirement, violated (module docstring)")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    ap.add_argument("--whole", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        _child(args.child[0], args.child[1], args.whole)
        return
    with tempfile.TemporaryDirectory(prefix="fretc-log-memory-") as tmp:
        folder = Path(tmp)
        fret = folder / "m.fret"
        fret.write_text(REQUIREMENTS + (VIOLATED if args.violation else ""))
        (folder / "m.bindings.toml").write_text(BINDINGS)
        logs = {}
        for hours in args.hours:
            path = folder / f"run_{hours:g}h.mcap"
            t = time.perf_counter()
            n = write_log(path, hours)
            logs[hours] = path
            print(f"wrote {path.name}: {n} messages, {path.stat().st_size / 1e6:.1f} MB, "
                  f"in {time.perf_counter() - t:.1f} s")
        print(f"\npeak memory of a fresh process auditing the log "
              f"({5 if args.violation else 4} requirements, 100 ms tick):")
        for hours, path in logs.items():
            for whole in ((False, True) if not args.no_whole else (False,)):
                m = audit_child(path, fret, whole)
                mode = "every clock's columns kept" if whole else "judged as read"
                print(f"  {hours:5g} h  {m['ticks']:8d} ticks  {mode:27s} heap peak "
                      f"{m['heap_mb']:7.1f} MB  max RSS {m['rss_mb']:7.1f} MB  "
                      f"({m['cpu']:.1f} s CPU; {', '.join(m['verdicts'])})")
        first = logs[args.hours[0]]
        plains = [plain_decode(first) for _ in range(args.repeat)]
        audits = [audit_child(first, fret)["cpu"] for _ in range(args.repeat)]
        p, a = min(plains), min(audits)
        print(f"\n{args.hours[0]:g} h log, CPU time, best of {args.repeat}: plain mcap read + "
              f"rosbags decode {p:.2f} s; fretc audit {a:.2f} s; ratio {a / p:.2f} x "
              "(aim <= 0.35x)")


if __name__ == "__main__":
    main()
