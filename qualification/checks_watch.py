"""The validation suite's checks of ``fretc watch`` (docs/guide/watch.md): the command run as
a user runs it (the installed click group, in this process) on messages of a log written
here, against ``fretc audit`` of the same messages; and the messages a watch loses (a
dropped connection, its bounded queue overflowing, an undecodable message, a publisher
that leaves and comes back) made gaps: their ticks unknown, never held, the run partial.

The first check serves the log on the loopback interface with fretc's own Foxglove
WebSocket server (:mod:`fretc.live.websocket.serve`, what ``fretc replay --serve`` runs) and
watches it over the network stack; it is skipped where ``foxglove-sdk`` or ``websockets``
(the ``watch`` extra) cannot be imported. The second feeds the watch a scripted transport:
the events every transport puts on the watch's bounded queue
(:class:`fretc.live.events.EventQueue`, :mod:`fretc.live.protocol`'s tuples), in an order
fixed here, so each loss happens at the same message on every run; everything after the
socket (the queue, :class:`fretc.live.source.WatchSource`, the watch, its JSON, recording
and exit code) is the code a user runs.
"""

from __future__ import annotations

import contextlib
import json
import random
import threading
import time
from collections import deque
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from fretc.qualification.checks import SEED, Check, CheckSkipped, Run
from fretc.qualification.checks_audit import fretc, verdicts
from fretc.qualification.checks_logs import MS, S, write_mcap

#: the watched requirements: one violated, one with triggers and a deadline, one satisfied
WATCH_REQUIREMENTS = ("R1: the sw shall always satisfy a < 5\n"
                      "R2: upon b > 3 the sw shall within 3 ticks satisfy a < 1\n"
                      "R3: the sw shall always satisfy b > -1\n")
WATCH_BINDINGS = ('[tick]\nperiod = "100 ms"\n\n[variables]\na = "/a.data"\nb = "/b.data"\n')
#: what may differ between two audit JSONs' verdicts of the same messages: the log's name
PLACE = ("log",)
#: what the watched run and the log must agree on beside the verdicts
LOG_FIELDS = ("partial", "messages", "ticks_evaluated", "warmup_ticks", "gaps",
              "problem_counts")


def _comparable(doc: dict[str, Any] | None) -> dict[str, dict[str, Any]]:
    """The audit JSON's verdicts by requirement id, without what names the log."""
    return {rid: {k: v for k, v in verdict.items() if k not in PLACE}
            for (_, rid), verdict in verdicts(doc).items()}


def _differences(a: dict[str, dict[str, Any]], b: dict[str, dict[str, Any]]) -> list[str]:
    """The requirement ids and fields where verdicts ``a`` and ``b`` differ, one sentence
    each (the first three fields of each)."""
    out = []
    for rid in sorted(set(a) | set(b)):
        x, y = a.get(rid), b.get(rid)
        if x is None or y is None:
            out.append(f"{rid}: only in one of them")
            continue
        fields = sorted(k for k in set(x) | set(y) if x.get(k) != y.get(k))
        if fields:
            out.append(f"{rid}: {', '.join(fields[:3])} differ (e.g. {fields[0]}: "
                       f"{str(x.get(fields[0]))[:80]} against {str(y.get(fields[0]))[:80]})")
    return out


@contextlib.contextmanager
def _watch_seen(seen: list[Any]) -> Iterator[None]:
    """Inside the block, each :class:`fretc.live.watch.Watch` that runs is appended to
    ``seen`` (the server's thread reads how far it got); as before after it."""
    from fretc.live import watch

    run = watch.Watch.run

    def seen_run(self: Any) -> Any:
        seen.append(self)
        return run(self)

    watch.Watch.run = seen_run  # type: ignore[method-assign]
    try:
        yield
    finally:
        watch.Watch.run = run  # type: ignore[method-assign]


def _watched_log(folder: Path) -> Path:
    """/a and /b (std_msgs/msg/Float64) every 50 ms for 4 s from 1 s, random values
    (:data:`SEED`): a in [0, 6) (R1 violated), b in [0, 4)."""
    rnd = random.Random(SEED + 21)
    msgs = sorted([("/a", S + k * 50 * MS, round(rnd.uniform(0, 6), 3)) for k in range(80)]
                  + [("/b", S + k * 50 * MS + 25 * MS, round(rnd.uniform(0, 4), 3))
                     for k in range(80)], key=lambda m: m[1])
    log = folder / "served.mcap"
    write_mcap(log, msgs)
    return log


