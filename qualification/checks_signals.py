"""The validation suite's checks of the signals fretc reads from logs, end to end on MCAP
logs written here by ``mcap`` and ``rosbags``: a topic's age to the log's end, the messages
between ticks, the bindings checked against the schemas, the limits on ticks and on a
chunk's size, and entity keys read exactly in MCAP's four message encodings (written here
by ``rosbags``, ``json``, ``cbor2`` and ``protobuf``) (docs/guide/ticks.md,
docs/bindings.md, docs/guide/audits.md).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from fretc.qualification.checks import Check, Run
from fretc.qualification.checks_audit import fretc, verdicts
from fretc.qualification.checks_logs import MS, PERIOD, T1, S, mcap_audit, write_mcap


def _said(code: int, v: dict[str, Any], text: str) -> str:
    """The exit code, verdict and the output's end, for a failure's sentence."""
    return f"exit {code}, {v.get('verdict')}: {text.strip()[-200:]}"


def check_age_to_the_end(run: Run) -> list[str]:
    """``age(/scan) > 0.3`` of a topic that stops at 2.9 s of a 10 s log (another topic goes
    on): violated from 3.3 s (tick 33 of the grid from 0), its clock ticking to the log's
    end; a requirement over /scan's values alone ends at its last message."""
    msgs = sorted([("/other", k * 100 * MS + MS, 1.0) for k in range(100)]
                  + [("/scan", k * 100 * MS, 1.0) for k in range(30)], key=lambda m: m[1])
    req = ("S: the lidar shall always satisfy !stale\n"
           "V: the lidar shall always satisfy scan_ok\n")
    bindings = ('[tick]\nperiod = "100 ms"\n\n[variables]\nstale = "age(/scan) > 0.3"\n'
                'scan_ok = "/scan.data > 0"\n')
    code, doc, text = mcap_audit(run, "age", msgs, req, bindings)
    got = verdicts(doc)
    s, v = got.get(("age.mcap", "S"), {}), got.get(("age.mcap", "V"), {})
    out = []
    fv = (s.get("first_violation") or {}).get("tick_time_ns")
    if (s.get("verdict"), fv, s.get("last_tick_ns")) != ("violated", 3_300 * MS, 10 * S):
        out.append(f"age: {s.get('verdict')} first at {fv} ns, last tick {s.get('last_tick_ns')}"
                   f"; expected violated at 3.3 s, ticks to 10 s ({_said(code, s, text)})")
    if (v.get("verdict"), v.get("last_tick_ns")) != ("satisfied", 2_900 * MS):
        out.append(f"values: {v.get('verdict')} to {v.get('last_tick_ns')} ns; expected "
                   "satisfied to /scan's last message at 2.9 s")
    return out


def check_messages_between_ticks(run: Run) -> list[str]:
    """A spike of /x between two ticks (at 1.15 s, 100 ms ticks): ``max_of_messages(/x.data)``
    folds it (violated at the tick after it, 1.2 s), where sample and hold never sees it."""
    msgs = [("/x", S + k * 50 * MS, 9.0 if k == 3 else 1.0) for k in range(10)]
    req = "M: the sw shall always satisfy peak < 5\n" + T1
    bindings = PERIOD + 'peak = "max_of_messages(/x.data)"\n'
    # the 9.0 at 1.15 s: the ticks at 1.1 and 1.2 s hold 1.0 (1.2 s's own message)
    code, doc, text = mcap_audit(run, "between", msgs, req, bindings)
    got = verdicts(doc)
    m, t = got.get(("between.mcap", "M"), {}), got.get(("between.mcap", "T1"), {})
    out = []
    fv = (m.get("first_violation") or {}).get("tick_time_ns")
    if (m.get("verdict"), fv) != ("violated", 1_200 * MS):
        out.append(f"max_of_messages: {m.get('verdict')} first at {fv} ns; expected violated "
                   f"at 1.2 s ({_said(code, m, text)})")
    if t.get("verdict") != "satisfied":
        out.append(f"sample and hold: {t.get('verdict')}; expected satisfied (the spike falls "
                   "between ticks)")
    return out


