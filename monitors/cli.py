"""``fretc audit``: check recorded runs against FRETish requirements (click command).

::

    fretc audit [--requirements PATH]... [--bindings FILE]... [--bind NAME=EXPR]...
                [--tick-period "100 ms" | --tick-topic /scan] [--time-base log|header]
                [-j N] [--json FILE] [--junit FILE] [--no-progress] LOGS...

LOGS are ``.mcap`` files (ROS 1 or ROS 2 encodings), ROS 1 ``.bag`` files, rosbag2 folders,
``.csv`` traces, or folders searched for them. Binding files default to every
``*.bindings.toml`` beside the requirement files or folders. Exit status
(:data:`monitors.report_model.EXIT_CODES`): 0 every verdict satisfied (or vacuous) on
complete logs, 1 a requirement is violated, 2 usage or input errors (including a
requirement that could not be audited on some log), 3 no violation but a log is partial or
had data problems (``--allow-partial``: 0).

Only click is imported at module level; the engine loads on first use.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .fleet_cli import ray_options

__all__ = ["audit_cmd", "audit_input_options", "audit_config"]


def audit_input_options(f):
    """The options that say what to audit and how (shared by ``fretc audit`` and
    ``fretc report``): requirements, bindings, tick, time base, jobs, engine, window."""
    options = [
        click.option("-r", "--requirements", "requirements", multiple=True,
                     type=click.Path(exists=True),
                     help="Requirement file (.fret, FRET JSON export) or folder; repeatable. "
                          "Default: ./requirements."),
        click.option("-b", "--bindings", "bindings", multiple=True,
                     type=click.Path(exists=True),
                     help="Signal binding file (TOML); repeatable. Default: *.bindings.toml "
                          "beside the requirements."),
        click.option("--bind", "inline", multiple=True, metavar="NAME=EXPR",
                     help="Bind a FRET variable inline, e.g. "
                          "--bind 'too_close=min(/scan.ranges) < 0.9'."),
        click.option("--tick-period", default=None, metavar="DURATION",
                     help="Fixed tick with sample-and-hold, e.g. \"100 ms\" (overrides the "
                          "bindings)."),
        click.option("--tick-topic", default=None, metavar="TOPIC",
                     help="One tick per message of TOPIC (overrides the bindings)."),
        click.option("--time-base", type=click.Choice(["log", "header"]), default=None,
                     help="Message time: log time (default) or header.stamp."),
        click.option("-j", "--jobs", type=click.IntRange(min=1), default=1,
                     show_default=True, help="Audit this many logs in parallel processes."),
        click.option("--engine", type=click.Choice(["auto", "stepwise", "vectorized"]),
                     default="auto", show_default=True,
                     help="stepwise: the generated monitors' step() on every tick; "
                          "vectorized: numpy over the sampled columns; auto: vectorized on "
                          "long logs."),
        click.option("--window", type=click.IntRange(min=0), default=5, show_default=True,
                     help="Ticks of values kept each side of a trigger and a violation."),
    ]
    for option in reversed(options):
        f = option(f)
    return f


def audit_config(requirements, bindings, inline, tick_period, tick_topic, time_base, engine,
                 window):
    """The :class:`monitors.audit.AuditConfig` of :func:`audit_input_options`' values
    (requirements default to ./requirements; raises ``click.UsageError`` without one)."""
    from .audit import AuditConfig

    if not requirements:
        if not Path("requirements").is_dir():
            raise click.UsageError("no --requirements given and no ./requirements folder")
        requirements = ("requirements",)
    return AuditConfig(requirements=tuple(requirements),
                       bindings=tuple(bindings) if bindings else None, inline=tuple(inline),
                       tick_period=tick_period, tick_topic=tick_topic, time_base=time_base,
                       engine=engine, window=window)


@click.command("audit")
@click.argument("logs", nargs=-1, required=True)
@audit_input_options
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the verdicts and evidence as JSON to FILE ('-': stdout).")
@click.option("--junit", "junit_path", type=click.Path(dir_okay=False), default=None,
              help="Write JUnit XML to FILE: one test case per requirement x log.")
@click.option("--no-progress", is_flag=True, help="No progress bar.")
@click.option("--allow-partial", is_flag=True,
              help="Exit 0 instead of 3 when nothing is violated but a log is partial or had "
                   "data problems.")
@click.option("-v", "--verbose", is_flag=True,
              help="Full evidence: every value row around each violation and every note.")
@ray_options
@click.pass_context
def audit_cmd(ctx, logs, requirements, bindings, inline, tick_period, tick_topic, time_base,
              jobs, json_path, junit_path, no_progress, engine, window, allow_partial,
              verbose):
    """Audit recorded runs (LOGS: .mcap, .bag, rosbag2 folders, .csv, or folders of them)
    against FRETish requirements.

    \b
    Exit codes:
      0  every verdict satisfied or vacuous, on complete logs
      1  a requirement is violated
      2  usage or input error (bad option, requirement, binding or log; a
         requirement that could not be audited on some log)
      3  no violation, but a log is partial (cut short, damaged) or had data
         problems, or a verdict is unknown (--allow-partial: 0)

    \b
    Binding reference (expressions, functions, slices, units, NaN/inf rules,
    examples): docs/bindings.md."""
    from rich.console import Console
    from .audit_output import escape  # markup and control characters escaped

    from .audit import AuditInputError, find_logs, load_plan
    from .audit_junit import junit_xml
    from .audit_output import AuditProgress, print_summary
    from .fleet import expand_log_args, run_audits
    from .report_model import audit_json, exit_code

    to_stdout_json = json_path == "-"
    out = Console(stderr=to_stdout_json, width=None if sys.stdout.isatty() else 160,
                  highlight=False)
    err = Console(stderr=True, highlight=False, soft_wrap=True)
    config = audit_config(requirements, bindings, inline, tick_period, tick_topic, time_base,
                          engine, window)
    try:
        plan = load_plan(config)
        paths = find_logs(expand_log_args(logs))
    except AuditInputError as exc:
        err.print(f"[red]error:[/red] {escape(str(exc))}")
        ctx.exit(2)
        return
    for w in plan.warnings:
        err.print(f"[yellow]warning:[/yellow] {escape(w)}")
    input_errors = False
    for r in plan.requirements:
        if r.error is not None:
            input_errors = True
            err.print(f"[red]error:[/red] {escape(f'{r.id} ({r.source}): {r.error}')}")
    show = not no_progress and sys.stderr.isatty()
    if show:
        with AuditProgress(err, len(paths)) as prog:
            results = run_audits(plan, paths, jobs=jobs, progress=prog, ctx=ctx)
    else:
        results = run_audits(plan, paths, jobs=jobs, ctx=ctx)
    print_summary(out, results, plan, verbose=verbose, allow_partial=allow_partial,
                  input_errors=input_errors)
    doc = audit_json(results, plan.requirements_json(), plan.bindings_json(), input_errors,
                     allow_partial)
    if json_path:
        if to_stdout_json:
            click.echo(doc, nl=False)
        else:
            Path(json_path).write_text(doc, encoding="utf-8")
    if junit_path:
        Path(junit_path).write_text(junit_xml(results), encoding="utf-8")
    code = exit_code(results, input_errors, allow_partial)
    ctx.exit(code)
