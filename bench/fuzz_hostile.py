"""Fuzz fretc with hostile inputs other than requirement text: forged MCAP indexes,
decompression bombs, cut and bit-flipped logs, schemas that lie, hostile binding files,
hostile live frames (Foxglove and rosbridge) and buses (DDS, Zenoh), and hostile requirement
sources, outputs and test runs:

    python bench/fuzz_hostile.py --count 2000 [--seed N] [--classes index,bomb,...] [--shard K/N]

Each run takes a fresh seed unless ``--seed`` is given; the seed is printed first, and the
same seed gives the same inputs. Per class:

* ``index``: a small MCAP with its ChunkIndex records (times, offsets, lengths, channel
  lists), MessageIndex records and summary CRC forged at random; audited;
* ``bomb``: a chunk whose records are replaced by a zstd or LZ4 stream of up to 64 MiB of
  zeros, declaring a random uncompressed size; audited;
* ``cut``: a shipped trace (or the small MCAP) cut at a random byte or with 1-100 random bit
  flips; audited;
* ``schema``: the small MCAP with its Twist schema lying (fields swapped, renamed,
  retyped, dropped, added); audited;
* ``lost``: the small MCAP with a second ``/a`` channel whose messages, at random places
  mid-log, cannot be decoded (a schema that lies, bad CDR, a truncated body, an unknown
  message encoding); audited: a verdict on ``/a`` must be decided (LTL3) before the first
  such message, the requirement on ``/cmd_vel`` alone must equal the intact log's, and the
  data problems must count every message lost;
* ``nan``: the small MCAP with NaN values of ``/a`` at random places (or only NaN),
  audited with ``a > 0`` compared in the requirement: a verdict must be decided (LTL3)
  before the first NaN;
* ``bindings``: a binding file mutated (deep nesting, long chains, chained and doubling
  references, deep TOML, huge durations, random characters); parsed;
* ``frames``: a sequence of Foxglove or rosbridge frames (non-object JSON, fields of the
  wrong type, huge log times, truncated message frames, advertisement floods) handed to the
  client's session and the watch source;
* ``ws``: a hostile Foxglove WebSocket server (publisher restarts, deep frames, huge schemas,
  old and huge log times, cut payloads) watched by ``fretc watch --duration 3``;
* ``bus``: hostile DDS or Zenoh publishers (random payloads, one publisher leaving while the
  others go on, a publisher leaving and coming back, floods) watched for 4 s;
* ``typed``: a command fed a wrongly typed value in a FRET JSON export, a binding file, a
  ``--psl-map`` file or a falsify space (``bench/fuzz_live_inputs.py`` has these three);
* ``lsp``: a hostile session of ``fretc lsp`` (framing, documents, requests at random
  places; ``bench/fuzz_lsp.py``): no traceback, every request answered within 15 s, under
  1 GB, a clean exit;
* ``flight``: damaged PX4 ULogs and ArduPilot DataFlash logs (cut, zeroed spans, garbage
  after the formats; ``bench/fuzz_flight.py``), audited against the intact log's verdicts;
* ``reqif``, ``doorstop``, ``exports``, ``explain``: hostile ReqIF files and XHTML values,
  Doorstop trees, exported results read back by each format's library, and ``fretc
  explain``/``simulate`` of random requirements and traces (``bench/fuzz_sources.py``);
* ``statistics``: hostile fleets, campaigns and option values against the statistics of
  probability requirements (``bench/fuzz_statistics.py``: its oracle, never a bound decided
  that the trials do not support);
* ``crunner``, ``split``, ``prism``, ``entities``, ``windows`` (the C runner's input and
  names, PRISM, the entity bound, windows at 10^6 messages: ``bench/fuzz_emit.py``),
  ``testsjson``, ``drive``, ``lspnest`` (``bench/fuzz_runs.py``).

A failure is a traceback (any exception but an input error), or for an audited log a verdict
the damaged log does not support (:func:`unsupported`: the rule of
``tests/audit/test_damaged_logs.py`` against the intact log's verdicts and LTL3
verdicts), or a forged schema read as if true. Printed with the class, seed and input
number; the summary line gives inputs, tracebacks, unsupported verdicts and the peak RSS
(``resource.getrusage``). Exit 1 when anything failed.
"""

