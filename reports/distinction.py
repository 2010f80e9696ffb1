"""How ``fretc distinguish`` shows its answer (:mod:`fretc.check.distinguish`): the words
``not equivalent`` / ``equivalent`` / ``unknown`` first, then each wording with its verdict on
the distinguishing trace, and the trace drawn as ``fretc explain`` draws its traces (a row
per variable, ``T``/``.`` per tick for a boolean, the values for a number), then how it was
found or proved. Same input, same text."""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

from fretc.common.textsafe import xml_text

if TYPE_CHECKING:
    from fretc.check.distinguish import Distinction

__all__ = ["distinction_text", "distinction_svg"]

_CELL, _ROW, _LABEL = 14, 20, 130


def _x(text) -> str:
    """Text for SVG: control and bidi characters made visible, then XML-escaped."""
    return html.escape(xml_text(str(text)))


def _cell(value) -> str:
    if isinstance(value, bool):
        return "T" if value else "."
    return f"{value:g}" if isinstance(value, float) else str(value)


def _rows(trace: dict[str, list]) -> list[str]:
    """The trace's rows: booleans one character a tick, numbers in aligned columns."""
    n = len(next(iter(trace.values())))
    numeric = any(not isinstance(v, bool) for vals in trace.values() for v in vals)
    width = max([len(_cell(v)) for vals in trace.values() for v in vals] + [len(str(n - 1))])
    sep = " " if numeric else ""
    w = max(len(v) for v in list(trace) + ["tick"])
    if numeric:
        head = sep.join(f"{i:>{width}}" for i in range(n))
        body = [f"    {v:<{w}}  " + sep.join(f"{_cell(x):>{width}}" for x in vals)
                for v, vals in trace.items()]
    else:
        head = "".join(str(i % 10) for i in range(n))
        body = [f"    {v:<{w}}  " + "".join(_cell(x) for x in vals) for v, vals in trace.items()]
    return [f"    {'tick':<{w}}  {head}"] + body


def distinction_text(d: Distinction, label_a: str, text_a: str, label_b: str, text_b: str) -> str:
    """The answer ``d`` (:class:`fretc.check.distinguish.Distinction`) for the terminal;
    ``label_*`` name the two wordings (an id, or ``A``/``B``), ``text_*`` are their texts."""
    wa = max(len(label_a), len(label_b))
    if d.equivalent is False:
        assert d.trace is not None and d.verdicts is not None  # (not equivalent: shown)
        n = len(next(iter(d.trace.values())))
        out = [f"not equivalent: {label_a} and {label_b} disagree on "
               + ("this shortest trace" if d.shortest else "this trace")
               + f" of {n} tick{'s' if n != 1 else ''}",
               f"  {label_a:<{wa}}  {d.verdicts[0]:<9}  {text_a}",
               f"  {label_b:<{wa}}  {d.verdicts[1]:<9}  {text_b}", ""]
        out += _rows(d.trace)
        out += ["", f"  found by: {d.proof}"]
    elif d.equivalent:
        out = [f"equivalent: {label_a} and {label_b} give the same verdict on every finite "
               "trace", f"  {label_a:<{wa}}  {text_a}", f"  {label_b:<{wa}}  {text_b}", "",
               f"  proof: {d.proof}"]
    else:
        out = [f"unknown: whether {label_a} and {label_b} are equivalent was not decided",
               f"  {label_a:<{wa}}  {text_a}", f"  {label_b:<{wa}}  {text_b}", "",
               f"  why: {d.why}"]
    out += [f"  note: {n}" for n in d.notes]
    return "\n".join(out) + "\n"


def distinction_svg(d: Distinction, label_a: str, text_a: str, label_b: str, text_b: str) -> str:
    """The distinguishing trace of ``d`` as an SVG, drawn as ``fretc explain`` draws its
    diagrams (a row per variable: a filled cell where a boolean holds, the value where it is
    a number), under the two wordings and their verdicts; raises ``ValueError`` when ``d``
    has no trace (equivalent or unknown)."""
    if d.trace is None or d.verdicts is None:
        raise ValueError("no distinguishing trace to draw")
    n = len(next(iter(d.trace.values())))
    numeric = any(not isinstance(v, bool) for vals in d.trace.values() for v in vals)
    cell = max(_CELL, 7 * max(len(_cell(v)) for vals in d.trace.values() for v in vals)
               if numeric else _CELL)
    w = _LABEL + cell * n + 10
    h = _ROW * (len(d.trace) + 5)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{max(w, 480)}" height="{h}" '
           'font-family="sans-serif" font-size="11">',
           f"<title>{_x(label_a)} and {_x(label_b)}: not equivalent</title>",
           f'<text x="4" y="13">{_x(label_a)}: {_x(d.verdicts[0])} ({_x(text_a)})</text>',
           f'<text x="4" y="{13 + _ROW}">{_x(label_b)}: {_x(d.verdicts[1])} '
           f'({_x(text_b)})</text>']
    for r, (name, vals) in enumerate(d.trace.items()):
        y = _ROW * (r + 2) + 4
        out.append(f'<text x="4" y="{y + 12}">{_x(name)}</text>')
        out.append(f'<line x1="{_LABEL}" y1="{y + 14}" x2="{_LABEL + cell * n}" '
                   f'y2="{y + 14}" stroke="#ccc"/>')
        for i, v in enumerate(vals):
            x0 = _LABEL + cell * i
            if isinstance(v, bool):
                if v:
                    out.append(f'<rect x="{x0}" y="{y + 2}" width="{cell}" height="12" '
                               'fill="#455a64"/>')
            else:
                out.append(f'<text x="{x0 + 2}" y="{y + 12}">{_x(_cell(v))}</text>')
    y = _ROW * (len(d.trace) + 2) + 14
    for i in range(0, n, 5):
        out.append(f'<text x="{_LABEL + cell * i}" y="{y}">{i}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"
