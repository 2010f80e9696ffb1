"""``fretc shield-replay``: a generated shield run over recorded runs
(:mod:`fretc.shield.replay`): what the Safety System would have done on the robot's runs.

Design notes: ARCHITECTURE.md, `fretc/cli/shield_replay.py`."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import click

from fretc.cli.options import shown

__all__ = ["shield_replay_cmd", "faults_code", "faults_text"]


@click.command("shield-replay")
@click.argument("shield_dir", type=click.Path(file_okay=False))
@click.argument("logs", nargs=-1, required=True)
@click.option("-o", "--output", "out_dir", type=click.Path(file_okay=False), required=True,
              help="The folder the shielded recordings (NAME.shielded.mcap) are written to.")
@click.option("-r", "--requirements", "requirements", multiple=True, metavar="PATH",
              help="The requirements the shielded runs are audited against (repeatable); "
              "default: the files the shield's enforced requirements were read from.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the overrides and the audit of each shielded run as JSON to FILE "
              "('-': stdout).")
@click.pass_context
def shield_replay_cmd(ctx: click.Context, shield_dir: str, logs: tuple[str, ...],
                      out_dir: str, requirements: tuple[str, ...],
                      json_path: str | None) -> None:
    """Run the shield of SHIELD_DIR (fretc shield --emit python -b BINDINGS -o DIR) over
    recorded runs (LOGS: .mcap, .bag, rosbag2 folders): write each shielded recording
    into DIR (every recorded message as it was; the corrected outputs added at each tick
    of the requirements), print the overrides per requirement and the audit of the
    shielded run.

    \b
    Exit codes:
      0  every verdict of the shielded runs satisfied or vacuous
      1  a requirement is violated in a shielded run
      2  usage or input error (the folder, a log, a topic or a log time named)
      3  no violation, but a fault the shield did not answer (a tick with an
         unreadable input at which it published nothing), a verdict unknown, a
         log partial or a recording replayed damaged (damage replays the span
         before it: the shielded run's audit is partial there), or data problems
         where no input of the shield was unreadable
      6  no violation; the logs had faults (ticks with an unreadable input) and
         the shield answered every one (its fallback, or outputs safe for every
         value the input could have had); no verdict unknown, no log partial or
         damaged (the audit's data problems are listed above it)

    \b
    Each log's summary ends with its faults: "faults: N ticks with an unreadable
    input, N answered by the shield", and the first unanswered one's log time
    (--json: "faults" per run)."""
    from fretc.common.outputs import output_folder, refuse_replacing_inputs
    from fretc.fretish.files import requirement_files
    from fretc.shield.replay import ReplayError, load_folder, replay_log, shielded_name

    folder = load_folder(shield_dir)
    reqs = requirements or tuple(folder.sources())
    absent = [r for r in reqs if not Path(r).exists()]
    if absent or not reqs:
        raise ReplayError(f"{folder.module}: the requirement files it was generated from ("
                          f"{', '.join(absent) or 'none named'}) are not here: give the "
                          "requirements to audit the shielded runs with -r FILE")
    names = [shielded_name(log) for log in logs]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ReplayError(f"two logs would be written to {', '.join(twice)} in {out_dir}: "
                          "replay them into different folders")
    # (hostile round 9, R1: -o d with d/a.shielded.mcap given as a log overwrote it before reading)
    refuse_replacing_inputs(
        [("-o", Path(out_dir) / n) for n in names] + [("--json", json_path)],
        [("the log", log) for log in logs]
        + [("the requirement file", r) for r in requirement_files(list(reqs))]
        + [("the shield's module", folder.module),
           ("the shield's binding file", folder.bindings_file)])
    output_folder(out_dir)
    results = []
    for log, name in zip(logs, names):
        result = replay_log(folder, log, Path(out_dir) / name)
        results.append(result)
        click.echo(shown(_overrides_text(result)), err=json_path == "-")
    click.echo(shown("enforced by the shield: " + (", ".join(folder.requirements) or "none")
                     + "; any other requirement is judged on the recorded inputs (a replay "
                     "does not move the robot: what its sensors saw is as recorded)"),
               err=json_path == "-")
    audits, code = _audit(reqs, str(folder.bindings_file), [r.written for r in results],
                          to_stdout=json_path == "-")
    whole = [r.log for r in results
             if r.damage is not None and r.damage["damage_time_ns"] is None]
    if code == 0 and whole:  # (every message replayed, but the recording is damaged)
        code = 3
        click.echo(shown(f"exit 3: {', '.join(whole)} is damaged, though every message in "
                         "it was replayed (fretc audit of it is partial)"),
                   err=json_path == "-")
    code, why = faults_code(code, results, audits)
    if why:
        click.echo(shown(why), err=json_path == "-")
    if json_path:
        doc = {"shield": str(folder.module), "bindings": str(folder.bindings_file),
               "requirements": list(reqs),
               "runs": [{**r.as_json(), "audit": a.to_json()} for r, a in zip(results, audits)],
               "exit_code": code}
        _write_json(doc, json_path)
    ctx.exit(code)


def _ticks(n: int) -> str:
    return f"{n} tick" if n == 1 else f"{n} ticks"


def _time(t: int | None, start: int | None) -> str:
    """A log time (ns) as seconds from the replay's first tick."""
    return "-" if t is None or start is None else f"{(t - start) / 1e9:.3f} s"


def _overrides_text(r: Any) -> str:
    """The terminal lines of one replay: what was written, the ticks, the overrides per
    requirement (ticks, first and last), the faults and what was kept under another topic."""
    s = r.first_tick
    lines = [f"shield replay {r.log} -> {r.written}: {r.ticks} ticks "
             f"({_time(r.first_tick, s)} .. {_time(r.last_tick, s)} from the first tick, "
             f"log time {r.first_tick} ns), {r.overridden.ticks} overridden"]
    for rid, span in r.overrides.items():
        lines.append(f"  {rid}: {_ticks(span.ticks)} overridden, first {_time(span.first, s)}, "
                     f"last {_time(span.last, s)}")
    if not r.overrides:
        lines.append("  no requirement's machine overrode the proposal")
    for label, span in (("no message the bindings give (no requirement broken)", r.unshaped),
                        ("an input not read: decided for every value it could have had",
                         r.input_faults),
                        ("a proposal not read: replaced", r.proposal_faults),
                        ("nothing published (no fallback)", r.silent)):
        if span.ticks:
            lines.append(f"  {label}: {_ticks(span.ticks)}, first {_time(span.first, s)} "
                         f"({span.why}), last {_time(span.last, s)}")
    for a, t in r.broken.items():
        lines.append(f"  assumption {a} of the environment broken at {_time(t, s)}: the "
                     "shield's guarantee no longer holds from there")
    for topic in getattr(r, "own_proposals", ()):
        lines.append(f"  proposals of {topic}: its recorded messages ([shield] proposals "
                     "names none for it)")
    for topic, kept in r.renamed.items():
        lines.append(f"  recorded {topic} kept as {kept} (the shield publishes {topic})")
    if r.damage is not None:
        end, why = r.damage["damage_time_ns"], "; ".join(r.damage["problems"][:1])
        lines.append(
            f"  the recording is damaged: replayed up to log time {end} ns "
            f"({_time(end, s)} from the first tick), nothing from there on (the audit of the "
            f"shielded run is partial there): {why}" if end is not None else
            f"  the recording is damaged (every message in it replayed): {why}")
    said = set(r.damage["problems"]) if r.damage is not None else set()
    others = [p for p in r.problems if p not in said]  # (the damage's said above)
    if others:
        lines.append(f"  the log's data problems: {len(others)} (fretc audit of the log "
                     f"lists them): {others[0]}")
    lines.append("  " + faults_text(r))
    return "\n".join(lines)


def faults_text(r: Any) -> str:
    """The faults of one replay (a :class:`fretc.shield.replay.ReplayResult`) in one line:
    the ticks with an unreadable input, how many the shield answered (its fallback, or
    outputs safe for every value the input could have had, published), and the first
    unanswered one's log time (ns) and reason."""
    f, un = r.faults, r.unanswered
    if not f.ticks:
        return "faults: no tick with an unreadable input"
    text = (f"faults: {_ticks(f.ticks)} with an unreadable input, {r.answered} answered by "
            "the shield (its fallback, or outputs safe for every value the input could have "
            "had)")
    if un.ticks:
        text += (f", {un.ticks} unanswered: the first at log time {un.first} ns "
                 f"({_time(un.first, r.first_tick)} from the first tick; {un.why})")
    return text


def faults_code(code: int, results: list[Any], audits: list[Any]) -> tuple[int, str]:
    """The exit code of the replays ``results`` (:class:`fretc.shield.replay.ReplayResult`)
    whose shielded runs' audits (``audits``, :class:`fretc.audit.verdict.LogAudit`) exit
    ``code``, with their faults told apart, and the line that says why it changed ("" when
    it did not): 3 for a fault the shield did not answer where the audit found nothing
    (0); 6 where the audit's 3 has no cause but the faults and the shield answered every one
    (no verdict unknown, no log partial, no recording damaged)."""
    faults = sum(r.faults.ticks for r in results)
    unanswered = [r for r in results if r.unanswered.ticks]
    if code == 0 and unanswered:
        r = unanswered[0]
        return 3, (f"exit 3: a fault the shield did not answer: {r.log} at log time "
                   f"{r.unanswered.first} ns ({r.unanswered.why})")
    if code != 3 or not faults or unanswered:
        return code, ""
    unknown = any(v.verdict == "unknown" for a in audits for v in a.verdicts)
    if unknown or any(a.partial for a in audits) or any(r.damage for r in results):
        return code, ""
    return 6, (f"exit 6: no violation; the logs had faults ({_ticks(faults)} with an "
               "unreadable input) and the shield answered every one")


def _audit(requirements: tuple[str, ...], bindings_file: str, paths: list[str],
           to_stdout: bool) -> tuple[list[Any], int]:
    """The audit of the shielded recordings ``paths`` with ``requirements`` and the
    shield's binding file, printed as ``fretc audit`` prints it; (the logs' audits, the
    exit code)."""
    from rich.console import Console

    from fretc.audit import AuditInputError, audit_logs, load_plan
    from fretc.audit.verdict import exit_code
    from fretc.cli.options import audit_config
    from fretc.reports.terminal import escape, print_summary

    out = Console(stderr=to_stdout, width=None if sys.stdout.isatty() else 160,
                  highlight=False, emoji=False)
    config = audit_config(requirements, (bindings_file,), (), None, None, None, 5)
    try:
        plan = load_plan(config)
    except AuditInputError as exc:
        Console(stderr=True, highlight=False, soft_wrap=True, emoji=False).print(
            f"[red]error:[/red] {escape(str(exc))}")
        sys.exit(2)
    err = Console(stderr=True, highlight=False, soft_wrap=True, emoji=False)
    for w in plan.warnings:  # (on stderr, as fretc audit prints them)
        err.print(f"[yellow]warning:[/yellow] {escape(w)}")
    results = audit_logs(plan, paths)
    input_errors = any(r.error is not None for r in plan.requirements)
    click.echo(shown("audit of the shielded run" + ("s" if len(paths) > 1 else "") + ":"),
               err=to_stdout)
    print_summary(out, results, plan, input_errors=input_errors,
                  command="fretc shield-replay")
    return results, exit_code(results, input_errors)


def _write_json(doc: dict[str, Any], json_path: str) -> None:
    """``doc`` as JSON to ``json_path`` ('-': stdout), through the repo's writer (never
    through a link planted there)."""
    text = json.dumps(doc, indent=2, sort_keys=False) + "\n"
    if json_path == "-":
        sys.stdout.write(text)
        return
    from fretc.common.outputs import write_file

    write_file(json_path, text)
