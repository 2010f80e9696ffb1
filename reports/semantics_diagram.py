"""FRET's semantics diagram of a requirement, as FRET's "Semantics" panel draws it: one
timeline with the scope's interval(s) (``in M`` shades every interval where ``M`` holds,
``after M`` the rest of the run past the first one, ...), the condition's trigger point(s)
(``TC``), the stop condition (``SC``) and, from a trigger, the timing's window with where
the response (``Res``) must, or must not, hold; a duration ``n`` is drawn as a bracket of
``n`` ticks from the trigger.

Design notes: ARCHITECTURE.md, `reports/semantics_diagram.py`."""

from __future__ import annotations

import html
from dataclasses import dataclass
from fractions import Fraction

from fretc.common.textsafe import xml_text
from fretc.compiler.printers import expr_text
from fretc.fretish import ast as A

__all__ = ["Window", "SemanticsLayout", "layout", "svg", "MAX_DRAWN", "CELL", "LEFT"]

#: The longest duration drawn to scale (ticks); a longer one is drawn this long, its
#: bracket saying the real length and "not to scale".
MAX_DRAWN = 10
#: Pixels per tick, and the x of tick 0 (the labels' column is left of it).
CELL, LEFT = 16, 200
_ROW = 26

Interval = tuple[int, int]

#: The obligation from a trigger t in a scope interval [s, e] (README section 4), as
#: windows: (quantifier, the response's value, start, end), ``k`` the duration, ``sc``
#: the first tick of the stop condition at or after t.
_PLAIN = {
    "immediately": lambda t, e, k, sc: [("every", True, t, t)],
    "next": lambda t, e, k, sc: [("every", True, t + 1, t + 1)] if t < e else [],
    "finally": lambda t, e, k, sc: [("every", True, e, e)],
    "eventually": lambda t, e, k, sc: [("some", True, t, e)],
    "null": lambda t, e, k, sc: [("some", True, t, e)],
    "always": lambda t, e, k, sc: [("every", True, t, e)],
    "never": lambda t, e, k, sc: [("every", False, t, e)],
    "within": lambda t, e, k, sc: [("some", True, t, t + k)],
    "for": lambda t, e, k, sc: [("every", True, t, min(t + k, e))],
    "after": lambda t, e, k, sc: [("every", False, t, t + k), ("every", True, t + k + 1,
                                                                 t + k + 1)],
    "until": lambda t, e, k, sc: [("every", True, t, min(sc - 1, e))],
    "before": lambda t, e, k, sc: [("some", True, t, min(sc - 1, e))],
}

_SAY = {
    ("every", True): "{r} at every tick", ("some", True): "{r} at some tick",
    ("every", False): "{r} at no tick", ("some", False): "{r} false at some tick",
}


@dataclass(frozen=True)
class Window:
    """Where a trigger's response is owed: ticks ``start..end`` (inclusive) from the trigger
    ``trigger``; ``quantifier`` ``"every"`` (at every tick of it) or ``"some"`` (at one
    tick at least); ``value`` True where the response must hold, False where it must not
    (``never``, ``after``'s wait, every window of an ``only*`` scope)."""

    trigger: int
    start: int
    end: int
    quantifier: str
    value: bool


@dataclass(frozen=True)
class SemanticsLayout:
    """The laid-out picture of one requirement (ticks from 0 to ``n - 1``).

    Attributes:
        key: FRET's template key.
        n: ticks drawn.
        mode: the scope mode's truth per tick (None for the null scope).
        intervals: the scope intervals where the obligation is checked (inclusive; in an
            ``only*`` scope those outside the scope, where the response is forbidden).
        negated: an ``only*`` scope (the obligation checked is the negated one).
        condition: the condition's truth per tick (None without a condition).
        triggers: every trigger point, in order.
        stop: the stop condition's truth per tick (``until``/``before``; else None).
        windows: the response windows of the first trigger of each interval.
        k: the requirement's duration in ticks (``within``/``for``/``after``; else None).
        drawn_k: ``k`` as drawn (at most :data:`MAX_DRAWN`).
    """

    key: str
    n: int
    mode: tuple[bool, ...] | None
    intervals: tuple[Interval, ...]
    negated: bool
    condition: tuple[bool, ...] | None
    triggers: tuple[int, ...]
    stop: tuple[bool, ...] | None
    windows: tuple[Window, ...]
    k: int | None
    drawn_k: int | None