from __future__ import annotations

import argparse
import asyncio
import io
import json
import random
import resource
import struct
import sys
import tempfile
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "monitors"))

from fuzz_gaps import LOST, run_lost, run_nan  # noqa: E402  (the lost and nan classes)
from fuzz_live_inputs import run_bus, run_inputs, run_ws  # noqa: E402  (ws, bus, typed)
from fuzz_lsp import run_lsp  # noqa: E402  (lsp)
from fuzz_statistics import run_statistics  # noqa: E402  (the statistics class)
from fuzz_flight import run_flight  # noqa: E402  (the flight class)
from fuzz_sources import run_doorstop, run_explain, run_exports, run_reqif  # noqa: E402
from fuzz_emit import EMIT_CLASSES  # noqa: E402  (crunner, split, prism, entities, windows)
from fuzz_runs import RUN_CLASSES  # noqa: E402  (testsjson, drive, lspnest)

#: the share of ``cut`` inputs taken from the shipped traces (the rest: the small MCAP)
TRACE_SHARE = 0.3
MORE = {**EMIT_CLASSES, **RUN_CLASSES}  # name -> (runner(rng, tmp), weight)
CLASSES = ("index", "bomb", "cut", "schema", "lost", "nan", "bindings", "frames", "ws",
           "bus", "typed", "lsp", "statistics", "flight", "reqif", "doorstop", "exports",
           "explain", *MORE)
FRET = ("@tick_period 100 ms\nRA: the robot shall always satisfy a_ok\n"
        "RV: the robot shall always satisfy v_ok\n"
        "RE: the robot shall eventually satisfy !a_ok\n")
BINDINGS = ('[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\n'
            'a_ok = "/a.data > 0"\nv_ok = "/cmd_vel.linear.x < 100"\n')
TWIST = ("Vector3 linear\nVector3 angular\n" + "=" * 80 + "\nMSG: geometry_msgs/Vector3\n"
         "float64 x\nfloat64 y\nfloat64 z\n")
S = 1_000_000_000


# --------------------------------------------------------------------------- logs
def small_mcap(schema: str = TWIST, dip: int = 37, chunk_size: int = 700,
               lost: tuple | None = None, values: list[float] | None = None) -> bytes:
    """A small chunked MCAP: /a (Float64, 1.0 but 0.0 at message ``dip``; ``values``
    instead when given) and /cmd_vel (Twist, linear.x 1.0, angular.x 500.0), 60 of each,
    50 ms apart; ``lost = (how, indexes)``: at those indexes /a's message is on a second
    channel that cannot be decoded (:data:`LOST`)."""
    from mcap.writer import CompressionType, Writer

    out = io.BytesIO()
    w = Writer(out, chunk_size=chunk_size, compression=CompressionType.ZSTD)
    w.start("ros2", "fretc-fuzz")
    fs = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data")
    ts = w.register_schema("geometry_msgs/msg/Twist", "ros2msg", schema.encode())
    a, v = w.register_channel("/a", "cdr", fs), w.register_channel("/cmd_vel", "cdr", ts)
    bad_at, bad, payload = set(), None, b""
    if lost is not None:
        (text, enc, payload), bad_at = LOST[lost[0]], set(lost[1])
        bad = w.register_channel("/a", enc, w.register_schema("std_msgs/msg/Float64",
                                                              "ros2msg", text))
    for k in range(60):
        t = 10 * S + k * 50_000_000
        x = values[k] if values is not None else (0.0 if k == dip else 1.0)
        if k in bad_at:
            w.add_message(bad, log_time=t, publish_time=t, data=payload)
        else:
            w.add_message(a, log_time=t, publish_time=t,
                          data=b"\x00\x01\x00\x00" + struct.pack("<d", x))
        w.add_message(v, log_time=t, publish_time=t, data=b"\x00\x01\x00\x00" + struct.pack(
            "<6d", 1.0, 0.0, 0.0, 500.0, 0.0, 0.0))
    w.finish()
    return out.getvalue()


