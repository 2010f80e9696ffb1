"""Timeline plots of a violation as inline SVG, for the traceability report (``fretc report``).

A small deterministic SVG writer (no matplotlib, no JavaScript, no external fonts): the same
verdict gives byte-identical text. Input is the audit's JSON (schema ``fretc-audit/1``, see
:mod:`monitors.report_model`): one verdict object and the log object it belongs to.

The picture, top to bottom, all in log time (seconds since the log's first tick
``start_time_ns``, what Foxglove shows as elapsed time):

* a legend;
* **whole log** - one bar from the first to the last tick, with the scope interval, the
  response window, the trigger, the first violation, the LTL3 verdict time, the damage of a
  partial log, and grey frames around the stretches drawn in detail below;
* **detail** - one lane per FRET variable the audit sampled around the trigger and the
  violation (``values``: boolean lanes filled where the variable is true, numeric lanes as a
  sample-and-hold step line with the requirement's comparison thresholds dashed), and one lane
  per bound topic with a dot at the log time of every message held at those ticks
  (``sources``: a gap in the dots is a silent topic). The audit only carries values in
  windows of a few ticks around the trigger and the violation, so the time axis is broken
  between windows (the break is labelled with the time skipped); nothing is interpolated
  across a break. Tick ``k`` is drawn as the cell from its time to the next tick's time.

Every marker carries ``data-mark`` and ``data-ns`` (log time, integer ns) attributes so tests
and tools can check the picture against the JSON.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple
from xml.sax.saxutils import escape as _xml_escape, quoteattr as _xml_quoteattr

from fretish.textsafe import xml_text


def escape(s: str) -> str:
    """XML character data from the inputs: control and bidi characters shown escaped
    (:func:`fretish.textsafe.xml_text`: a NUL must not make the SVG unparseable)."""
    return _xml_escape(xml_text(s, keep=""))


def quoteattr(s: str) -> str:
    """A quoted XML attribute value, made safe like :func:`escape`."""
    return _xml_quoteattr(xml_text(s, keep=""))

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

WIDTH = 980
LABEL_MIN_W = 120      # lane labels on the left: as wide as the longest label needs
LABEL_MAX_W = 300
MONO_CHAR_W = 6.7      # width of a character of the 11 px monospace lane labels
RIGHT_PAD = 24
PLOT_X1 = WIDTH - RIGHT_PAD
BREAK_W = 34           # width of an axis break between two detail windows
MIN_SEG_W = 150        # narrowest detail window
BOOL_H = 26
NUM_H = 64
TOPIC_H = 20
LANE_GAP = 8
FONT = "system-ui,-apple-system,'Segoe UI',Roboto,Helvetica,Arial,sans-serif"


@dataclass(frozen=True)
class Threshold:
    """A comparison of a numeric variable with a constant in the requirement (``clearance >
    0``): drawn as a dashed line in that variable's lane. ``op`` is FRET's comparison
    operator, ``value`` the constant."""

    variable: str
    op: str
    value: float


def _f(x: float) -> str:
    """A coordinate, rounded to 0.1 px, without a trailing ``.0``."""
    s = f"{x:.1f}"
    return s[:-2] if s.endswith(".0") else s


def _secs(ns: int, start: int, decimals: int = 3) -> str:
    return f"{(ns - start) / 1e9:.{decimals}f}"


def _num(v: Any) -> Optional[float]:
    """A JSON value as a float: ``"nan"``, ``"inf"`` and ``"-inf"`` (how the audit writes
    non-finite values) become floats; booleans 0/1; anything else None."""
    if isinstance(v, bool):
        return 1.0 if v else 0.0
    if isinstance(v, (int, float)):
        return float(v)
    if v in ("nan", "inf", "-inf"):
        return float(v)
    return None


def _fmt_value(v: Any) -> str:
    if isinstance(v, bool):
        return "T" if v else "F"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


@dataclass
class _Seg:
    """One detail window: ticks ``t0..t1`` (inclusive), times ``a..b`` ns (b = end of the
    last tick's cell), pixels ``p..q``."""

    t0: int
    t1: int
    a: int
    b: int
    p: float = 0.0
    q: float = 0.0


@dataclass
class _Svg:
    parts: List[str] = field(default_factory=list)

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


def _nice_step_ns(span_ns: float, px: float, min_px: float = 72.0) -> int:
    """The smallest 1-2-5 step (ns) that keeps tick labels at least ``min_px`` apart."""
    if span_ns <= 0 or px <= 0:
        return 10**9
    per_px = span_ns / px
    for exp in range(3, 13):          # 1 us .. 1000 s
        for m in (1, 2, 5):
            step = m * 10**exp
            if step / per_px >= min_px:
                return step
    return 10**12


def _step_decimals(step_ns: int) -> int:
    return max(0, min(6, -int(math.floor(math.log10(step_ns / 1e9) + 1e-9))))


def _tick_times(values: Dict[str, list], sources: Dict[str, list]) -> Dict[int, int]:
    """tick -> time_ns over every sampled row."""
    out: Dict[int, int] = {}
    for rows in list(values.values()) + list(sources.values()):
        for r in rows:
            if isinstance(r, dict) and r.get("tick") is not None and r.get("time_ns") is not None:
                out[int(r["tick"])] = int(r["time_ns"])
    return out


def _period_ns(ticks: Dict[int, int], period_ns: Optional[int]) -> int:
    if period_ns:
        return int(period_ns)
    ks = sorted(ticks)
    diffs = sorted(ticks[b] - ticks[a] for a, b in zip(ks, ks[1:]) if b == a + 1)
    if diffs:
        return max(1, diffs[len(diffs) // 2])
    return 10**8


def _segments(ticks: Dict[int, int], period: int) -> List[_Seg]:
    ks = sorted(ticks)
    segs: List[_Seg] = []
    for k in ks:
        if segs and k == segs[-1].t1 + 1:
            segs[-1].t1 = k
        else:
            segs.append(_Seg(k, k, ticks[k], 0))
    for s in segs:
        s.b = ticks[s.t1] + period
    return segs


def _layout(segs: List[_Seg], x0: float) -> None:
    """Give each detail window its pixels: widths proportional to duration, none narrower
    than MIN_SEG_W, BREAK_W between windows."""
    n = len(segs)
    avail = (PLOT_X1 - x0) - BREAK_W * (n - 1)
    durs = [max(1, s.b - s.a) for s in segs]
    widths = [avail * d / sum(durs) for d in durs]
    small = [i for i, w in enumerate(widths) if w < MIN_SEG_W]
    if small and len(small) < n:
        rest = avail - MIN_SEG_W * len(small)
        big = [i for i in range(n) if i not in small]
        tot = sum(durs[i] for i in big)
        widths = [MIN_SEG_W if i in small else rest * durs[i] / tot for i in range(n)]
    elif small:
        widths = [avail / n] * n
    x = x0
    for s, w in zip(segs, widths):
        s.p, s.q = x, x + w
        x += w + BREAK_W


class _Axis:
    """Log time (ns) -> x over the broken detail axis. ``clip`` tells whether a time fell
    outside every window (before the first, after the last: clamped to the edge; in a break:
    placed proportionally inside the break)."""

    def __init__(self, segs: List[_Seg], x0: float):
        self.segs = segs
        self.x0 = x0

    def x(self, ns: int) -> Tuple[float, str]:
        segs = self.segs
        if ns < segs[0].a:
            return segs[0].p, "before"
        for i, s in enumerate(segs):
            if s.a <= ns <= s.b:
                return s.p + (s.q - s.p) * (ns - s.a) / max(1, s.b - s.a), ""
            if i + 1 < len(segs) and s.b < ns < segs[i + 1].a:
                nxt = segs[i + 1]
                return s.q + (nxt.p - s.q) * (ns - s.b) / max(1, nxt.a - s.b), "break"
        return segs[-1].q, "after"


def _tp(d: Optional[dict], key_ns: str = "time_ns") -> Optional[int]:
    if not d:
        return None
    v = d.get(key_ns)
    return int(v) if v is not None else None


def timeline_svg(verdict: dict, log: dict, *, period_ns: Optional[int] = None,
                 thresholds: Sequence[Threshold] = (), title: str = "") -> str:
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

    Returns:
        SVG text, deterministic for equal input.

    Raises:
        ValueError: the verdict has no ``first_violation`` or the log no ``start_time_ns``.
    """
    fv = verdict.get("first_violation")
    if not fv:
        raise ValueError(f"{verdict.get('requirement')}: not violated, no timeline")
    start = log.get("start_time_ns")
    if start is None:
        raise ValueError(f"{log.get('log')}: no start time")
    start = int(start)
    end = int(log.get("end_time_ns") or fv["log_time_ns"])
    values: Dict[str, list] = verdict.get("values") or {}
    sources: Dict[str, list] = verdict.get("sources") or {}
    ticks = _tick_times(values, sources)
    period = _period_ns(ticks, period_ns)
    if not ticks:  # no sampled values: one window around the violation
        ticks = {int(fv["tick"]): int(fv["log_time_ns"])}
    segs = _segments(ticks, period)
    log_end = end + period

    # ---- the marks, in log time
    marks: List[Tuple[str, int, str]] = []   # (kind, ns, label)
    trig = fv.get("trigger")
    viol_ns = int(fv["log_time_ns"])
    scope = fv.get("scope_interval")
    window = fv.get("window")
    ltl3 = verdict.get("ltl3") or {}
    ltl3_ns = ltl3.get("time_ns") if ltl3.get("status") in ("violated", "satisfied") else None
    if trig:
        marks.append(("trigger", int(trig["time_ns"]),
                      f"trigger {_secs(int(trig['time_ns']), start)} s (#{trig['tick']})"))
    marks.append(("violation", viol_ns, f"violation {_secs(viol_ns, start)} s (#{fv['tick']})"))
    if ltl3_ns is not None:
        marks.append(("ltl3", int(ltl3_ns),
                      f"LTL3 {ltl3['status']} {_secs(int(ltl3_ns), start)} s (#{ltl3['tick']})"))
    damage = log.get("damage_time_ns")

    scope_ab = None
    if scope:
        scope_ab = (int(scope["start"]["time_ns"]), int(scope["end"]["time_ns"]) + period)
    win_ab = None
    win_past_end = False
    if window and window.get("start_time_ns") is not None:
        hi = window.get("end_time_ns")
        win_past_end = hi is None or int(hi) > end
        hi_ns = (int(hi) if hi is not None else end) + period
        win_ab = (int(window["start_time_ns"]), min(hi_ns, log_end))

    # ---- lanes
    lanes: List[Tuple[str, str, Any]] = []   # (kind, name, rows)
    th_by_var: Dict[str, List[Threshold]] = {}
    for t in thresholds:
        th_by_var.setdefault(t.variable, []).append(t)
    for name in values:   # audit order (the monitor's VARIABLES)
        rows = [r for r in values[name] if isinstance(r, dict)]
        kind = "bool" if rows and all(isinstance(r.get("value"), bool) for r in rows) else "num"
        lanes.append((kind, name, rows))
    for topic in sorted(sources):
        lanes.append(("topic", topic, [r for r in sources[topic] if isinstance(r, dict)]))
    longest = max([len(_lane_label(k, n)) for k, n, _ in lanes] + [10])
    x0 = min(LABEL_MAX_W, max(LABEL_MIN_W, MONO_CHAR_W * longest + 26))
    _layout(segs, x0)
    axis = _Axis(segs, x0)

    svg = _Svg()
    y = 6.0
    # ---- legend
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
    y += 26

    # ---- overview of the whole log
    ov_y, ov_h = y + 14, 22
    svg.text(8, ov_y + 15, "whole log", size=12, extra=' font-weight="600"')
    span = max(1, log_end - start)

    def ox(ns: int) -> float:
        return x0 + (PLOT_X1 - x0) * (min(max(ns, start), log_end) - start) / span

    svg.add('<g data-part="overview">')
    svg.rect(x0, ov_y, PLOT_X1 - x0, ov_h, "#f5f7f8",
             f' stroke="{COLORS["axis"]}" stroke-width="0.6"')
    if scope_ab:
        svg.rect(ox(scope_ab[0]), ov_y, ox(scope_ab[1]) - ox(scope_ab[0]), ov_h, COLORS["scope"],
                 f' data-mark="scope" data-ns="{scope_ab[0]}"')
    if win_ab:
        svg.rect(ox(win_ab[0]), ov_y + 4, max(1.5, ox(win_ab[1]) - ox(win_ab[0])), ov_h - 8,
                 COLORS["window"], f' stroke="{COLORS["window_edge"]}" stroke-width="0.8"'
                 f' data-mark="window" data-ns="{win_ab[0]}"')
    if damage is not None:
        svg.rect(ox(int(damage)), ov_y, PLOT_X1 - ox(int(damage)), ov_h, COLORS["damage"],
                 f' opacity="0.5" data-mark="damage" data-ns="{int(damage)}"')
    for s in segs:
        svg.rect(ox(s.a), ov_y - 3, max(2.0, ox(s.b) - ox(s.a)), ov_h + 6, "none",
                 f' stroke="{COLORS["detail"]}" stroke-width="1.2" data-mark="detail"'
                 f' data-ns="{s.a}"')
    for kind, ns, _ in sorted(marks, key=lambda m: {"ltl3": 0, "trigger": 1}.get(m[0], 2)):
        dash = ' stroke-dasharray="4 3"' if kind == "ltl3" else ""
        svg.line(ox(ns), ov_y - 4, ox(ns), ov_y + ov_h + 4, COLORS[kind], 2.0,
                 f'{dash} data-mark="{kind}" data-ns="{ns}"')
    svg.add("</g>")
    # overview axis
    step = _nice_step_ns(span, PLOT_X1 - x0, 60)
    dec = _step_decimals(step)
    t = 0
    while start + t <= log_end:
        x = ox(start + t)
        svg.line(x, ov_y + ov_h, x, ov_y + ov_h + 4, COLORS["axis"], 0.8)
        svg.text(x, ov_y + ov_h + 15, f"{t / 1e9:.{dec}f}", size=10, fill=COLORS["muted"],
                 anchor="middle")
        t += step
    y = ov_y + ov_h + 30

    # ---- detail: marker labels
    svg.text(8, y + 12, "detail", size=12, extra=' font-weight="600"')
    label_rows: List[float] = []   # right end of the last label on each row
    placed: List[Tuple[str, float, int, str]] = []
    for kind, ns, label in sorted(marks, key=lambda m: (axis.x(m[1])[0], m[0])):
        x, _ = axis.x(ns)
        w = 6.3 * len(label)
        anchor_x = min(x + 4, PLOT_X1 - w) if x + 4 + w > WIDTH - 2 else x + 4
        row = next((i for i, r in enumerate(label_rows) if r < anchor_x - 6), None)
        if row is None:
            row = len(label_rows)
            label_rows.append(0.0)
        label_rows[row] = anchor_x + w
        placed.append((kind, anchor_x, row, label))
    n_rows = max(1, len(label_rows))
    lab_y0 = y + 4
    lanes_y0 = lab_y0 + 14 * n_rows + 6
    # lane heights
    heights = [BOOL_H if k == "bool" else NUM_H if k == "num" else TOPIC_H for k, _, _ in lanes]
    lanes_h = sum(heights) + LANE_GAP * max(0, len(lanes) - 1) if lanes else 24
    lanes_y1 = lanes_y0 + lanes_h

    # ---- detail: background bands
    svg.add('<g data-part="detail">')
    for s in segs:
        svg.rect(s.p, lanes_y0 - 2, s.q - s.p, lanes_h + 4, "#fafbfc",
                 f' stroke="{COLORS["grid"]}" stroke-width="1"')

    def band(ab, color, kind, edge=None):
        for s in segs:
            lo, hi = max(ab[0], s.a), min(ab[1], s.b)
            if lo < hi:
                bx0, bx1 = axis.x(lo)[0], axis.x(hi)[0]
                extra = f' data-mark="{kind}" data-ns="{ab[0]}"'
                if edge:
                    extra += f' stroke="{edge}" stroke-width="0.8"'
                svg.rect(bx0, lanes_y0 - 2, bx1 - bx0, lanes_h + 4, color, extra)

    if scope_ab:
        band(scope_ab, COLORS["scope"], "scope")
    if win_ab:
        band(win_ab, COLORS["window"], "window", COLORS["window_edge"])
    if damage is not None:
        band((int(damage), log_end), COLORS["damage"], "damage")

    # ---- lanes
    ly = lanes_y0
    for (kind, name, rows), h in zip(lanes, heights):
        svg.add(f'<g data-lane={quoteattr(name)} data-kind="{kind}">')
        label = _lane_label(kind, name)
        svg.text(x0 - (16 if kind == "bool" else 8), ly + min(h, 26) / 2 + 4, label, size=11,
                 anchor="end",
                 fill=COLORS["topic"] if kind == "topic" else COLORS["text"],
                 extra=' font-family="ui-monospace,Menlo,Consolas,monospace"')
        cells = _cells(rows, ticks, period)
        if kind == "bool":
            _bool_lane(svg, axis, segs, cells, ly, h)
        elif kind == "num":
            _num_lane(svg, axis, segs, cells, ly, h, th_by_var.get(name, []))
        else:
            _topic_lane(svg, axis, segs, rows, ly, h, start, period)
        svg.add("</g>")
        ly += h + LANE_GAP

    # ---- vertical markers over the lanes (the violation drawn last: on top when they meet)
    draw_order = {"ltl3": 0, "trigger": 1, "violation": 2}
    for kind, ns, label in sorted(marks, key=lambda m: draw_order[m[0]]):
        x, where = axis.x(ns)
        dash = ' stroke-dasharray="5 3"' if kind == "ltl3" else ""
        svg.line(x, lab_y0 + 2, x, lanes_y1 + 2, COLORS[kind], 2.0 if kind != "ltl3" else 1.6,
                 f'{dash} data-mark="{kind}" data-ns="{ns}"'
                 + (f' data-clipped="{where}"' if where else ""))
        if kind == "violation":
            cell_end = axis.x(ns + period)[0]
            svg.rect(x, lanes_y1 + 2, max(2.0, cell_end - x), 5, COLORS["violation"])
    for kind, ax, row, label in placed:
        svg.text(ax, lab_y0 + 11 + 14 * row, label, size=11, fill=COLORS[kind],
                 extra=' font-weight="600"')
    svg.add("</g>")

    # ---- detail time axis and breaks
    ay = lanes_y1 + 10
    for i, s in enumerate(segs):
        svg.line(s.p, ay, s.q, ay, COLORS["axis"], 0.8)
        step = _nice_step_ns(s.b - s.a, s.q - s.p, 64)
        dec = _step_decimals(step)
        first = -(-(s.a - start) // step) * step
        t = first
        while start + t <= s.b:
            x = axis.x(start + t)[0]
            svg.line(x, ay, x, ay + 4, COLORS["axis"], 0.8)
            svg.text(x, ay + 15, f"{t / 1e9:.{dec}f}", size=10, fill=COLORS["muted"],
                     anchor="middle")
            t += step
        if i + 1 < len(segs):
            nxt = segs[i + 1]
            mx = (s.q + nxt.p) / 2
            for dx in (-3, 3):
                svg.line(mx + dx - 3, lanes_y0 + lanes_h / 2 + 8, mx + dx + 3,
                         lanes_y0 + lanes_h / 2 - 8, COLORS["axis"], 1.2)
                svg.line(mx + dx - 3, ay + 5, mx + dx + 3, ay - 5, COLORS["axis"], 1.2)
            svg.text(mx, lanes_y0 + lanes_h / 2 + 22, f"{(nxt.a - s.b) / 1e9:.1f} s",
                     size=9, fill=COLORS["muted"], anchor="middle")
            svg.text(mx, lanes_y0 + lanes_h / 2 + 32, "skipped", size=9,
                     fill=COLORS["muted"], anchor="middle")
    y = ay + 34
    notes = []
    if scope_ab and scope_ab[0] < segs[0].a:
        notes.append(f"scope interval from {_secs(scope_ab[0], start)} s")
    if win_ab and win_ab[0] < segs[0].a:
        notes.append(f"response window from {_secs(win_ab[0], start)} s")
    if win_past_end:
        notes.append("response window reaches past the end of the log"
                     + (f" (tick {window['end_tick']})" if window else ""))
    if damage is not None:
        notes.append(f"log damaged at {_secs(int(damage), start)} s (partial)")
    svg.text(x0, y, f"time: s since the log's first tick (t0 = {start} ns log time); tick k "
             f"drawn from its time to the next tick ({period / 1e6:g} ms)", size=10,
             fill=COLORS["muted"])
    y += 14
    svg.text(x0, y, "boolean lanes: filled where true; topic lanes: a dot at the log time of "
             "each message held (sample-and-hold)", size=10, fill=COLORS["muted"])
    if notes:
        y += 14
        svg.text(x0, y, "; ".join(notes), size=10, fill=COLORS["muted"])
    height = int(y + 10)
    head = (f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH} {height}" '
            f'width="{WIDTH}" height="{height}" role="img" font-family="{FONT}" '
            f'class="timeline" data-requirement={quoteattr(str(verdict.get("requirement")))} '
            f'data-log={quoteattr(str(verdict.get("log")))}>')
    body = [head, f"<title>{escape(title or _default_title(verdict, start, viol_ns))}</title>",
            f'<rect x="0" y="0" width="{WIDTH}" height="{height}" fill="#ffffff"/>']
    return "\n".join(body + svg.parts + ["</svg>"]) + "\n"


def _default_title(verdict: dict, start: int, viol_ns: int) -> str:
    return (f"{verdict.get('requirement')} violated on {verdict.get('log')} at "
            f"{_secs(viol_ns, start)} s")


def _lane_label(kind: str, name: str) -> str:
    return f"{name} msgs" if kind == "topic" else name


def _cells(rows: List[dict], ticks: Dict[int, int], period: int) -> List[Tuple[int, int, Any]]:
    """(start_ns, end_ns, value) of each sampled tick: a tick's cell ends at the next tick's
    time, or one period later when the next tick was not sampled."""
    out = []
    for r in rows:
        k, ns = int(r["tick"]), int(r["time_ns"])
        nxt = ticks.get(k + 1)
        out.append((ns, nxt if nxt is not None else ns + period, r.get("value")))
    return out


def _runs(segs: List[_Seg], cells):
    """Cells grouped by detail window, in time order."""
    for s in segs:
        yield s, [c for c in cells if s.a <= c[0] < s.b]


def _bool_lane(svg: _Svg, axis: _Axis, segs, cells, y: float, h: float) -> None:
    hi, lo = y + 3, y + h - 3
    svg.line(axis.x0, lo, PLOT_X1, lo, COLORS["grid"], 0.6)
    svg.text(axis.x0 - 4, hi + 6, "T", size=8, fill=COLORS["muted"], anchor="end")
    svg.text(axis.x0 - 4, lo + 1, "F", size=8, fill=COLORS["muted"], anchor="end")
    for s, cs in _runs(segs, cells):
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


def _num_lane(svg: _Svg, axis: _Axis, segs, cells, y: float, h: float,
              thresholds: List[Threshold]) -> None:
    finite = [x for x in (_num(v) for _, _, v in cells) if x is not None and math.isfinite(x)]
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
    for s, cs in _runs(segs, cells):
        path: List[str] = []
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


def _topic_lane(svg: _Svg, axis: _Axis, segs, rows, y: float, h: float, start: int,
                period: int) -> None:
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
            svg.text(s.p + 3, cy - 3, f"\u2190 held from {_secs(min(older), start)} s",
                     size=9, fill=COLORS["topic"])
        if any(r.get("message_log_time_ns") is None for r in seg_rows):
            svg.text(s.p + 3, cy + 9, "no message yet", size=9, fill=COLORS["topic"])
