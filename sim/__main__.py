"""Command line: ``python -m fretc.sim record|serve|list|verdicts|drive`` (see ``python -m fretc.sim --help``)."""

from __future__ import annotations

import time
from pathlib import Path

import click

from fretc.sim.faults import FAULT_KINDS, faults_from_options
from fretc.sim.logs import REQUIREMENTS, counts, expected_verdicts, read_log
from fretc.sim.run import record as do_record
from fretc.sim.scenarios import SCENARIOS
from fretc.sim.serve import serve as do_serve


@click.group()
def main() -> None:
    """Simulated Safe-ROS robot: record Scout Mini inspection runs as MCAP."""


@main.command("list")
def list_scenarios() -> None:
    """List the scenarios."""
    for name, sc in SCENARIOS.items():
        click.echo(f"{name:20s} {sc.description}")


@main.command()
@click.option("--scenario", "-s", type=click.Choice(list(SCENARIOS)), default="nominal",
              show_default=True, help="Scenario to simulate.")
@click.option("--seed", type=int, default=1, show_default=True, help="Random seed.")
@click.option("--output", "-o", type=click.Path(dir_okay=False), required=True,
              help="MCAP file to write.")
@click.option("--ros1", is_flag=True, help="ROS 1 messages (profile ros1) instead of ROS 2 (cdr).")
@click.option("--png", type=click.Path(dir_okay=False), default=None,
              help="Also draw the run to this PNG.")
@click.option("--threshold", type=float, default=0.9, show_default=True,
              help="SIF minimum-range threshold [m].")
@click.option("--stop-delay", type=float, default=None,
              help="Delay of /gwendolen_control [s] in the stop_delay scenario (default 2.0).")
@click.option("--compression", type=click.Choice(["zstd", "lz4"]), default="zstd",
              show_default=True, help="MCAP chunk compression.")
@click.option("--safety", default="sif", show_default=True, metavar="sif|shield:DIR",
              help="The Safety System: the hand-written SIF and cmd_vel_interceptor, or the "
              "shield fretc shield --emit python -b BINDINGS wrote into DIR.")
@click.option("--fault", "fault_kinds", multiple=True, type=click.Choice(list(FAULT_KINDS)),
              help="Inject this fault (repeatable; docs/guide/simulator.md): a silent, "
              "invalid (all or a sector NaN), frozen or stale-stamped LiDAR, spurious near "
              "returns, the controller's NaN/inf/huge /cmd_vel, the Safety System's restart.")
@click.option("--fault-start", "fault_starts", multiple=True, type=float, metavar="S",
              help="Sim time [s] each fault starts (once for all, or once per --fault).")
@click.option("--fault-duration", "fault_durations", multiple=True, type=float, metavar="S",
              help="How long [s] each fault lasts (once for all, or once per --fault).")
@click.option("--fault-sector", "fault_sectors", multiple=True, metavar="LO:HI",
              help="The beams' sector [degrees, REP 103: 0 ahead, counter-clockwise] of "
              "sector_nan (required) and near_returns (default: the whole scan).")
def record(scenario: str, seed: int, output: str, ros1: bool, png: str | None, threshold: float,
           stop_delay: float | None, compression: str, safety: str,
           fault_kinds: tuple[str, ...], fault_starts: tuple[float, ...],
           fault_durations: tuple[float, ...], fault_sectors: tuple[str, ...]) -> None:
    """Record one scenario to an MCAP file."""
    try:
        faults = faults_from_options(fault_kinds, fault_starts, fault_durations,
                                     fault_sectors)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--fault") from None
    t0 = time.perf_counter()
    try:
        res = do_record(scenario, seed=seed, output=output, ros1=ros1, png=png,
                        threshold=threshold, stop_delay=stop_delay, compression=compression,
                        safety=safety, faults=faults)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--safety") from None
    wall = time.perf_counter() - t0
    reached = ", ".join(f"goal {g + 1} at {t:.1f} s" for g, t, _, _ in res.reached)
    clr = ("<= 0 (contact)" if res.min_clearance <= 0 else f"{res.min_clearance:.3f} m")
    click.echo(f"{output}: {scenario} seed {seed}: {res.outcome}; {res.duration:.2f} s sim "
               f"in {wall:.1f} s wall; reached: {reached or 'none'}; min clearance {clr}")
    for flt in faults:
        click.echo(f"  fault {flt.kind}: {flt.start:g} s for {flt.duration:g} s"
                   + (f", sector {flt.sector[0]:g}:{flt.sector[1]:g} degrees"
                      if flt.sector is not None else ""))
    if safety != "sif":
        why: dict[str, int] = {}
        for _t, reasons, _changed in res.overrides:
            for r in reasons:
                why[r] = why.get(r, 0) + 1
        click.echo(f"  shield: {len(res.overrides)} of {res.shield_ticks} ticks overridden"
                   + (" (" + ", ".join(f"{k}: {v}" for k, v in sorted(why.items())) + ")"
                      if why else ""))
    else:
        stops = sum(1 for e in res.sif_events if e.stop)
        click.echo(f"  SIF: {stops} stop requests")


@main.command()
@click.option("--scenario", "-s", type=click.Choice(list(SCENARIOS)), default="nominal",
              show_default=True, help="Scenario to simulate.")
@click.option("--seed", type=int, default=1, show_default=True, help="Random seed.")
@click.option("--rate", type=float, default=1.0, show_default=True,
              help="Times real time (0: as fast as possible).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Interface to bind (loopback by default).")
@click.option("--port", type=int, default=8765, show_default=True)
@click.option("--ros1", is_flag=True, help="ROS 1 messages instead of ROS 2 (cdr).")
@click.option("--wait/--no-wait", default=True, show_default=True,
              help="Start the run once a client subscribed.")