def _records(data, start: int, end: int):
    pos = start
    while pos + 9 <= end:
        opcode, length = struct.unpack_from("<BQ", data, pos)
        yield pos, opcode, length
        pos += 9 + length


def forge_index(rng: random.Random, data: bytes) -> bytes:
    """``data`` with its ChunkIndex and MessageIndex records forged at random (module
    docstring) and the summary CRC set to 0 ("not computed")."""
    d = bytearray(data)
    start = struct.unpack_from("<Q", d, len(d) - 28)[0]
    struct.pack_into("<I", d, len(d) - 12, 0)  # the footer's summary CRC
    big = (0, 1, 2**63 - 1, 2**63, 2**64 - 1, rng.getrandbits(64))
    for pos, opcode, length in list(_records(d, 8, start)):
        if opcode == 0x07 and rng.random() < 0.5:  # MessageIndex
            struct.pack_into("<H", d, pos + 9, rng.randrange(5))
            for k in range(pos + 15, pos + 9 + length - 7, 8):
                struct.pack_into("<Q", d, k, rng.choice(big))
        if opcode == 0x0F and rng.random() < 0.5:  # DataEnd: data CRC "not computed"
            struct.pack_into("<I", d, pos + 9, 0)
    for pos, opcode, _length in list(_records(d, start, len(d) - 37)):
        if opcode != 0x08 or rng.random() < 0.4:
            continue
        field = rng.randrange(5)
        if field < 4:  # start, end, chunk offset, chunk length
            old = struct.unpack_from("<Q", d, pos + 9 + 8 * field)[0]
            near = (old + rng.randrange(-9, 9)) % 2**64
            struct.pack_into("<Q", d, pos + 9 + 8 * field, rng.choice(big + (near,)))
        else:  # the channel list
            n = struct.unpack_from("<I", d, pos + 41)[0]
            for k in range(pos + 45, pos + 45 + n, 10):
                struct.pack_into("<HQ", d, k, rng.randrange(5), rng.choice(big))
    return bytes(d)


def bomb(rng: random.Random, data: bytes, n: int | None = None, codec: str | None = None,
         declared: int | None = None) -> bytes:
    """The first chunk of ``data`` with its records replaced by a ``codec`` stream of ``n``
    zero bytes (random: up to 64 MiB, zstd or lz4) declaring ``declared`` uncompressed bytes
    (random; later offsets shift: the summary then disagrees with the data)."""
    import lz4.frame
    import zstandard

    pos = next(p for p, op, _ in _records(data, 8, len(data)) if op == 0x06)
    n = n if n is not None else rng.choice((1, 16, 64)) * 2**20
    codec = codec or rng.choice(("zstd", "lz4"))
    stream = (zstandard.ZstdCompressor().compress(bytes(n)) if codec == "zstd"
              else lz4.frame.compress(bytes(n)))
    if declared is None:
        declared = rng.choice((0, 100, n, n - 1, 2**40, 2**64 - 1))
    body = struct.pack("<QQQI", 10 * S, 13 * S, declared, 0)
    body += struct.pack("<I", len(codec)) + codec.encode() + struct.pack("<Q", len(stream))
    body += stream
    _op, length = struct.unpack_from("<BQ", data, pos)
    return data[:pos] + struct.pack("<BQ", 0x06, len(body)) + body + data[pos + 9 + length:]


SCHEMA_LIES = [
    lambda t: t.replace("Vector3 linear\nVector3 angular", "Vector3 angular\nVector3 linear"),
    lambda t: t.replace("float64 x\nfloat64 y", "float64 y\nfloat64 x"),
    lambda t: t.replace("float64 x", "int64 x"),
    lambda t: t.replace("float64", "float32"),
    lambda t: t.replace("\nVector3 angular", ""),
    lambda t: t.replace("Vector3 angular\n", "Vector3 angular\nVector3 extra\n"),
    lambda t: t.replace("Vector3 angular", "Vector3[] angular"),
    lambda t: t.replace("linear", "lin"),
    lambda t: t.replace("float64 z", "float64 z\nstring s"),
]


