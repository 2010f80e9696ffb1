"""``fretc watch URL`` and ``fretc replay LOG.mcap --serve``: the audit's monitors on a
running robot over the Foxglove WebSocket protocol or rosbridge, and a server to watch.

Design notes: ARCHITECTURE.md, `fretc/cli/watch.py`."""

from __future__ import annotations

import json
import signal
import sys
import threading
import time

import click
from typing import TYPE_CHECKING, Any

from fretc.common.units import format_offset

from fretc.cli.options import FiniteRange, audit_config, live_input_options

if TYPE_CHECKING:
    from rich.console import Group

    from fretc.live.watch import Watch
    from fretc.live.watch_event import WatchEvent
    from fretc.live.diagnostics import DiagnosticsPublisher

__all__ = ["watch_cmd", "replay_cmd", "live_table", "register", "connection_line"]


def live_table(w: Watch) -> Group:
    """The live table of a :class:`fretc.live.watch.Watch`: per requirement its own
    clock's ticks and the time of the last one, the pt verdict now, the LTL3 status and when
    it became definite, obligations violated and pending so far
    (:func:`fretc.live.watch.split_pending`), the last trigger (times in s from the
    first tick)."""
    # lazy: rich and the watch engine only when the command runs (start-up of fretc)
    from rich.console import Group
    from rich.table import Table
    from rich.text import Text

    w.refresh_evidence()
    st0 = w.start_time

    def s(ns):
        return format_offset(ns, st0, decimals=1)

    table = Table(header_style="bold", title=None)
    for col in ("req", "ticks", "pt now", "LTL3", "definite at", "violated", "pending",
                "last trigger"):
        table.add_column(col, no_wrap=True)
    for r in w.plan.requirements:
        times = w.tick_times(r.index)
        st = w.live[r.index]
        if st.error is not None:
            table.add_row(r.id, "", Text("error", style="red"), Text(st.error[:60]), "", "",
                          "", "")
            continue
        # the requirement's own clock: its ticks and the time of its last one
        ticks = f"{len(times)} ({s(times[-1])})" if times else "0"
        if st.offline:
            pt = Text("offline", style="dim")
        elif st.pt is None:
            pt = Text("-")
        else:
            pt = Text("holds", style="green") if st.pt else Text("violated", style="bold red")
        style = {"violated": "bold red", "satisfied": "green"}.get(st.status, "")
        definite = "-"
        if st.status_tick is not None and st.status_tick < len(times):
            definite = f"{s(times[st.status_tick])} (#{st.status_tick})"
        trig = "-"
        if st.last_trigger is not None and st.last_trigger < len(times):
            trig = f"{s(times[st.last_trigger])} (#{st.last_trigger})"
        table.add_row(r.id, ticks, pt, Text(st.status, style=style), definite,
                      str(st.violations), str(st.pending), trig)
    src = w.source
    gaps = len(src.gaps)
    line = (f"{w.status_line} | unknown ticks {w.unknown_ticks} | gaps {gaps} | "
            f"problems {len(src.problems)}")
    return Group(Text(line, style="dim"), table)


class _Renderable:
    def __init__(self, w):
        self.w = w

    def __rich__(self):
        return live_table(self.w)


def _seconds(ctx, param, value):
    """A click callback: a duration (``"2 s"``, ``"500 ms"``, a number of seconds) in s."""
    if value is None:
        return None
    from fretc.common.units import parse_seconds

    try:
        return float(parse_seconds(value if not _number(value) else float(value)))
    except ValueError as exc:
        raise click.BadParameter(str(exc), ctx=ctx, param=param) from None


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _topic_types(ctx, param, values):
    out = {}
    for v in values:
        topic, sep, name = v.partition("=")
        if not sep or not topic.startswith("/") or not name:
            raise click.BadParameter(f"{v!r}: expected TOPIC=TYPE, e.g. "
                                     "/scan=sensor_msgs/msg/LaserScan", ctx=ctx, param=param)
        out[topic] = name
    return out


