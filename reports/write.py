"""Traceability reports (``fretc report``): requirement -> formulas -> monitor -> verdict, with
the evidence of every recorded run, as one self-contained HTML page and the same content in
Markdown.

::

    fretc report -r requirements/ traces/ -o report/ [--annotate annotated/]   # runs the audit
    fretc report --from-json audit.json -o report/ [--annotate annotated/]     # reads one

Input is the audit's JSON document (schema ``fretc-audit/1``, :mod:`fretc.audit.verdict`);
what it does not carry (parent, rationale, the FRETish field spans, ft / ft_inf / pt, the
generated monitor module, the AJPF property) comes from compiling the requirement files the
audit names (``requirements[].source``), exactly as ``fretc audit`` does
(:func:`fretc.audit.load_plan`). With ``--from-json`` those files are looked up relative
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
and witness; per violation a timeline (:mod:`fretc.reports.timeline`) and the sampled values;
coverage (requirements never triggered, runs missing a bound topic, damaged runs); the runs;
the generated monitor modules.

Deterministic: the same inputs give byte-identical files except the one line stating the
generation time (UTC; ``SOURCE_DATE_EPOCH`` fixes it).

The command is :mod:`fretc.cli.report`; the library, one job per module (this module
re-exports their names):
:mod:`fretc.reports.trace` (the requirements traced by compiling their files),
:mod:`fretc.reports.verdicts` (a verdict as a cell, witness and values table),
:mod:`fretc.reports.context` (the data record the templates are fed),
:mod:`fretc.reports.render` (Jinja2), :mod:`fretc.reports.files` (reading the audit
document, writing the folder).
"""

from __future__ import annotations

from fretc.reports.context import GENERATED_PREFIX, report_context
from fretc.reports.files import ReportFiles, load_audit_json, write_report
from fretc.reports.render import render_html, render_markdown
from fretc.reports.trace import (FIELD_NAMES, ModuleInfo, ReportError, RequirementTrace, marked_fields,
    trace_requirements)

__all__ = ["ReportError", "RequirementTrace", "ModuleInfo", "ReportFiles", "load_audit_json",
           "trace_requirements", "report_context", "render_html", "render_markdown",
           "write_report", "marked_fields", "FIELD_NAMES", "GENERATED_PREFIX"]