def check_schema_errors(run: Run) -> list[str]:
    """A binding naming a field the message does not have is an error of the requirements
    that read it, listing the message's fields and the closest name; the others are judged."""
    msgs = [("/x", S + k * 100 * MS, 1.0) for k in range(5)]
    req = "B: the sw shall always satisfy bad < 5\n" + T1
    code, doc, text = mcap_audit(run, "schema", msgs, req, PERIOD + 'bad = "/x.dat"\n')
    got = verdicts(doc)
    b, t = got.get(("schema.mcap", "B"), {}), got.get(("schema.mcap", "T1"), {})
    error = str(b.get("error") or "")
    out = []
    if code != 2 or b.get("verdict") != "error" or "data" not in error \
            or "did you mean 'data'" not in error:
        out.append(f"the misspelt field: {_said(code, b, text)}; error {error!r}, expected "
                   "exit 2, an error listing the field data and suggesting it")
    if t.get("verdict") != "satisfied":
        out.append(f"the requirement beside it: {t.get('verdict')}, expected satisfied")
    return out


def check_tick_limit(run: Run) -> list[str]:
    """A tick period that would give more than 10^8 ticks over the log (1 us over 1000 s) is
    an input error saying how many (exit 2), raised before the ticks are made."""
    msgs = [("/x", S, 1.0), ("/x", 1_001 * S, 1.0)]
    bindings = PERIOD.replace('"100 ms"', '"1 us"')
    code, doc, text = mcap_audit(run, "limit", msgs, T1, bindings)
    said = text + " ".join(str(v.get("error") or "") for v in verdicts(doc).values())
    if code != 2 or "ticks" not in said:
        return [f"exit {code}, expected 2 with the number of ticks: {said.strip()[-300:]}"]
    return []


def check_chunk_cap(run: Run) -> list[str]:
    """A compressed chunk that would expand past the cap (``FRETC_MAX_CHUNK_BYTES``, here
    64 KiB, beneath the 400 KiB chunks written) is damage named in the problems (exit 3),
    never read into memory whole."""
    msgs = [("/x", S + k * MS, 1.0) for k in range(6000)]
    old = os.environ.get("FRETC_MAX_CHUNK_BYTES")
    os.environ["FRETC_MAX_CHUNK_BYTES"] = str(64 * 1024)
    try:
        code, doc, text = mcap_audit(run, "bomb", msgs, T1, PERIOD, chunk_size=400 * 1024)
    finally:
        if old is None:
            os.environ.pop("FRETC_MAX_CHUNK_BYTES", None)
        else:
            os.environ["FRETC_MAX_CHUNK_BYTES"] = old
    problems = [] if doc is None else doc["logs"][0]["problems"]
    if code != 3 or not problems:
        return [f"exit {code} with {len(problems)} problems; expected 3 and the chunk named: "
                f"{text.strip()[-200:]}"]
    return []