@click.option("--safety", default="sif", show_default=True, metavar="sif|shield:DIR",
              help="The Safety System: the hand-written SIF and cmd_vel_interceptor, or the "
              "shield fretc shield --emit python -b BINDINGS wrote into DIR (a shielded run "
              "watched live).")
def serve(scenario: str, seed: int, rate: float, host: str, port: int, ros1: bool, wait: bool,
          safety: str) -> None:
    """Run one scenario live over the Foxglove WebSocket protocol (foxglove-sdk)."""
    def ready(server):
        click.echo(f"serving {scenario} on {server.url} at {rate:g}x"
                   + ("; waiting for a client to subscribe" if wait else ""), err=True)

    try:
        res = do_serve(scenario, seed=seed, rate=rate, host=host, port=port, ros1=ros1,
                       wait=wait, on_ready=ready, safety=safety)
    except KeyboardInterrupt:
        return
    except ValueError as exc:  # (a --safety that names no shield folder)
        raise click.BadParameter(str(exc), param_hint="--safety") from None
    except RuntimeError as exc:  # no foxglove-sdk (the watch extra): one line, exit 2
        click.echo(f"error: {exc}", err=True)
        raise SystemExit(2) from None
    click.echo(f"{scenario}: {res.outcome}; {res.duration:.2f} s sim", err=True)


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("--threshold", type=float, default=0.9, show_default=True)
@click.option("--markdown", is_flag=True, help="Print Markdown tables.")
def verdicts(files: tuple[str, ...], threshold: float, markdown: bool) -> None:
    """Evaluate R1-R6 on recorded runs with the reference evaluator (sim.logs)."""
    rows = []
    for f in files:
        log = read_log(f)
        v = expected_verdicts(log, threshold)
        dur = (log.end_ns - log.start_ns) / 1e9
        rows.append((Path(f).name, log.profile, dur, Path(f).stat().st_size, counts(f), v))
    if markdown:
        click.echo("| log | " + " | ".join(REQUIREMENTS) + " |")
        click.echo("|---|" + "---|" * len(REQUIREMENTS))
        for name, _, _, _, _, v in rows:
            click.echo(f"| {name} | " + " | ".join(v[r].text() for r in REQUIREMENTS) + " |")
        click.echo()
        topics = sorted({t for r in rows for t in r[4]})
        click.echo("| log | profile | duration [s] | size [bytes] | " + " | ".join(topics) + " |")
        click.echo("|---|---|---|---|" + "---|" * len(topics))
        for name, prof, dur, size, cnt, _ in rows:
            click.echo(f"| {name} | {prof} | {dur:.2f} | {size} | "
                       + " | ".join(str(cnt.get(t, 0)) for t in topics) + " |")
    else:
        for name, prof, dur, size, _cnt, v in rows:
            click.echo(f"{name} ({prof}, {dur:.2f} s, {size} bytes)")
            for r in REQUIREMENTS:
                click.echo(f"  {r}: {v[r].text()}  [{v[r].triggers} triggering ticks]")


@main.command()
@click.argument("trace", type=click.Path(exists=True, dir_okay=False))
@click.argument("log", type=click.Path(dir_okay=False))
@click.option("--bindings", "-b", "bindings_file", required=True,
              type=click.Path(exists=True, dir_okay=False),
              help="The binding file of the trace's variables (requirements/"
                   "safe_ros.bindings.toml).")
@click.option("--scenario", "-s", type=click.Choice(list(SCENARIOS)), default="nominal",
              show_default=True, help="Scenario (world and faults) the robot runs in.")
@click.option("--seed", type=int, default=1, show_default=True, help="Random seed.")
@click.option("--lead-in", type=float, default=None,
              help="Seconds simulated before the trace's first tick (default 3.0).")
@click.option("--lead-out", type=float, default=None,
              help="Seconds simulated after the trace's last tick, its inputs held "
                   "(default 2.0).")
def drive(trace: str, log: str, bindings_file: str, scenario: str, seed: int,
          lead_in: float | None, lead_out: float | None) -> None:
    """Drive the robot with TRACE's input variables (a fretc testgen CSV) and record the run to
    LOG (MCAP). The robot's SIF, interceptor and navigation produce the outputs."""
    import sys

    from fretc.common.errors import FretcError
    from fretc.monitors.simulate import read_trace
    from fretc.signals.bindings.files import load_bindings
    from fretc.sim.drive import LEAD_IN_S, LEAD_OUT_S, DriveError
    from fretc.sim.drive import drive as do_drive

    try:
        b = load_bindings(bindings_file)
        data = read_trace(trace)
        n = len(next(iter(data.values()), []))
        rows = [{k: v[i] for k, v in data.items()} for i in range(n)]
        roles, res = do_drive(rows, b, log, scenario=scenario, seed=seed,
                              lead_in=LEAD_IN_S if lead_in is None else lead_in,
                              lead_out=LEAD_OUT_S if lead_out is None else lead_out)
    except DriveError as exc:  # a trace's tick or column: named with the trace
        click.echo(f"error: {trace}: {exc}", err=True)
        sys.exit(2)
    except (FretcError, OSError) as exc:  # these name their file
        click.echo(f"error: {exc}", err=True)
        sys.exit(2)
    click.echo(f"{log}: {scenario} seed {seed} driven by {trace} ({n} ticks): "
               f"{res.duration:.1f} s sim; {res.outcome or 'mission under way'}", err=True)
    click.echo(f"  driven from the trace: {', '.join(roles.driven) or 'none'}", err=True)
    click.echo(f"  the robot's own: {', '.join(roles.system) or 'none'}", err=True)
    for name, why in roles.not_drivable.items():
        click.echo(f"  not drivable: {name}: {why}", err=True)


if __name__ == "__main__":
    main()
