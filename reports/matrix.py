"""The traceability matrix for auditors: requirement (its tool, tool id, version) ->
formalization -> check result -> monitor module hash -> run audited -> verdict and
robustness, one row per requirement and run (one row for a requirement no run judged or
that was not formalized), as CSV (:func:`matrix_csv`) and as an HTML page (:func:`matrix_html`,
``matrix.html`` of ``fretc report``).

Design notes: ARCHITECTURE.md, `reports/matrix.py`."""

from __future__ import annotations

import html
from dataclasses import astuple, dataclass, fields

from fretc.common.textsafe import csv_line, one_line

from fretc.reports.export_results import requirement_results
from fretc.reports.rollup import NOT_IN_AUDIT, parents_of, rollups

__all__ = ["MatrixRow", "matrix_rows", "matrix_csv", "matrix_html", "STALE", "COLUMNS", "stale_state"]

STALE = "stale evidence"


@dataclass(frozen=True)
class MatrixRow:
    """One row of the matrix (module docstring); every field text."""

    requirement: str
    tool: str
    tool_id: str
    version: str
    text: str
    formalization: str
    check: str
    monitor_hash: str
    run: str
    verdict: str
    robustness: str
    parents: str
    rolled_up: str
    stale: str


COLUMNS = tuple(f.name for f in fields(MatrixRow))


def stale_state(req: dict, current: dict | None) -> str:
    """:data:`STALE`, ``removed`` or "" for the audited requirement ``req`` (audit JSON)."""
    if current is None:
        return ""
    now = current.get(req["id"])
    if now is None:
        return "removed"
    origin = req.get("origin") or {}
    then_version = origin.get("version")
    now_version = now.origin.version if now.origin is not None else None
    if then_version != now_version or (req.get("text") or "").strip() != now.text.strip():
        return STALE
    return ""


def _check_cells(check: dict | None) -> dict[str, str]:
    """Requirement id -> its ``fretc check`` result in one cell."""
    if check is None:
        return {}
    from fretc.reports.check_section import check_context

    return {r["id"]: "; ".join([f"satisfiable {r['satisfiable']}",
                                f"non-vacuous {r['non_vacuous']}",
                                f"redundant {r['redundant']}"]
                               + [f"{f['kind']}: {f['message']}"
                                  + (f" (witness {f['witness']})" if f["witness"] else "")
                                  for f in r["findings"]])
            for r in check_context(check)["rows"]}


def _requirement_cells(req: dict, checks: dict, current) -> list[str]:
    origin = req.get("origin") or {}
    form = req.get("key") or ""
    if req.get("ft"):
        form = f"{form}: ft {req['ft']}" if form else f"ft {req['ft']}"
    return [req["id"], origin.get("format") or "fret-text", origin.get("tool_id") or req["id"],
            origin.get("version") or "", one_line(req.get("text") or ""),
            one_line(form or (req.get("error") or "").split("\n")[0]),
            checks.get(req["id"], "not checked"), req.get("source_hash") or "",
            ]


def matrix_rows(doc: dict, current: dict | None = None,
                check: dict | None = None) -> list[MatrixRow]:
    """The rows of the audit document ``doc`` (``fretc audit --json``), in its requirement
    and run order, then its ``not_formalized`` items. ``current``: requirement id ->
    :class:`fretc.fretish.files.RequirementEntry` as the sources hold it now (None: staleness not
    checked); ``check``: a ``fretc check -o`` document (None: "not checked")."""
    checks = _check_cells(check)
    parents = parents_of(doc)
    rolled = rollups(doc, {k: r.verdict for k, r in requirement_results(doc, "", "").items()})

    def tree(rid: str) -> list[str]:
        return ["; ".join(parents.get(rid, ())), rolled[rid].text() if rid in rolled else ""]
    per: dict[str, list[tuple[str, dict]]] = {}
    for la in doc.get("logs") or []:
        for v in la.get("verdicts") or []:
            per.setdefault(v.get("requirement"), []).append((la.get("log") or "", v))
    rows = []
    for req in doc.get("requirements") or []:
        head = _requirement_cells(req, checks, current)
        stale = stale_state(req, current)
        runs = per.get(req["id"]) or [("", {"verdict": "not judged"})]
        for log, v in runs:
            rob = (v.get("robustness") or {}).get("value")
            rows.append(MatrixRow(*head, log, v.get("verdict") or "",  # type: ignore[call-arg]  # (head: the first cells)
                                  "" if rob is None else str(rob), *tree(req["id"]), stale))
    for item in doc.get("not_formalized") or []:
        origin = item.get("origin") or {}
        rows.append(MatrixRow(item["id"], origin.get("format") or "", origin.get("tool_id")  # type: ignore[call-arg]  # (tree: the last cells)
                              or item["id"], origin.get("version") or "", "",
                              "not formalized (no FRETish text)", "not checked", "", "",
                              "not formalized", "", *tree(item["id"]), ""))
    for rid, ru in rolled.items():
        if ru.own == NOT_IN_AUDIT:
            rows.append(MatrixRow(rid, "", rid, "", "", "", "not checked", "", "", NOT_IN_AUDIT,
                                  "", "", ru.text(), ""))
    return rows


def _csv_cell(text: str) -> str:
    """A cell a spreadsheet shows as text: a leading ``= + - @`` (a formula to Excel)
    quoted by a leading apostrophe, unless the cell is a number."""
    if text[:1] in ("=", "+", "-", "@"):
        try:
            float(text)
        except ValueError:
            return "'" + text
    return text