# --------------------------------------------------------------------------- the oracle
def unsupported(original, damaged) -> list[str]:
    """The verdicts of ``damaged`` (a LogAudit of a damaged copy) that the damaged log does not
    support, judged against ``original`` (the intact log's, one way of filling what the
    damage lost: ../shared/DESIGN.md "Damage is a gap"): a violation or a pass the intact log
    does not have, a changed verdict where nothing was lost, a verdict on an unreadable
    log."""
    out = []
    if damaged.error is not None:
        return [f"{v.requirement}: {v.verdict} on an unreadable log"
                for v in damaged.verdicts if v.verdict != "error"]
    passed = ("satisfied", "vacuous")
    for ov, dv in zip(original.verdicts, damaged.verdicts):
        who, verdict = dv.requirement, dv.verdict
        if verdict in ("error", "unknown"):
            continue
        if not damaged.partial or not damaged.damage_cut:
            if verdict != ov.verdict:
                out.append(f"{who}: {verdict} != {ov.verdict} with nothing lost")
            continue
        if verdict == "violated" and ov.verdict != "violated":
            out.append(f"{who}: violated, the intact log is {ov.verdict}")
        if verdict in passed and ov.verdict not in passed:
            out.append(f"{who}: {verdict}, the intact log is {ov.verdict}")
    return out


class Audits:
    """Audit logs in-process with the fuzz requirements (or the shipped ones for traces) and
    keep the intact logs' audits."""

    def __init__(self, tmp: Path) -> None:
        from fretc.audit import AuditConfig, load_plan

        (tmp / "f.fret").write_text(FRET, encoding="utf-8")
        (tmp / "f.bindings.toml").write_text(BINDINGS, encoding="utf-8")
        self.small = load_plan(AuditConfig((str(tmp / "f.fret"),)))
        self._traces = None
        self.tmp = tmp
        self.originals: dict = {}

    @property
    def traces(self):
        """The plan of the shipped requirements (for the shipped traces), loaded once."""
        if self._traces is None:
            from fretc.audit import AuditConfig, load_plan

            self._traces = load_plan(AuditConfig((str(ROOT / "requirements"),)))
        return self._traces

    def audit(self, plan, data: bytes, name: str = "x.mcap"):
        from fretc.audit import audit_log

        path = self.tmp / name
        path.write_bytes(data)
        try:
            return audit_log(plan, str(path))
        finally:
            path.unlink()

    def original(self, key: str, plan, data: bytes):
        if key not in self.originals:
            self.originals[key] = self.audit(plan, data)
        return self.originals[key]


# --------------------------------------------------------------------------- log classes
def run_log_class(kind: str, rng: random.Random, audits: Audits) -> list[str]:
    """One input of a log class; the unsupported verdicts (an exception propagates)."""
    if kind == "cut":
        traces = sorted((ROOT / "traces").glob("*.mcap"))
        if rng.random() < TRACE_SHARE and traces:
            path = rng.choice(traces)
            data, plan, key = path.read_bytes(), audits.traces, path.name
        else:
            data, plan, key = small_mcap(dip=rng.randrange(60)), audits.small, None
        if rng.random() < 0.6:
            damaged = data[:rng.randrange(len(data))]
        else:
            d = bytearray(data)
            for _ in range(rng.choice((1, 10, 100))):
                d[rng.randrange(len(d))] ^= 1 << rng.randrange(8)
            damaged = bytes(d)
        original = audits.original(key or f"small{data[:0]}{hash(data)}", plan, data)
        return unsupported(original, audits.audit(plan, damaged))
    if kind == "lost":
        return run_lost(rng, audits, small_mcap)
    if kind == "nan":
        return run_nan(rng, audits, small_mcap)
    data = small_mcap(dip=rng.randrange(60))
    original = audits.original(f"small{hash(data)}", audits.small, data)
    if kind == "index":
        return unsupported(original, audits.audit(audits.small, forge_index(rng, data)))
    if kind == "bomb":
        return unsupported(original, audits.audit(audits.small, bomb(rng, data)))
    lie = rng.choice(SCHEMA_LIES)(TWIST)
    la = audits.audit(audits.small, small_mcap(lie, dip=rng.randrange(60)))
    rv = next(v for v in la.verdicts if v.requirement == "RV")
    return [] if rv.verdict == "error" else [f"RV: {rv.verdict} on a lying schema"]