def check_watch_equals_audit(run: Run) -> list[str]:
    """An MCAP log served on 127.0.0.1 by fretc's Foxglove WebSocket server (``fretc
    replay --serve``'s) and watched to the server's close by ``fretc watch --json
    --record``: its exit code and every verdict of its audit JSON (verdict, first violation,
    evidence, robustness, LTL3, ticks) equal ``fretc audit``'s of the log; ``fretc audit``
    of its recording gives them again (docs/guide/watch.md, Ending, outputs and exit code).
    Skipped without ``foxglove-sdk`` or ``websockets``."""
    import importlib.util

    missing = [m for m, spec in (("foxglove-sdk", "foxglove"), ("websockets", "websockets"))
               if importlib.util.find_spec(spec) is None]
    if missing:
        raise CheckSkipped(f"{' and '.join(missing)} not importable (the watch extra: "
                           "pip install 'fretc[watch]')")
    from fretc.live.websocket.serve import FoxgloveServer, advertise_mcap, replay_mcap

    folder = run.work / "watch"
    folder.mkdir(parents=True, exist_ok=True)
    log = _watched_log(folder)
    (folder / "w.fret").write_text(WATCH_REQUIREMENTS, encoding="utf-8")
    (folder / "w.bindings.toml").write_text(WATCH_BINDINGS, encoding="utf-8")
    reqs = ["-r", str(folder / "w.fret"), "--bindings", str(folder / "w.bindings.toml")]
    code, text = fretc(run, ["audit", *reqs, str(log), "--json", str(folder / "audit.json"),
                             "--no-progress"])
    audited = _comparable(_read(folder / "audit.json"))
    server = FoxgloveServer(port=0, start=False)
    advertise_mcap(str(log), server)
    server.start()
    seen: list[Any] = []
    sent: dict[str, Any] = {}

    def serve() -> None:
        try:
            if not server.wait_subscribed({"/a", "/b"}, timeout=10):
                sent["error"] = "the watch did not subscribe to /a and /b within 10 s"
                return
            sent["count"], sent["last"] = replay_mcap(str(log), server, rate=0.0)
            deadline = time.monotonic() + 10  # (the last messages reach the watch)
            while (time.monotonic() < deadline and not (
                    seen and (seen[0].source._last_time or 0) >= sent["last"])):
                time.sleep(0.02)
        finally:
            server.stop()  # the end of the run: an orderly close

    thread = threading.Thread(target=serve, name="fretc-qualify-serve", daemon=True)
    try:
        with _watch_seen(seen):
            thread.start()
            wcode, wtext = fretc(run, ["watch", server.url, *reqs, "--json",
                                       str(folder / "watch.json"), "--record",
                                       str(folder / "recorded.mcap"), "--no-live",
                                       "--wait", "5", "--duration", "30"])
    finally:
        server.stop()
        thread.join(15)
    if "error" in sent:
        return [sent["error"]]
    out = []
    watched = _comparable(_read(folder / "watch.json"))
    if (wcode, code) != (1, 1) or not audited:
        out.append(f"exit codes: watch {wcode}, audit {code}; expected 1 both (R1 violated): "
                   f"{wtext.strip()[-200:]} | {text.strip()[-200:]}")
    out += [f"watch against audit: {d}" for d in _differences(watched, audited)]
    runs = [{k: (doc or {"logs": [{}]})["logs"][0].get(k) for k in LOG_FIELDS}
            for doc in (_read(folder / "watch.json"), _read(folder / "audit.json"))]
    if runs[0] != runs[1]:
        out.append(f"the watched run {runs[0]}, the log {runs[1]}")
    rcode, rtext = fretc(run, ["audit", *reqs, str(folder / "recorded.mcap"), "--json",
                               str(folder / "recorded.json"), "--no-progress"])
    if rcode != wcode:
        out.append(f"the recording's audit exits {rcode}, the watch {wcode}: "
                   f"{rtext.strip()[-200:]}")
    out += [f"recording's audit against watch: {d}"
            for d in _differences(_comparable(_read(folder / "recorded.json")), watched)]
    return out[:6]


