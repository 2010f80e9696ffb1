"""``fretc report``: the traceability report (HTML + Markdown) of an audit, run here on LOGS
or read from ``--from-json FILE`` (the report itself: :mod:`fretc.reports`).

::

    fretc report -r requirements/ traces/ -o report/ [--annotate annotated/]   # runs the audit
    fretc report --from-json audit.json -o report/ [--annotate annotated/]     # reads one
"""

from __future__ import annotations

import json
from pathlib import Path

import click

from fretc.reports.write import ReportError, load_audit_json, write_report

from fretc.cli.options import audit_config, audit_input_options, ray_options, run_audits

__all__ = ["report_cmd"]


@click.command("report")
@click.argument("logs", nargs=-1)
@audit_input_options
@click.option("--from-json", "from_json", type=click.Path(exists=True, dir_okay=False),
              default=None, help="Report an audit document (fretc audit --json) instead of "
                                 "running the audit.")
@click.option("--base", type=click.Path(file_okay=False), default=None,
              help="--from-json: folder the document's relative paths start from (default: "
                   "the current folder, then the document's folder).")
@click.option("-o", "--output", required=True, type=click.Path(file_okay=False),
              help="Report folder (report.html, report.md, audit.json, timelines/).")
@click.option("--annotate", "annotate_dir", type=click.Path(file_okay=False), default=None,
              help="Also write a copy of each MCAP log here with a foxglove.Log channel "
                   "/fretc/verdicts of the verdict events.")
@click.option("--psl-map", type=click.Path(exists=True), default=None,
              help="TOML mapping of variables to AJPF beliefs (as fretc --emit psl).")
@click.option("--title", default=None, help="Report title.")
@click.option("--check", "check_json", type=click.Path(exists=True, dir_okay=False),
              default=None, help="Show the findings of fretc check -o FILE beside the "
                                 "requirements.")
@ray_options
@click.pass_context
def report_cmd(ctx: click.Context, logs: tuple[str, ...], requirements: tuple[str, ...],
               bindings: tuple[str, ...], inline: tuple[str, ...], tick_period: str | None,
               tick_topic: str | None, time_base: str | None, jobs: int, window: int,
               from_json: str | None, base: str | None, output: str, annotate_dir: str | None,
               psl_map: str | None, title: str | None, check_json: str | None = None,
               msg_path: tuple[str, ...] = ()) -> None:
    """Write the traceability report (HTML + Markdown) of an audit: requirements x runs,
    formulas, monitors, AJPF properties, verdicts, witnesses and violation timelines.

    Either LOGS (the audit runs here, as fretc audit) or --from-json FILE. Exit status as
    fretc audit: 0 every verdict satisfied or vacuous, 1 a violation, 2 input errors or a
    requirement that could not be audited (the report is still written)."""
    plan = None
    if from_json and logs:
        raise click.UsageError("give LOGS or --from-json, not both")
    if not from_json and not logs:
        raise click.UsageError("give the LOGS to audit, or --from-json FILE")
    if from_json:
        try:
            doc = load_audit_json(from_json)
        except ReportError as exc:
            click.echo(f"error: {exc}", err=True)
            ctx.exit(2)
            return
        json_dir = str(Path(from_json).resolve().parent)
        _refuse_replacing_inputs(output, [("--from-json", from_json)], check_json, psl_map)
    else:
        # lazy: the audit engine only when the logs are audited here
        from fretc.audit import AuditInputError, find_logs, load_plan
        from fretc.audit.discovery import expand_log_args
        from fretc.audit.fleet.statistics import plan_statistics
        from fretc.audit.verdict import audit_json

        json_dir = None
        config = audit_config(requirements, bindings, inline, tick_period, tick_topic,
                              time_base, window, msg_path)
        try:
            plan = load_plan(config)
            paths = find_logs(expand_log_args(logs))
        except AuditInputError as exc:
            click.echo(f"error: {exc}", err=True)
            ctx.exit(2)
            return
        from fretc.fretish.files import requirement_files

        _refuse_replacing_inputs(
            output, [("the log", p) for p in paths]
            + [("the requirement file", f) for f in requirement_files(list(requirements))]
            + [("the binding file", f) for f in plan.binding_files], check_json, psl_map)
        input_errors = any(r.error is not None for r in plan.requirements)
        results = run_audits(plan, paths, jobs=jobs, ctx=ctx)
        doc = json.loads(audit_json(results, plan.requirements_json(), plan.bindings_json(),
                                    input_errors, extra=plan.sources_json(),
                                    statistics=plan_statistics(plan, results)))
    check = _check_document(check_json, ctx) if check_json else None
    try:
        files = write_report(doc, output, plan=plan, base=base, json_dir=json_dir,
                             psl_map=psl_map, annotate_dir=annotate_dir, title=title,
                             check=check)
    except ReportError as exc:
        click.echo(f"error: {exc}", err=True)
        ctx.exit(2)
        return
    for n in files.notes:
        click.echo(f"note: {n}", err=True)
    s = doc.get("summary") or {}
    click.echo(f"fretc report: {len(doc.get('requirements') or [])} requirements x "
               f"{len(doc.get('logs') or [])} runs: {s.get('satisfied', 0)} satisfied, "
               f"{s.get('vacuous', 0)} vacuous, {s.get('violated', 0)} violated, "
               f"{s.get('error', 0)} error", err=True)
    click.echo(f"wrote {files.html}", err=True)
    click.echo(f"wrote {files.markdown}", err=True)
    click.echo(f"wrote {files.audit_json} and {len(files.timelines)} timelines", err=True)
    for r in files.annotated:
        extra = f" (partial: {r.damage})" if r.partial else ""
        click.echo(f"wrote {r.output}: {r.messages} messages + {r.events} verdict events on "
                   f"/fretc/verdicts{extra}", err=True)
    ctx.exit(int(s.get("exit_code", 0) or 0))


def _check_document(path: str, ctx: click.Context) -> dict | None:
    """The ``fretc check -o`` document of ``--check``; exit 2 naming the file when it is not
    one (its findings go into the report's "Check findings" section)."""
    from fretc.check.report import load_check  # lazy: only with --check

    try:
        return load_check(path)
    except (ValueError, OSError) as exc:  # (json.JSONDecodeError is a ValueError)
        click.echo(f"error: --check {path}: {exc}", err=True)
        ctx.exit(2)
        return None


#: The files ``fretc report -o DIR`` writes in DIR (:func:`fretc.reports.files.write_report`;
#: its timelines go into DIR/timelines, a folder of its own)
REPORT_FILES = ("report.html", "report.md", "audit.json", "matrix.html", "coverage.html")


def _refuse_replacing_inputs(output: str, inputs: list, check_json: str | None,
                             psl_map: str | None) -> None:
    """No file the report writes in ``output`` (:data:`REPORT_FILES`) is one of its
    ``inputs`` (``(what, path)``), ``--check`` or ``--psl-map`` (hostile round 9, R1: ``fretc report
    --from-json out/audit.json -o out`` replaced its own input); checked before the audit
    runs. (``--annotate`` never writes over the original log: a note says so.)

    Raises:
        OutputError: one is (:func:`fretc.common.outputs.refuse_replacing_inputs`)."""
    from fretc.common.outputs import refuse_replacing_inputs

    refuse_replacing_inputs([("-o", Path(output) / n) for n in REPORT_FILES],
                            inputs + [("--check", check_json), ("--psl-map", psl_map)])