#: URL schemes ``fretc watch`` speaks: Foxglove WebSocket, rosbridge v2, DDS, Zenoh (kept equal
#: to live.transports.URL_SCHEMES, which is not imported at start-up).
URL_SCHEMES = ("ws://", "wss://", "rosbridge://", "rosbridge+wss://", "dds://", "zenoh://")


@click.command("watch")
@click.argument("url")
@live_input_options
@click.option("--duration", type=FiniteRange(0, 1e7, min_open=True), default=None,
              metavar="SECONDS",
              help="End the run after this many seconds (default: until the server ends it "
                   "or Ctrl-C).")
@click.option("--until-idle", default=None, metavar="DURATION", callback=_seconds,
              help="End the run when no message came for DURATION (e.g. \"2 s\").")
@click.option("--restart-grace", default="2 s", show_default=True, metavar="DURATION",
              callback=_seconds,
              help="How long a restarting publisher has to advertise its topic again before "
                   "the run counts as cut short (0: at once).")
@click.option("--allow-partial", is_flag=True,
              help="Exit 0 instead of 3 when a run without violations was incomplete "
                   "(connection gaps, data problems), as `fretc audit --allow-partial`.")
@click.option("--topic-type", "topic_types", multiple=True, metavar="TOPIC=TYPE",
              callback=_topic_types,
              help="rosbridge: the message type of TOPIC when the server's rosapi does not "
                   "give it, e.g. /scan=sensor_msgs/msg/LaserScan; repeatable.")
@click.option("--record", "record", type=click.Path(dir_okay=False), default=None,
              help="Write the watched messages and the verdict events (/fretc/verdicts) to "
                   "this MCAP; `fretc audit` of it gives the watch's verdicts.")
@click.option("--jsonl", is_flag=True, help="One JSON line per verdict event on stdout.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the final verdicts and evidence as the audit's JSON to FILE.")
@click.option("--wait", type=FiniteRange(0, 1e7), default=3.0, show_default=True, metavar="SECONDS",
              help="After connecting, wait this long for the bound topics' advertisements.")
@click.option("--connect-timeout", type=FiniteRange(0, 1e7, min_open=True), default=None,
              metavar="SECONDS",
              help="Give up when no connection was made within this time (default: retry "
                   "until stopped).")
@click.option("--no-live", is_flag=True, help="No live table (also when stderr is no terminal).")
@click.option("--dds-config", type=click.Path(exists=True, dir_okay=False), default=None,
              help="dds://: a Cyclone DDS XML configuration (network interfaces, peers, DDS "
                   "Security / SROS2) used instead of the default loopback-free one.")
@click.option("--merge-hold", type=FiniteRange(0, 10), default=0.1, show_default=True,
              metavar="SECONDS", help="dds://, zenoh://: hold each message this long to merge "
              "the topics into log-time order (the latency a verdict gains; a message "
              "overtaken by more is reported, clock_backwards); dds:// releases earlier, "
              "once every matched writer has sent a later message (the watermark).")
@click.option("--zenoh-config", type=click.Path(exists=True, dir_okay=False), default=None,
              help="zenoh://: a Zenoh JSON5 session configuration (TLS, access control) read "
                   "before fretc sets peer mode and the endpoint.")
@click.option("--publish-diagnostics", is_flag=True,
              help="dds://, zenoh://: publish the verdicts as a diagnostic_msgs/DiagnosticArray "
                   "on /diagnostics over the watched transport, at 1 Hz and on every change.")