def matrix_csv(rows: list[MatrixRow]) -> str:
    """The rows as CSV (RFC 4180, ``\\n`` line ends), with a header of :data:`COLUMNS`; a
    cell with a comma, a quote, a line feed or a carriage return quoted
    (:func:`fretc.common.textsafe.csv_line`: Python's ``csv`` writer leaves a lone carriage
    return unquoted, and a reader ends the row there)."""
    lines = [csv_line(list(COLUMNS))]
    lines += [csv_line([_csv_cell(c) for c in astuple(r)]) for r in rows]
    return "\n".join(lines) + "\n"


#: Sort orders of the HTML page: (anchor, column, key of a row)
_SORTS = (("by-requirement", "requirement", lambda r: ()),
          ("by-tool-id", "tool_id", lambda r: (r.tool_id,)),
          ("by-verdict", "verdict", lambda r: (_VERDICT_RANK.get(r.verdict, 9),)),
          ("by-robustness", "robustness", lambda r: (_number(r.robustness),)),
          ("by-stale", "stale", lambda r: (r.stale != STALE, r.stale)))
_VERDICT_RANK: dict[str, int] = {"error": 0, "violated": 1, "unknown": 2, "not formalized": 3,
                 "not judged": 4, NOT_IN_AUDIT: 4, "vacuous": 5, "satisfied": 6}


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return float("inf")


#: The matrix page's columns: one row per requirement and run (the verdict near the left,
#: so a 1,400 px window shows it without scrolling), then one row per requirement with what
#: repeats on each of its runs (its text, formalization, check result and monitor hash)
_RUN_COLUMNS = ("requirement", "run", "verdict", "robustness", "stale", "rolled_up",
                "tool_id", "parents")
_REQUIREMENT_COLUMNS = ("requirement", "tool", "tool_id", "version", "text",
                        "formalization", "check", "monitor_hash")
_CSS = ("body{font-family:sans-serif;margin:1.5em;max-width:1350px}table{border-collapse:"
        "collapse;font-size:90%}td,th{border:1px solid #bbb;padding:3px 6px;"
        "vertical-align:top;overflow-wrap:anywhere}th{background:#eee;text-align:left}"
        ".v-violated,.v-error{background:#fdd}.v-satisfied{background:#dfd}"
        ".stale{font-weight:bold;color:#a00}td.hash{font-family:monospace;font-size:85%}"
        "section.order{display:none}section.order:target{display:block}"
        "section.order:last-of-type{display:block}"
        "section.order:target~section.order:last-of-type{display:none}")


def _anchor(requirement: str) -> str:
    """The id of a requirement's row in the page's requirement table."""
    return "req-" + "".join(c if c.isalnum() or c in "-_." else "_" for c in requirement)


def _run_table(rows: list[MatrixRow], links: dict[str, str]) -> list[str]:
    """The table of requirement x run rows (the order as given)."""
    e = html.escape
    out = ["<table><tr>"]
    for c in _RUN_COLUMNS:
        label = e(c.replace("_", " "))
        out.append(f'<th><a href="#{links[c]}">{label}</a></th>' if c in links
                   else f"<th>{label}</th>")
    out.append("</tr>")
    for r in rows:
        cells = []
        for name in _RUN_COLUMNS:
            c = getattr(r, name)
            if name == "requirement":
                cells.append(f'<td><a href="#{e(_anchor(c))}">{e(c)}</a></td>')
            elif name == "verdict":
                cells.append(f'<td class="verdict">{e(c)}</td>')
            elif name == "stale" and c == STALE:
                cells.append(f'<td class="stale">{e(c)}</td>')
            else:
                cells.append(f"<td>{e(c)}</td>")
        out.append(f'<tr class="v-{e(r.verdict.replace(" ", "-"))}">' + "".join(cells)
                   + "</tr>")
    out.append("</table>")
    return out


def _requirement_table(rows: list[MatrixRow]) -> list[str]:
    """Each requirement once, with the cells its run rows share."""
    e = html.escape
    out = ['<h2 id="requirements">Requirements</h2><table><tr>'
           + "".join(f"<th>{e(c.replace('_', ' '))}</th>" for c in _REQUIREMENT_COLUMNS)
           + "</tr>"]
    seen: set[str] = set()
    for r in rows:
        if r.requirement in seen:
            continue
        seen.add(r.requirement)
        cells = [f'<td class="{"hash" if name == "monitor_hash" else name}">'
                 f"{e(getattr(r, name))}</td>" for name in _REQUIREMENT_COLUMNS]
        out.append(f'<tr id="{e(_anchor(r.requirement))}">' + "".join(cells) + "</tr>")
    out.append("</table>")
    return out


def matrix_html(rows: list[MatrixRow], title: str = "Traceability matrix") -> str:
    """A self-contained page of the matrix (inline CSS, no script): the requirement x run
    rows with their verdicts, sortable by the header links (module docstring; the first
    order, requirement, shows by default), then each requirement once with its text,
    formalization, check result and monitor hash (the CSV repeats them on every row)."""
    e = html.escape
    links = {col: anchor for anchor, col, _k in _SORTS}
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>{e(title)}</title><style>", _CSS,
             "</style></head><body>", f"<h1>{e(title)}</h1>",
             f"<p>{len(rows)} rows; sort by a linked column header; each requirement's text, "
             'formalization, check result and monitor hash are in <a href="#requirements">'
             "the requirement table</a> below.</p>"]
    orders = list(_SORTS[1:]) + [_SORTS[0]]  # the default order last (CSS above)
    for anchor, _col, key in orders:
        ordered = [r for _i, r in sorted(enumerate(rows), key=lambda ir: (key(ir[1]), ir[0]))]
        parts.append(f'<section class="order" id="{anchor}">')
        parts += _run_table(ordered, links)
        parts.append("</section>")
    parts += _requirement_table(rows)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
