"""How ``fretc simulate`` shows its results (:mod:`fretc.monitors.simulate`): a text table in the
terminal (one row per requirement's ft, pt and part, one column per tick), one SVG per
requirement and an HTML page holding them (``-o DIR``), and the JSON document (``--json``).
Same input, same bytes: no time or path of the machine is written."""

from __future__ import annotations

import html

from fretc.common.outputs import output_folder, write_file
from fretc.common.textsafe import file_stems, xml_text
import json
from pathlib import Path
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:
    from fretc.monitors.simulate import Simulation

def _x(text) -> str:
    """Text for SVG/XHTML: control and bidi characters made visible, then XML-escaped (a
    hostile requirement id or text must not make the file unparseable)."""
    return html.escape(xml_text(text))


__all__ = ["text_table", "svg", "write_outputs", "json_document"]

_CELL = 14  # px per tick in the SVG
_ROW = 18
_LABEL = 110


_VERDICT = {True: "satisfied", False: "violated",
            None: "unknown (the NaN values leave it undecided)"}


def _mark(v: Any) -> str:
    return "?" if v is None else ("T" if v else ".")


def text_table(sims: list, n: int) -> str:
    """Rows ``ID ft``, ``ID pt``, ``ID part`` of marks (``T`` true, ``.`` false, ``?``
    unread or unknown: a NaN), one column per tick, with a tick ruler every 10 ticks, then
    each requirement's verdict on the whole trace."""
    rows = [("", "".join(str(i // 10 % 10) if i % 10 == 0 else " " for i in range(n)))]
    for s in sims:
        rows.append((f"{s.id} ft", "".join(_mark(v) for v in s.ft)))
        rows.append((f"{s.id} pt", "".join(_mark(v) for v in s.pt)))
        for name, vals in s.parts.items():
            rows.append((f"  {name}", "".join(_mark(v) for v in vals)))
    width = max(len(a) for a, _b in rows)
    lines = [f"{a:<{width}}  {b}" for a, b in rows]
    verdicts = [f"{s.id}: {_VERDICT[s.ft[0]]} on the whole trace (ft at tick 0, pt at tick "
                f"{n - 1})" for s in sims if s.ft]
    return "\n".join(lines + [""] + verdicts)


def svg(sim: Simulation, n: int) -> str:
    """One requirement's timelines (ft, pt, then its parts) as an SVG: a filled cell where
    the value is true, an empty one where false, a hatched one where unread."""
    rows = [("ft", sim.ft), ("pt", sim.pt)] + list(sim.parts.items())
    w = _LABEL + _CELL * max(n, 1) + 10
    h = _ROW * (len(rows) + 2)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="11">',
           f'<title>{_x(sim.id)}: {_x(sim.text)}</title>',
           f'<text x="4" y="12">{_x(sim.id)}: {_x(sim.text[:120])}</text>']
    for r, (name, vals) in enumerate(rows):
        y = _ROW * (r + 1) + 4
        out.append(f'<text x="4" y="{y + 11}">{_x(name)}</text>')
        for i, v in enumerate(vals):
            x = _LABEL + _CELL * i
            fill = "#d9d9d9" if v is None else ("#2e7d32" if v else "#ffffff")
            out.append(f'<rect x="{x}" y="{y}" width="{_CELL - 2}" height="{_ROW - 6}" '
                       f'fill="{fill}" stroke="#555"/>')
    y = _ROW * (len(rows) + 1) + 14
    for i in range(0, n, 5):
        out.append(f'<text x="{_LABEL + _CELL * i}" y="{y}">{i}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def json_document(sims: list, n: int) -> dict:
    """``{"ticks": n, "requirements": [{"id", "text", "ft", "pt", "parts"}]}``."""
    return {"ticks": n, "requirements": [s.to_json() for s in sims]}


def write_outputs(sims: list, n: int, out_dir: str | None, json_path: str | None) -> list[str]:
    """Write ``DIR/<id>.svg`` and ``DIR/simulation.html`` (``out_dir``) and the JSON
    (``json_path``); the paths written."""
    written = []
    if out_dir is not None:
        d = Path(output_folder(out_dir))
        parts = []
        stems = file_stems([s.id for s in sims])
        for s in sims:
            name = stems[s.id] + ".svg"
            text = svg(s, n)
            write_file(d / name, text)
            written.append(str(d / name))
            parts.append(f"<section><h2>{_x(s.id)}</h2>"
                         f"<p>{_x(s.text)}</p>{text}</section>")
        page = ("<!doctype html><html><head><meta charset='utf-8'><title>fretc simulate"
                "</title></head><body><h1>fretc simulate</h1><p>Filled: true; empty: false; "
                "grey: unknown (a NaN read). ft at a tick: on the trace from that tick; pt: on the "
                "trace up to it.</p>" + "".join(parts) + "</body></html>\n")
        write_file(d / "simulation.html", page)
        written.append(str(d / "simulation.html"))
    if json_path is not None:
        write_file(json_path, json.dumps(json_document(sims, n), indent=1) + "\n")
        written.append(json_path)
    return written