@click.pass_context
def watch_cmd(ctx: click.Context, url: str, requirements: tuple[str, ...],
              bindings: tuple[str, ...], inline: tuple[str, ...], tick_period: str | None,
              tick_topic: str | None, time_base: str | None, window: int, duration: float | None,
              until_idle: float | None, restart_grace: float, allow_partial: bool,
              topic_types: dict[str, str], record: str | None, jsonl: bool, json_path: str | None,
              wait: float, connect_timeout: float | None, no_live: bool, dds_config: str | None,
              zenoh_config: str | None, publish_diagnostics: bool, msg_path: tuple[str, ...] = (),
              merge_hold: float = 0.1) -> None:
    """Watch a robot live (URL ws://host:8765: Foxglove WebSocket, e.g. foxglove_bridge;
    rosbridge://host:9090: rosbridge v2; dds://DOMAIN: the robot's DDS (Cyclone DDS);
    zenoh://host:7447: rmw_zenoh; zenoh://host:7447?layout=bridge: zenoh-bridge-ros2dds)
    with the requirements and bindings that audit its logs, until the run ends (the server
    closes, --duration, --until-idle, Ctrl-C, or every
    bound topic's publisher left for longer than --restart-grace). Exit codes as
    `fretc audit`."""
    # lazy: rich and the watch engine only when the command runs (start-up of fretc)
    from rich.console import Console
    from rich.markup import escape

    from fretc.audit import AuditInputError, load_plan
    from fretc.live.protocol import MissingDependency
    from fretc.live.watch import Watch, WatchOptions

    if not url.startswith(URL_SCHEMES):
        raise click.BadParameter(f"{url!r}: expected ws://host:port, rosbridge://host:port, "
                                 "dds://DOMAIN or zenoh://host:port", param_hint="URL")
    _check_ros2_url(url, "URL")
    if publish_diagnostics and not url.startswith(("dds://", "zenoh://")):
        raise click.BadParameter("--publish-diagnostics needs a dds:// or zenoh:// URL",
                                 param_hint="--publish-diagnostics")
    err = Console(stderr=True, highlight=False, soft_wrap=True, emoji=False)
    config = audit_config(requirements, bindings, inline, tick_period, tick_topic, time_base,
                          window, msg_path)
    lock = threading.Lock()
    diagnostics: list[DiagnosticsPublisher] = []

    def on_event(e):
        if diagnostics and e.kind in ("pt", "ltl3", "problem", "gap"):
            diagnostics[0].changed()
        said = connection_line(e, connect_timeout)
        if said is not None:
            err.print(said, markup=False)
        if jsonl:
            with lock:
                sys.stdout.write(json.dumps(e.to_json(), sort_keys=True) + "\n")
                sys.stdout.flush()

    try:
        plan = load_plan(config)
        _refuse_replacing_inputs(plan, record, json_path, dds_config or zenoh_config)
        w = Watch(plan, WatchOptions(url=url, duration=duration, wait=wait,
                                     connect_timeout=connect_timeout, record=record,
                                     until_idle=until_idle, types=topic_types or None,
                                     restart_grace=restart_grace, msg_path=tuple(msg_path),
                                     config=dds_config or zenoh_config,
                                     merge_hold=merge_hold),
                  on_event=on_event)
    except (AuditInputError, MissingDependency) as exc:
        err.print(f"[red]error:[/red] {escape(str(exc))}")
        ctx.exit(2)
        return
    input_errors = False
    for r in plan.requirements:
        if r.error is not None:
            input_errors = True
            err.print(f"[red]error:[/red] {escape(f'{r.id} ({r.source}): {r.error}')}")
    if publish_diagnostics:
        diagnostics.append(_diagnostics(w, url, dds_config).start())
    la = _run_watch(w, err, no_live)
    if diagnostics:
        diagnostics[0].finish(la)
        getattr(w.client, "close", lambda: None)()
    ctx.exit(_report(w, la, w.plan, input_errors, allow_partial, jsonl, record, json_path))