# --------------------------------------------------------------------------- bindings
def hostile_binding(rng: random.Random) -> str:
    """A binding file mutated at random (module docstring)."""
    head = '[tick]\nperiod = "100 ms"\n[variables]\n'
    field = rng.choice(["/scan.ranges[0]", "/a.data", "/x.y.z", "/a.data[99999999999]"])
    n = rng.choice([1, 10, 199, 200, 201, 1000, 5000, 20000])
    kind = rng.randrange(9)
    if kind == 0:
        return head + f'x = "{rng.choice("-!(~") * n}{field}{")" * rng.randrange(3)}"\n'
    if kind == 1:
        op = rng.choice(["+", "*", "&", "|", "-", "/", "and", "<"])
        return head + 'x = "' + f" {op} ".join([field] * n) + '"\n'
    if kind == 2:
        m = min(n, 5000)
        return head + 'x = "v0"\n' + "".join(f'v{i} = "v{i + 1}"\n' for i in range(m)) + \
            f'v{m} = "{field}"\n'
    if kind == 3:
        m = rng.choice([5, 20, 60])
        return head + 'x = "v0 > 0"\n' + "".join(f'v{i} = "v{i + 1} + v{i + 1}"\n'
                                                 for i in range(m)) + f'v{m} = "{field}"\n'
    if kind == 4:
        return "x = " + "[" * n + "]" * n + "\n"
    if kind == 5:
        return "[" + ".".join(["a"] * n) + "]\nx = 1\n"
    if kind == 6:
        dur = rng.choice(["1e300 h", "1e999 s", "-1 s", "0 s", "nan s", "inf ms", "1e-400 s",
                          "9" * 400 + " ns", "100 parsecs", ""])
        return f'[tick]\nperiod = "{dur}"\n[variables]\nx = "{field} > 0"\n'
    if kind == 7:
        return head + 'x = "v0"\nv0 = "x"\n'
    text = head + f'x = "{field} > 0"\ny = "hold({field}, 1e999 s)"\n'
    k = rng.randrange(len(text))
    return text[:k] + rng.choice(['"', "\\", "\x00", "\u202e", "[", "=", "\n", "{", "é"]) + \
        text[k + 1:]


def run_binding(rng: random.Random) -> list[str]:
    """Parse one hostile binding file: an input error or a binding set (an exception that is
    not an input error propagates)."""
    from fretc.common.errors import FretcError
    from fretc.signals.bindings.files import parse_bindings

    try:
        parse_bindings(hostile_binding(rng), "b.toml")
    except FretcError:
        pass
    return []


# --------------------------------------------------------------------------- live frames
class FakeSocket:
    """The server side of a connection as the clients read it: ``frames`` then the end."""

    def __init__(self, frames: list) -> None:
        self.frames = frames
        self.sent: list = []

    def __aiter__(self):
        return self._gen()

    async def _gen(self):
        for f in self.frames:
            yield f

    async def send(self, text) -> None:
        self.sent.append(text)


def _json_value(rng: random.Random, depth: int = 0):
    """A random JSON value (nesting at most 3 deep), leaning to the protocols' words."""
    k = rng.randrange(9 if depth < 3 else 6)
    if k < 6:
        return [None, True, rng.choice((0, -1, 2**63, 2**64, 1e300, float("nan"))), "x" * 3,
                "/a", rng.choice(("advertise", "publish", "status", "unadvertise"))][k]
    if k == 6:
        return [_json_value(rng, depth + 1) for _ in range(rng.randrange(4))]
    if k == 7:
        keys = ("op", "id", "topic", "channels", "channelIds", "msg", "values", "clock", "sec",
                "level")
        return {rng.choice(keys): _json_value(rng, depth + 1) for _ in range(rng.randrange(4))}
    return {"op": rng.choice(("advertise", "unadvertise", "publish", "status",
                              "service_response", "serverInfo")),
            "channels": _json_value(rng, depth + 1), "topic": "/a",
            "msg": _json_value(rng, depth + 1)}


