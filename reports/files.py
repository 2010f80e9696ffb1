"""The report's files (``fretc report``): reading the audit document, and writing the
report folder::

    report.html        self-contained: inline CSS and SVG, no script, no external asset
    report.md          the same content (timelines as image links to timelines/)
    audit.json         the audit document the report was made from
    timelines/*.svg    one timeline per violation (the same SVG as inlined in the HTML)
    matrix.html        the traceability matrix for auditors (:mod:`fretc.reports.matrix`)
    matrix.csv         the same rows as CSV
    coverage.html      with an audit run with --coverage: the coverage matrix
                       (:mod:`fretc.reports.coverage`)

and, on request, annotated copies of the MCAP logs (:mod:`fretc.audit.annotate`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from fretc.audit.annotate import AnnotateResult, annotate_mcap
from fretc.common.outputs import output_folder, sub_folder, write_file
from fretc.common.textsafe import no_surrogates
from fretc.reports.context import report_context
from fretc.audit.verdict import SCHEMA
from fretc.reports.render import render_html, render_markdown
from fretc.reports.check_section import check_context
from fretc.reports.matrix import matrix_csv, matrix_html, matrix_rows
from fretc.reports.trace import ReportError, resolve_input, split_source, trace_requirements

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan

__all__ = ["load_audit_json", "schema_problem", "ReportFiles", "write_report"]


def load_audit_json(path: str) -> dict:
    """Read an audit document. Raises :class:`~fretc.reports.trace.ReportError` when it
    cannot be read, is not JSON, or is not schema ``fretc-audit/1``."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise ReportError(f"{path}: cannot read: {exc}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ReportError(f"{path}: not JSON: {exc}") from None
    except RecursionError:
        raise ReportError(f"{path}: not an audit document: JSON nested too deeply") from None
    if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
        raise ReportError(f"{path}: not a fretc audit document (schema {SCHEMA!r} expected, "
                          f"got {doc.get('schema') if isinstance(doc, dict) else None!r})")
    problem = schema_problem(doc)
    if problem is not None:
        raise ReportError(f"{path}: not a valid fretc audit document: {problem}")
    return doc


def schema_problem(doc: dict) -> str | None:
    """Where ``doc`` breaks the audit document's JSON Schema (``audit.schema.json``, installed
    with :mod:`fretc.reports`; the reference page shows it), as ``$.logs[0].log: None is not
    of type 'string'`` (the first error in document order), or None. Checked with the
    ``jsonschema`` library (JSON Schema 2020-12)."""
    import jsonschema  # lazy: only where an audit document is read back

    schema = json.loads((Path(__file__).parent / "audit.schema.json").read_text("utf-8"))
    errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(doc),
                    key=lambda e: [str(p) for p in e.absolute_path])
    if not errors:
        return None
    first = _deepest(errors[0])
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return f"{first.json_path}: {_message(first)}{more}"


def _deepest(error):
    """The error that names the failing value: for a member valid under none of the
    alternatives of an ``anyOf``/``oneOf`` (an object, or null), the deepest of the errors
    of its alternatives (``jsonschema``'s ``context``), not the whole instance."""
    while error.context:
        error = max(error.context, key=lambda e: (len(e.absolute_path), -len(e.message)))
    return error


def _message(error) -> str:
    """The error in words, the failing value shortened (never the whole document)."""
    value = repr(error.instance)
    if len(value) > 80:
        value = value[:77] + "..."
    words = {"enum": f"is not one of {error.validator_value!r}",
             "type": f"is not of type {error.validator_value!r}"}.get(error.validator)
    return f"{value} {words}" if words else error.message[:200]


@dataclass
class ReportFiles:
    """What :func:`write_report` wrote: the paths, and the annotation results."""

    html: Path
    markdown: Path
    audit_json: Path
    timelines: list[Path]
    annotated: list[AnnotateResult] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _annotate_all(doc: dict, annotate_dir: Path, base: Path | None, json_dir: Path | None,
                  out_dir: Path, notes: list[str]
                  ) -> tuple[dict[int, dict], list[AnnotateResult]]:
    """Annotated copies of the document's MCAP logs in ``annotate_dir`` (names made
    unique; never over the original): (log index -> what the report says of its copy, the
    results). What cannot be copied becomes a note."""
    done: dict[int, dict] = {}
    results = []
    used: set[str] = set()
    for j, la in enumerate(doc.get("logs") or []):
        src = la.get("log")
        if not src or la.get("error"):
            continue
        p = resolve_input(src, base, json_dir)
        if p is None or p.is_dir() or p.suffix.lower() != ".mcap":
            if p is None:
                notes.append(f"--annotate: {src} not found")
            continue
        name = p.name
        k = 2
        while name in used:
            name = f"{p.stem}_{k}{p.suffix}"
            k += 1
        used.add(name)
        dst = annotate_dir / name
        if dst.exists() and dst.resolve() == p.resolve():
            notes.append(f"--annotate: {dst} is the original log; not overwritten")
            continue
        try:
            res = annotate_mcap(str(p), str(dst), la)
        except (OSError, ValueError) as exc:
            notes.append(f"--annotate: {src}: {exc}")
            continue
        results.append(res)
        done[j] = {"path": os.path.relpath(dst, out_dir).replace(os.sep, "/"),
                   "events": res.events, "partial": res.partial, "damage": res.damage,
                   "compression": res.compression}
    return done, results


