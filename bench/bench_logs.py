"""Reading speed of the log formats beside ROS's CDR: a PX4 ULog audit against pyulog's own
read of the same topics, and a json / protobuf MCAP audit against a plain read and decode of
every message (the ``mcap`` reader with Python's ``json``, or with mcap-protobuf-support's
decoder). Each figure is the CPU time (user + system) of a command run as a user runs it,
start-up included, measured in this one run; the ratio is ours over the baseline.

    python bench/bench_logs.py            # needs ../shared (the PX4 logs)

The json and protobuf logs are copies of ``traces/stop_delay.mcap`` written by
``tests/logs/_encode.py`` (the mcap writer).
"""

from __future__ import annotations

import resource
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
PLAIN_ULOG = """
import sys
from pyulog import ULog
u = ULog(sys.argv[1], message_name_filter_list=sys.argv[2].split(","))
n = sum(len(d.data["timestamp"]) for d in u.data_list)
print(n)
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


def _cpu(cmd: list[str], cwd: Path) -> float:
    """CPU seconds (user + system) of ``cmd`` run to its end."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode not in (0, 1, 3):
        raise SystemExit(f"{' '.join(cmd)} failed ({out.returncode}): {out.stderr[-500:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _fretc() -> list[str]:
    return [sys.executable, "-m", "fretc"]


def main() -> int:
    """Print the figures; 2 when the PX4 logs of ../shared are absent."""
    if not PX4.exists():
        print(f"{PX4} is absent (../shared)")
        return 2
    sys.path.insert(0, str(ROOT / "tests" / "logs"))
    from _encode import copy_as

    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        (tmp / "px4.fret").write_text(PX4_FRET)
        (tmp / "px4.bindings.toml").write_text(PX4_BINDINGS)
        ours = _cpu(_fretc() + ["audit", "-r", str(tmp / "px4.fret"), str(PX4),
                                "--no-progress"], ROOT)
        plain = _cpu([sys.executable, "-c", PLAIN_ULOG, str(PX4), ",".join(TOPICS)], ROOT)
        print(f"ULog {PX4.name}: fretc audit {ours:.2f} s CPU, pyulog read of the same "
              f"{len(TOPICS)} topics {plain:.2f} s CPU: ratio {ours / plain:.2f}")
        for enc in ("json", "protobuf"):
            log = copy_as(ROOT / "traces" / "stop_delay.mcap", tmp / f"stop_{enc}.mcap", enc)
            ours = _cpu(_fretc() + ["audit", "-r", "requirements", str(log), "--no-progress"],
                        ROOT)
            plain = _cpu([sys.executable, "-c", PLAIN_MCAP, str(log), enc], ROOT)
            print(f"{enc} MCAP (stop_delay, 10 topics): fretc audit of every requirement "
                  f"{ours:.2f} s CPU, plain read + decode of every message {plain:.2f} s CPU: "
                  f"ratio {ours / plain:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
