"""How ``fretc explain`` shows a requirement (:mod:`fretc.monitors.explain`): its reading and a
diagram in the terminal (one text row per signal, the scope, the triggers and the windows)
and as SVG (``-o DIR``). Same input, same bytes."""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

from fretc.common.textsafe import xml_text

if TYPE_CHECKING:
    from fretc.monitors.explain import Explanation

def _x(text) -> str:
    """Text for SVG/XHTML: control and bidi characters made visible, then XML-escaped (a
    hostile requirement id or text must not make the file unparseable)."""
    return html.escape(xml_text(text))


__all__ = ["text", "svg"]

_CELL, _ROW, _LABEL = 14, 20, 130


def _rows(d) -> list[tuple[str, str, list[int]]]:
    """(label, kind, ticks) rows: ``signal`` ticks that hold, ``scope``/``window``
    intervals as ticks, ``trigger`` ticks."""
    rows = [(name, "signal", [i for i, v in enumerate(vals) if v])
            for name, vals in d.signals.items()]
    rows.append(("scope interval" + ("s (only*: negated)" if d.negated else "s"), "scope",
                 [i for a, b in d.scope for i in range(a, b + 1)]))
    label = "triggers" if d.bound is None else f"triggers ({d.bound} each)"
    rows.append((label, "trigger", list(d.triggers)))
    if d.required is not None:
        rows.append(("response required", "window", list(range(d.required[0],
                                                               d.required[1] + 1))))
    if d.forbidden is not None:
        rows.append(("response forbidden", "forbidden", list(range(d.forbidden[0],
                                                                  d.forbidden[1] + 1))))
    return rows


def text(x: Explanation) -> str:
    """The explanation ``x`` (:class:`fretc.monitors.explain.Explanation`) for the terminal."""
    d = x.diagram
    mark = {"signal": "T", "scope": "=", "trigger": "^", "window": "#", "forbidden": "x"}
    out = [f"{x.id}  ({x.key})", f"  {x.text}", "", f"  {x.reading}", ""]
    width = max(len(r[0]) for r in _rows(d))
    out.append(f"  {'tick':<{width}}  " + "".join(str(i % 10) for i in range(d.n)))
    for label, kind, ticks in _rows(d):
        on = set(ticks)
        out.append(f"  {label:<{width}}  " + "".join(mark[kind] if i in on else "."
                                                      for i in range(d.n)))
    if d.drawn_ticks is not None:
        out += ["", f"  not to scale: the duration of {x.ticks} ticks is drawn as "
                    f"{d.drawn_ticks}"]
    if d.obligation:
        out += ["", f"  obligation from each trigger t (scope interval [s, e]): {d.obligation}"]
    words = (("satisfies", "violates") if d.bound is None else
             ("meets every trigger's obligation", "fails a trigger's obligation (a failed "
              "trial, not a violation)"))
    for what, trace in zip(words, (x.satisfying, x.violating)):
        if trace:
            n = len(next(iter(trace.values())))
            out += ["", f"  shortest trace that {what} ({n} tick{'s' if n != 1 else ''}):"]
            w = max(len(v) for v in trace)
            out += [f"    {v:<{w}}  " + "".join("T" if b else "." for b in vals)
                    for v, vals in trace.items()]
    if x.search_note:
        out += ["", f"  shortest traces: {x.search_note}"]
    return "\n".join(out) + "\n"


def svg(x: Explanation) -> str:
    """The diagram of ``x`` as an SVG: a row per signal, the scope intervals shaded, the
    triggers as arrows, the required window green and the forbidden one red."""
    d = x.diagram
    rows = _rows(d)
    w = _LABEL + _CELL * d.n + 10
    h = _ROW * (len(rows) + 4)
    colour = {"signal": "#455a64", "scope": "#bbdefb", "trigger": "#f57c00",
              "window": "#2e7d32", "forbidden": "#c62828"}
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="11">',
           f"<title>{_x(x.id)}: {_x(x.text)}</title>",
           f'<text x="4" y="13">{_x(x.id)} ({_x(x.key)})</text>']
    for r, (label, kind, ticks) in enumerate(rows):
        y = _ROW * (r + 1) + 4
        out.append(f'<text x="4" y="{y + 12}">{_x(label)}</text>')
        out.append(f'<line x1="{_LABEL}" y1="{y + 14}" x2="{_LABEL + _CELL * d.n}" '
                   f'y2="{y + 14}" stroke="#ccc"/>')
        for i in ticks:
            x0 = _LABEL + _CELL * i
            if kind == "trigger":
                out.append(f'<path d="M{x0 + 6},{y + 2} l-5,10 h10 z" fill="{colour[kind]}"/>')
            else:
                out.append(f'<rect x="{x0}" y="{y + 2}" width="{_CELL}" height="12" '
                           f'fill="{colour[kind]}"/>')
    y = _ROW * (len(rows) + 1) + 14
    for i in range(0, d.n, 5):
        out.append(f'<text x="{_LABEL + _CELL * i}" y="{y}">{i}</text>')
    if d.obligation:
        out.append(f'<text x="4" y="{y + 16}">{_x(d.obligation)}</text>')
    if d.drawn_ticks is not None:
        out.append(f'<text x="4" y="{y + 32}">not to scale: the duration of {x.ticks} '
                   f'ticks is drawn as {d.drawn_ticks}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"
