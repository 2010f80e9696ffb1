"""``fretc explain``: a requirement's reading in plain English and its diagram in FRET's
manner (the scope interval, the trigger points, the window in which the response must or
must not hold), as FRET's assistant shows them (FRET's manual, "Semantics" panel).

The diagram is not drawn from a table of pictures: it is *computed* by the audit's interval
semantics (:mod:`fretc.monitors.interval`, :mod:`fretc.monitors.obligations`) on an example trace laid
out for the requirement's template: its scope mode holds (or not) so that one scope
interval is wide, its condition rises two ticks into it, its stop condition comes a few
ticks after the trigger. The windows are those the obligation checker looks at for the
first trigger, found by running it on a response that never holds (where the response is
required) and on one that always holds (where it is forbidden). So every one of FRET's 288
template keys has a diagram, and the diagram says what the audit checks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.fretish import ast as A
from fretc.compiler.printers import expr_text

from fretc.monitors.interval import IntervalStream, Violation
from fretc.monitors.obligations import OBLIGATIONS

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["Diagram", "Explanation", "explain", "diagram", "shortest_traces", "MAX_SEARCH"]

#: The shortest-trace search: at most this many ticks and boolean variables (2^v letters).
MAX_SEARCH = (12, 5)
#: The longest duration drawn to scale: a diagram of a longer one draws it this long and
#: says so (a 10^6-tick window drawn tick by tick was a 138 MB SVG)
MAX_DRAWN_TICKS = 40

Interval = tuple[int, int]


@dataclass
class Diagram:
    """The example trace of a requirement and what the semantics makes of it: ``n`` ticks;
    ``signals`` (name -> bool per tick: the scope mode, the condition, the stop condition
    as laid out); ``scope`` intervals; ``triggers`` (of every interval); the ``required``
    and ``forbidden`` windows of the first trigger (inclusive ticks; None when the
    obligation has none) and its ``obligation`` text; ``negated``: an only* scope;
    ``bound``: the probability bound each trigger carries (FRET 3.1: per trigger)."""

    n: int
    signals: dict[str, list[bool]] = field(default_factory=dict)
    scope: list[Interval] = field(default_factory=list)
    triggers: list[int] = field(default_factory=list)
    required: Interval | None = None
    forbidden: Interval | None = None
    obligation: str = ""
    negated: bool = False
    #: the duration as drawn when the requirement's is longer than :data:`MAX_DRAWN_TICKS`
    #: (the diagram is then not to scale); None when drawn as it is
    drawn_ticks: int | None = None
    #: a probability requirement's bound at each trigger (``"P>=0.9"``), else None
    bound: str | None = None


@dataclass
class Explanation:
    """One requirement explained: ``id``, ``text``, template ``key``, the plain-English
    ``reading``, the durations (``ticks`` and the tick period's seconds), the ``diagram``,
    the shortest ``satisfying`` and ``violating`` traces (variable -> bool per tick, or None
    with ``search_note`` saying why: :func:`shortest_traces`)."""

    id: str
    text: str
    key: str
    reading: str
    ticks: int | None
    period_s: Fraction | None
    diagram: Diagram
    satisfying: dict | None = None
    violating: dict | None = None
    search_note: str | None = None


def _mode_layout(kind: str, n: int, w: int) -> np.ndarray | None:
    """The scope mode's truth at each tick so that the interesting scope interval is
    ``[4, 4 + w]`` (or starts at 4 and runs to the end)."""
    m = np.zeros(n, dtype=np.bool_)
    if kind == "null":
        return None
    if kind == "in":
        m[4:5 + w] = True
    elif kind in ("notin", "onlyIn"):
        m[:4] = True
        m[5 + w:] = True
    elif kind == "after":
        m[2:4] = True
    elif kind == "onlyAfter":
        m[3 + w:5 + w] = True
    elif kind == "before":
        m[5 + w:] = True
    elif kind == "onlyBefore":
        m[4:6] = True
    return m


def diagram(req: A.Requirement, k: int | None) -> Diagram:
    """The :class:`Diagram` of ``req`` (parsed, not free-form) with its duration ``k`` in
    ticks (None without one): module docstring. A duration past :data:`MAX_DRAWN_TICKS` is
    drawn that long (``drawn_ticks``), so a diagram has at most ``MAX_DRAWN_TICKS + 22``
    ticks whatever the requirement's.

    Raises:
        ValueError: a free-form requirement.
    """
    if req.freeform:
        raise ValueError("a free-form requirement has no diagram")
    drawn = None
    if k is not None and k > MAX_DRAWN_TICKS:
        drawn = k = MAX_DRAWN_TICKS
    kk = k or 0
    w = 12 + kk
    n = w + 10
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    mode = _mode_layout(scope, n, w)
    none = np.zeros(n, dtype=np.bool_)
    intervals = _judged(req, kk, mode, none, none, none, n).intervals
    d = Diagram(n=n, scope=intervals, negated=scope.startswith("only"), drawn_ticks=drawn)
    if mode is not None:
        d.signals["scope mode"] = mode.tolist()
    if not intervals:
        return d
    s, e = intervals[0]
    C = np.zeros(n, dtype=np.bool_)
    C[min(s + 2, e):min(s + 5, e + 1)] = True
    if cond != "null":
        d.signals["condition"] = C.tolist()
    d.triggers += _judged(req, kk, mode, none, C, none, n).triggers.tolist()
    S = None
    t = d.triggers[0] if d.triggers else s
    if timing in A.STOP_TIMINGS:
        S = np.zeros(n, dtype=np.bool_)
        S[min(t + 4 + kk // 2, e)] = True
        d.signals["stop condition"] = S.tolist()
    d.obligation = OBLIGATIONS.get(timing, ("", ""))[1 if d.negated else 0]
    if not d.triggers:
        return d
    for value in (False, True):
        R = np.full(n, value, dtype=np.bool_)
        bad = _failed(_judged(req, kk, mode, R, C, S, n), t)
        if bad is None:
            continue
        window = bad.window
        if value is False:
            d.required = (window[0], window[1])  # R never holds: where it was required
        else:
            d.forbidden = (window[0], window[1])  # R always holds: where it was forbidden
    if timing == "after" and not d.negated and d.required is not None:
        # "after k": R must not hold on [t, t+k] and must hold at t+k+1 (the checker
        # reports the whole [t, t+k+1] either way)
        lo, hi = d.required
        d.required, d.forbidden = (hi, hi), (lo, hi - 1)
    return d


def _judged(req: A.Requirement, k: int, mode: np.ndarray | None, R: np.ndarray,
            C: np.ndarray, S: np.ndarray | None, n: int) -> IntervalStream:
    """FRET's interval semantics of ``req``'s kinds over the drawn signals (``n`` ticks;
    ``k`` the duration drawn), every interval and trigger recorded, finished."""
    s = IntervalStream(req, k, limit=n + 1, record=True)
    s.feed_signals(mode, R, C, S if S is not None else np.zeros(n, np.bool_), n,
                   np.arange(n, dtype=np.int64))
    s.finish()
    return s


def _failed(s: IntervalStream, t: int) -> Violation | None:
    """The failed obligation of the trigger ``t`` of the finished stream ``s``, or None."""
    return next((v for v in s.finish()[0].listed if v.trigger_tick == t), None)


_SCOPES = {
    "null": "At every tick of the run",
    "in": "While {m} holds (each interval where it holds is a scope interval)",
    "notin": "While {m} does not hold",
    "after": "After {m}: from the tick after the first interval in which {m} holds, to the "
             "end",
    "before": "Before {m}: from the start until {m} first holds",
    "onlyIn": "Only while {m} holds: outside it (where this is checked) the response must "
              "not be given",
    "onlyAfter": "Only after {m}: up to the end of its first interval (where this is "
                 "checked) the response must not be given",
    "onlyBefore": "Only before {m}: from the tick {m} first holds (where this is checked) "
                  "the response must not be given",
}
_CONDITIONS = {
    "null": "from the start of each scope interval",
    "regular": "each time {c} becomes true (the tick it turns true, or the interval's first "
               "tick if it holds there)",
    "holding": "at every tick at which {c} holds",
}
_TIMINGS = {
    "immediately": "satisfy {r} at that very tick",
    "next": "satisfy {r} at the next tick (if the interval has one)",
    "finally": "satisfy {r} at the last tick of the scope interval",
    "eventually": "satisfy {r} at some tick from then until the scope interval ends",
    "null": "satisfy {r} at some tick from then until the scope interval ends",
    "always": "satisfy {r} at every tick from then until the scope interval ends",
    "never": "satisfy {r} at no tick from then until the scope interval ends",
    "within": "satisfy {r} at least once within {d} of it (that tick and the next {k} "
              "ticks; nothing is owed if the interval ends sooner)",
    "for": "satisfy {r} at every tick for {d} (that tick and the next {k} ticks, cut at the "
           "interval's end)",
    "after": "not satisfy {r} for {d} (that tick and the next {k}) and satisfy it at the "
             "tick after",
    "until": "satisfy {r} at every tick until {s} holds (or the interval ends)",
    "before": "satisfy {r} at least once before {s} holds (if it ever does)",
}


def _duration_text(d: A.Duration | None, k: int | None, period: Fraction | None) -> str:
    if d is None:
        return ""
    unit = d.unit[:-1] if d.amount == "1" and d.unit.endswith("s") else d.unit
    written = f"{d.amount} {unit}" + (f" (= {d.name})" if d.name else "")
    if k is None:
        return written
    secs = f", {float(k * period):g} s" if period is not None else ""
    return f"{written} ({k} ticks{secs})"


def _as_written(req: A.Requirement, e) -> str:
    """An expression of ``req`` as the sentence writes it (FRET's printed form when its
    span is not in the text)."""
    if e is None:
        return ""
    text = req.text[e.span.start:e.span.end] if e.span.end > e.span.start else ""
    return text.strip() or expr_text(e)


def reading(req: A.Requirement, k: int | None, period: Fraction | None) -> str:
    """FRET's reading of ``req`` in plain English (scope, trigger, what must hold and when,
    durations in ticks and time; a probability bound at each trigger, as FRET's
    ``probabilistic_description`` reads it)."""
    m = _as_written(req, req.scope.mode)
    c = _as_written(req, req.condition.expr)
    r = _as_written(req, req.response)
    s = _as_written(req, req.timing.stop)
    dtext = _duration_text(req.timing.duration, k, period)
    comp = req.component or "the component"
    first = _SCOPES[req.scope.kind].format(m=m)
    second = _CONDITIONS[req.condition.kind].format(c=c)
    third = _TIMINGS[req.timing.kind].format(r=r, s=s, d=dtext, k=k if k is not None else "k")
    p = req.probability
    if p is None:
        return f"{first}, {second}, {comp} shall {third}."
    bound = f"{p.op} {p.value}"
    return (f"{first}, {second}, {comp} shall, with probability {bound} at each trigger, "
            f"{third}. The bound is per trigger (FRET's probabilistic reading): each trigger "
            f"is one trial, and across runs the probability that a trigger's obligation is "
            f"met must be {bound}; one run does not decide it.")


def explain(compiled: Compiled) -> Explanation:
    """The :class:`Explanation` of a compiled requirement (formalized, not free-form).

    Raises:
        ValueError: a requirement that did not formalize, or a free-form one.
    """
    f = compiled.formalization
    if f is None:
        raise ValueError(f"{compiled.id} has no formalization: {compiled.error}")
    req = compiled.requirement
    assert req is not None  # (it formalized)
    period = getattr(compiled.entry, "tick_period", None)
    # FRET's five parts with a probability
    key = (compiled.key_pctl if req.probability is not None else None) or f.key
    x = Explanation(compiled.id, compiled.text, key, reading(req, f.ticks, period),
                    f.ticks, period, diagram(req, f.ticks))
    if req.probability is not None:
        x.diagram.bound = f"P{req.probability.op}{req.probability.value}"
    x.satisfying, x.violating, x.search_note = shortest_traces(compiled)
    return x


def shortest_traces(compiled: Compiled, max_ticks: int = MAX_SEARCH[0],
                    max_vars: int = MAX_SEARCH[1]
                    ) -> tuple[dict[str, list[bool]] | None, dict[str, list[bool]] | None,
                               str | None]:
    """(shortest trace that satisfies, shortest that violates, note) of a compiled
    requirement: a breadth-first search over the states of its generated runtime monitor
    (the pt formula's state machine, :mod:`fretc.compiler.codegen`), one letter per valuation of
    its boolean variables, so the first trace found of each verdict is a shortest one (FRET's
    finite-trace verdict at its last tick). Traces are ``{variable: [bool per tick]}``; None
    (and the note) when none exists within ``max_ticks``, when a variable is a number (the
    letters would not be finite), or when there are more than ``max_vars`` variables."""
    import copy
    from itertools import product

    from fretc.compiler import ir
    from fretc.compiler.codegen import build_monitor_modules

    f = compiled.formalization
    assert f is not None  # (explain() refused a requirement that did not formalize)
    if any(n.op in ("cmp", "num", "call", "pre") for n in ir.walk(f.ft)):
        return None, None, "a variable is a number: no trace searched (use fretc check's witnesses)"
    names = list(f.variables)
    if len(names) > max_vars:
        return None, None, f"{len(names)} variables: no trace searched (at most {max_vars})"
    modules = build_monitor_modules([compiled])
    if not modules:
        return None, None, "no runtime monitor: no trace searched"
    ns: dict = {"__name__": "fretc_explain_monitor"}
    exec(compile(next(iter(modules.values())).text, "<fretc explain>", "exec"), ns)
    cls = ns["MONITORS"].get(compiled.id)
    if cls is None:
        return None, None, "no runtime monitor: no trace searched"
    letters = [dict(zip(names, bits)) for bits in product((False, True), repeat=len(names))]
    found: dict[bool, list] = {}
    frontier: list[tuple[Any, list[dict[str, bool]]]] = [(None, [])]
    seen = set()
    for _depth in range(max_ticks):
        nxt = []
        for state, trace in frontier:
            for letter in letters:
                m = cls()
                if state is not None:  # (a copy: a window's deque is changed in place)
                    m._s, m.status, m.status_tick, m._bad, m._good = copy.deepcopy(state)
                verdict = bool(m.step(letter))
                run = trace + [letter]
                if verdict not in found:
                    found[verdict] = run
                key = repr((m._s[:-2], m._s[-1], m._bad, m._good))
                if key not in seen:
                    seen.add(key)
                    nxt.append(((m._s, m.status, m.status_tick, m._bad, m._good), run))
        if len(found) == 2 or not nxt:
            break
        frontier = nxt

    def columns(run: list[dict[str, bool]] | None) -> dict[str, list[bool]] | None:
        return None if run is None else {v: [row[v] for row in run] for v in names}
    note = None if len(found) == 2 else (f"no {'satisfying' if True not in found else 'violating'} "
                                         f"trace of at most {max_ticks} ticks")
    return columns(found.get(True)), columns(found.get(False)), note
