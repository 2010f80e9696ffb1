"""``fretc inspect`` against a plain read and an audit of the same log, as commands.

Usage::

    python bench/bench_inspect.py [LOG ...] [--runs N]

For each log (default: the ROS 1 bags and MCAP files of ``../shared/data/foreign_logs`` and
``traces/nominal.mcap``), in one run, the CPU time (user + system of the child, start-up
included; median of ``--runs``) of:

* ``inspect``: ``fretc inspect LOG`` (every message of every topic decoded and every field
  summarized);
* ``plain``: a plain read of the same log with the libraries fretc uses: ``rosbags``'
  reader for a ROS 1 bag (every message deserialized), ``mcap``'s reader with ``rosbags``'
  CDR deserializer for an MCAP (every message deserialized);
* ``audit``: ``fretc audit`` of one requirement on the first numeric field of the log's
  busiest topic (``always x < 1e300``), the field ``inspect`` lists for it.

It prints the three figures and the ratios inspect / plain and inspect / audit.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "foreign_logs"

PLAIN = r'''
import sys
path = sys.argv[1]
n = 0
if path.endswith(".bag"):
    from rosbags.highlevel import AnyReader
    with AnyReader([__import__("pathlib").Path(path)]) as r:
        for conn, t, raw in r.messages():
            try:
                r.deserialize(raw, conn.msgtype)
            except Exception:
                pass
            n += 1
else:
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg
    store = get_typestore(Stores.ROS2_HUMBLE)
    done = set()
    with open(path, "rb") as f:
        for schema, channel, m in make_reader(f).iter_messages():
            if schema is not None and schema.name not in done:
                done.add(schema.name)
                try:
                    store.register(get_types_from_msg(schema.data.decode(), schema.name))
                except Exception:
                    pass
            try:
                store.deserialize_cdr(m.data, schema.name)
            except Exception:
                pass
            n += 1
print(n)
'''


def _cpu(cmd: list[str], runs: int, cwd: Path) -> float:
    """Median CPU seconds (user + system) of ``runs`` runs of ``cmd``, after a warm-up."""
    out = []
    for i in range(runs + 1):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        proc = subprocess.run(cmd, capture_output=True, cwd=cwd)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if proc.returncode not in (0, 1, 3):
            raise SystemExit(f"{' '.join(cmd)}: exit {proc.returncode}\n"
                             + proc.stderr.decode(errors="replace")[-2000:])
        if i:
            out.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(out)


def _audit_files(log: Path, folder: Path) -> list[str] | None:
    """A requirement and binding on the first numeric field of the busiest topic."""
    doc = json.loads(subprocess.run([sys.executable, "-m", "fretc", "inspect", "--json",
                                     str(log)], capture_output=True, text=True).stdout)[0]
    for t in sorted(doc["topics"], key=lambda t: -t["messages"]):
        for path, f in t["fields"].items():
            if "min" in f and "[" not in path:
                (folder / "x.fret").write_text("R1: the log shall always satisfy x < 1e300\n")
                (folder / "x.bindings.toml").write_text(
                    '[tick]\nperiod = "100 ms"\n[variables]\nx = ' + json.dumps(path) + "\n")
                return ["-r", str(folder / "x.fret")]
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("logs", nargs="*", type=Path)
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args(argv)
    logs = args.logs or sorted(p for p in SHARED.rglob("*") if p.suffix in (".bag", ".mcap")
                               ) + [ROOT / "traces" / "nominal.mcap"]
    env_cache = tempfile.mkdtemp(prefix="fretc-bench-inspect-")
    os.environ["FRETC_CACHE_DIR"] = env_cache
    print(f"CPU s, median of {args.runs} (commands, start-up included)")
    print(f"{'log':44} {'inspect':>8} {'plain':>8} {'audit':>8} {'insp/plain':>10} "
          f"{'insp/audit':>10}")
    for log in logs:
        with tempfile.TemporaryDirectory() as tmp:
            req = _audit_files(log, Path(tmp))
            insp = _cpu([sys.executable, "-m", "fretc", "inspect", str(log)], args.runs, ROOT)
            plain = _cpu([sys.executable, "-c", PLAIN, str(log)], args.runs, ROOT)
            audit = (_cpu([sys.executable, "-m", "fretc", "audit", "--no-progress", *req,
                           str(log)], args.runs, ROOT) if req else float("nan"))
        name = str(log.relative_to(SHARED) if SHARED in log.parents else log.name)
        print(f"{name:44} {insp:8.2f} {plain:8.2f} {audit:8.2f} {insp / plain:10.2f} "
              f"{insp / audit:10.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