def _refuse_replacing_inputs(plan: Any, record: str | None, json_path: str | None,
                             config_file: str | None) -> None:
    """Neither ``--record`` nor ``--json`` is one of the watch's inputs (its requirement
    files, binding files, the transport's configuration file), checked before it connects.

    Raises:
        OutputError: one is (:func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    files, _ = requirement_inputs(list(plan.config.requirements))
    refuse_outputs_over_inputs(
        [("--record", record), ("--json", json_path)],
        files + [("the binding file", f) for f in plan.binding_files]
        + [("the transport's configuration", config_file)])


def connection_line(e: WatchEvent, connect_timeout: float | None) -> str | None:
    """What the watch says on the terminal about its connection, as ``ros2 topic echo`` and
    Foxglove's client do: at once when the first attempt fails (the URL and the reason),
    then after 2, 4, 8, ... failed attempts (a count, never silence), and once connected
    after failures; None for other events."""
    n = e.extra.get("attempts", 0) if e.kind == "unreachable" else 0
    if n == 1:
        give_up = (f"gives up after {connect_timeout:g} s" if connect_timeout is not None
                   else "--connect-timeout S gives up")
        return f"fretc watch: {e.detail}; retrying until it answers (Ctrl-C stops; {give_up})"
    if n > 1 and n & (n - 1) == 0:
        return f"fretc watch: still no connection after {n} attempts ({e.detail})"
    return None


def _check_ros2_url(url: str, hint: str) -> None:
    """A dds:// or zenoh:// URL of the wrong form is a usage error (exit 2)."""
    if url.startswith(("dds://", "zenoh://")):
        from fretc.live.ros2_names import parse_url

        try:
            parse_url(url)
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint=hint) from None


def _diagnostics(w, url: str, dds_config: str | None):
    """The /diagnostics publisher of a watch of ``url`` (its transport, in this process)."""
    from fretc.live.diagnostics import DiagnosticsPublisher

    if url.startswith("dds://"):
        from fretc.live.dds.serve import DdsServer

        return DiagnosticsPublisher(w, lambda: DdsServer(url, config_file=dds_config))
    from fretc.live.zenoh.serve import ZenohServer

    w.client.keep_session = True  # the final verdicts go out after the watch stopped reading
    return DiagnosticsPublisher(w, lambda: ZenohServer(url, name="fretc_watch",
                                                       session=w.client._session))


def _run_watch(w, err, no_live):
    """Run the watch (live table on a terminal), Ctrl-C ending the run; its LogAudit."""
    from rich.live import Live

    previous = signal.getsignal(signal.SIGINT)

    def on_sigint(signum, frame):
        w.stop()

    signal.signal(signal.SIGINT, on_sigint)
    try:
        if not no_live and err.is_terminal:
            with Live(_Renderable(w), console=err, refresh_per_second=4, transient=False):
                return w.run()
        return w.run()
    finally:
        signal.signal(signal.SIGINT, previous)


def _report(w, la, plan, input_errors, allow_partial, jsonl, record, json_path) -> int:
    """Print the summary, write --json; the exit code (:func:`fretc.audit.verdict.exit_code`,
    as ``fretc audit``)."""
    from rich.console import Console

    from fretc.audit.verdict import audit_json, exit_code
    from fretc.reports.terminal import print_summary

    out = Console(stderr=jsonl, highlight=False, width=None if sys.stdout.isatty() else 160,
                  emoji=False)
    print_summary(out, [la], plan, allow_partial=allow_partial, input_errors=input_errors,
                  command="fretc watch")
    if la.partial:
        out.print(f"connection gaps: {len(w.source.gaps)}; {w.unknown_ticks} ticks not "
                  "evaluated (unknown)", markup=False)
    if record:
        out.print(f"recorded {record}", markup=False)
    if json_path:
        doc = audit_json([la], plan.requirements_json(), plan.bindings_json(), input_errors,
                         allow_partial, plan.sources_json())
        from fretc.common.outputs import write_file

        write_file(json_path, doc)
    return exit_code([la], input_errors, allow_partial)


@click.command("replay")
@click.argument("log", type=click.Path(exists=True, dir_okay=False))
@click.option("--serve", is_flag=False, flag_value="ws", default=None, metavar="[URL]",
              help="Publish the log: alone, over the Foxglove WebSocket protocol (foxglove-sdk, "
                   "--host/--port); dds://DOMAIN as ROS 2 topics on Cyclone DDS; "
                   "zenoh://HOST:PORT as rmw_zenoh would (a Zenoh peer listening there).")
