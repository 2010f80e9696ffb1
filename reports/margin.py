"""The margin over time of one requirement, as inline SVG for the traceability report
(``fretc report``): one line per run, from the verdicts' ``robustness.margin`` in the audit
JSON (:mod:`fretc.audit.verdict`), time in seconds since each log's first tick, the zero
line dashed (below it the requirement is violated).

Only finite margins are drawn; a point of ``+inf`` / ``-inf`` (decided by a boolean, no
distance) breaks the line. A requirement whose margins are all infinite has no plot
(:func:`margin_svg` returns ``""``). Deterministic text: the same document gives the same
bytes.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import escape as _xml_escape

from fretc.common.textsafe import xml_text

__all__ = ["margin_svg"]

_W, _H = 720, 170
_X0, _X1, _Y0, _Y1 = 64, 560, 14, 146
_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf")


def _finite(v) -> float | None:
    return v if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) \
        else None


def _esc(text: str) -> str:
    """XML character data or attribute text from the inputs (control characters shown
    escaped, ``& < > "`` as entities)."""
    return _xml_escape(xml_text(text, keep=""), {'"': "&quot;"})


def _f(x: float) -> str:
    return f"{x:.1f}"


def _with_worst(rows: list, worst: tuple | None) -> list[tuple[float, float | None]]:
    """The plotted (time_s, value) points of a margin, the worst point (``worst``: its
    ``(time_s, value)``, the verdict's robustness) among them: the margin the audit keeps is
    thinned, and the worst one reported must lie on the line drawn."""
    pts = [(t, _finite(v)) for _tick, t, v in rows if t is not None]
    if worst is None or worst[0] is None or _finite(worst[1]) is None:
        return pts
    t_w, v_w = float(worst[0]), float(worst[1])
    pts = [(t, v) for t, v in pts if t != t_w]
    at = next((i for i, (t, _v) in enumerate(pts) if t > t_w), len(pts))
    return pts[:at] + [(t_w, v_w)] + pts[at:]


def margin_svg(series: list[tuple], title: str) -> str:
    """An SVG plot of margins over time.

    Args:
        series: ``(run name, margin)`` or ``(run name, margin, worst)`` per run, margin as
            in the audit JSON (``[[tick, time_s, value], ...]``, value a number or
            ``"inf"`` / ``"-inf"``), ``worst`` the robustness' ``(time_s, value)`` (seconds
            on the log clock) or None: drawn on the run's line and marked
            (``circle[data-mark="worst"]``).
        title: the plot's title (escaped here).

    Returns:
        The ``<svg>`` element, or ``""`` when no run has a finite margin.
    """
    pts = [(item[0], _with_worst(item[1], item[2] if len(item) > 2 else None))
           for item in series]
    worsts = {item[0]: item[2] for item in series
              if len(item) > 2 and item[2] is not None and _finite(item[2][1]) is not None
              and item[2][0] is not None}
    values = [v for _n, rows in pts for _t, v in rows if v is not None]
    if not values:
        return ""
    times = [t for _n, rows in pts for t, _v in rows]
    lo, hi = min(min(values), 0.0), max(max(values), 0.0)
    if hi - lo < 1e-12:
        hi = lo + 1.0
    tmax = max(max(times), 1e-9)

    def x(t: float) -> float:
        return _X0 + (_X1 - _X0) * t / tmax

    def y(v: float) -> float:
        return _Y1 - (_Y1 - _Y0) * (v - lo) / (hi - lo)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" class="margin" width="{_W}" '
           f'height="{_H}" viewBox="0 0 {_W} {_H}" font-family="sans-serif" font-size="11">',
           f"<title>{_esc(title)}</title>",
           f'<rect x="{_X0}" y="{_Y0}" width="{_X1 - _X0}" height="{_Y1 - _Y0}" fill="none" '
           'stroke="#bbb"/>',
           f'<line x1="{_X0}" x2="{_X1}" y1="{_f(y(0.0))}" y2="{_f(y(0.0))}" stroke="#000" '
           'stroke-dasharray="4 3" data-mark="zero"/>']
    for v in (lo, hi):
        out.append(f'<text x="{_X0 - 4}" y="{_f(y(v) + 4)}" text-anchor="end">{v + 0.0:+.4g}</text>')
    out.append(f'<text x="{_X0}" y="{_H - 8}">0 s</text>')
    out.append(f'<text x="{_X1}" y="{_H - 8}" text-anchor="end">{tmax:.1f} s</text>')
    for k, (name, rows) in enumerate(pts):
        color = _COLORS[k % len(_COLORS)]
        lines: list[list[str]] = []
        cur: list[str] = []
        for t, value in rows:
            if value is None:
                if cur:
                    lines.append(cur)
                cur = []
            else:
                cur.append(f"{_f(x(t))},{_f(y(value))}")
        if cur:
            lines.append(cur)
        for ln in lines:
            out.append(f'<polyline fill="none" stroke="{color}" stroke-width="1.2" '
                       f'data-log="{_esc(name)}" points="{" ".join(ln)}"/>')
        if name in worsts:
            t_w, v_w = float(worsts[name][0]), float(worsts[name][1])
            out.append(f'<circle cx="{_f(x(t_w))}" cy="{_f(y(v_w))}" r="3.5" fill="{color}" '
                       f'data-mark="worst" data-log="{_esc(name)}" data-time-s="{t_w!r}" '
                       f'data-value="{v_w!r}"><title>{_esc(name)}: worst margin '
                       f"{v_w + 0.0:+.4g} at {t_w:.3f} s</title></circle>")
        out.append(f'<text x="{_X1 + 10}" y="{_Y0 + 10 + 14 * k}" fill="{color}">'
                   f"{_esc(name)}</text>")
    out.append("</svg>")
    return "\n".join(out)
