"""Window functions of the binding language (docs/bindings.md, "Windows over time"): a call
whose last argument is a span (:class:`~fretc.signals.bindings.expression.Span`: ``2s``,
``1 min``, ``50 messages``) aggregates its first argument over the messages of its topic in
that sliding window: ``mean(/battery.current, 2s)``, ``count(/estop.data, 1min)``,
``percentile(/loop.period, 95, 10s)``, ``rate(/scan, 1s)``. The functions are RTLola's
``aggregate(over: 2s, using: ...)`` ones (Faymonville et al., "StreamLAB", CAV 2019). This
module checks a window binding and describes it (:class:`WindowSpec`); the values are
computed by :class:`fretc.signals.windows.SlidingWindow`.
"""

from __future__ import annotations

from dataclasses import dataclass

from fretc.signals.bindings.expression import (Const, Expr, ExprLocation, Field, FuncCall, Slice,
                                               Span, walk)

__all__ = ["WINDOW_FUNCS", "WindowSpec", "check_window", "is_window_call"]

#: The window functions: name -> the type of the value they aggregate ("number",
#: "bool" for ``count``: the messages on which it held; None for ``rate``: every message).
WINDOW_FUNCS = {"mean": "number", "sum": "number", "count": "bool", "min": "number",
                "max": "number", "median": "number", "percentile": "number",
                "variance": "number", "rate": None}


@dataclass(frozen=True)
class WindowSpec:
    """One window binding.

    Attributes:
        func: the window function (a key of :data:`WINDOW_FUNCS`).
        topic: the topic whose messages the window holds.
        span_ns: the window's duration (ns), or None for a count of messages.
        count: the number of messages (a count window), or None.
        q: the percentile (0..100) of ``percentile``, else None.
        text: the span as written (``"2s"``).
        parts: for ``waiting`` (a service's calls), the fields read from each event message:
            ``info.event_type``, ``info.sequence_number`` and the 16 bytes of
            ``info.client_gid`` (a call is matched with its response by the last two).
    """

    func: str
    topic: str
    span_ns: int | None
    count: int | None
    q: float | None
    text: str
    parts: tuple = ()


def is_window_call(node: Expr) -> bool:
    """Whether ``node`` is a call whose last argument is a span (a window function)."""
    return isinstance(node, FuncCall) and bool(node.args) and isinstance(node.args[-1], Span)


