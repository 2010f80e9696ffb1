"""The recorded messages ``fretc shield-replay`` copies into the shielded recording: fretc's
own MCAP reader with the messages' bytes kept
(:class:`fretc.shield.replay_records.RecordedLog`, which reads a damaged file up to its
damage as the audit does) against the ``mcap`` library's
``make_reader(f).iter_messages(log_time_order=True)`` (which stops at the first damaged
chunk or record; what the replay used before), over the same MCAP files, in one run.

Prints, per file: the messages copied (equal: asserted, with their bytes and log times),
the best of ``--repeat`` CPU times of each, and their ratio (ours / the library's). The
replay's command, start-up included, is timed by ``--command``: ``fretc shield-replay`` of
the docs' shield over each file, CPU time of the child process.

    python bench/bench_replay_records.py                      # the shipped traces
    python bench/bench_replay_records.py --repeat 5 --command
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def library(path: Path) -> list[tuple[int, str, bytes]]:
    """(log time, topic, bytes) of every message, by the mcap library."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        return [(m.log_time, c.topic, bytes(m.data))
                for _s, c, m in make_reader(f).iter_messages(log_time_order=True)]


def ours(path: Path) -> list[tuple[int, str, bytes]]:
    """(log time, topic, bytes) of every message, by the replay's reader."""
    from fretc.shield.replay_records import RecordedLog

    return [(r.log_time, r.channel.topic, r.data) for r in RecordedLog(path, "mcap").records()]


def cpu(fn, path: Path, repeat: int) -> float:
    """The best of ``repeat`` CPU times (s) of ``fn(path)``."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        fn(path)
        best = min(best, time.process_time() - t0)
    return best


def command_cpu(path: Path, shield: Path, out: Path) -> float:
    """CPU time (s) of ``fretc shield-replay`` over ``path`` in a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-m", "fretc", "shield-replay", str(shield), str(path),
                    "-o", str(out), "-r", str(ROOT / "requirements" / "shield" /
                                              "release.fret")],
                   capture_output=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--command", action="store_true",
                    help="also time fretc shield-replay over each file (CPU, start-up in)")
    args = ap.parse_args()
    files = args.files or sorted((ROOT / "traces").glob("*.mcap"))
    tmp = Path(tempfile.mkdtemp())
    shield = tmp / "shield"
    if args.command:
        subprocess.run([sys.executable, "-m", "fretc", "shield",
                        str(ROOT / "requirements" / "safe_ros.fret"),
                        str(ROOT / "requirements" / "shield" / "release.fret"), "-b",
                        str(ROOT / "requirements" / "shield" / "safe_ros_shield.bindings.toml"),
                        "--inputs", "too_close,scan_stale,clearance,obstacle_ahead,"
                        "obstacle_behind", "--outputs", "stopped,stop_requested,forwarded_zero,"
                        "linear_speed,angular_speed,linear_velocity", "--emit", "python", "-o",
                        str(shield)], check=True, capture_output=True)
    print(f"{'file':28} {'messages':>8} {'library s':>10} {'ours s':>8} {'ratio':>6}"
          + (f" {'command s':>10}" if args.command else ""))
    for path in files:
        a, b = library(path), ours(path)
        assert sorted(a) == sorted(b), f"{path}: the readers disagree"
        t_lib, t_ours = cpu(library, path, args.repeat), cpu(ours, path, args.repeat)
        line = (f"{path.name:28} {len(a):8d} {t_lib:10.3f} {t_ours:8.3f} "
                f"{t_ours / t_lib:6.2f}")
        if args.command:
            line += f" {command_cpu(path, shield, tmp / 'out'):10.2f}"
        print(line)


if __name__ == "__main__":
    main()