def _mode(kind: str, w: int) -> tuple[list[Interval], int]:
    """Where the scope mode holds (inclusive runs) and the ticks drawn, so that each checked
    interval is ``w`` ticks wide (README section 2)."""
    two_gaps = [(0, 1), (w + 2, w + 4), (2 * w + 5, 2 * w + 6)]  # !M twice for w ticks
    return {
        "null": ([], w),
        "in": ([(2, w + 1), (w + 5, 2 * w + 4)], 2 * w + 7),
        "notin": (two_gaps, 2 * w + 7),
        "onlyIn": (two_gaps, 2 * w + 7),
        "after": ([(1, 3)], w + 4),
        "onlyAfter": ([(w, w + 1)], w + 4),
        "before": ([(w, w + 1)], w + 3),
        "onlyBefore": ([(3, 4)], w + 3),
    }[kind]


def _intervals(kind: str, runs: list[Interval], n: int) -> list[Interval]:
    """The checked scope intervals (README section 2; ``only*``: the complement where the
    negated obligation is checked) of a mode holding on ``runs``, drawn over ``n`` ticks."""
    gaps, at = [], 0
    for a, b in runs:
        if a > at:
            gaps.append((at, a - 1))
        at = b + 1
    if at < n:
        gaps.append((at, n - 1))
    if kind == "null":
        return [(0, n - 1)]
    if kind == "in":
        return list(runs)
    if kind in ("notin", "onlyIn"):
        return gaps
    first = runs[0]
    return {"after": [(first[1] + 1, n - 1)], "onlyAfter": [(0, first[1])],
            "before": [(0, first[0] - 1)], "onlyBefore": [(first[0], n - 1)]}[kind]


def _negated(q: str, value: bool) -> tuple[str, bool]:
    """The dual window of an ``only*`` scope: "R at every tick" becomes "!R at some tick"."""
    return ("some" if q == "every" else "every"), not value


def layout(req: A.Requirement, ticks: int | None = None) -> SemanticsLayout:
    """Lay out FRET's semantics diagram of ``req``.

    Args:
        req: a parsed requirement (not free-form).
        ticks: its duration in ticks as compiled (``Formalization.ticks``); None reads a
            duration's amount as ticks (FRET's reading without a tick period).

    Returns:
        The :class:`SemanticsLayout` (module docstring for the shape chosen).

    Raises:
        ValueError: a free-form requirement, or a duration that is not a whole number of
            ticks without ``ticks``.
    """
    if req.freeform or req.response is None:
        raise ValueError("a free-form requirement has no semantics diagram")
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    k = None
    if timing in A.DURATION_TIMINGS:
        if ticks is None:
            assert req.timing.duration is not None  # (a duration timing has one)
            amount = Fraction(req.timing.duration.amount or "0")
            if amount.denominator != 1:
                raise ValueError(f"the duration {amount} is not a whole number of ticks")
            ticks = int(amount)
        k = int(ticks)
    drawn = None if k is None else min(k, MAX_DRAWN)
    w = (drawn or 0) + 9
    runs, n = _mode(scope, w)
    intervals = _intervals(scope, runs, n)
    C = [False] * n
    S = [False] * n
    triggers: list[int] = []
    windows: list[Window] = []
    negated = scope.startswith("only")
    for s, e in intervals:
        for i in range(s + 2, min(s + 5, e + 1)):
            C[i] = True
        for i in range(s + 7, min(s + 9, e + 1)):
            S[i] = True
        mine = {"null": [s], "regular": [s + 2], "holding": list(range(s + 2, s + 5))}[cond]
        triggers += mine
        t = mine[0]
        sc = next((i for i in range(t, e + 1) if S[i]), e + 1)
        for q, v, a, b in _PLAIN[timing](t, e, drawn or 0, sc):
            if negated:
                q, v = _negated(q, v)
            windows.append(Window(t, a, b, q, v))
    mode = None if scope == "null" else tuple(any(a <= i <= b for a, b in runs)
                                              for i in range(n))
    return SemanticsLayout(
        key=req.key or "", n=n, mode=mode, intervals=tuple(intervals), negated=negated,
        condition=None if cond == "null" else tuple(C), triggers=tuple(triggers),
        stop=tuple(S) if timing in A.STOP_TIMINGS else None, windows=tuple(windows),
        k=k, drawn_k=drawn)