def _read(path: Path) -> dict[str, Any] | None:
    """The JSON document at ``path``, None when none was written."""
    return json.loads(path.read_text("utf-8")) if path.exists() else None


# --------------------------------------------------------------------------- lost messages
T0 = S
#: /a's messages of the scripted runs: every 50 ms from 1 s for 2 s; those the losses take
#: (10 .. 19, 1.5 .. 1.95 s) would violate R
LOST = range(10, 20)
MESSAGES = 40
GAP_REQUIREMENT = "R: the sw shall always satisfy a < 5\n"
GAP_BINDINGS = '[tick]\nperiod = "100 ms"\n\n[variables]\na = "/a.data"\n'


def _f64(x: float) -> bytes:
    """std_msgs/msg/Float64 as CDR (little endian)."""
    import struct

    return b"\x00\x01\x00\x00" + struct.pack("<d", x)


def _channel(cid: int) -> Any:
    """/a advertised as std_msgs/msg/Float64 (ROS 2 CDR) on channel ``cid``."""
    from fretc.live.protocol import Advertised

    return Advertised(cid, "/a", "cdr", "std_msgs/msg/Float64", "float64 data", "ros2msg")


def _message(k: int, payload: bytes | None = None) -> tuple:
    """Message ``k`` of /a (log time 1 s + k * 50 ms), 9.0 where a loss takes it."""
    return ("message", "/a", T0 + k * 50 * MS,
            payload if payload is not None else _f64(9.0 if k in LOST else 1.0),
            time.time_ns())


def _script(loss: str) -> tuple[list[list[tuple]], int]:
    """The steps of a scripted run (each step the events a transport puts at once) and its
    queue's bound: connect, advertise /a, its messages one a step, the loss ``loss`` where
    messages 10 .. 19 come, close. ``connection``: dropped after message 9, back (and /a
    advertised again) before message 20; ``overflow``: messages 10 .. 29 put at once on a
    queue of 8 (the 12 oldest dropped); ``undecodable``: 10 .. 19 cut short; ``publisher``:
    /a unadvertised after message 9 and advertised again on a new channel before message 20
    (a node's restart over foxglove_bridge); ``none``: nothing lost (R violated at 1.5 s)."""
    now = time.time_ns()
    steps: list[list[tuple]] = [[("connected", now, "foxglove.websocket.v1", ""),
                                 ("advertise", now, [_channel(1)])]]
    steps += [[_message(k)] for k in range(10)]
    after = 20
    if loss == "connection":
        steps += [[("disconnected", now, "the connection was lost without a close frame")],
                  [("connected", now, "foxglove.websocket.v1", ""),
                   ("advertise", now, [_channel(1)])]]
    elif loss == "overflow":
        steps.append([_message(k) for k in range(10, 30)])
        after = 30
    elif loss == "undecodable":
        steps += [[_message(k, b"\x00\x01\x00\x00\x00")] for k in LOST]
    elif loss == "publisher":
        steps += [[("unadvertise", now, ["/a"])], [("advertise", now, [_channel(2)])]]
    else:
        steps += [[_message(k)] for k in LOST]
    steps += [[_message(k)] for k in range(after, MESSAGES)]
    steps.append([("closed", now, "the server closed the connection (code 1000)")])
    return steps, 8


class _ScriptedClient:
    """A transport for :class:`fretc.live.watch.Watch` whose events are ``steps``: each
    step is put on the watch's bounded queue (a real :class:`~fretc.live.events.EventQueue`
    of ``bound`` messages) when the watch has taken everything before it, so that the
    order of events, and what the queue drops, is the same on every run."""

    hears_new_publishers = False  # (a WebSocket client: a restart may lose messages)

    def __init__(self, steps: list[list[tuple]], bound: int) -> None:
        from fretc.live.events import EventQueue

        script = deque(steps)

        class Scripted(EventQueue):
            def get(self, block: bool = True, timeout: float | None = None) -> tuple:
                if self.empty() and script:
                    for event in script.popleft():
                        self.put(event)
                return super().get(block, timeout)

        self.events = Scripted(max_messages=bound)

    def start(self) -> _ScriptedClient:
        """Nothing to connect (the script holds the events)."""
        return self

    def stop(self) -> None:
        """Nothing to close."""


