"""``fretc audit``: check recorded runs against FRETish requirements (click command).

Design notes: ARCHITECTURE.md, `fretc/cli/audit.py`."""

from __future__ import annotations

import sys
from pathlib import Path
from collections.abc import Callable
from typing import Any

import click

from fretc.common.collections_gc import with_fewer_full_collections
from fretc.cli.options import (audit_config, audit_input_options, ray_options, run_audits,
                               statistics_options)

__all__ = ["audit_cmd"]


@click.command("audit")
@click.argument("logs", nargs=-1, required=True)
@audit_input_options
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the verdicts and evidence as JSON to FILE ('-': stdout).")
@click.option("--junit", "junit_path", type=click.Path(dir_okay=False), default=None,
              help="Write JUnit XML to FILE: one test case per requirement x log.")
@click.option("--no-progress", is_flag=True, help="No progress bar.")
@click.option("--allow-partial", is_flag=True,
              help="Exit 0 instead of 3 when nothing is violated but a log is partial, had "
                   "data problems or a verdict is unknown (the verdicts stay as they are: "
                   "an unknown is never a pass).")
@statistics_options
@click.option("--coverage", "coverage", is_flag=True,
              help="Also measure which coverage obligations of each requirement (each atom's "
                   "own effect, the trigger, the scope entered and left, the deadline reached "
                   "and missed, each threshold's two sides) the runs exercised: per log and "
                   "over the fleet, in the JSON ('coverage') and as a summary.")
@click.option("-v", "--verbose", is_flag=True,
              help="Full evidence: every value row around each violation and every note.")
@click.option("--write-csv", "csv_dir", type=click.Path(file_okay=False), default=None,
              help="Also write what the audit of each log judged, one CSV trace per log "
                   "in DIR (LOG-STEM.csv): each requirement's own clock (its ticks, the "
                   "values of its variables, what the log's damage left unknown); the "
                   "input of fretc audit and of the C monitors' runner, which give the "
                   "log's verdicts on it.")
