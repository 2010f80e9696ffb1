"""Traceability reports (``fretc report``): requirement -> formulas -> monitor -> verdict, with
the evidence of every recorded run, as one self-contained HTML page and the same content in
Markdown.

Input is the audit's JSON document (schema ``fretc-audit/1``, :mod:`fretc.audit.verdict`),
run by ``fretc report`` or read with ``--from-json``; what it does not carry comes from
compiling the requirement files it names (:func:`fretc.audit.load_plan`). Output folder:
``report.html`` (self-contained: no script, no external asset), ``report.md``,
``audit.json``, ``timelines/*.svg``. Deterministic: byte-identical files but the one
generation-time line (``SOURCE_DATE_EPOCH`` fixes it). This module re-exports the library's
names (:mod:`fretc.reports.trace`, :mod:`fretc.reports.verdicts`,
:mod:`fretc.reports.context`, :mod:`fretc.reports.render`, :mod:`fretc.reports.files`); the
command lines, the folder and what the report holds in full: ARCHITECTURE.md
("Traceability reports").
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