@contextlib.contextmanager
def _scripted(steps: list[list[tuple]], bound: int) -> Iterator[None]:
    """``fretc watch`` inside the block is given a :class:`_ScriptedClient` of ``steps``
    for its transport; its own transports again after it."""
    from fretc.live import watch

    make = watch.make_client
    scripted: Any = lambda *args, **kwargs: _ScriptedClient(steps, bound)  # noqa: E731
    watch.make_client = scripted  # (a transport putting the same events)
    try:
        yield
    finally:
        watch.make_client = make


#: per loss: the data problem it must give, and the ticks inside it (the unknown ticks:
#: 1.5 .. 1.9 s; 1.5 .. 2.0 s for the overflow, whose first message after it is at 2.1 s)
LOSSES = {"connection": ("connection_gap", 5), "overflow": ("queue_overflow", 6),
          "undecodable": ("undecodable", 5), "publisher": ("publisher_restart", 5)}


def check_watch_gaps(run: Run) -> list[str]:
    """Messages a watch loses, scripted at /a's messages 10 .. 19 (values that would
    violate R, which the watch never reads) of a run whose every message read is fine: a
    dropped connection, the bounded queue overflowing, undecodable payloads, a publisher
    that leaves and comes back. Each gives its data problem, R ``unknown`` with the ticks
    inside the loss unknown (never held over it: held, R would be satisfied), the run
    partial and exit 3, and the audit of ``--record``'s recording agrees; the same run
    without the loss is violated at 1.5 s, exit 1 (docs/guide/watch.md, Faults)."""
    folder = run.work / "watch-gaps"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "g.fret").write_text(GAP_REQUIREMENT, encoding="utf-8")
    (folder / "g.bindings.toml").write_text(GAP_BINDINGS, encoding="utf-8")
    reqs = ["-r", str(folder / "g.fret"), "--bindings", str(folder / "g.bindings.toml")]
    out = []
    for loss, (kind, inside) in [*LOSSES.items(), ("none", ("", 0))]:
        steps, bound = _script(loss)
        jpath, rec = folder / f"{loss}.json", folder / f"{loss}.mcap"
        with _scripted(steps, bound):
            code, text = fretc(run, ["watch", "ws://127.0.0.1:9", *reqs, "--json", str(jpath),
                                     "--record", str(rec), "--no-live", "--wait", "2",
                                     "--connect-timeout", "2", "--duration", "20"])
        doc = _read(jpath)
        v = _comparable(doc).get("R", {})
        log = doc["logs"][0] if doc is not None else {}
        kinds = {p.get("kind") for p in log.get("problems", [])}
        first = (v.get("first_violation") or {}).get("tick_time_ns")
        got: tuple[Any, ...] = (code, v.get("verdict"), v.get("unknown_ticks"),
                                log.get("partial"), kind in kinds if kind else not kinds,
                                first)
        want = ((3, "unknown", inside, True, True, None) if kind else
                (1, "violated", 0, False, True, T0 + 500 * MS))
        if got != want:
            out.append(f"{loss}: (exit, verdict, unknown ticks, partial, {kind or 'no'} "
                       f"problem, first violation) = {got}, expected {want}: "
                       f"{text.strip()[-200:]}")
            continue
        rcode, rtext = fretc(run, ["audit", *reqs, str(rec), "--json",
                                   str(folder / f"{loss}-recorded.json"), "--no-progress"])
        again = _comparable(_read(folder / f"{loss}-recorded.json")).get("R", {})
        if (rcode, again.get("verdict")) != (code, v.get("verdict")):
            out.append(f"{loss}: the recording's audit gives exit {rcode}, "
                       f"{again.get('verdict')}; the watch {code}, {v.get('verdict')}: "
                       f"{rtext.strip()[-200:]}")
    return out


#: the checks of fretc watch, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("watch-equals-audit", ("TOR-WCH-001",),
          "fretc watch of a served log: the verdicts, evidence and exit code of its audit",
          check_watch_equals_audit),
    Check("watch-gaps", ("TOR-WCH-002",),
          "messages a watch loses are gaps: unknown ticks, a partial run, exit 3",
          check_watch_gaps),
)