@click.option("--rate", type=FiniteRange(0, 1e6), default=1.0, show_default=True,
              help="Times real time (0: as fast as possible).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Interface to bind (loopback by default).")
@click.option("--port", type=int, default=8765, show_default=True)
@click.option("--wait/--no-wait", default=True, show_default=True,
              help="Start publishing once a client subscribed.")
@click.option("--loop", is_flag=True, help="Start again at the end.")
@click.option("--dds-config", type=click.Path(exists=True, dir_okay=False), default=None,
              help="dds://: a Cyclone DDS XML configuration instead of the loopback one.")
@click.option("--zenoh-config", type=click.Path(exists=True, dir_okay=False), default=None,
              help="zenoh://: a Zenoh JSON5 session configuration read first.")
def replay_cmd(log: str, serve: str | None, rate: float, host: str, port: int, wait: bool,
               loop: bool, dds_config: str | None, zenoh_config: str | None) -> None:
    """Publish a recorded MCAP LOG (--serve: over the Foxglove WebSocket protocol; --serve
    dds://DOMAIN or zenoh://HOST:PORT: on the robot's middleware, with ROS 2's names and
    types and each message's log time as its source timestamp), paced at RATE times real
    time; then close (a `fretc watch` of it ends there)."""
    if serve is None:
        raise click.UsageError("--serve is required (alone for the Foxglove WebSocket, or "
                               "--serve dds://DOMAIN, --serve zenoh://HOST:PORT)")
    # lazy: foxglove-sdk, Cyclone DDS, Zenoh only when the command runs
    from fretc.live.websocket.serve import advertise_mcap, replay_mcap

    server = _replay_server(log, serve, host, port, dds_config or zenoh_config)
    advertise_mcap(log, server)
    if hasattr(server, "start"):  # the Foxglove WebSocket server listens from here
        server.start()
    for topic, why in sorted(getattr(server, "skipped", {}).items()):
        click.echo(f"not published: {topic}: {why}", err=True)
    click.echo(f"serving {log} on {server.url} at {rate:g}x", err=True)
    try:
        while True:
            if wait:
                click.echo("waiting for a client to subscribe", err=True)
                server.wait_subscribed(timeout=1e9)
            t0 = time.perf_counter()
            n, _last = replay_mcap(log, server, rate)
            click.echo(f"sent {n} messages in {time.perf_counter() - t0:.1f} s", err=True)
            if not loop:
                break
        time.sleep(0.5)  # let the last messages leave
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()


def _replay_server(log: str, serve: str, host: str, port: int, config: str | None):
    """The server of ``--serve`` (``ws``: the Foxglove WebSocket server on host:port)."""
    from fretc.live.protocol import MissingDependency

    if serve != "ws":
        _check_ros2_url(serve, "--serve")
    try:
        if serve.startswith("dds://"):
            from fretc.live.dds.serve import DdsServer

            return DdsServer(serve, config_file=config)
        if serve.startswith("zenoh://"):
            from fretc.live.zenoh.serve import ZenohServer

            return ZenohServer(serve, name=f"fretc_replay_{log}", config_file=config)
        if serve != "ws":
            raise click.BadParameter(f"{serve!r}: expected dds://DOMAIN or zenoh://HOST:PORT "
                                     "(or --serve alone)", param_hint="--serve")
        from fretc.live.websocket.serve import FoxgloveServer

        # started once the log's channels are created (advertise_mcap): a client
        # connecting at once is advertised them all in one message
        return FoxgloveServer(host=host, port=port, name=f"fretc replay {log}", start=False)
    except (RuntimeError, MissingDependency) as exc:
        raise MissingExtra(str(exc)) from None


class MissingExtra(click.ClickException):
    """An optional dependency is missing or the server cannot start: ``Error: ...`` in one
    line, exit code 2 (as a usage or input error)."""

    exit_code = 2


def register(main: click.Group) -> None:
    """Add ``watch`` and ``replay`` to the ``fretc`` group."""
    main.add_command(watch_cmd, "watch")
    main.add_command(replay_cmd, "replay")