# --------------------------------------------------------------------------- drawing
def _x(text: object) -> str:
    """Text for SVG: control and bidi characters made visible, then XML-escaped."""
    return html.escape(xml_text(str(text)))


def _source(req: A.Requirement, e: A.Expr | None) -> str:
    """An expression as the requirement wrote it (its span), else FRET's printed form."""
    if e is None:
        return ""
    sp = getattr(e, "span", A.NO_SPAN)
    if sp != A.NO_SPAN and 0 <= sp.start < sp.end <= len(req.text):
        return req.text[sp.start:sp.end]
    return expr_text(e)


def _tx(t: int) -> int:
    return LEFT + CELL * t


def _runs(flags: tuple[bool, ...]) -> list[Interval]:
    out, start = [], None
    for i, f in enumerate(list(flags) + [False]):
        if f and start is None:
            start = i
        elif not f and start is not None:
            out.append((start, i - 1))
            start = None
    return out


def _bars(flags: tuple[bool, ...], y: int, cls: str, fill: str) -> list[str]:
    return [f'<rect class="{cls}" data-start="{a}" data-end="{b}" x="{_tx(a)}" y="{y}" '
            f'width="{CELL * (b - a + 1)}" height="14" fill="{fill}"/>'
            for a, b in _runs(flags)]


def _window(wd: Window, y: int) -> str:
    colour = "#2e7d32" if wd.value else "#c62828"
    solid = wd.quantifier == "every"
    style = (f'fill="{colour}" fill-opacity="0.75"' if solid else
             f'fill="{colour}" fill-opacity="0.15" stroke="{colour}" stroke-width="2" '
             'stroke-dasharray="4 2"')
    return (f'<rect class="window" data-trigger="{wd.trigger}" data-start="{wd.start}" '
            f'data-end="{wd.end}" data-quantifier="{wd.quantifier}" '
            f'data-value="{"R" if wd.value else "!R"}" x="{_tx(wd.start)}" y="{y}" '
            f'width="{CELL * (wd.end - wd.start + 1)}" height="14" {style}/>')


def _rows(req: A.Requirement, lay: SemanticsLayout) -> list[tuple[str, str, list[str]]]:
    """(class, label, elements at y=0) of each row, top to bottom."""
    rows: list[tuple[str, str, list[str]]] = []
    if lay.mode is not None:
        rows.append(("mode", f"M: {_source(req, req.scope.mode)}",
                     _bars(lay.mode, 0, "mode-on", "#78909c")))
    label = ("outside it (checked)" if lay.negated else
             "scope interval" + ("s" if len(lay.intervals) > 1 else ""))
    scope = [f'<rect class="scope" data-start="{a}" data-end="{b}" x="{_tx(a)}" y="0" '
             f'width="{CELL * (b - a + 1)}" height="14" fill="#bbdefb" stroke="#1565c0"/>'
             for a, b in lay.intervals]
    rows.append(("scope", f"{req.scope.kind}: {label}", scope))
    if lay.condition is not None:
        rows.append(("condition", f"TC: {_source(req, req.condition.expr)}",
                     _bars(lay.condition, 0, "condition-on", "#f9a825")))
    marks = [f'<path class="trigger" data-tick="{t}" d="M{_tx(t) + CELL // 2},0 l-6,13 h12 z" '
             f'fill="#ef6c00"/>' for t in lay.triggers]
    rows.append(("triggers", f"triggers ({req.condition.kind})", marks))
    if lay.stop is not None:
        rows.append(("stop", f"SC: {_source(req, req.timing.stop)}",
                     _bars(lay.stop, 0, "stop-on", "#6a1b9a")))
    rows.append(("response", f"Res: {_source(req, req.response)}",
                 [_window(wd, 0) for wd in lay.windows]))
    if lay.k is not None and lay.windows:
        rows.append(("duration", "n", _brackets(lay)))
    return rows


