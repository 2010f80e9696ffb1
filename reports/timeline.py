"""Timeline plots of a violation as inline SVG, for the traceability report (``fretc report``).

A small deterministic SVG writer (no matplotlib, no JavaScript, no external fonts): the same
verdict gives byte-identical text. Input is the audit's JSON (schema ``fretc-audit/1``, see
:mod:`fretc.audit.verdict`): one verdict object and the log object it belongs to.

Design notes: ARCHITECTURE.md, `reports/timeline.py`."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field
from xml.sax.saxutils import escape as _xml_escape, quoteattr as _xml_quoteattr

from fretc.common.textsafe import xml_text
from fretc.common.units import format_offset

from fretc.reports.timeline_layout import (LANE_GAP, BOOL_H, NUM_H, PLOT_X1, TOPIC_H, WIDTH, Axis, Segment,
    Threshold, Timeline, cells, cells_by_segment, lane_label, nice_step_ns, plan_timeline,
    step_decimals)

__all__ = ["timeline_svg", "Threshold", "COLORS"]

#: Colours of the marks (also used by the report's legend and CSS).
COLORS = {
    "scope": "#d6e6f5",
    "scope_edge": "#7aa6d6",
    "window": "#fbe3b8",
    "window_edge": "#e0952b",
    "trigger": "#1f5fbf",
    "violation": "#c62828",
    "ltl3": "#7b1fa2",
    "damage": "#9e9e9e",
    "bool": "#00897b",
    "numeric": "#263238",
    "threshold": "#c62828",
    "topic": "#6d4c41",
    "axis": "#546e7a",
    "grid": "#e3e7ea",
    "text": "#1d2329",
    "muted": "#607d8b",
    "detail": "#90a4ae",
}

FONT = "system-ui,-apple-system,'Segoe UI',Roboto,Helvetica,Arial,sans-serif"
#: Width of a character of the 10 px notes, for wrapping them (a sans-serif font's average
#: plus a margin: a line never runs past the picture's right edge)
NOTE_CHAR_W = 6.0


def escape(s: str) -> str:
    """XML character data from the inputs: control and bidi characters shown escaped
    (:func:`fretc.common.textsafe.xml_text`: a NUL must not make the SVG unparseable)."""
    return _xml_escape(xml_text(s, keep=""))


def quoteattr(s: str) -> str:
    """A quoted XML attribute value, made safe like :func:`escape`."""
    return _xml_quoteattr(xml_text(s, keep=""))


def _f(x: float) -> str:
    """A coordinate, rounded to 0.1 px, without a trailing ``.0``."""
    s = f"{x:.1f}"
    return s[:-2] if s.endswith(".0") else s


def _num(v) -> float | None:
    """A JSON value as a float: ``"nan"``, ``"inf"`` and ``"-inf"`` (how the audit writes
    non-finite values) become floats; booleans 0/1; anything else None."""
    if isinstance(v, bool):
        return 1.0 if v else 0.0
    if isinstance(v, (int, float)):
        return float(v)
    if v in ("nan", "inf", "-inf"):
        return float(v)
    return None


@dataclass
class _Svg:
    parts: list[str] = field(default_factory=list)

    def add(self, s: str) -> None:
        self.parts.append(s)

    def rect(self, x, y, w, h, fill, extra="") -> None:
        if w <= 0 or h <= 0:
            return
        self.add(f'<rect x="{_f(x)}" y="{_f(y)}" width="{_f(w)}" height="{_f(h)}" '
                 f'fill="{fill}"{extra}/>')

    def line(self, x1, y1, x2, y2, stroke, width=1.0, extra="") -> None:
        self.add(f'<line x1="{_f(x1)}" y1="{_f(y1)}" x2="{_f(x2)}" y2="{_f(y2)}" '
                 f'stroke="{stroke}" stroke-width="{_f(width)}"{extra}/>')

    def text(self, x, y, s, size=11, fill=COLORS["text"], anchor="start", extra="") -> None:
        self.add(f'<text x="{_f(x)}" y="{_f(y)}" font-size="{size}" fill="{fill}" '
                 f'text-anchor="{anchor}"{extra}>{escape(s)}</text>')


@dataclass
class _Detail:
    """Where the detail part lies: the marker label rows start at ``lab_y0``, the lanes
    span ``lanes_y0 .. lanes_y1`` (``lanes_h`` high; ``heights`` per lane)."""

    lab_y0: float
    lanes_y0: float
    lanes_h: float
    lanes_y1: float
    heights: list[int]


def timeline_svg(verdict: dict, log: dict, *, period_ns: int | None = None,
                 thresholds: Sequence[Threshold] = (), title: str = "",
                 caption: str = "") -> str:
    """The SVG text (one ``<svg>`` element, UTF-8, no XML declaration) of a violated
    verdict's timeline.

    Args:
        verdict: a verdict object of the audit JSON (``logs[i].verdicts[j]``) with
            ``first_violation`` set; ``values``/``sources`` give the lanes.
        log: its log object (``logs[i]``): ``start_time_ns``, ``end_time_ns``,
            ``damage_time_ns``.
        period_ns: the tick period (ns) when the bindings tick at a fixed period; None for a
            topic tick (the median spacing of the sampled ticks is used for cell widths).
        thresholds: comparison constants to dash in numeric lanes (:class:`Threshold`).
        title: the accessible title (``<title>``).
        caption: the caption drawn at the top of the picture (``text.caption``), so that
            the image alone names what it shows; default: the requirement id, its verdict,
            the run (log file) and the first violation's time on the log clock.

    Returns:
        SVG text, deterministic for equal input.

    Raises:
        ValueError: the verdict has no ``first_violation`` or the log no ``start_time_ns``.
    """
    lay = plan_timeline(verdict, log, period_ns, thresholds)
    svg = _Svg()
    svg.add(f'<text class="caption" x="8" y="17" font-size="13" font-weight="bold" '
            f'fill="{COLORS["text"]}">{escape(caption or _default_caption(verdict, lay))}</text>')
    y = _draw_legend(svg, lay.x0, 30.0)
    y = _draw_overview(svg, lay, y)
    det = _draw_detail(svg, lay, y)
    y = _draw_detail_axis(svg, lay, det)
    y = _draw_notes(svg, lay, y)
    height = int(y + 10)
    head = (f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH} {height}" '
            f'width="{WIDTH}" height="{height}" role="img" font-family="{FONT}" '
            f'class="timeline" data-requirement={quoteattr(str(verdict.get("requirement")))} '
            f'data-log={quoteattr(str(verdict.get("log")))}>')
    body = [head, f"<title>{escape(title or _default_title(verdict, lay))}</title>",
            f'<rect x="0" y="0" width="{WIDTH}" height="{height}" fill="#ffffff"/>']
    return "\n".join(body + svg.parts + ["</svg>"]) + "\n"


def _default_caption(verdict: dict, lay: Timeline) -> str:
    return (f"{verdict.get('requirement')} {verdict.get('verdict') or 'violated'} on run "
            f"{verdict.get('log')}: first violation at {format_offset(lay.viol_ns, lay.start)}"
            " on the log clock")


def _default_title(verdict: dict, lay: Timeline) -> str:
    return (f"{verdict.get('requirement')} violated on {verdict.get('log')} at "
            f"{format_offset(lay.viol_ns, lay.start)}")


def _draw_legend(svg: _Svg, x0: float, y: float) -> float:
    """The legend row at ``y``; returns the y below it."""
    lx = x0
    legend = [("scope", "scope interval"), ("window", "response window"),
              ("trigger", "trigger"), ("violation", "violation"), ("ltl3", "LTL3 verdict")]
    for key, label in legend:
        if key in ("scope", "window"):
            svg.rect(lx, y + 2, 14, 10, COLORS[key],
                     f' stroke="{COLORS[key + "_edge"]}" stroke-width="1"')
        else:
            dash = ' stroke-dasharray="4 3"' if key == "ltl3" else ""
            svg.line(lx + 7, y, lx + 7, y + 14, COLORS[key], 2.5, dash)
        svg.text(lx + 19, y + 11, label)
        lx += 19 + 7 * len(label) + 22
    svg.text(8, y + 11, "log time [s]", fill=COLORS["muted"])
    return y + 26


def _draw_overview(svg: _Svg, lay: Timeline, y: float) -> float:
    """The whole log as one bar with the marks and frames around the detail windows, and
    its time axis; returns the y below it."""
    x0, start, log_end = lay.x0, lay.start, lay.log_end
    ov_y, ov_h = y + 14, 22
    svg.text(8, ov_y + 15, "whole log", size=12, extra=' font-weight="600"')
    span = max(1, log_end - start)

    def ox(ns: int) -> float:
        return x0 + (PLOT_X1 - x0) * (min(max(ns, start), log_end) - start) / span

    svg.add('<g data-part="overview">')
    svg.rect(x0, ov_y, PLOT_X1 - x0, ov_h, "#f5f7f8",
             f' stroke="{COLORS["axis"]}" stroke-width="0.6"')
    if lay.scope_ab:
        a, b = lay.scope_ab
        svg.rect(ox(a), ov_y, ox(b) - ox(a), ov_h, COLORS["scope"],
                 f' data-mark="scope" data-ns="{a}"')
    if lay.win_ab:
        a, b = lay.win_ab
        svg.rect(ox(a), ov_y + 4, max(1.5, ox(b) - ox(a)), ov_h - 8,
                 COLORS["window"], f' stroke="{COLORS["window_edge"]}" stroke-width="0.8"'
                 f' data-mark="window" data-ns="{a}"')
    if lay.damage is not None:
        svg.rect(ox(lay.damage), ov_y, PLOT_X1 - ox(lay.damage), ov_h, COLORS["damage"],
                 f' opacity="0.5" data-mark="damage" data-ns="{lay.damage}"')
    for s in lay.segs:
        svg.rect(ox(s.a), ov_y - 3, max(2.0, ox(s.b) - ox(s.a)), ov_h + 6, "none",
                 f' stroke="{COLORS["detail"]}" stroke-width="1.2" data-mark="detail"'
                 f' data-ns="{s.a}"')
    for kind, ns, _ in sorted(lay.marks, key=lambda m: {"ltl3": 0, "trigger": 1}.get(m[0], 2)):
        dash = ' stroke-dasharray="4 3"' if kind == "ltl3" else ""
        svg.line(ox(ns), ov_y - 4, ox(ns), ov_y + ov_h + 4, COLORS[kind], 2.0,
                 f'{dash} data-mark="{kind}" data-ns="{ns}"')
    svg.add("</g>")
    # overview axis
    step = nice_step_ns(span, PLOT_X1 - x0, 60)
    dec = step_decimals(step)
    t = 0
    while start + t <= log_end:
        x = ox(start + t)
        svg.line(x, ov_y + ov_h, x, ov_y + ov_h + 4, COLORS["axis"], 0.8)
        svg.text(x, ov_y + ov_h + 15, f"{t / 1e9:.{dec}f}", size=10, fill=COLORS["muted"],
                 anchor="middle")
        t += step
    return ov_y + ov_h + 30


def _place_labels(lay: Timeline) -> tuple[list[tuple[str, float, int, str]], int]:
    """The marker labels placed left to right in rows so that none overlaps:
    ((kind, x, row, label) ..., number of rows)."""
    label_rows: list[float] = []   # right end of the last label on each row
    placed: list[tuple[str, float, int, str]] = []
    for kind, ns, label in sorted(lay.marks, key=lambda m: (lay.axis.x(m[1])[0], m[0])):
        x, _ = lay.axis.x(ns)
        w = 6.3 * len(label)
        anchor_x = min(x + 4, PLOT_X1 - w) if x + 4 + w > WIDTH - 2 else x + 4
        row = next((i for i, r in enumerate(label_rows) if r < anchor_x - 6), None)
        if row is None:
            row = len(label_rows)
            label_rows.append(0.0)
        label_rows[row] = anchor_x + w
        placed.append((kind, anchor_x, row, label))
    return placed, max(1, len(label_rows))


def _draw_detail(svg: _Svg, lay: Timeline, y: float) -> _Detail:
    """The detail part at ``y``: the marker labels, the scope / window / damage bands, one
    lane per variable and topic, the vertical markers."""
    svg.text(8, y + 12, "detail", size=12, extra=' font-weight="600"')
    placed, n_rows = _place_labels(lay)
    lab_y0 = y + 4
    lanes_y0 = lab_y0 + 14 * n_rows + 6
    heights = [BOOL_H if k == "bool" else NUM_H if k == "num" else TOPIC_H
               for k, _, _ in lay.lanes]
    lanes_h = sum(heights) + LANE_GAP * max(0, len(lay.lanes) - 1) if lay.lanes else 24
    det = _Detail(lab_y0, lanes_y0, lanes_h, lanes_y0 + lanes_h, heights)
    svg.add('<g data-part="detail">')
    _draw_bands(svg, lay, det)
    _draw_lanes(svg, lay, det)
    _draw_markers(svg, lay, det)
    for kind, ax, row, label in placed:
        svg.text(ax, lab_y0 + 11 + 14 * row, label, size=11, fill=COLORS[kind],
                 extra=' font-weight="600"')
    svg.add("</g>")
    return det


def _draw_bands(svg: _Svg, lay: Timeline, det: _Detail) -> None:
    """The detail windows' backgrounds, then the scope, window and damage bands."""
    for s in lay.segs:
        svg.rect(s.p, det.lanes_y0 - 2, s.q - s.p, det.lanes_h + 4, "#fafbfc",
                 f' stroke="{COLORS["grid"]}" stroke-width="1"')

    def band(ab, color, kind, edge=None):
        for s in lay.segs:
            lo, hi = max(ab[0], s.a), min(ab[1], s.b)
            if lo < hi:
                bx0, bx1 = lay.axis.x(lo)[0], lay.axis.x(hi)[0]
                extra = f' data-mark="{kind}" data-ns="{ab[0]}"'
                if edge:
                    extra += f' stroke="{edge}" stroke-width="0.8"'
                svg.rect(bx0, det.lanes_y0 - 2, bx1 - bx0, det.lanes_h + 4, color, extra)

    if lay.scope_ab:
        band(lay.scope_ab, COLORS["scope"], "scope")
    if lay.win_ab:
        band(lay.win_ab, COLORS["window"], "window", COLORS["window_edge"])
    if lay.damage is not None:
        band((lay.damage, lay.log_end), COLORS["damage"], "damage")


