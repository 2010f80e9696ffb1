"""The findings of ``fretc check`` beside the requirements in ``fretc report``:
``fretc report ... --check check.json`` (the document of ``fretc check -o``) adds a
"Check findings" section to report.md and report.html, one row per requirement with its
satisfiability, non-vacuity, redundancy and the findings naming it."""

from __future__ import annotations

import html
import json
from pathlib import Path

from fretc.common.outputs import write_file

__all__ = ["load_check", "findings_rows", "add_to_report"]


def load_check(path: str) -> dict:
    """Read a ``fretc check -o`` JSON document; ``ValueError`` when it is not one."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    if not isinstance(doc, dict) or doc.get("tool") != "fretc check":
        raise ValueError(f"{path}: not a fretc check result (fretc check -o FILE)")
    return doc


def _yn(v) -> str:
    return {True: "yes", False: "no", None: "-"}.get(v, str(v)) if not isinstance(v, str) else v


def findings_rows(doc: dict) -> list[dict]:
    """One row per requirement: ``id``, ``source``, ``satisfiable``, ``non_vacuous``,
    ``redundant``, ``findings`` (texts ``KIND: message``); a project checked per FRET
    component (``"fret_components"``, :func:`fretc.check.fret_components.project_json`):
    the rows of each component's check, in the components' order."""
    if "fret_components" in doc:
        return [row for c in doc["fret_components"] for row in findings_rows(c["check"])]
    rows = []
    for r in doc.get("requirements", []):
        texts = [f"{doc['findings'][k]['kind']}: {doc['findings'][k]['message']}"
                 + (f" (witness {doc['findings'][k]['witness']})"
                    if doc['findings'][k].get("witness") else "")
                 for k in r.get("findings", [])]
        rows.append({"id": r["id"], "source": f"{r['source']}:{r['line']}",
                     "satisfiable": _yn(r["satisfiable"]),
                     "non_vacuous": _yn(r["non_vacuous"]), "redundant": _yn(r["redundant"]),
                     "findings": texts})
    return rows


def add_to_report(markdown_path: str, html_path: str, doc: dict) -> None:
    """Append the section to the written report files (Markdown table; HTML section before
    ``</body>``, text escaped)."""
    rows = findings_rows(doc)
    md = ["", "## Check findings (fretc check)", "",
          "| requirement | source | satisfiable | non-vacuous | redundant | findings |",
          "|---|---|---|---|---|---|"]
    for r in rows:
        cell = "<br>".join(t.replace("|", "\\|") for t in r["findings"]) or "-"
        md.append(f"| {r['id']} | {r['source']} | {r['satisfiable']} | {r['non_vacuous']} | "
                  f"{r['redundant']} | {cell} |")
    p = Path(markdown_path)
    write_file(p, p.read_text(encoding="utf-8").rstrip("\n") + "\n" + "\n".join(md) + "\n")
    e = html.escape
    body = ['<section id="check-findings"><h2>Check findings (fretc check)</h2><table>',
            "<tr><th>requirement</th><th>source</th><th>satisfiable</th><th>non-vacuous</th>"
            "<th>redundant</th><th>findings</th></tr>"]
    for r in rows:
        body.append(f"<tr><td>{e(r['id'])}</td><td>{e(r['source'])}</td>"
                    f"<td>{e(r['satisfiable'])}</td><td>{e(r['non_vacuous'])}</td>"
                    f"<td>{e(r['redundant'])}</td><td>"
                    + "<br>".join(e(t) for t in r["findings"]) + "</td></tr>")
    body.append("</table></section>")
    h = Path(html_path)
    text = h.read_text(encoding="utf-8")
    block = "\n".join(body)
    text = text.replace("</body>", block + "\n</body>", 1) if "</body>" in text \
        else text + block
    write_file(h, text)
