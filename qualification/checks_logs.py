"""The validation suite's checks on recorded logs: MCAP files written here by the ``mcap``
and ``rosbags`` libraries (not by fretc), audited by ``fretc audit`` with bindings, against
the tick rules (docs/guide/ticks.md), damage (docs/guide/audits.md) and REP 117's LaserScan
readings (docs/bindings.md); and a CSV trace still being written while it is audited
(docs/guide/audits.md, Long CSV traces).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fretc.qualification.checks import Check, Run
from fretc.qualification.checks_audit import fretc, verdicts

S = 1_000_000_000
MS = 1_000_000
#: a message to write: (topic, log time in ns, value: a float for std_msgs/msg/Float64, a
#: list of ranges for sensor_msgs/msg/LaserScan)
Message = tuple[str, int, Any]


def write_mcap(path: Path, messages: list[Message], chunk_size: int = 1 << 20,
               stamps: dict[int, int] | None = None) -> None:
    """An MCAP file of ``messages`` (ROS 2 CDR by ``rosbags``, framed by ``mcap``'s writer,
    with CRCs): a list value is a LaserScan's ranges (0.1 .. 10 m, 4 beams over 90 degrees),
    its header stamp its log time or ``stamps[i]`` (ns) for the i-th message, any other a
    Float64."""
    import numpy as np
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=chunk_size)
        w.start(profile="ros2", library="fretc-qualify")
        channels: dict[str, tuple[int, str]] = {}
        for i, (topic, time_ns, value) in enumerate(messages):
            typ = "sensor_msgs/msg/LaserScan" if isinstance(value, list) else \
                "std_msgs/msg/Float64"
            if topic not in channels:
                schema = w.register_schema(typ, "ros2msg", store.generate_msgdef(
                    typ, ros_version=2)[0].encode())
                channels[topic] = (w.register_channel(topic, "cdr", schema), typ)
            if isinstance(value, list):
                T = store.types
                at = (stamps or {}).get(i, time_ns)
                stamp = T["builtin_interfaces/msg/Time"](sec=at // S, nanosec=at % S)
                msg = T[typ](header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="laser"),
                             angle_min=-0.785, angle_max=0.785, angle_increment=0.5233,
                             time_increment=0.0, scan_time=0.1, range_min=0.1, range_max=10.0,
                             ranges=np.array(value, dtype=np.float32),
                             intensities=np.array([], dtype=np.float32))
            else:
                msg = store.types[typ](data=value)
            w.add_message(channels[topic][0], log_time=time_ns,
                          data=bytes(store.serialize_cdr(msg, typ)), publish_time=time_ns,
                          sequence=i)
        w.finish()


def mcap_audit(run: Run, name: str, messages: list[Message], requirements: str,
               bindings: str, chunk_size: int = 1 << 20, cut: float | None = None
               ) -> tuple[int, dict[str, Any] | None, str]:
    """Audit ``requirements`` with ``bindings`` (TOML texts) on an MCAP log of
    ``messages`` written in the folder ``name`` (``cut``: only that fraction of the file
    kept): (exit code, the audit JSON or None, the command's output)."""
    folder = run.work / name
    folder.mkdir(parents=True, exist_ok=True)
    log = folder / f"{name}.mcap"
    write_mcap(log, messages, chunk_size)
    if cut is not None:
        data = log.read_bytes()
        log.write_bytes(data[:int(len(data) * cut)])
    (folder / "requirements.fret").write_text(requirements, encoding="utf-8")
    (folder / "b.toml").write_text(bindings, encoding="utf-8")
    out = folder / "audit.json"
    code, text = fretc(run, ["audit", "-r", str(folder / "requirements.fret"), "--bindings",
                             str(folder / "b.toml"), str(log), "--json", str(out),
                             "--no-progress"])
    return code, (json.loads(out.read_text("utf-8")) if out.exists() else None), text


T1 = "T1: the sw shall always satisfy x < 5\n"
PERIOD = '[tick]\nperiod = "100 ms"\n\n[variables]\nx = "/x.data"\n'


def check_mcap_ticks(run: Run) -> list[str]:
    """The tick rules on an MCAP log at a 100 ms period: the grid from the first multiple
    of the period at or after the first message to the first at or after the last; a
    message exactly at a tick is held by that tick (sample and hold)."""
    msgs = [("/x", 1_050 * MS, 1.0), ("/x", 1_200 * MS, 9.0), ("/x", 1_250 * MS, 1.0),
            ("/x", 1_350 * MS, 1.0)]
    code, doc, text = mcap_audit(run, "ticks", msgs, T1, PERIOD)
    v = verdicts(doc).get(("ticks.mcap", "T1"), {})
    fv = v.get("first_violation") or {}
    got = (code, v.get("verdict"), fv.get("tick"), fv.get("tick_time_ns"),
           v.get("first_tick_ns"), v.get("last_tick_ns"))
    want = (1, "violated", 1, 1_200 * MS, 1_100 * MS, 1_400 * MS)
    if got != want:
        return [f"(exit, verdict, violation tick, its time, first tick, last tick) = {got}, "
                f"expected {want}: {text.strip()[-200:]}"]
    return []


def check_tick_topic_and_warmup(run: Run) -> list[str]:
    """One tick per message of the tick topic, at its time; the ticks before every topic
    of the requirement has had a message are warm-up, not evaluated; and a requirement's
    verdict is the same audited alone as beside another requirement of other topics."""
    msgs = [("/x", 1_000 * MS + i * 100 * MS, 9.0 if i == 1 else 1.0) for i in range(6)]
    msgs += [("/y", 1_250 * MS + i * 100 * MS, 1.0) for i in range(4)]
    msgs.sort(key=lambda m: m[1])
    both = "T2: the sw shall always satisfy x < 5 & y < 5\n"
    bindings = ('[tick]\ntopic = "/x"\nnominal_rate = "10 Hz"\n\n[variables]\n'
                'x = "/x.data"\ny = "/y.data"\n')
    code, doc, text = mcap_audit(run, "tick-topic", msgs, both, bindings)
    v = verdicts(doc).get(("tick-topic.mcap", "T2"), {})
    got = (code, v.get("verdict"), v.get("ticks_evaluated"), v.get("warmup_ticks"),
           v.get("first_tick_ns"))
    # /x ticks at 1.0 .. 1.5 s; /y's first message at 1.25 s: ticks 1.0 .. 1.2 are warm-up
    # (the 9 at 1.1 s among them), 1.3 .. 1.5 s evaluated
    want = (0, "satisfied", 3, 3, 1_300 * MS)
    out = [] if got == want else [f"(exit, verdict, ticks evaluated, warm-up, first tick) = "
                                  f"{got}, expected {want}: {text.strip()[-200:]}"]
    _, alone, _ = mcap_audit(run, "alone", msgs, T1, bindings)
    _, beside, _ = mcap_audit(run, "beside", msgs, T1 + both, bindings)
    a, b = verdicts(alone).get(("alone.mcap", "T1")), verdicts(beside).get(("beside.mcap", "T1"))
    where = {"log": "", "source": ""}  # (each audit's own file names)
    if a is None or b is None or {**a, **where} != {**b, **where}:
        out.append("T1 audited beside T2 (which waits for /y) differs from T1 alone")
    return out


def check_mcap_damage(run: Run) -> list[str]:
    """An MCAP log cut short (a crashed recording) is read up to the damage: the log is
    partial, the damage listed, the exit code 3 (no violation in what was read) and no
    verdict claims a satisfaction the lost part could break."""
    msgs = [("/x", S + i * 50 * MS, 1.0) for i in range(400)]
    code, doc, text = mcap_audit(run, "damage", msgs, T1, PERIOD, chunk_size=2048, cut=0.6)
    if doc is None:
        return [f"no audit JSON (exit {code}): {text.strip()[-200:]}"]
    log = doc["logs"][0]
    v = verdicts(doc).get(("damage.mcap", "T1"), {})
    out = []
    if code != 3 or not log["partial"] or not log["problems"]:
        out.append(f"exit {code}, partial {log['partial']}, problems {len(log['problems'])}; "
                   "expected 3, partial, the damage listed")
    if v.get("verdict") == "satisfied" and not v.get("partial"):
        out.append("the damaged log's verdict is satisfied without being marked partial")
    return out


def check_blind_lidar(run: Run) -> list[str]:
    """REP 117 on a LaserScan: a scan whose every range is NaN (a blind LiDAR still
    publishing) makes ``min(/scan.ranges) < 0.5`` unknown, never a clear path; a scan
    whose every range is +inf (no return) is clear."""
    req = "L1: the robot shall always satisfy !too_close\n"
    bindings = ('[tick]\nperiod = "100 ms"\n\n[variables]\n'
                'too_close = "min(/scan.ranges) < 0.5"\n')
    nan, inf = float("nan"), float("inf")
    out = []
    for name, middle, want_code, want in (("blind", nan, 3, "unknown"),
                                          ("no-return", inf, 0, "satisfied")):
        msgs = [("/scan", S + i * 100 * MS, [middle] * 4 if 2 <= i < 5 else [5.0] * 4)
                for i in range(8)]
        code, doc, text = mcap_audit(run, name, msgs, req, bindings)
        v = verdicts(doc).get((f"{name}.mcap", "L1"), {})
        if (code, v.get("verdict")) != (want_code, want):
            out.append(f"{name}: exit {code}, {v.get('verdict')}; expected {want_code}, "
                       f"{want}: {text.strip()[-200:]}")
    return out


def check_csv_extent(run: Run) -> list[str]:
    """A CSV trace still being written during ``fretc audit`` (1000 rows, 1 s apart; rows
    appended once the first read is over, before the second: a logger going on) is judged
    over the bytes the first read found: R1 streamed and satisfied, R2 (a NaN at its first
    row: judged whole, from a second read) unknown, R3 streamed and violated at row 500
    (its values shown from a read again), each over 1000 rows to the same last tick
    (999 s), though the rows appended would violate R2 and R3 and double the ticks
    (docs/guide/audits.md, Long CSV traces)."""
    from fretc.audit import streamed

    folder = run.work / "extent"
    folder.mkdir(parents=True, exist_ok=True)
    req = folder / "r.fret"
    req.write_text("R1: the s shall always satisfy x <= 1\nR2: the s shall always satisfy y <= 1\n"
                   "R3: the s shall always satisfy z <= 1\n", encoding="utf-8")
    rows = ["x,y,z", "0,nan,0"] + ["0,0,0"] * 999
    rows[501] = "0,0,7"
    log = folder / "growing.csv"
    log.write_text("\n".join(rows) + "\n", encoding="ascii")
    size = log.stat().st_size
    sizes: list[int] = []
    close = streamed.CsvStreams.close

    def close_then_grow(self: Any, source: Any) -> None:
        close(self, source)
        sizes.append(log.stat().st_size)
        with open(log, "a", encoding="ascii") as f:
            f.write("5,5,5\n" * 1000)

    jpath = folder / "audit.json"
    streamed.CsvStreams.close = close_then_grow  # type: ignore[method-assign]
    try:
        code, text = fretc(run, ["audit", "-r", str(req), str(log), "--json", str(jpath),
                                 "--no-progress"])
    finally:
        streamed.CsvStreams.close = close  # type: ignore[method-assign]
    if sizes != [size]:
        return [f"the trace's sizes at the end of the first read {sizes}, expected [{size}] "
                "(the audit did not read it as it streams a CSV trace)"]
    doc = json.loads(jpath.read_text("utf-8")) if jpath.exists() else None
    got = {rid: v for (_, rid), v in verdicts(doc).items()}
    said = tuple((got.get(r, {}).get("verdict"), got.get(r, {}).get("ticks_evaluated"),
                  got.get(r, {}).get("last_tick_ns")) for r in ("R1", "R2", "R3"))
    want = (("satisfied", 1000, 999 * S), ("unknown", 1000, 999 * S),
            ("violated", 1000, 999 * S))
    out = []
    if (code, said) != (1, want):
        out.append(f"(exit, (verdict, ticks, last tick) of R1, R2, R3) = {(code, said)}, "
                   f"expected {(1, want)}: {text.strip()[-200:]}")
    fv = got.get("R3", {}).get("first_violation") or {}
    if fv.get("tick") != 500:
        out.append(f"R3's first violation at tick {fv.get('tick')}, expected 500")
    shown = {x.get("tick"): x.get("value") for x in
             (got.get("R3", {}).get("values") or {}).get("z", [])}
    if not shown or max(t for t in shown if t is not None) >= 1000 or shown.get(500) != 7.0:
        out.append("R3's values shown around its violation are not the first extent's rows "
                   f"(z at tick 500: {shown.get(500)}, expected 7.0; ticks up to "
                   f"{max((t for t in shown if t is not None), default=None)}, expected < 1000)")
    return out


#: the checks on MCAP logs, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("mcap-ticks", ("TOR-TCK-002", "TOR-TCK-003", "TOR-LOG-001"),
          "the tick grid and sample and hold on an MCAP log", check_mcap_ticks),
    Check("mcap-tick-topic", ("TOR-TCK-001", "TOR-TCK-004", "TOR-TCK-005"),
          "a tick topic, warm-up, and a requirement's own clock", check_tick_topic_and_warmup),
    Check("mcap-damage", ("TOR-DMG-001",),
          "an MCAP log cut short: partial, damage listed, exit 3", check_mcap_damage),
    Check("lidar-rep117", ("TOR-BND-002",),
          "a blind LiDAR is unknown, a LiDAR without return clear", check_blind_lidar),
    Check("csv-extent", ("TOR-LOG-002",),
          "a CSV trace growing during its audit: every requirement over one extent",
          check_csv_extent),
)