def _draw_lanes(svg: _Svg, lay: Timeline, det: _Detail) -> None:
    """One group per lane: its label and its drawing."""
    ly = det.lanes_y0
    for (kind, name, rows), h in zip(lay.lanes, det.heights):
        svg.add(f'<g data-lane={quoteattr(name)} data-kind="{kind}">')
        label = lane_label(kind, name)
        svg.text(lay.x0 - (16 if kind == "bool" else 8), ly + min(h, 26) / 2 + 4, label,
                 size=11, anchor="end",
                 fill=COLORS["topic"] if kind == "topic" else COLORS["text"],
                 extra=' font-family="ui-monospace,Menlo,Consolas,monospace"')
        cs = cells(rows, lay.ticks, lay.period)
        if kind == "bool":
            _bool_lane(svg, lay.axis, lay.segs, cs, ly, h)
        elif kind == "num":
            _num_lane(svg, lay.axis, lay.segs, cs, ly, h, lay.thresholds.get(name, []))
        else:
            _topic_lane(svg, lay.axis, lay.segs, rows, ly, h, lay.start, lay.period)
        svg.add("</g>")
        ly += h + LANE_GAP


def _draw_markers(svg: _Svg, lay: Timeline, det: _Detail) -> None:
    """Vertical markers over the lanes (the violation drawn last: on top when they meet),
    and the violated tick's cell under them."""
    draw_order = {"ltl3": 0, "trigger": 1, "violation": 2}
    for kind, ns, _label in sorted(lay.marks, key=lambda m: draw_order[m[0]]):
        x, where = lay.axis.x(ns)
        dash = ' stroke-dasharray="5 3"' if kind == "ltl3" else ""
        svg.line(x, det.lab_y0 + 2, x, det.lanes_y1 + 2, COLORS[kind],
                 2.0 if kind != "ltl3" else 1.6,
                 f'{dash} data-mark="{kind}" data-ns="{ns}"'
                 + (f' data-clipped="{where}"' if where else ""))
        if kind == "violation":
            cell_end = lay.axis.x(ns + lay.period)[0]
            svg.rect(x, det.lanes_y1 + 2, max(2.0, cell_end - x), 5, COLORS["violation"])


