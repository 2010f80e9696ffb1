"""``fretc export``: an audit's results written back into the requirements' own format, as a
sphinx-needs ``needs.json`` and a StrictDoc document, and the traceability matrix (click
command; the writers are :mod:`fretc.reports.export_reqif`, :mod:`fretc.reports.export_doorstop`,
:mod:`fretc.reports.export_fret`, :mod:`fretc.reports.export_needs`,
:mod:`fretc.reports.export_sdoc`, :mod:`fretc.reports.matrix`).

Design notes: ARCHITECTURE.md, `fretc/cli/export.py`."""

from __future__ import annotations

import datetime as _dt
import os

import click

from fretc.cli.options import TEXT_ATTRIBUTE_OPTION, shown, text_attribute

__all__ = ["export_cmd"]


def _kind(src: str) -> str:
    """``reqif``, ``doorstop`` or ``fret`` for the source ``src`` (a UsageError otherwise)."""
    from fretc.fretish.files import is_fret_export
    from fretc.fretish.sources import tool_source_kind

    kind = tool_source_kind(src)
    if kind is not None:
        return kind
    if os.path.isfile(src) and src.lower().endswith(".json") and is_fret_export(src):
        return "fret"
    raise click.UsageError(f"{src}: fretc export writes into a ReqIF file (.reqif, .reqifz), "
                           "a Doorstop tree or a FRET export (.json)")


def _audit_date(value: str | None) -> str | None:
    """``--audit-date`` as an ISO 8601 date-time in UTC (a date alone: its midnight)."""
    if value is None:
        return None
    try:
        when = _dt.datetime.fromisoformat(value.replace("Z", "+00:00"))
    except ValueError:
        raise click.BadParameter(f"{value!r} is not an ISO 8601 date or date-time",
                                 param_hint="--audit-date") from None
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.UTC)
    return when.astimezone(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


@click.command("export")
@click.option("-r", "--requirements", "src", default=None, type=click.Path(exists=True),
              help="The requirements the audit read, as they are now: a .reqif/.reqifz file, "
                   "a Doorstop tree or a FRET export (.json) to write the results into "
                   "(-o); any requirement source to flag stale evidence.")
@click.option("--from-json", "from_json", required=True,
              type=click.Path(exists=True, dir_okay=False),
              help="The audit document (fretc audit --json FILE).")
@click.option("-o", "--output", default=None, type=click.Path(),
              help="Where to write the requirements (-r) with the results: a file of the "
                   "same format, or for a Doorstop tree a new (or empty) folder.")
@click.option("--needs", "needs_path", type=click.Path(dir_okay=False), default=None,
              help="Also write the results as a sphinx-needs needs.json to FILE: a need per "
                   "requirement with its verdicts, parents rolled up.")
@click.option("--sdoc", "sdoc_path", type=click.Path(dir_okay=False), default=None,
              help="Also write the results as a StrictDoc document (.sdoc) to FILE: test "
                   "results linked to the requirements by Parent relations.")
@click.option("--audit-date", default=None, metavar="DATE",
              help="The audit's date (ISO 8601) written with the results. Default: the "
                   "modification time of the --from-json file.")
@click.option("--matrix", "matrix_csv", type=click.Path(dir_okay=False), default=None,
              help="Also write the traceability matrix as CSV to FILE.")
@click.option("--matrix-html", type=click.Path(dir_okay=False), default=None,
              help="Also write the traceability matrix as an HTML page to FILE.")
@click.option("--check", "check_json", type=click.Path(exists=True, dir_okay=False),
              default=None, help="fretc check -o FILE: its results in the matrix.")
@TEXT_ATTRIBUTE_OPTION
@click.pass_context
def export_cmd(ctx: click.Context, src: str | None, from_json: str, output: str | None,
               needs_path: str | None, sdoc_path: str | None, audit_date: str | None,
               matrix_csv: str | None, matrix_html: str | None, check_json: str | None) -> None:
    """Write an audit's verdicts back into the requirements' format (ReqIF attributes,
    Doorstop custom attributes, a member of each FRET requirement), keeping everything that
    was there; as a sphinx-needs needs.json (--needs) and a StrictDoc document (--sdoc); and
    the traceability matrix (--matrix, --matrix-html). A parent requirement gets its
    children's verdicts rolled up. Requirements changed since the audit are flagged
    "stale evidence" (with -r)."""
    # lazy: the readers and writers only when the command runs
    from fretc.reports.export_results import audit_identity, requirement_results, write_atomic
    from fretc.reports.write import ReportError, load_audit_json
    from fretc.common.textsafe import no_surrogates

    if output is not None and src is None:
        raise click.UsageError("-o writes the results into the requirements' file: give it "
                               "with -r")
    if not any((output, needs_path, sdoc_path, matrix_csv, matrix_html)):
        raise click.UsageError("nothing to write: give -o (with -r), --needs, --sdoc, "
                               "--matrix or --matrix-html")
    from fretc.common.outputs import refuse_replacing_inputs

    # (hostile round 9, R1: no output replaces an input; -r's a file, or a Doorstop tree read whole)
    refuse_replacing_inputs([("-o", output), ("--needs", needs_path), ("--sdoc", sdoc_path),
                             ("--matrix", matrix_csv), ("--matrix-html", matrix_html)],
                            [("the requirements (-r)", src), ("--from-json", from_json),
                             ("--check", check_json)])
    kind = _kind(src) if output is not None and src is not None else None  # (src: refused above)
    try:
        doc = no_surrogates(load_audit_json(from_json))  # a log name that is not UTF-8
    except ReportError as exc:
        click.echo(shown(f"error: {exc}"), err=True)
        ctx.exit(2)
        return
    with open(from_json, "rb") as f:
        audit_id, date = audit_identity(from_json, f.read(), _audit_date(audit_date))
    results = requirement_results(doc, audit_id, date)
    current = None
    if src is not None:
        from fretc.fretish.files import load_requirements

        unformalized: list = []
        entries = load_requirements(src, text_attribute=text_attribute(),
                                    not_formalized=unformalized)
        current = {e.id: e for e in entries + unformalized}
        if not set(results) & set(current):
            click.echo(shown(f"error: {from_json} judged none of the requirements of {src}"),
                       err=True)
            ctx.exit(2)
            return
    outputs = _matrix_outputs(doc, current, check_json, matrix_csv, matrix_html)
    outputs += _tool_outputs(doc, results, needs_path, sdoc_path)
    written = (_write_export(kind, src, output, results, current)
               if kind and src is not None and output is not None else None)  # (kind: both)
    for path, data in outputs:
        write_atomic(path, data)
    _report(doc, current, written, output, [p for p, _d in outputs])


def _tool_outputs(doc, results, needs_path, sdoc_path) -> list[tuple[str, bytes]]:
    """The needs.json and .sdoc files to write: (path, bytes)."""
    out = []
    if needs_path:
        from fretc.reports.export_needs import needs_json

        out.append((needs_path, needs_json(doc, results).encode("utf-8")))
    if sdoc_path:
        from fretc.reports.export_sdoc import sdoc_text

        notes: list[str] = []
        out.append((sdoc_path, sdoc_text(doc, results, notes=notes).encode("utf-8")))
        for note in notes:
            click.echo(shown(f"note: {sdoc_path}: {note}"), err=True)
    return out


def _matrix_outputs(doc, current, check_json, csv_path, html_path) -> list[tuple[str, bytes]]:
    """The matrix files to write: (path, bytes)."""
    if not csv_path and not html_path:
        return []
    from fretc.reports.matrix import matrix_csv, matrix_html, matrix_rows

    check = None
    if check_json:
        from fretc.check.report import load_check  # lazy: only with --check
        try:
            check = load_check(check_json)
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint="--check") from None
    rows = matrix_rows(doc, current, check)
    out = []
    if csv_path:
        out.append((csv_path, matrix_csv(rows).encode("utf-8")))
    if html_path:
        out.append((html_path, matrix_html(rows).encode("utf-8")))
    return out