def _gap_log(run: Run) -> tuple[Path, int, int]:
    """/v and /w at 10 Hz for 30 s, every value 1.0, /v's messages written first (so each
    chunk holds one topic), one /v chunk in the middle with a flipped bit: (the log, the
    bad chunk's first and last message time in ns)."""
    from mcap.reader import make_reader

    folder = run.work / "gap"
    folder.mkdir(parents=True, exist_ok=True)
    log = folder / "gap.mcap"
    write_mcap(log, [("/v", S + k * S // 10, 1.0) for k in range(300)]
               + [("/w", S + k * S // 10, 1.0) for k in range(300)], chunk_size=1024)
    with open(log, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None  # (the mcap writer writes a summary)
    chunks = sorted((c for c in summary.chunk_indexes
                     if {summary.channels[i].topic for i in c.message_index_offsets} == {"/v"}),
                    key=lambda c: c.message_start_time)
    bad = chunks[len(chunks) // 2]
    data = bytearray(log.read_bytes())
    data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x20
    log.write_bytes(bytes(data))
    return log, bad.message_start_time, bad.message_end_time


def check_gaps(run: Run) -> list[str]:
    """A chunk of /v failing its CRC in the middle of a 30 s log: the gap is listed (/v,
    chunk_crc, its span), ``v < 5`` is unknown (nothing held over the gap), ``w < 5`` is
    satisfied and the log is read to its end (exit 3); ``--bridge-gaps`` longer than the gap
    holds /v over it (satisfied, the gap listed as bridged), one not longer does not."""
    log, start, end = _gap_log(run)
    folder = log.parent
    (folder / "r.fret").write_text("RV: the sys shall always satisfy v < 5\n"
                                   "RW: the sys shall always satisfy w < 5\n", encoding="utf-8")
    (folder / "r.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                            'v = "/v.data"\nw = "/w.data"\n', "utf-8")
    out = []
    for bridge, want in ((None, "unknown"), (end - start, "unknown"),
                         (end - start + MS, "satisfied")):
        jpath = folder / f"a-{bridge}.json"
        extra = [] if bridge is None else ["--bridge-gaps", f"{bridge / 1e9!r} s"]
        code, text = fretc(run, ["audit", "-r", str(folder / "r.fret"), str(log), "--json",
                                 str(jpath), "--no-progress", *extra])
        doc = json.loads(jpath.read_text("utf-8")) if jpath.exists() else None
        got = {rid: v for (_, rid), v in verdicts(doc).items()}
        gaps = [] if doc is None else doc["logs"][0]["gaps"]
        g = gaps[0] if len(gaps) == 1 else {}
        said = (code, got.get("RV", {}).get("verdict"), got.get("RW", {}).get("verdict"),
                g.get("topics"), g.get("cause"), g.get("bridged"),
                (g.get("start_ns"), g.get("end_ns")),
                None if doc is None else doc["logs"][0].get("end_time_ns", 0) >= 30 * S)
        expected = (3, want, "satisfied", ["/v"], "chunk_crc", want == "satisfied",
                    (start, end), True)
        if said != expected:
            out.append(f"bridge {bridge} ns: (exit, RV, RW, gap topics, cause, bridged, span, "
                       f"read to the end) = {said}, expected {expected}: {text.strip()[-200:]}")
    return out


def check_header_time(run: Run) -> list[str]:
    """Header stamps as the time base (``time = "header"``, ``header_lag = "100 ms"``, a tick
    per /scan message): messages are released in stamp order once the newest stamp is the
    lag past them; a stamp older than one already released is skipped and reported
    (``header_backwards``), and one later than the lag allows is reported late
    (``header_late``)."""
    from fretc.common import problems as P
    from fretc.logs import open_log
    from fretc.signals.bindings.files import parse_bindings
    from fretc.signals.clock import sample

    #          log time, header stamp (ms), the first range
    rows = [(1000, 900, 1.0), (1100, 1050, 2.0), (1200, 1000, 3.0), (5000, 4900, 4.0),
            (5100, 1020, 5.0), (5200, 5150, 6.0)]
    folder = run.work / "header"
    folder.mkdir(parents=True, exist_ok=True)
    log = folder / "h.mcap"
    write_mcap(log, [("/scan", lt * MS, [x] * 4) for lt, _, x in rows],
               stamps={i: hs * MS for i, (_, hs, _) in enumerate(rows)})
    b = parse_bindings('[tick]\ntopic = "/scan"\ntime = "header"\nheader_lag = "100 ms"\n'
                       '[variables]\nx = "/scan.ranges[0]"\n')
    s = sample(open_log(str(log)), b)
    got = [(t.time // MS, round(float(t.values["x"]), 3)) for t in s]
    want = [(900, 1.0), (1000, 3.0), (1050, 2.0), (4900, 4.0), (5150, 6.0)]
    kinds = [(p.kind, None if p.log_time is None else p.log_time // MS)
             for p in s.signal_problems]
    want_kinds = [(P.HEADER_BACKWARDS, 1200), (P.HEADER_BACKWARDS, 5100), (P.HEADER_LATE, 5100)]
    out = []
    if got != want:
        out.append(f"ticks (stamp ms, value) {got}, expected {want}")
    if kinds != want_kinds:
        out.append(f"problems {kinds}, expected {want_kinds}")
    return out


#: the window functions of the windows check, with their reference over a window's values
WINDOWS: dict[str, tuple[str, Any]] = {
    "w_mean": ("mean(/a.data, 700 ms)", lambda xs: sum(xs) / len(xs)),
    "w_sum": ("sum(/a.data, 700 ms)", sum),
    "w_max": ("max(/a.data, 700 ms)", max),
    "w_median": ("median(/a.data, 700 ms)", lambda xs: _quantile(xs, 0.5)),
    "w_p90": ("percentile(/a.data, 90, 700 ms)", lambda xs: _quantile(xs, 0.9)),
    "w_var": ("variance(/a.data, 700 ms)",
              lambda xs: (sum((x - sum(xs) / len(xs)) ** 2 for x in xs) / (len(xs) - 1)
                          if len(xs) > 1 else float("nan"))),
}


def _quantile(xs: list[float], q: float) -> float:
    """The ``q`` quantile of ``xs`` interpolated linearly between order statistics (the
    definition pandas' ``quantile`` and numpy's ``percentile`` default to)."""
    ys = sorted(xs)
    pos = q * (len(ys) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(ys) - 1)
    return ys[lo] + (ys[hi] - ys[lo]) * (pos - lo)


def check_windows(run: Run) -> list[str]:
    """Windows over time (``mean(/a.data, 700 ms)``, sum, max, median, percentile,
    variance) sampled at 100 ms ticks of an MCAP log with irregular messages: at each tick
    each equals its function over the values of the messages in the window (t - 700 ms, t],
    computed here (no NaN where a window holds a message; the ticks before the first
    complete window are warm-up)."""
    import math
    import random as _random

    from fretc.logs import open_log
    from fretc.qualification.checks import SEED
    from fretc.signals.arrays import sample_arrays
    from fretc.signals.bindings.spec import TickSpec, make_bindings

    rnd = _random.Random(SEED + 8)
    # (and messages exactly a window's span before a tick: 1.3 s before the tick at 2.0 s)
    times = sorted(set(rnd.sample(range(0, 4000), 60)) | {1300, 2100, 2900})
    values = [round(rnd.uniform(-20, 20), 3) for _ in times]
    folder = run.work / "windows"
    folder.mkdir(parents=True, exist_ok=True)
    log = folder / "w.mcap"
    write_mcap(log, [("/a", S + t * MS, x) for t, x in zip(times, values, strict=True)])
    bindings = make_bindings({k: e for k, (e, _) in WINDOWS.items()},
                             TickSpec(period_ns=100 * MS))
    arrays = sample_arrays(open_log(str(log)), bindings)
    out = []
    for name, (_, f) in WINDOWS.items():
        for k, t in enumerate(arrays.times.tolist()):
            xs = [x for m, x in zip(times, values, strict=True)
                  if t - 700 * MS < S + m * MS <= t]
            want = f(xs) if xs else float("nan")
            got = float(arrays.columns[name][k])
            if not (math.isclose(got, want, rel_tol=1e-9, abs_tol=1e-9)
                    or (math.isnan(got) and math.isnan(want))):
                out.append(f"{WINDOWS[name][0]} at {t} ns: {got}, expected {want}")
                break
    if not len(arrays.times):
        out.append("no tick sampled")
    return out


#: the ids of the entity keys check: a float64 merges 2**53 with 2**53 + 1 and 2**64 - 2
#: with 2**64 - 1 (2**53 - 1 and 2**53 are two doubles, the control); GHOST rides only in
#: the messages between ticks
KEYS = (2**53 - 1, 2**53, 2**53 + 1, 2**64 - 2, 2**64 - 1)
VIOLATORS = (2**53 + 1, 2**64 - 1)
GHOST = 2**60 + 3
TRACK_MSG = "uint64 id\nfloat64 distance"
#: the entity bindings of the check (tests/_logs.py's tracks): each track's distance, and
#: the track present where it is in the message held at the tick
TRACK_BINDINGS = ('[tick]\nperiod = "100 ms"\n[entities]\ntrack = "/tracks.tracks[:].id"\n'
                  '[variables]\ndist = \'min(/tracks.tracks[:]{id==$track}.distance)\'\n'
                  "present = 'count(/tracks.tracks[:]{id==$track}.distance >= 0) = 1'\n")


def _tracks(k: int) -> list[dict[str, Any]]:
    """The tracks of message ``k`` (every 50 ms from 1 s): the five keys 2 m away, the
    violators 0.2 m at k = 6 (the tick at 1.3 s), the ghost in the odd messages alone
    (between ticks: the last message, at the last tick, is even)."""
    out = [{"id": i, "distance": 0.2 if k == 6 and i in VIOLATORS else 2.0} for i in KEYS]
    return out + ([{"id": GHOST, "distance": 2.0}] if k % 2 else [])


def _track_payloads(encoding: str) -> tuple[tuple[str, str, bytes], list[bytes]]:
    """``/tracks`` (``trk64/msg/TrackArray`` of ``uint64 id``, ``float64 distance``) in
    ``encoding`` (cdr by rosbags, json with a JSON Schema, cbor without schema, protobuf
    with a ``FileDescriptorSet``): ((schema name, schema encoding, schema bytes), the thirteen
    messages' bytes). The ids are written as the integers they are, by the libraries."""
    docs = [{"tracks": _tracks(k)} for k in range(13)]
    if encoding == "cdr":
        import numpy as np
        from rosbags.typesys import Stores, get_typestore, get_types_from_msg

        store = get_typestore(Stores.ROS2_HUMBLE)
        store.register(get_types_from_msg(TRACK_MSG, "trk64/msg/Track"))
        store.register(get_types_from_msg("trk64/Track[] tracks", "trk64/msg/TrackArray"))
        T = store.types

        def cdr(doc: dict[str, Any]) -> bytes:
            msg = T["trk64/msg/TrackArray"](tracks=[
                T["trk64/msg/Track"](id=np.uint64(t["id"]), distance=t["distance"])
                for t in doc["tracks"]])
            return bytes(store.serialize_cdr(msg, "trk64/msg/TrackArray"))
        text = f"trk64/Track[] tracks\n{'=' * 80}\nMSG: trk64/Track\n{TRACK_MSG}\n"
        return ("trk64/msg/TrackArray", "ros2msg", text.encode()), [cdr(d) for d in docs]
    if encoding == "json":
        schema = {"type": "object", "title": "trk64/msg/TrackArray", "properties": {
            "tracks": {"type": "array", "items": {"type": "object", "properties": {
                "id": {"type": "integer"}, "distance": {"type": "number"}}}}}}
        return (("trk64/msg/TrackArray", "jsonschema", json.dumps(schema).encode()),
                [json.dumps(d).encode() for d in docs])
    if encoding == "cbor":
        import cbor2

        return ("", "", b""), [cbor2.dumps(d) for d in docs]
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    f = descriptor_pb2.FileDescriptorProto(name="trk64/msg.proto", package="trk64.msg",
                                           syntax="proto3")
    track = f.message_type.add(name="Track")
    track.field.add(name="id", number=1, type=4, label=1)  # TYPE_UINT64
    track.field.add(name="distance", number=2, type=1, label=1)  # TYPE_DOUBLE
    f.message_type.add(name="TrackArray").field.add(
        name="tracks", number=1, type=11, label=3, type_name=".trk64.msg.Track")
    fds = descriptor_pb2.FileDescriptorSet(file=[f])
    pool = descriptor_pool.DescriptorPool()
    pool.Add(f)
    Arr = message_factory.GetMessageClass(pool.FindMessageTypeByName("trk64.msg.TrackArray"))

    def pb(doc: dict[str, Any]) -> bytes:
        msg: Any = Arr()
        for t in doc["tracks"]:
            item = msg.tracks.add()
            item.id, item.distance = t["id"], t["distance"]
        return bytes(msg.SerializeToString())
    return (("trk64.msg.TrackArray", "protobuf", fds.SerializeToString()),
            [pb(d) for d in docs])


def _track_log(path: Path, encoding: str) -> None:
    """An MCAP of the thirteen ``/tracks`` messages (every 50 ms from 1 s to 1.6 s) in
    ``encoding``."""
    from mcap.writer import Writer

    (name, schema_encoding, data), payloads = _track_payloads(encoding)
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2" if encoding == "cdr" else "", library="fretc-qualify")
        sid = w.register_schema(name, schema_encoding, data) if name else 0
        cid = w.register_channel("/tracks", encoding, sid)
        for k, payload in enumerate(payloads):
            t = S + k * 50 * MS
            w.add_message(cid, log_time=t, data=payload, publish_time=t, sequence=k)
        w.finish()


def check_entity_keys(run: Run) -> list[str]:
    """uint64 entity keys past 2**53 (2**53 and 2**53 + 1, 2**64 - 2 and 2**64 - 1: one
    double each pair) in ROS 2 CDR, JSON, CBOR and protobuf MCAP logs written here: each id
    is its own entity named exactly, the violators (0.2 m at 1.3 s) violated there, the
    others satisfied, the requirement violated (exit 1); a track carried only by the
    messages between ticks is read at no tick: ``unknown`` with that reason, never
    satisfied (docs/bindings.md, One verdict per entity)."""
    req = "@tick_period 100 ms\nT: in present mode the robot shall always satisfy dist > 0.5\n"
    want = {f"T[track={i}]": "violated" if i in VIOLATORS else "satisfied" for i in KEYS}
    want[f"T[track={GHOST}]"] = "unknown"
    want["T"] = "violated"
    out = []
    for encoding in ("cdr", "json", "cbor", "protobuf"):
        folder = run.work / f"keys-{encoding}"
        folder.mkdir(parents=True, exist_ok=True)
        log = folder / f"tracks-{encoding}.mcap"
        _track_log(log, encoding)
        (folder / "t.fret").write_text(req, encoding="utf-8")
        (folder / "t.bindings.toml").write_text(TRACK_BINDINGS, encoding="utf-8")
        jpath = folder / "audit.json"
        code, text = fretc(run, ["audit", "-r", str(folder / "t.fret"), str(log), "--json",
                                 str(jpath), "--no-progress"])
        doc = json.loads(jpath.read_text("utf-8")) if jpath.exists() else None
        got = {rid: v for (_, rid), v in verdicts(doc).items()}
        said = {rid: v.get("verdict") for rid, v in got.items()}
        if said != want or code != 1:
            out.append(f"{encoding}: exit {code}, verdicts {said}; expected exit 1, {want}: "
                       f"{text.strip()[-200:]}")
            continue
        for i in VIOLATORS:
            fv = (got[f"T[track={i}]"].get("first_violation") or {}).get("tick_time_ns")
            if fv != S + 300 * MS:
                out.append(f"{encoding}: track {i} first violated at {fv} ns, expected "
                           f"{S + 300 * MS} (1.3 s)")
        reason = str(got[f"T[track={GHOST}]"].get("unknown_reason") or "")
        if "read at no tick" not in reason:
            out.append(f"{encoding}: the track read at no tick is unknown for {reason!r}, "
                       "expected 'read at no tick'")
    return out


#: the checks of the signals and the logs' limits, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("signals-age", ("TOR-TCK-006",),
          "a topic silent to the log's end is stale there", check_age_to_the_end),
    Check("signals-between-ticks", ("TOR-BND-005",),
          "the messages between ticks folded by max_of_messages", check_messages_between_ticks),
    Check("ticks-header-time", ("TOR-TCK-008",),
          "header stamps: released in stamp order, backwards and late reported",
          check_header_time),
    Check("bindings-windows", ("TOR-BND-004",),
          "windows over time against their functions computed here", check_windows),
    Check("bindings-schema", ("TOR-BND-001",),
          "a misspelt field: an error listing the fields, the others judged",
          check_schema_errors),
    Check("ticks-limit", ("TOR-TCK-009",),
          "too many ticks: an input error before they are made", check_tick_limit),
    Check("mcap-gaps", ("TOR-DMG-002", "TOR-DMG-006"),
          "a damaged chunk is a gap: unknown, never held, but bridged", check_gaps),
    Check("mcap-chunk-cap", ("TOR-DMG-005",),
          "a chunk expanding past the cap is damage", check_chunk_cap),
    Check("bindings-entity-keys", ("TOR-BND-003",),
          "uint64 entity keys past 2^53 exact in four encodings; a track read at no tick "
          "unknown", check_entity_keys),
)