def _draw_detail_axis(svg: _Svg, lay: Timeline, det: _Detail) -> float:
    """The detail time axis, one stretch per window, and the breaks between windows
    (labelled with the time skipped); returns the y below it."""
    start, segs = lay.start, lay.segs
    ay = det.lanes_y1 + 10
    for i, s in enumerate(segs):
        svg.line(s.p, ay, s.q, ay, COLORS["axis"], 0.8)
        step = nice_step_ns(s.b - s.a, s.q - s.p, 64)
        dec = step_decimals(step)
        first = -(-(s.a - start) // step) * step
        t = first
        while start + t <= s.b:
            x = lay.axis.x(start + t)[0]
            svg.line(x, ay, x, ay + 4, COLORS["axis"], 0.8)
            svg.text(x, ay + 15, f"{t / 1e9:.{dec}f}", size=10, fill=COLORS["muted"],
                     anchor="middle")
            t += step
        if i + 1 < len(segs):
            _draw_break(svg, s, segs[i + 1], det, ay)
    return ay + 34


def _draw_break(svg: _Svg, s: Segment, nxt: Segment, det: _Detail, ay: float) -> None:
    mid_y = det.lanes_y0 + det.lanes_h / 2
    mx = (s.q + nxt.p) / 2
    for dx in (-3, 3):
        svg.line(mx + dx - 3, mid_y + 8, mx + dx + 3, mid_y - 8, COLORS["axis"], 1.2)
        svg.line(mx + dx - 3, ay + 5, mx + dx + 3, ay - 5, COLORS["axis"], 1.2)
    svg.text(mx, mid_y + 22, format_offset(nxt.a, s.b, decimals=1),
             size=9, fill=COLORS["muted"], anchor="middle")
    svg.text(mx, mid_y + 32, "skipped", size=9, fill=COLORS["muted"], anchor="middle")


def _draw_notes(svg: _Svg, lay: Timeline, y: float) -> float:
    """The notes under the picture (time base, lane legend, what lies outside the
    windows); returns the y of the last line."""
    start, segs = lay.start, lay.segs
    notes = []
    if lay.scope_ab and lay.scope_ab[0] < segs[0].a:
        notes.append(f"scope interval from {format_offset(lay.scope_ab[0], start)}")
    if lay.win_ab and lay.win_ab[0] < segs[0].a:
        notes.append(f"response window from {format_offset(lay.win_ab[0], start)}")
    if lay.win_past_end:
        notes.append("response window reaches past the end of the log"
                     + (f" (tick {lay.window['end_tick']})" if lay.window else ""))
    if lay.damage is not None:
        notes.append(f"log damaged at {format_offset(lay.damage, start)} (partial)")
    paragraphs = [f"time: s since the log's start, its first message (t0 = {start} ns log "
                  f"time); tick k drawn from its time to the next tick "
                  f"({lay.period / 1e6:g} ms)",
                  "boolean lanes: filled where true; topic lanes: a dot at the log time of "
                  "each message held (sample-and-hold)"]
    if notes:
        paragraphs.append("; ".join(notes))
    width = int((WIDTH - lay.x0 - 8) / NOTE_CHAR_W)  # characters that fit on a line
    first = True
    for text in paragraphs:
        for line in textwrap.wrap(text, width) or [""]:
            if not first:
                y += 14
            first = False
            svg.text(lay.x0, y, line, size=10, fill=COLORS["muted"])
    return y


def _bool_lane(svg: _Svg, axis: Axis, segs: list[Segment], lane_cells, y: float,
               h: float) -> None:
    hi, lo = y + 3, y + h - 3
    svg.line(axis.x0, lo, PLOT_X1, lo, COLORS["grid"], 0.6)
    svg.text(axis.x0 - 4, hi + 6, "T", size=8, fill=COLORS["muted"], anchor="end")
    svg.text(axis.x0 - 4, lo + 1, "F", size=8, fill=COLORS["muted"], anchor="end")
    for s, cs in cells_by_segment(segs, lane_cells):
        pts = []
        for a, b, v in cs:
            x0, x1 = axis.x(a)[0], axis.x(min(b, s.b))[0]
            level = hi if v is True else lo
            if v is True:
                svg.rect(x0, hi, x1 - x0, lo - hi, COLORS["bool"], ' opacity="0.28"')
            pts.append((x0, level))
            pts.append((x1, level))
        if pts:
            svg.add(f'<polyline points="{" ".join(f"{_f(px)},{_f(py)}" for px, py in pts)}" '
                    f'fill="none" stroke="{COLORS["bool"]}" stroke-width="1.6"/>')


def _num_lane(svg: _Svg, axis: Axis, segs: list[Segment], lane_cells, y: float, h: float,
              thresholds: list[Threshold]) -> None:
    finite = [x for x in (_num(v) for _, _, v in lane_cells) if x is not None and math.isfinite(x)]
    lo_v = min(finite) if finite else 0.0
    hi_v = max(finite) if finite else 1.0
    for t in thresholds:
        if finite and (lo_v - (hi_v - lo_v) <= t.value <= hi_v + (hi_v - lo_v)):
            lo_v, hi_v = min(lo_v, t.value), max(hi_v, t.value)
    if hi_v == lo_v:
        pad = abs(hi_v) * 0.1 or 1.0
        lo_v, hi_v = lo_v - pad, hi_v + pad
    pad = (hi_v - lo_v) * 0.08
    lo_v, hi_v = lo_v - pad, hi_v + pad
    top, bot = y + 4, y + h - 4

    def vy(v: float) -> float:
        if v == math.inf:
            return top
        if v == -math.inf:
            return bot
        return bot - (bot - top) * (v - lo_v) / (hi_v - lo_v)

    svg.line(axis.x0, bot, PLOT_X1, bot, COLORS["grid"], 0.6)
    svg.line(axis.x0 - 3, top, axis.x0, top, COLORS["axis"], 0.8)
    svg.line(axis.x0 - 3, bot, axis.x0, bot, COLORS["axis"], 0.8)
    svg.text(axis.x0 - 5, top + 22, f"max {hi_v - pad:.4g}", size=9, fill=COLORS["muted"],
             anchor="end")
    svg.text(axis.x0 - 5, bot, f"min {lo_v + pad:.4g}", size=9, fill=COLORS["muted"],
             anchor="end")
    for t in thresholds:
        if lo_v <= t.value <= hi_v:
            ty = vy(t.value)
            svg.line(axis.x0, ty, PLOT_X1, ty, COLORS["threshold"], 1.0,
                     f' stroke-dasharray="6 4" opacity="0.8" data-mark="threshold"'
                     f' data-value="{t.value:g}"')
            svg.text(PLOT_X1 - 2, ty - 3, f"{t.variable} {t.op} {t.value:g}", size=9,
                     fill=COLORS["threshold"], anchor="end")
    for s, cs in cells_by_segment(segs, lane_cells):
        path: list[str] = []
        pen = False
        for a, b, v in cs:
            x = _num(v)
            x0, x1 = axis.x(a)[0], axis.x(min(b, s.b))[0]
            if x is None or math.isnan(x):
                pen = False
                svg.text((x0 + x1) / 2, bot - 2, "NaN", size=8, fill=COLORS["violation"],
                         anchor="middle")
                continue
            yy = vy(x)
            path.append(f"{'L' if pen else 'M'}{_f(x0)},{_f(yy)} L{_f(x1)},{_f(yy)}")
            pen = True
        if path:
            svg.add(f'<path d="{" ".join(path)}" fill="none" stroke="{COLORS["numeric"]}" '
                    'stroke-width="1.6"/>')


def _topic_lane(svg: _Svg, axis: Axis, segs: list[Segment], rows, y: float, h: float,
                start: int, period: int) -> None:
    cy = y + h / 2
    svg.line(axis.x0, cy, PLOT_X1, cy, COLORS["grid"], 0.6)
    held = sorted({int(r["message_log_time_ns"]) for r in rows
                   if r.get("message_log_time_ns") is not None})
    for s in segs:
        inside = [t for t in held if s.a <= t < s.b]
        for t in inside:
            svg.add(f'<circle cx="{_f(axis.x(t)[0])}" cy="{_f(cy)}" r="2.6" '
                    f'fill="{COLORS["topic"]}" data-mark="message" data-ns="{t}"/>')
        seg_rows = [r for r in rows if s.a <= int(r["time_ns"]) < s.b]
        older = [int(r["message_log_time_ns"]) for r in seg_rows
                 if r.get("message_log_time_ns") is not None
                 and int(r["message_log_time_ns"]) < s.a - period]
        if older:
            svg.text(s.p + 3, cy - 3,
                     f"\u2190 held from {format_offset(min(older), start)}", size=9,
                     fill=COLORS["topic"])
        if any(r.get("message_log_time_ns") is None for r in seg_rows):
            svg.text(s.p + 3, cy + 9, "no message yet", size=9, fill=COLORS["topic"])