def hostile_frames(rng: random.Random, foxglove: bool) -> list:
    """A session's frames (module docstring): the /a channel advertised first (Foxglove),
    then a random mix of good, wrong-shaped and huge frames."""
    frames = []
    adv = {"op": "advertise", "channels": [{"id": 1, "topic": "/a", "encoding": "cdr",
                                            "schemaName": "std_msgs/msg/Float64",
                                            "schema": "float64 data",
                                            "schemaEncoding": "ros2msg"}]}
    if foxglove:
        frames.append(json.dumps(adv))
    for _ in range(rng.randrange(1, 30)):
        k = rng.randrange(7)
        t = rng.choice((10 * S, 2**63 - 1, 2**63, 2**64 - 1, 0, 10 * S + rng.getrandbits(40)))
        if k == 0:
            frames.append(json.dumps(_json_value(rng), allow_nan=True))
        elif k == 1 and foxglove:
            frames.append(struct.pack("<BIQ", rng.choice((1, 1, 2, 9)), rng.randrange(3), t)
                          + rng.choice((b"\x00\x01\x00\x00" + struct.pack("<d", 1.0), b"",
                                        b"\x00\x01")))
        elif k == 1:
            sec = rng.choice((10, 2**40, -5, "x", None, 1.5, 2**70))
            frames.append(json.dumps({"op": "publish", "topic": "/clock",
                                      "msg": {"clock": {"sec": sec, "nanosec": 0}}}))
        elif k == 2:
            frames.append(rng.choice((b"\x01\x00", b"", "{", "[]", "1", '"x"', "null")))
        elif k == 3 and foxglove:
            n = rng.choice((10, 2000))
            frames.append(json.dumps({"op": "advertise", "channels": [
                {"id": i + 5, "topic": f"/x{i}"} for i in range(n)]}))
        elif k == 4:
            frames.append(json.dumps({"op": "publish", "topic": "/a",
                                      "msg": rng.choice(({"data": 1.0}, {"data": "x"}, [],
                                                         {"data": 1e308}))}))
        else:
            frames.append(json.dumps({"op": "unadvertise", "channelIds":
                                      rng.choice(([1], [[1]], "x", [2**70]))}))
    return frames


def run_frames(rng: random.Random) -> list[str]:
    """Hand hostile frames to a client's session and its events to a watch source (an
    exception propagates)."""
    from fretc.live.websocket.foxglove import FoxgloveClient
    from fretc.live.websocket.rosbridge import RosbridgeClient
    from fretc.live.source import WatchSource

    foxglove = rng.random() < 0.6
    frames = hostile_frames(rng, foxglove)
    if foxglove:
        client = FoxgloveClient("ws://127.0.0.1:1", lambda t: t == "/a")
        asyncio.run(client._session(FakeSocket(frames)))
    else:
        client = RosbridgeClient("rosbridge://127.0.0.1:1", lambda t: t == "/a")
        state = {"clock": 0, "types": {"/a": "std_msgs/msg/Float64"}}
        client._put("advertise", 0, [__import__("fretc.live.websocket.rosbridge", fromlist=["x"])
                                     .advertisement(1, "/a", "std_msgs/msg/Float64")])
        asyncio.run(client._read(FakeSocket(frames), {}, state))
    src = WatchSource("ws://fuzz", client)
    src.want({"/a"})
    src.counts = {}
    src.max_jump_ns = 10**6 * 100_000_000
    while not client.events.empty():
        ev = client.events.get_nowait()
        if ev[0] == "message":
            src._deliver(ev[1], ev[2], ev[3])
        else:
            src._handle(ev)
    return []