def _write_export(kind: str, src: str, output: str, results, current) -> int:
    """Write the export of ``kind``; returns how many requirements got results."""
    from fretc.reports.export_results import write_atomic

    if kind == "doorstop":
        from fretc.reports.export_doorstop import export_doorstop

        files = {e.id: e.origin.file for e in current.values()
                 if e.origin is not None and e.origin.format == "doorstop"}
        try:
            return export_doorstop(src, output, results, files)
        except (FileExistsError, ValueError) as exc:
            raise click.UsageError(str(exc)) from None
    if os.path.isdir(output):
        raise click.UsageError(f"{output} is a folder: give the file to write")
    if kind == "reqif":
        from fretc.reports.export_reqif import export_reqif
        data, n = export_reqif(src, results)
    else:
        from fretc.reports.export_fret import export_fret
        data, n = export_fret(src, results)
    write_atomic(output, data)
    return n


def _report(doc, current, written: int | None, output: str | None,
            others: list[str]) -> None:
    """The command's lines on stderr: what was written, and the stale requirements (when
    the sources were read: ``current``)."""
    from fretc.reports.matrix import STALE, stale_state

    audited = (doc.get("requirements") or []) if current is not None else []
    for req in audited:
        state = stale_state(req, current)
        if state:
            click.echo(shown(f"warning: {req['id']}: {state} (changed since the audit)"
                             if state == STALE else
                             f"warning: {req['id']}: removed from the sources since the "
                             "audit"), err=True)
    if output is not None:
        click.echo(shown(f"wrote {output}: results on {written} requirements"), err=True)
    for m in others:
        click.echo(shown(f"wrote {m}"), err=True)