@ray_options
@click.pass_context
@with_fewer_full_collections
def audit_cmd(ctx: click.Context, logs: tuple[str, ...], requirements: tuple[str, ...],
              bindings: tuple[str, ...], inline: tuple[str, ...], tick_period: str | None,
              tick_topic: str | None, time_base: str | None, jobs: int, json_path: str | None,
              junit_path: str | None, no_progress: bool, window: int, allow_partial: bool,
              confidence: float, trial: str, unknown_runs: str, verbose: bool, coverage: bool,
              csv_dir: str | None = None, msg_path: tuple[str, ...] = ()) -> None:
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
      4  internal error of fretc
      5  no violation, but a 'with probability' requirement is undecided: too
         few runs for its bound (docs/guide/statistics.md)

    \b
    Requirements 'with probability OP p' bound each trigger (FRET's reading) and are
    judged over the triggers of the logs, each log's triggers a cluster (--trial run:
    one trial a log): exit 1 when the Clopper-Pearson interval of the probability
    lies on the wrong side of p, never for a violated run alone. Audits of several
    logs print and write (--json "statistics") per requirement the runs of each
    verdict, the triggers per run, the estimate and its interval.

    \b
    Binding reference (expressions, functions, slices, units, NaN/inf rules,
    examples): docs/bindings.md."""
    # lazy: the audit engine (numpy, mcap, rosbags, rich) only when the command runs
    from rich.console import Console
    from fretc.audit import AuditInputError, find_logs, load_plan
    from fretc.reports.terminal import escape, print_summary
    from fretc.audit.discovery import expand_log_args
    from fretc.audit.fleet.statistics import plan_statistics
    from fretc.audit.verdict import exit_code, write_audit_json
    from fretc.common.errors import FretcError

    to_stdout_json = json_path == "-"
    out = Console(stderr=to_stdout_json, width=None if sys.stdout.isatty() else 160,
                  highlight=False, emoji=False)
    err = Console(stderr=True, highlight=False, soft_wrap=True, emoji=False)
    config = audit_config(requirements, bindings, inline, tick_period, tick_topic, time_base,
                          window, msg_path)
    try:  # (an output that is one of the inputs refused before any log is read)
        plan = load_plan(config)
        paths = find_logs(expand_log_args(logs))
        _refuse_replacing_inputs(plan, paths, json_path, junit_path, csv_dir)
    except (AuditInputError, FretcError) as exc:
        err.print(f"[red]error:[/red] {escape(str(exc))}")
        ctx.exit(2)
        return
    _mark_coverage(plan, coverage)
    for w in plan.warnings:
        err.print(f"[yellow]warning:[/yellow] {escape(w)}")
    # a requirement that does not formalize is an error verdict on every log: its
    # diagnostic (source line and caret) is printed once, with the other errors
    input_errors = any(r.error is not None for r in plan.requirements)
    results = _run(plan, paths, jobs, ctx, err, progress=not no_progress)
    stats = plan_statistics(plan, results, confidence, unknown_runs, trial)
    print_summary(out, results, plan, verbose=verbose, allow_partial=allow_partial,
                  input_errors=input_errors, statistics=stats)
    reqs = plan.requirements_json()
    extra = {**plan.sources_json(), **_coverage(plan, results, out, coverage)}
    if json_path:  # (the document only when asked: 100,000 entities' verdicts take seconds)
        _write_json(lambda write: write_audit_json(
            write, results, reqs, plan.bindings_json(), input_errors, allow_partial, extra,
            stats), json_path)
    if junit_path:
        from fretc.common.outputs import write_file
        from fretc.reports.junit import junit_xml  # lazy: only with --junit (start-up time)

        write_file(junit_path, junit_xml(results, stats, reqs))
    code = exit_code(results, input_errors, allow_partial, stats)
    if csv_dir is not None and not _write_csvs(plan, paths, results, csv_dir, err):
        code = 2
    ctx.exit(code)


def _refuse_replacing_inputs(plan, paths: list[str], json_path: str | None,
                             junit_path: str | None, csv_dir: str | None) -> None:
    """No output of the audit (``--json``, ``--junit``, each ``--write-csv`` trace as
    :func:`_write_csvs` names it) is one of its inputs (the logs, the requirement files, the
    binding files), checked before any log is read (hostile round 9, N4: ``fretc audit runs/*.csv
    --write-csv runs`` replaced each input CSV with its sampled trace).

    Raises:
        OutputError: one is (:func:`fretc.common.outputs.refuse_replacing_inputs`).
        FretishFileError: a requirement path that is no file or folder."""
    from fretc.common.outputs import refuse_replacing_inputs
    from fretc.fretish.files import requirement_files

    outputs: list = [("--json", json_path), ("--junit", junit_path)]
    if csv_dir is not None:
        from fretc.audit.sampled.csv import csv_name

        used: set[str] = set()  # (the names _write_csvs gives, in the same order)
        outputs += [("--write-csv", Path(csv_dir) / csv_name(str(p), used)) for p in paths]
    inputs = ([("the log", p) for p in paths]
              + [("the requirement file", f)
                 for f in requirement_files(list(plan.config.requirements))]
              + [("the binding file", f) for f in plan.binding_files])
    refuse_replacing_inputs(outputs, inputs)


def _write_json(document: Callable[[Callable[[str], Any]], None], json_path: str) -> None:
    """``--json PATH``: the audit document to PATH, or to standard output for ``-``, written
    piece by piece (``document(write)``: :func:`fretc.audit.verdict.write_audit_json`), so
    its memory is a verdict's, not the whole document's; a file whole or not at all."""
    if json_path == "-":
        document(sys.stdout.write)
        sys.stdout.flush()
    else:
        from fretc.common.outputs import open_output

        with open_output(json_path) as f:
            document(f.write)


def _run(plan, paths: list[str], jobs: int, ctx: click.Context, err, progress: bool) -> list:
    """The audits of ``paths`` (:func:`fretc.cli.options.run_audits`), with a progress bar on
    a terminal's stderr unless ``progress`` is False (``--no-progress``)."""
    if progress and sys.stderr.isatty():
        from fretc.reports.progress import AuditProgress

        with AuditProgress(err, len(paths)) as prog:
            return run_audits(plan, paths, jobs=jobs, progress=prog, ctx=ctx)
    return run_audits(plan, paths, jobs=jobs, ctx=ctx)


def _mark_coverage(plan, coverage: bool) -> None:
    """``--coverage``: every plan (the binding files' ``[logs]`` variants too) records each
    verdict's coverage obligations."""
    for p in [plan] + [sub for _s, _f, sub in plan.variants]:
        p.coverage = coverage


def _coverage(plan, results, out, coverage: bool) -> dict:
    """``--coverage``: the fleet's coverage printed on ``out`` and as the JSON member
    (:mod:`fretc.audit.coverage`); ``{}`` without it."""
    if not coverage:
        return {}
    from fretc.audit.coverage import coverage_text, fleet_coverage
    from fretc.reports.terminal import escape

    cov = fleet_coverage(plan, results)
    for line in coverage_text(cov).splitlines():
        out.print(escape(line))
    return {"coverage": cov}


def _write_csvs(plan, paths, results, folder: str, err) -> bool:
    """``--write-csv``: what the audit of each log judged, each requirement on its own
    clock (:mod:`fretc.audit.sampled.csv`); False when one could not be written (reported
    on ``err``)."""
    from fretc.audit.sampled.csv import csv_name, write_sampled_csv
    from fretc.common.errors import FretcError
    from fretc.logs.csv.source import not_sampled_lines
    from fretc.reports.terminal import escape

    used: set[str] = set()
    ok = True
    for path in paths:
        out = Path(folder) / csv_name(str(path), used)
        try:
            _la, clocks = write_sampled_csv(plan, str(path), out)
        except (FretcError, ValueError, OSError) as exc:
            err.print(f"[red]error:[/red] {escape(f'{path}: cannot write {out}: {exc}')}")
            ok = False
            continue
        err.print(escape(_written(out, clocks, not_sampled_lines(out))))
    return ok


def _written(out: Path, clocks: list, left_out: dict[str, str]) -> str:
    """What ``--write-csv`` wrote, in one line: per clock its requirements and ticks (a
    per-entity requirement's entities counted together), what it left out and why."""
    parts: list[str] = []
    entities: dict[str, list[int]] = {}
    for c in clocks:
        if c.entity_of is None:
            parts.append(", ".join(c.ids) + f" {len(c.times)}")
        else:
            entities.setdefault(c.entity_of, []).append(len(c.times))
    parts += [f"{rid} {len(n)} entit{'ies' if len(n) != 1 else 'y'} {sum(n)}"
              for rid, n in entities.items()]
    ticks = sum(len(c.times) for c in clocks)
    plain = [i for i in left_out if "[" not in i]
    return (f"wrote {out} ({len(clocks)} clock{'s' if len(clocks) != 1 else ''}, {ticks} ticks: "
            + "; ".join(parts) + ")"
            + (f"; not sampled: {', '.join(f'{i} ({left_out[i]})' for i in plain)}"
               if plain else ""))