def _write_files(out: Path, files: ReportFiles, ctx: dict, html: str, md: str,
                 doc: dict) -> None:
    """Replace the timelines and write every file (``OSError`` passes through)."""
    for old in sorted((out / "timelines").glob("*.svg")):
        old.unlink()
    for v in ctx["violations"]:
        p = out / v["svg_file"]
        write_file(p, v["svg"])
        files.timelines.append(p)
    write_file(files.html, html)
    write_file(files.markdown, md)
    write_file(files.audit_json, json.dumps(doc, indent=2, sort_keys=True) + "\n")
    write_file(out / "matrix.html", matrix_html(ctx["matrix_rows"]))
    write_file(out / "matrix.csv", matrix_csv(ctx["matrix_rows"]))
    if isinstance(doc.get("coverage"), dict):
        from fretc.reports.coverage import coverage_html  # lazy: only with coverage

        write_file(out / "coverage.html", coverage_html(doc))


def _current_entries(doc: dict, base: Path | None, json_dir: Path | None) -> dict | None:
    """Requirement id -> :class:`fretc.fretish.files.RequirementEntry` as the requirement sources the
    audit names read now (to flag stale evidence in the matrix); None when they cannot be
    found or read (staleness is then not shown)."""
    from fretc.common.errors import FretcError
    from fretc.fretish.files import load_requirements

    files = []
    for r in (doc.get("requirements") or []) + (doc.get("not_formalized") or []):
        f, _ = split_source(r.get("source") or "")
        if f and f not in files:
            files.append(f)
    found = [resolve_input(f, base, json_dir) for f in files]
    if not files or not all(found):
        return None
    unformalized: list = []
    try:
        entries = load_requirements([str(p) for p in found], not_formalized=unformalized)
    except (FretcError, OSError):
        return None
    return {e.id: e for e in entries + unformalized}


def write_report(doc: dict, out_dir: str, *, plan: AuditPlan | None = None,
                 base: str | None = None,
                 json_dir: str | None = None, psl_map: str | None = None,
                 annotate_dir: str | None = None, title: str | None = None,
                 generated: str | None = None, check: dict | None = None) -> ReportFiles:
    """Write the report of an audit document into ``out_dir`` (created).

    Args:
        doc: the audit document (``fretc-audit/1``).
        out_dir: the report folder: ``report.html``, ``report.md``, ``audit.json``,
            ``timelines/*.svg``.
        plan: the audit's :class:`~fretc.audit.AuditPlan` when it ran in this process.
        base, json_dir: where the document's relative paths are looked up.
        psl_map: AJPF mapping TOML (``--psl-map``).
        annotate_dir: also write annotated MCAP copies there (:mod:`fretc.audit.annotate`).
        title: report title.
        generated: the generation line (default: now, or ``SOURCE_DATE_EPOCH``).
        check: a ``fretc check -o`` document (``--check``): its findings in a section of
            their own (:mod:`fretc.reports.check_section`) and the matrix's check column.

    Raises:
        ReportError: the output cannot be written, or the psl map is bad.
    """
    out = Path(out_dir)
    basep = Path(base) if base else None
    jd = Path(json_dir) if json_dir else None
    try:
        sub_folder(output_folder(out), "timelines")  # (a link planted there: refused)
    except OSError as exc:
        raise ReportError(f"{out_dir}: cannot create: {exc}") from None
    traces, modules, notes = trace_requirements(doc, plan=plan, base=basep, json_dir=jd,
                                                psl_map=psl_map)
    annotated: dict[int, dict] = {}
    results: list[AnnotateResult] = []
    if annotate_dir:
        annotated, results = _annotate_all(doc, Path(annotate_dir), basep, jd, out, notes)
    doc = no_surrogates(doc)  # a log name that is not UTF-8: written escaped, never an error
    ctx = report_context(doc, traces, modules, notes=notes, annotated=annotated, title=title,
                         base=basep, json_dir=jd, generated=generated)
    ctx["matrix_rows"] = matrix_rows(doc, _current_entries(doc, basep, jd), check=check)
    ctx["check"] = check_context(check) if check is not None else None
    html, md = render_html(ctx), render_markdown(ctx)
    files = ReportFiles(out / "report.html", out / "report.md", out / "audit.json", [],
                        results, notes)
    try:
        _write_files(out, files, ctx, html, md, doc)
    except OSError as exc:
        raise ReportError(f"{out_dir}: cannot write: {exc}") from None
    return files
