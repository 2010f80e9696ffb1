"""Reading speed of the log formats beside ROS's CDR, measured in one run: a PX4 ULog audit
against pyulog's own read, and a json / protobuf MCAP audit against a plain read and decode
of every message (the ``mcap`` reader with Python's ``json``, or with mcap-protobuf-support's
decoder). Each figure is the CPU time (user + system) of a command run as a user runs it,
start-up included, the least of ``--repeat`` runs (default 3) alternated with its
baseline's; the ratio is ours over the baseline. Bytecode caches are written first (one
untimed run of each command), as an installed fretc has them.

Two sizes of each input:

* short: the real SITL flight ``sample_px4_events.ulg`` (42 s) of ``../shared``, and json /
  protobuf copies of ``traces/stop_delay.mcap`` (the copies written by
  ``tests/logs/_encode.py``); there the start-up of the command is most of it;
* long: the same flight's data section repeated with shifted timestamps (``--copies``,
  default 20: about 11 minutes, 590,000 ULog messages), and the 20-minute synthetic robot
  log of ``bench/bench_read.py`` (LaserScan of 720 beams, Twist, Odometry; 48,000 messages)
  copied as json and protobuf, audited with its six bindings and three requirements (one
  violated, so the audit's second pass for the operands runs too).

The baselines read what the audit needs at least: pyulog the three bound uORB topics
(``message_name_filter_list``); the MCAP read decodes every message. fretc's ULog reader
walks every message of every topic once and dates dropouts as pyulog's read of every topic
does (by the last timestamp read before them, whatever the bindings), so pyulog's read of
every topic is printed too.

The long logs are also measured in one process (the audit after its imports and a warm-up
audit of the short log, against the plain read in the same process): the ratio of the
reading alone, start-up left out.

    python bench/bench_logs.py            # needs ../shared (the PX4 logs)
"""

from __future__ import annotations

import argparse
import os
import resource
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PX4 = ROOT.parent / "shared" / "data" / "foreign_logs" / "px4" / "sample_px4_events.ulg"
TOPICS = ["battery_status", "vehicle_status", "actuator_outputs"]
PX4_FRET = """@tick_period 100 ms
PB: the drone shall always satisfy battery_high
PO: whenever armed the drone shall immediately satisfy outputs_in_range
PR: upon rtl the drone shall within 10 seconds satisfy disarmed
"""
PX4_BINDINGS = """[tick]
period = "100 ms"
[variables]
battery_high = '"battery_status".remaining > 0.9'
armed = '"vehicle_status".arming_state = 2'
outputs_in_range = 'max("actuator_outputs".output[0:4]) <= 2000'
rtl = '"vehicle_status".nav_state = 5'
disarmed = '"vehicle_status".arming_state = 1'
"""
SYN_FRET = """@tick_period 100 ms
S1: whenever too_close the robot shall within 1 second satisfy stopped
S2: the robot shall always satisfy linear_speed <= 0.45
S3: the robot shall always satisfy !scan_stale
"""
PLAIN_ULOG = """
import sys
from pyulog import ULog
names = sys.argv[2].split(",") if sys.argv[2] else None
u = ULog(sys.argv[1], message_name_filter_list=names)
print(sum(len(d.data["timestamp"]) for d in u.data_list))
"""
PLAIN_MCAP = """
import json, sys
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
n = 0
with open(sys.argv[1], "rb") as f:
    if sys.argv[2] == "json":
        for _s, _c, m in make_reader(f).iter_messages():
            json.loads(m.data)
            n += 1
    else:
        for _d in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            n += 1
print(n)
"""

#: the audit and the plain read in one process, CPU of each after the imports and a warm-up
#: audit of a short log of the same kind (argv: kind, log, requirements, short log)
IN_PROCESS = """
import json, sys, time
from fretc.audit import AuditConfig, audit_log, load_plan
kind, log, fret, short = sys.argv[1:5]
plan = load_plan(AuditConfig(requirements=(fret,)))
audit_log(plan, short)
t = time.process_time()
audit_log(plan, log)
ours = time.process_time() - t
if kind == "ulog":
    from pyulog import ULog
    t = time.process_time()
    u = ULog(log, message_name_filter_list=sys.argv[5].split(","))
    plain = [time.process_time() - t]
    t = time.process_time()
    u = ULog(log)
    plain.append(time.process_time() - t)
else:
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory
    t = time.process_time()
    with open(log, "rb") as f:
        if kind == "json":
            for _s, _c, m in make_reader(f).iter_messages():
                json.loads(m.data)
        else:
            for _d in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
                pass
    plain = [time.process_time() - t]
print(json.dumps([ours] + plain))
"""