def check_window(node: Expr, where: ExprLocation) -> tuple[WindowSpec, Expr] | None:
    """The window of a binding whose whole expression ``node`` is a window function, and the
    expression evaluated on each message (``Const(True)`` for ``rate`` and a bare topic's
    ``count``); None when ``node`` is none.

    Raises:
        BindingError: a window that is part of a larger expression, an unknown window
            function, wrong arguments (a percentile outside 0..100, ``rate`` over a count of
            messages), a span inside the argument, or an argument reading other than the
            fields of one topic (``age()``, ``tf()``, two topics), at its column.
    """
    events = _event_window(node)
    if events is not None:
        return events
    for n in walk(node):
        if isinstance(n, FuncCall) and n.func in ("waiting", "goal_waiting") and n is not node:
            raise where.error("waiting() is the whole binding: bind it to its own variable and "
                              "compare it in the requirement (waiting_arm <= 0.1)", n.col)
    inner_spans = [n for n in walk(node) if isinstance(n, Span)]
    if not is_window_call(node):
        if inner_spans:
            raise where.error("a window function (mean(x, 2s) ...) is the whole binding, not "
                              "a part of one: bind it to its own variable and compare the "
                              "variable in the requirement", inner_spans[0].col)
        return None
    assert isinstance(node, FuncCall)
    span = node.args[-1]
    assert isinstance(span, Span)
    if node.func == "count_ticks":
        return _tick_window(node, span, inner_spans, where)
    if node.func not in WINDOW_FUNCS:
        raise where.error(f"{node.func}() has no window: the window functions are "
                          f"{', '.join(WINDOW_FUNCS)} (e.g. mean(/battery.current, 2s))",
                          node.col)
    want = 3 if node.func == "percentile" else 2
    if len(node.args) != want:
        example = ("percentile(/loop.period, 95, 10s)" if want == 3
                   else f"{node.func}(/topic.field, 2s)")
        raise where.error(f"{node.func}() over a window takes {want} arguments, e.g. "
                          f"{example}", node.col)
    if len(inner_spans) > 1:
        raise where.error("a window's argument has no span of its own: windows do not nest",
                          inner_spans[1].col if inner_spans[0] is span else inner_spans[0].col)
    q = None
    if node.func == "percentile":
        qa = node.args[1]
        if not (isinstance(qa, Const) and isinstance(qa.value, float)
                and 0 <= qa.value <= 100):
            raise where.error("percentile()'s second argument is a number from 0 to 100",
                              qa.col)
        q = qa.value
    if node.func == "rate" and span.ns is None:
        raise where.error("rate() is messages per second over a duration (rate(/scan, 1s)), "
                          "not over a count of messages", span.col)
    body = node.args[0]
    topics = set()
    for n in walk(body):
        if isinstance(n, FuncCall) and n.func in ("age", "tf"):
            raise where.error(f"{node.func}() over a window aggregates the fields of one "
                              f"topic's messages; {n.func}() is not a field of a message", n.col)
        if isinstance(n, Field):
            topics.add(n.topic)
    if len(topics) != 1:
        raise where.error(f"{node.func}() over a window reads the messages of one topic, but "
                          f"its argument reads {len(topics)} ({', '.join(sorted(topics))})"
                          if topics else f"{node.func}() over a window needs a topic",
                          node.col)
    if isinstance(body, Field) and not body.path:
        if node.func not in ("rate", "count"):
            raise where.error(f"{body.topic} is a topic, not a value: {node.func}() needs a "
                              f"field (e.g. {body.topic}.data)", body.col)
        body = Const(body.col, True)
    elif node.func == "rate":
        raise where.error("rate() counts every message of a topic: rate(/topic, 1s) (to count "
                          "those where a condition holds: count(CONDITION, 1s))", body.col)
    spec = WindowSpec(node.func, topics.pop(), span.ns, span.messages, q, span.text)
    return spec, body


def _tick_window(node: FuncCall, span: Span, inner_spans: list, where: ExprLocation
                 ) -> tuple[WindowSpec, Expr]:
    """``count_ticks(COND, 1min)``: the ticks of the clock in the window where COND held
    (:mod:`fretc.signals.tick_windows`); COND reads any variables and topics.

    Raises:
        BindingError: not two arguments, a span that is not a duration, a span or a window
            inside COND, at its column.
    """
    if len(node.args) != 2:
        raise where.error("count_ticks() takes a condition and a duration, e.g. "
                          "count_ticks(too_close, 1min)", node.col)
    if span.ns is None:
        raise where.error("count_ticks() counts the ticks of a duration (count_ticks(x, "
                          "1min)); to count messages: count(/topic.field > 0, 50 messages)",
                          span.col)
    if len(inner_spans) > 1:
        raise where.error("a window's argument has no span of its own: windows do not nest",
                          inner_spans[0].col)
    return WindowSpec("count_ticks", "", span.ns, None, None, span.text), node.args[0]


def _event_window(node: Expr) -> tuple[WindowSpec, Expr] | None:
    """``waiting(/arm/_service_event)`` and ``goal_waiting(/nav/_action/status)`` (as
    parse.py writes them) as windows whose messages give their :attr:`WindowSpec.parts`."""
    if isinstance(node, FuncCall) and node.func == "waiting":
        topic = node.args[0].topic  # type: ignore[attr-defined]
        parts = ((Field(node.col, topic, ("info", "event_type")),
                  Field(node.col, topic, ("info", "sequence_number")))
                 + tuple(Field(node.col, topic, ("info", "client_gid", i)) for i in range(16)))
        return WindowSpec("waiting", topic, None, 0, None, "", parts), Const(node.col, True)
    if isinstance(node, FuncCall) and node.func == "goal_waiting":
        topic = node.args[0].topic  # type: ignore[attr-defined]
        parts = (Field(node.col, topic, ("status_list", Slice(None, None), "status")),
                 Field(node.col, topic, ("status_list", Slice(None, None), "goal_info",
                                         "goal_id", "uuid")))
        return WindowSpec("goal_waiting", topic, None, 0, None, "", parts), Const(node.col, True)
    return None