def _brackets(lay: SemanticsLayout) -> list[str]:
    """The duration's bracket from each drawn trigger: ``n`` ticks after it."""
    out = []
    k, drawn = lay.k or 0, lay.drawn_k or 0
    say = f"n = {k} tick{'s' if k != 1 else ''}" + (" (not to scale)" if k != drawn else "")
    for t in sorted({wd.trigger for wd in lay.windows}):
        x0, x1 = _tx(t) + CELL // 2, _tx(t + drawn) + CELL // 2
        out.append(f'<g class="duration" data-from="{t}" data-to="{t + drawn}" data-ticks="{k}">'
                   f'<path d="M{x0},2 v8 H{x1} v-8" fill="none" stroke="#333"/>'
                   f'<text x="{x0 + 2}" y="22">{_x(say)}</text></g>')
    return out


def _legend(req: A.Requirement, lay: SemanticsLayout) -> list[str]:
    """The lines under the picture: what a window means, and the timing's obligation."""
    r = _source(req, req.response)
    said = sorted({(wd.quantifier, wd.value) for wd in lay.windows})
    lines = [f"{'green' if v else 'red'}{'' if q == 'every' else ' outline'}: "
             + _SAY[(q, v)].format(r=r) for q, v in said]
    if lay.negated:
        lines.append(f"{req.scope.kind}: the response is forbidden outside the scope "
                     "(the negated obligation, checked there)")
    if req.timing.kind == "after" and lay.negated:
        lines.append("only* with after: violated when both windows are met")
    if req.timing.kind in A.STOP_TIMINGS:
        lines.append(f"{req.timing.kind}: the window ends the tick before "
                     f"{_source(req, req.timing.stop)} first holds")
    drawn = {wd.trigger for wd in lay.windows}
    if len(lay.triggers) > len(drawn):
        lines.append("windows drawn from the first trigger of each interval; every trigger "
                     "owes its own")
    if not lay.windows:
        lines.append("no window: the trigger has none in its interval")
    return lines


def svg(req: A.Requirement, ticks: int | None = None, ident: str = "") -> str:
    """FRET's semantics diagram of ``req`` as an SVG (a string, deterministic).

    Args:
        req: a parsed requirement (not free-form).
        ticks: its duration in ticks as compiled (as :func:`layout`).
        ident: the requirement's id, for the title.

    Returns:
        The SVG document: elements carry ``class`` and ``data-*`` attributes in ticks
        (``rect.scope``, ``path.trigger``, ``rect.window``, ``g.duration``) for tools and
        tests; x = :data:`LEFT` + :data:`CELL` * tick.

    Raises:
        ValueError: as :func:`layout`.
    """
    lay = layout(req, ticks)
    rows = _rows(req, lay)
    legend = _legend(req, lay)
    head = f"{ident}  {lay.key}".strip()
    width = max(_tx(lay.n) + 12, 7 * max(len(req.text), len(head)) + 12)
    height = 48 + _ROW * len(rows) + 26 + 16 * len(legend)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" class="fret-semantics" '
           f'width="{width}" height="{height}" viewBox="0 0 {width} {height}" '
           f'font-family="sans-serif" font-size="11" data-key="{_x(lay.key)}">',
           f"<title>{_x(ident)}: FRET semantics of {_x(req.text)}</title>",
           f'<rect x="0" y="0" width="{width}" height="{height}" fill="#fff"/>',
           f'<text x="6" y="15" font-weight="bold">{_x(head)}</text>',
           f'<text x="6" y="31">{_x(req.text)}</text>']
    y = 44
    for cls, label, elements in rows:
        short = label if len(label) <= 30 else label[:29] + "\u2026"
        out.append(f'<g class="row {cls}" transform="translate(0,{y})">'
                   f'<text x="6" y="11"><title>{_x(label)}</title>{_x(short)}</text>'
                   f'<line x1="{LEFT}" y1="14" x2="{_tx(lay.n)}" y2="14" stroke="#ccc"/>')
        out += elements
        out.append("</g>")
        y += _ROW
    out.append(f'<g class="axis" transform="translate(0,{y})">'
               f'<text x="6" y="11">tick</text>')
    out += [f'<text x="{_tx(i) + 2}" y="11">{i}</text>' for i in range(0, lay.n, 5)]
    out.append("</g>")
    y += 26
    for line in legend:
        out.append(f'<text class="legend" x="6" y="{y}">{_x(line)}</text>')
        y += 16
    out.append("</svg>")
    return "\n".join(out) + "\n"