def _in_process(kind: str, log: Path, fret: Path, short: Path, cwd: Path) -> list[float]:
    """[fretc's audit, the plain read(s)] CPU seconds in one process (:data:`IN_PROCESS`)."""
    import json

    out = subprocess.run([sys.executable, "-c", IN_PROCESS, kind, str(log), str(fret),
                          str(short), ",".join(TOPICS)], cwd=cwd, capture_output=True,
                         text=True)
    if out.returncode != 0:
        raise SystemExit(f"in-process run failed: {out.stderr[-500:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cpu(cmd: list[str], cwd: Path) -> float:
    """CPU seconds (user + system) of ``cmd`` run to its end."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode not in (0, 1, 3):
        raise SystemExit(f"{' '.join(cmd)} failed ({out.returncode}): {out.stderr[-500:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


#: runs of each command (``--repeat``): alternated, the best of each kept
REPEAT = [3]


def _best(*cmds: list[str], cwd: Path = ROOT) -> list[float]:
    """The least CPU seconds of each command over :data:`REPEAT` rounds, the commands
    alternated within a round (a machine whose speed drifts slows both alike), after one
    untimed run of each that writes the bytecode caches, as an installed fretc has them."""
    for cmd in cmds:
        _cpu(cmd, cwd)
    runs = [[_cpu(cmd, cwd) for cmd in cmds] for _ in range(REPEAT[0])]
    return [min(r[i] for r in runs) for i in range(len(cmds))]


def _fretc() -> list[str]:
    return [sys.executable, "-m", "fretc"]


def long_ulog(src: Path, dst: Path, copies: int) -> None:
    """``src`` with its data section written ``copies`` times, each copy's timestamps shifted
    past the previous one (PX4 "ULog File Format": a 3-byte header ``uint16 size, uint8
    type`` per message; a ``D`` message is ``uint16 msg_id`` then the fields, ``timestamp``
    first; an ``L`` message is ``uint8 level, uint64 timestamp, text``). Copies keep the
    data of topics whose format starts with ``uint64_t timestamp``, the logged text and the
    sync markers; subscriptions and parameters are written once."""
    b = src.read_bytes()
    formats: dict[str, bool] = {}
    subs: dict[int, bool] = {}
    records: list[tuple[int, bytes]] = []
    data_start = None
    first = last = None
    pos = 16
    while pos + 3 <= len(b):
        size, typ = struct.unpack_from("<HB", b, pos)
        body = b[pos + 3:pos + 3 + size]
        if typ == ord("F"):
            name, fields = body.decode().split(":", 1)
            formats[name] = fields.split(";")[0].strip() == "uint64_t timestamp"
        elif typ == ord("A"):
            data_start = len(records) if data_start is None else data_start
            _multi, mid = struct.unpack_from("<BH", body, 0)
            subs[mid] = formats.get(body[3:].decode(), False)
        elif typ == ord("D"):
            mid, ts = struct.unpack_from("<HQ", body, 0)
            if subs.get(mid) and ts:
                first = ts if first is None else min(first, ts)
                last = ts if last is None else max(last, ts)
        records.append((typ, body))
        pos += 3 + size
    span = last - first + 1_000_000
    out = bytearray(b[:16])
    for typ, body in records:
        out += struct.pack("<HB", len(body), typ) + body
    for k in range(1, copies):
        for typ, body in records[data_start:]:
            if typ == ord("D"):
                mid, ts = struct.unpack_from("<HQ", body, 0)
                if not subs.get(mid) or ts == 0:
                    continue
                body = body[:2] + struct.pack("<Q", ts + k * span) + body[10:]
            elif typ == ord("L"):
                ts, = struct.unpack_from("<Q", body, 1)
                body = body[:1] + struct.pack("<Q", ts + k * span) + body[9:]
            elif typ != ord("S"):
                continue
            out += struct.pack("<HB", len(body), typ) + body
    dst.write_bytes(bytes(out))


def _line(label: str, ours: float, base_label: str, base: float) -> None:
    print(f"  {label}: fretc audit {ours:.2f} s CPU, {base_label} {base:.2f} s CPU: "
          f"ratio {ours / base:.2f}")


def main() -> int:
    """Print the figures; 2 when the PX4 logs of ../shared are absent."""
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--copies", type=int, default=20, help="copies of the flight (long ULog)")
    ap.add_argument("--minutes", type=float, default=20.0, help="length of the long MCAP")
    ap.add_argument("--repeat", type=int, default=3,
                    help="alternated runs of each command (best kept)")
    args = ap.parse_args()
    REPEAT[0] = max(1, args.repeat)
    if not PX4.exists():
        print(f"{PX4} is absent (../shared)")
        return 2
    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    sys.path.insert(0, str(ROOT / "bench"))
    from _encode import copy_as
    import bench_read

    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        start, = _best(_fretc() + ["--version"])
        print(f"start-up: fretc --version {start:.2f} s CPU")
        (tmp / "px4.fret").write_text(PX4_FRET)
        (tmp / "px4.bindings.toml").write_text(PX4_BINDINGS)
        long = tmp / "long.ulg"
        long_ulog(PX4, long, args.copies)
        for label, log in (("short", PX4), (f"long ({args.copies} copies)", long)):
            ours, plain, every = _best(
                _fretc() + ["audit", "-r", str(tmp / "px4.fret"), str(log), "--no-progress"],
                [sys.executable, "-c", PLAIN_ULOG, str(log), ",".join(TOPICS)],
                [sys.executable, "-c", PLAIN_ULOG, str(log), ""])
            print(f"ULog {label}, {log.stat().st_size / 1e6:.1f} MB:")
            _line("3 requirements", ours, f"pyulog's read of the {len(TOPICS)} topics", plain)
            _line("3 requirements", ours, "pyulog's read of every topic", every)
        ours, plain, every = _in_process("ulog", long, tmp / "px4.fret", PX4, ROOT)
        print(f"ULog long, in one process: audit {ours:.2f} s CPU, pyulog 3 topics "
              f"{plain:.2f} s / every topic {every:.2f} s: ratio {ours / plain:.2f} / "
              f"{ours / every:.2f}")

        syn = tmp / "syn.mcap"
        bench_read.write_log(syn, args.minutes, "zstd")
        (tmp / "syn.fret").write_text(SYN_FRET)
        (tmp / "syn.bindings.toml").write_text(bench_read.BINDINGS)
        for enc in ("json", "protobuf"):
            short = copy_as(ROOT / "traces" / "stop_delay.mcap", tmp / f"stop_{enc}.mcap", enc)
            longer = copy_as(syn, tmp / f"syn_{enc}.mcap", enc)
            print(f"{enc} MCAP:")
            ours, plain = _best(
                _fretc() + ["audit", "-r", "requirements", str(short), "--no-progress"],
                [sys.executable, "-c", PLAIN_MCAP, str(short), enc])
            _line("short (stop_delay, 10 topics, every requirement)", ours,
                  "plain read + decode of every message", plain)
            ours, plain = _best(
                _fretc() + ["audit", "-r", str(tmp / "syn.fret"), str(longer), "--no-progress"],
                [sys.executable, "-c", PLAIN_MCAP, str(longer), enc])
            _line(f"long ({args.minutes:g} min, {longer.stat().st_size / 1e6:.0f} MB)", ours,
                  "plain read + decode of every message", plain)
            ours, plain = _in_process(enc, longer, tmp / "syn.fret", short, ROOT)
            print(f"  long, in one process: audit {ours:.2f} s CPU, plain read + decode "
                  f"{plain:.2f} s CPU: ratio {ours / plain:.2f}")
        ours, = _best(_fretc() + ["audit", "-r", str(tmp / "syn.fret"), str(syn),
                                 "--no-progress"])
        print("cdr MCAP (the same long log, for comparison):")
        print(f"  fretc audit {ours:.2f} s CPU")
    return 0


if __name__ == "__main__":
    sys.exit(main())