# --------------------------------------------------------------------------- main
def _arguments(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=600, help="inputs in all")
    ap.add_argument("--seed", type=int, default=None, help="default: a fresh one, printed")
    ap.add_argument("--classes", default=",".join(CLASSES),
                    help="comma-separated; also NAME:WEIGHT (default weights below)")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--shard", default="0/1", metavar="K/N",
                    help="run only the inputs i with i mod N = K (the same inputs as in the "
                         "whole run: shards of one seed add up to it)")
    return ap.parse_args(argv)


#: the classes of bench/fuzz_sources.py
SOURCE_CLASSES = {"reqif": run_reqif, "doorstop": run_doorstop, "exports": run_exports,
                  "explain": run_explain}
#: inputs of each class per unit of --count (logs cost far more than frames)
WEIGHTS = {"index": 2, "bomb": 1, "cut": 3, "schema": 2, "lost": 2, "nan": 2,
           "bindings": 40, "frames": 40, "ws": 0.2, "bus": 0.1, "typed": 8, "lsp": 0.2,
           "statistics": 20, "flight": 1, "reqif": 2, "doorstop": 1, "exports": 1,
           "explain": 2, **{k: w for k, (_run, w) in MORE.items()}}


def plan_inputs(classes: str, count: int) -> list[str]:
    """The class of each input, ``count`` in all, in proportion to the weights."""
    weights = {}
    for part in classes.split(","):
        name, _, w = part.partition(":")
        if name not in CLASSES:
            raise SystemExit(f"unknown class {name!r} (classes: {', '.join(CLASSES)})")
        weights[name] = float(w) if w else WEIGHTS[name]
    total = sum(weights.values())
    out = []
    for name, w in weights.items():
        out += [name] * round(count * w / total)
    return out


def main(argv=None) -> int:
    args = _arguments(argv)
    seed = args.seed if args.seed is not None else random.SystemRandom().randrange(2**32)
    print(f"seed {seed} (reproduce with --seed {seed})", flush=True)
    kinds = plan_inputs(args.classes, args.count)
    random.Random(seed).shuffle(kinds)
    stats = {"inputs": 0, "tracebacks": 0, "unsupported": 0}
    stats.update({k: 0 for k in CLASSES})
    tmp = Path(tempfile.mkdtemp(prefix="fretc_hostile_"))
    audits = None
    flight_cache: dict = {}  # the flight class's plans and intact audits
    t0 = time.time()
    k, _, n = args.shard.partition("/")
    shard, shards = int(k), int(n)
    for i, kind in enumerate(kinds):
        if i % shards != shard:
            continue
        rng = random.Random(f"{seed}:{i}")
        stats["inputs"] += 1
        stats[kind] += 1
        try:
            if kind == "bindings":
                bad = run_binding(rng)
            elif kind == "frames":
                bad = run_frames(rng)
            elif kind == "ws":
                bad = run_ws(rng, tmp)
            elif kind == "bus":
                bad = run_bus(rng, tmp)
            elif kind == "typed":
                bad = run_inputs(rng, tmp)
            elif kind == "lsp":
                bad = run_lsp(rng, tmp)
            elif kind == "statistics":
                bad = run_statistics(rng, tmp)
            elif kind == "flight":
                bad = run_flight(rng, tmp, flight_cache)
            elif kind in SOURCE_CLASSES or kind in MORE:
                bad = (SOURCE_CLASSES.get(kind) or MORE[kind][0])(rng, tmp)
            else:
                audits = audits or Audits(tmp)
                bad = run_log_class(kind, rng, audits)
        except Exception:
            stats["tracebacks"] += 1
            print(f"TRACEBACK {kind} seed {seed} input {i}:\n{traceback.format_exc()[-2500:]}",
                  flush=True)
            continue
        if bad:
            stats["unsupported"] += len(bad)
            print(f"UNSUPPORTED {kind} seed {seed} input {i}: {bad}", flush=True)
    stats["seconds"] = round(time.time() - t0, 1)
    stats["peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    stats["seed"] = seed
    stats["shard"] = args.shard
    print(json.dumps(stats), flush=True)
    return 1 if stats["tracebacks"] or stats["unsupported"] else 0


if __name__ == "__main__":
    sys.exit(main())
