"""``fretc watch`` latency and throughput over the Foxglove WebSocket (a foxglove-sdk server),
DDS (Cyclone DDS, loopback only, multicast off) and Zenoh (a router on 127.0.0.1), in one run.

A child process serves a shipped trace (its bound topics) with the transport's replay server
(``fretc replay --serve``'s), paced at a replay rate, and notes the wall time (``time.time_ns()``, one clock for both processes)
at which each message leaves (just before ``Channel.log``). This process watches it with
the Safe-ROS requirements and notes, for every evaluated tick, when its monitors have
stepped. Two latencies per tick:

* **data -> verdict**: from the newest message the tick's values use leaving the server to
  the tick's verdicts. It includes waiting for the next message that closes the tick (sample
  and hold on a fixed grid cannot evaluate tick t before a message later than t arrives).
* **closing message -> verdict**: from the message whose arrival closed the tick leaving the
  server to the tick's verdicts (transport + decode + sampling + monitors).

Part 1: median and 99th percentile over a full nominal run at 10x (aim: p99 below one tick
period: 100 ms of run time, 10 ms of wall time at 10x). Part 2: the highest replay rate the
watch keeps up with (verdicts equal to ``fretc audit`` of the trace, the median closing
message -> verdict latency below one tick period of wall time at that rate, and the last
message used within 0.5 s of leaving the server), with the watch's CPU time against the audit's on
the same trace; the keep-up ratio (that rate; aim: 50x or more) and the message -> verdict
p50/p99 at it. Each run ends as a user's does: the server stops after the last message and
the watch ends by itself at its orderly close.

    python bench/bench_watch.py [--trace traces/nominal.mcap] [--rates 10 20 50 75 100 150]
                                [--transports ws dds zenoh]

DDS and Zenoh messages are held 0.1 s to be merged into log-time order (:mod:`fretc.live.merge`):
their latencies include that hold.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import resource
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def _server(url: str, config: str | None):
    """The replay server of ``url`` (``ws``: a foxglove-sdk server on a free port)."""
    if url.startswith("dds://"):
        from fretc.live.dds.serve import DdsServer

        return DdsServer(url, config_file=config)
    if url.startswith("zenoh://"):
        from fretc.live.zenoh.serve import ZenohServer

        return ZenohServer(url)
    from fretc.live.websocket.serve import FoxgloveServer

    return FoxgloveServer(port=0)


def _serve(trace: str, rate: float, topics, conn, url: str = "ws",
           config: str | None = None) -> None:
    from fretc.live.websocket.serve import advertise_mcap, replay_mcap

    server = _server(url, config)
    advertise_mcap(trace, server, topics=set(topics))
    conn.send(server.url)
    server.wait_subscribed(set(topics) & set(server.channels), timeout=60)
    sent = []

    def note(topic, log_time):
        sent.append((log_time, time.time_ns()))

    n, last = replay_mcap(trace, server, rate, topics=set(topics), on_message=note)
    conn.send((sent, last))
    time.sleep(0.5)  # the last messages leave
    server.stop()  # the end of the run: the watch ends by itself
    conn.recv()  # the watch is done


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _url(transport: str, run: int) -> str:
    """A fresh address of ``transport`` for one run (a DDS domain, a free port)."""
    if transport == "dds":
        return f"dds://{120 + run % 100}"
    if transport == "zenoh":
        import socket

        with socket.socket() as sock:
            sock.bind(("127.0.0.1", 0))
            return f"zenoh://127.0.0.1:{sock.getsockname()[1]}"
    return "ws"


def watch_once(plan, trace: str, rate: float, url: str = "ws", config: str | None = None):
    from fretc.live.watch import Watch, WatchOptions

    ctx = mp.get_context("spawn")
    parent, child = ctx.Pipe()
    # the bound topics, as the watch computes them
    probe = Watch(plan, WatchOptions(url="ws://127.0.0.1:1"))
    topics = sorted(probe.needed)
    proc = ctx.Process(target=_serve, args=(trace, rate, topics, child, url, config),
                       daemon=True)
    proc.start()
    url = parent.recv()
    w = Watch(plan, WatchOptions(url=url, wait=10.0, duration=600, config=config))
    ticks = []

    def on_tick(i, t, dep, closing):
        ticks.append((time.time_ns(), dep, closing))

    w.on_tick = on_tick
    result = {}

    def waiter():
        sent, last = parent.recv()
        result["sent"], result["last"] = sent, last
        deadline = time.monotonic() + 30
        while (w.source._last_time or 0) < last and time.monotonic() < deadline:
            time.sleep(0.005)
        result["used_at"] = time.time_ns()

    th = threading.Thread(target=waiter, daemon=True)
    th.start()
    c0 = _cpu()
    la = w.run()
    cpu = _cpu() - c0
    th.join(60)
    parent.send("done")
    proc.join(10)
    sent_at = {}
    for lt, wall in result["sent"]:
        sent_at[lt] = max(sent_at.get(lt, 0), wall)  # several topics at one log time: last
    data_lat, close_lat = [], []
    for wall, dep, closing in ticks:
        if dep in sent_at:
            data_lat.append((wall - sent_at[dep]) / 1e6)
        if closing in sent_at:
            close_lat.append((wall - sent_at[closing]) / 1e6)
    last_sent = sent_at[result["last"]]
    lag = (result["used_at"] - last_sent) / 1e9
    return la, np.array(data_lat), np.array(close_lat), lag, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trace", default=str(ROOT / "traces" / "nominal.mcap"))
    ap.add_argument("--rates", type=float, nargs="+", default=[10, 20, 50, 75, 100, 150])
    ap.add_argument("--transports", nargs="+", default=["ws", "dds", "zenoh"],
                    choices=["ws", "dds", "zenoh"])
    args = ap.parse_args()
    import tempfile

    from fretc.audit import AuditConfig, audit_log, load_plan
    from fretc.live.dds.idl_types import LOOPBACK_XML

    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))
    c0 = _cpu()
    ref = audit_log(plan, args.trace)
    audit_cpu = _cpu() - c0
    period_ms = plan.bindings.tick.period_ns / 1e6
    print(f"trace {Path(args.trace).name}: {ref.ticks_evaluated} ticks, tick period "
          f"{period_ms:g} ms; audit CPU {audit_cpu:.2f} s (in-process)")
    with tempfile.NamedTemporaryFile("w", suffix=".xml", delete=False) as f:
        f.write(LOOPBACK_XML)
    summary = []
    for transport in args.transports:
        print(f"\n== {transport}")
        best, kept_at = _rates(plan, args, transport, _key(ref), audit_cpu, period_ms,
                               f.name if transport == "dds" else None)
        summary.append((transport, best, kept_at.get(best)))
    print("\ntransport  keep-up  data->verdict ms p50 / p99  closing msg->verdict ms p50 / p99")
    for transport, best, lats in summary:
        if best is None:
            print(f"{transport:<9}  < {min(args.rates):g}x")
            continue
        dl, cl = lats
        print(f"{transport:<9}  {best:>5g}x  {np.median(dl):>9.2f} / {np.percentile(dl, 99):>7.2f}"
              f"        {np.median(cl):>9.2f} / {np.percentile(cl, 99):>7.2f}")


def _key(la) -> list:
    return [(v.requirement, v.verdict, v.ltl3.status, v.ltl3.tick,
             v.first_violation.at.tick if v.first_violation else None) for v in la.verdicts]


def _rates(plan, args, transport: str, key, audit_cpu: float, period_ms: float,
           config: str | None):
    """One transport at every rate: its table; (the highest rate kept up with or None,
    rate -> latencies)."""
    from fretc.live.merge import HOLD_SECONDS
    print("rate  ticks  data->verdict ms (median / p99)  closing msg->verdict ms (median / p99)"
          "  lag at end s  watch CPU s  CPU vs audit  verdicts = audit  kept up")
    best = None
    kept_at = {}
    for run, rate in enumerate(args.rates):
        la, dl, cl, lag, cpu = watch_once(plan, args.trace, rate, _url(transport, run),
                                          config)
        same = _key(la) == key
        # kept up: right verdicts, and ticks evaluated within one tick period (of wall
        # time at this rate) of their closing message on median: no backlog building up
        # (DDS and Zenoh: beyond their merge hold, released within a tenth of it)
        hold = HOLD_SECONDS * 1.1e3 if transport != "ws" else 0.0
        kept = same and lag < 0.5 and np.median(cl) < period_ms / rate + hold
        if kept:
            best = rate
            kept_at[rate] = (dl, cl)
        print(f"{rate:>4g}x {la.ticks_evaluated:>6d}  "
              f"{np.median(dl):>10.2f} / {np.percentile(dl, 99):>7.2f}            "
              f"{np.median(cl):>10.2f} / {np.percentile(cl, 99):>7.2f}              "
              f"{lag:>8.3f}   {cpu:>9.2f}   {cpu / audit_cpu:>8.2f}x     {same}  {kept}")
    print(f"keep-up ratio: {best:g}x real time ({'>=' if best >= 50 else '<'} 50x)"
          if best else "keep-up ratio: no rate kept up with (< 50x)")
    return best, kept_at


if __name__ == "__main__":
    main()
