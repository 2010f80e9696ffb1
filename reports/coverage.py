"""The coverage matrix of ``fretc report`` (``coverage.html``), written when the audit was run
with ``--coverage`` (the audit JSON's ``coverage``, :mod:`fretc.audit.coverage`): one row per
requirement and obligation, its description, the number of runs that cover it (coloured:
none red, one amber, two or more green, unknown grey) and one column per run with the tick
where the run met it. A static page: inline CSS, no script.
"""

from __future__ import annotations

import html

__all__ = ["coverage_html"]

_CSS = """body{font:14px system-ui,sans-serif;margin:1.5em}
table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:2px 6px;vertical-align:top}
th{background:#eee}.n0{background:#f4b6b6}.n1{background:#f8e1a0}.n2{background:#bfe3b4}
.unk{background:#ddd}.d{max-width:38em;font-size:12px;color:#333}td.t{text-align:right}"""


def _count_class(o: dict) -> str:
    n = len(o.get("runs") or [])
    if n == 0:
        return "unk" if o.get("status") == "unknown" else "n0"
    return "n1" if n == 1 else "n2"


def coverage_html(doc: dict, title: str = "Coverage matrix") -> str:
    """The page (module docstring) of an audit document with a ``coverage`` member;
    raises ``KeyError`` when it has none."""
    cov = doc["coverage"]
    logs = [la.get("log", "") for la in doc.get("logs") or []]
    e = html.escape
    head = "".join(f"<th>{e(x)}</th>" for x in
                   ["requirement", "obligation", "description", "runs"] + logs)
    rows = []
    for r in cov["requirements"]:
        for o in r["obligations"]:
            ticks = {x["log"]: x["tick"] for x in o.get("runs") or []}
            unknown = set(o.get("unknown_runs") or [])
            cells = "".join(
                f"<td class='t'>{e(str(ticks[lg]))}</td>" if lg in ticks else
                ("<td class='t unk'>?</td>" if lg in unknown else "<td class='t'></td>")
                for lg in logs)
            n = len(o.get("runs") or [])
            rows.append(f"<tr><td>{e(r['requirement'])}</td><td>{e(o['obligation'])}</td>"
                        f"<td class='d'>{e(o['description'])}</td>"
                        f"<td class='t {_count_class(o)}'>{n}</td>{cells}</tr>")
    summary = (f"{cov['covered']} of {cov['total']} obligations exercised by "
               f"{len(logs)} run{'s' if len(logs) != 1 else ''}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{e(title)}</title>"
            f"<style>{_CSS}</style></head><body><h1>{e(title)}</h1><p>{e(summary)}; a "
            "cell gives the tick where that run met the obligation (? the run could not "
            f"tell)</p><table><tr>{head}</tr>{''.join(rows)}</table></body></html>\n")
