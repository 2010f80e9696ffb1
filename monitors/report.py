"""Traceability reports (``fretc report``): requirement -> formulas -> monitor -> verdict, with
the evidence of every recorded run, as one self-contained HTML page and the same content in
Markdown.

::

    fretc report -r requirements/ traces/ -o report/ [--annotate annotated/]   # runs the audit
    fretc report --from-json audit.json -o report/ [--annotate annotated/]     # reads one

Input is the audit's JSON document (schema ``fretc-audit/1``, :mod:`monitors.report_model`);
what it does not carry (parent, rationale, the FRETish field spans, ft / ft_inf / pt, the
generated monitor module, the AJPF property) comes from compiling the requirement files the
audit names (``requirements[].source``), exactly as ``fretc audit`` does
(:func:`monitors.audit.load_plan`). With ``--from-json`` those files are looked up relative
to ``--base`` (default: the current folder, then the JSON's folder); a requirement whose text
differs from the audited one is flagged, and one whose file is gone is shown from the JSON
alone.

Output folder::

    report.html        self-contained: inline CSS and SVG, no script, no external asset
    report.md          the same content (timelines as image links to timelines/)
    audit.json         the audit document the report was made from
    timelines/*.svg    one timeline per violation (the same SVG as inlined in the HTML)

The report holds: the summary and inputs (files with SHA-256); the matrix requirements x runs
(verdict of each cell, linking to its evidence); per requirement its id, parent, rationale,
FRETish text with the fields (scope, condition, component, timing, response) marked from the
AST spans, FRET template key, ft / ft_inf / pt, the monitor class and module with their
hashes, the AJPF property label and formula (or why there is none), and per run the verdict
and witness; per violation a timeline (:mod:`monitors.timeline`) and the sampled values;
coverage (requirements never triggered, runs missing a bound topic, damaged runs); the runs;
the generated monitor modules.

Deterministic: the same inputs give byte-identical files except the one line stating the
generation time (UTC; ``SOURCE_DATE_EPOCH`` fixes it).

The library, one job per module (this module re-exports its names):
:mod:`monitors.report_trace` (the requirements traced by compiling their files),
:mod:`monitors.report_verdicts` (a verdict as a cell, witness and values table),
:mod:`monitors.report_context` (the data record the templates are fed),
:mod:`monitors.report_render` (Jinja2), :mod:`monitors.report_files` (reading the audit
document, writing the folder).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from .cli import audit_config, audit_input_options
from .fleet_cli import ray_options
from .report_context import GENERATED_PREFIX, report_context
from .report_files import ReportFiles, load_audit_json, write_report
from .report_render import render_html, render_markdown
from .report_trace import (FIELD_NAMES, ModuleInfo, ReportError, RequirementTrace,
                           marked_fields, trace_requirements)

__all__ = ["ReportError", "RequirementTrace", "ModuleInfo", "ReportFiles", "load_audit_json",
           "trace_requirements", "report_context", "render_html", "render_markdown",
           "write_report", "report_cmd", "marked_fields", "FIELD_NAMES",
           "GENERATED_PREFIX"]


# --------------------------------------------------------------------------- the command
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
def report_cmd(ctx, logs, requirements, bindings, inline, tick_period, tick_topic, time_base,
               jobs, engine, window, from_json, base, output, annotate_dir, psl_map, title,
               check_json=None):
    """Write the traceability report (HTML + Markdown) of an audit: requirements x runs,
    formulas, monitors, AJPF properties, verdicts, witnesses and violation timelines.

    Either LOGS (the audit runs here, as fretc audit) or --from-json FILE. Exit status as
    fretc audit: 0 every verdict satisfied or vacuous, 1 a violation, 2 input errors or a
    requirement that could not be audited (the report is still written)."""
    err = click.get_text_stream("stderr")
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
    else:
        from .audit import AuditInputError, find_logs, load_plan
        from .fleet import expand_log_args, run_audits
        from .report_model import audit_json

        json_dir = None
        config = audit_config(requirements, bindings, inline, tick_period, tick_topic,
                              time_base, engine, window)
        try:
            plan = load_plan(config)
            paths = find_logs(expand_log_args(logs))
        except AuditInputError as exc:
            click.echo(f"error: {exc}", err=True)
            ctx.exit(2)
            return
        input_errors = any(r.error is not None for r in plan.requirements)
        results = run_audits(plan, paths, jobs=jobs, ctx=ctx)
        doc = json.loads(audit_json(results, plan.requirements_json(), plan.bindings_json(),
                                    input_errors))
    try:
        files = write_report(doc, output, plan=plan, base=base, json_dir=json_dir,
                             psl_map=psl_map, annotate_dir=annotate_dir, title=title)
    except ReportError as exc:
        click.echo(f"error: {exc}", err=True)
        ctx.exit(2)
        return
    if check_json:  # fretc check findings beside the requirements (compiler/check_report.py)
        from compiler.check_report import add_to_report, load_check
        add_to_report(str(files.markdown), str(files.html), load_check(check_json))
    for n in files.notes:
        click.echo(f"note: {n}", file=err)
    s = doc.get("summary") or {}
    click.echo(f"fretc report: {len(doc.get('requirements') or [])} requirements x "
               f"{len(doc.get('logs') or [])} runs: {s.get('satisfied', 0)} satisfied, "
               f"{s.get('vacuous', 0)} vacuous, {s.get('violated', 0)} violated, "
               f"{s.get('error', 0)} error", file=err)
    click.echo(f"wrote {files.html}", file=err)
    click.echo(f"wrote {files.markdown}", file=err)
    click.echo(f"wrote {files.audit_json} and {len(files.timelines)} timelines", file=err)
    for r in files.annotated:
        extra = f" (partial: {r.damage})" if r.partial else ""
        click.echo(f"wrote {r.output}: {r.messages} messages + {r.events} verdict events on "
                   f"/fretc/verdicts{extra}", file=err)
    ctx.exit(int(s.get("exit_code", 0) or 0))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(report_cmd())
