"""Messages between ticks, for the block sampler (:mod:`fretc.signals.blocks`): the windows of
messages each tick of a clock folds for its aggregated bindings (``any_of_messages`` ...,
docs/bindings.md "Events between ticks"), their folded values, and the changes of plain
boolean bindings on messages no tick held. The tick-by-tick clock
(:class:`fretc.signals.clock.Clock`) folds the same windows message by message (tested equal).

``c`` below is a block clock (``signals.blocks._Group``): ``window_start`` (topic -> number
of the message held at the previous grid tick), ``stream`` (the buffered messages),
``next_grid`` and ``period``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fretc.common.problems import SignalError
from fretc.signals.bindings.binding import EMPTY_FOLD, Binding, fold
from fretc.signals.bindings.compile import EvalState, per_message_topic
from fretc.signals.bindings.expression import BinOp, Const, Expr, FuncCall, UnaryOp

_BOOLEAN_OPS = ("<", "<=", ">", ">=", "=", "!=", "&", "|", "->", "<->")


def is_boolean(node: Expr) -> bool:
    """Whether the expression ``node`` is a boolean by its form (a comparison, a logical
    operator, ``!``, ``any``/``all``, ``true``/``false``)."""
    if isinstance(node, BinOp):
        return node.op in _BOOLEAN_OPS
    if isinstance(node, UnaryOp):
        return node.op == "!"
    if isinstance(node, FuncCall):
        return node.func in ("any", "all")
    return isinstance(node, Const) and isinstance(node.value, bool)


def single_topic(b: Binding) -> str | None:
    """The topic of a boolean binding without aggregation that reads the fields of one
    topic only (its value on a skipped message can be compared with its value at a tick),
    else None."""
    if b.aggregate is not None or b.window is not None or b.uses_tf or not is_boolean(b.ast):
        return None
    return per_message_topic(b.ast)


def missed_changes(variables: list[Binding], stream: Any, topic: str, starts: np.ndarray,
                   held: np.ndarray, out: dict[str, int]) -> None:
    """Add to ``out`` (variable -> count) the messages of ``topic`` no tick held on which a
    boolean binding of that topic alone (:func:`single_topic`) differs from its value at the
    tick before. ``starts``/``held``: per evaluated tick, the number of the message held at
    the tick before and at the tick (counted from the topic's first message); the messages
    strictly between are the skipped ones. A binding that cannot be evaluated on them
    column-wise is not counted (the count is advice, never a verdict)."""
    from fretc.signals.columns import HeldColumns, Irregular

    gaps = held - starts - 1
    some = gaps > 0
    if not some.any():
        return
    buf = stream.buffers[topic]
    skipped = np.concatenate([np.arange(a + 1, e) for a, e in zip(starts[some], held[some])])
    refs = np.repeat(starts[some], gaps[some])
    at = np.concatenate((skipped, refs)) - buf.base
    if len(at) and at.min() < 0:  # released from the buffer: never read others in their place
        raise AssertionError(f"messages of {topic} were released before they were counted")
    times = stream.arrays(topic)[0]
    for b in variables:
        if single_topic(b) != topic:
            continue
        cols = HeldColumns(stream.messages(), times[at], {topic: times}, {topic: at})
        try:
            with np.errstate(all="ignore"):
                vals = b.evaluate_columns(cols)
        except (SignalError, Irregular):
            continue
        k = len(skipped)
        a, r = vals[:k], vals[k:]
        same = (a == r) | ((a != a) & (r != r)) if vals.dtype.kind == "f" else (a == r)
        n = int(np.count_nonzero(~same))
        if n:
            out[b.name] = out.get(b.name, 0) + n

__all__ = ["folded_topics", "windows_of", "folded", "is_boolean", "single_topic",
           "missed_changes"]


def windows_of(c: Any, times: np.ndarray, warm: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per topic of an aggregated binding, the messages each evaluated tick folds: numbers
    (counted from the topic's first message) from ``first`` to ``last`` inclusive, those
    after the message held at the previous grid tick (warm-up ticks included) up to the one
    held at the tick, as :class:`fretc.signals.clock.Clock` folds them message by message."""
    out = {}
    for topic, prev in c.window_start.items():
        buf = c.stream.buffers[topic]
        held = np.searchsorted(c.stream.arrays(topic)[0], times, side="right") - 1 + buf.base
        held = np.maximum(held, -1)
        before = np.concatenate(([prev], held[:-1]))
        c.window_start[topic] = int(held[-1])
        out[topic] = (before[warm:] + 1, held[warm:])
    return out


def folded(b: Binding, stream: Any, window: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """An aggregated binding at each tick: its expression on each message of its topic in
    the tick's window (:func:`windows_of`), folded; an empty window gives
    :data:`~fretc.signals.bindings.binding.EMPTY_FOLD` (or the held message's value).

    Raises:
        SignalError: the expression fails on a message of a window (named with its log time).
    """
    topic = next(iter(b.topics))
    buf = stream.buffers[topic]
    st = EvalState()
    out: list[Any] = []
    memo: dict[int, Any] = {}

    def value(k: int) -> Any:
        if k not in memo:
            j = k - buf.base
            if j < 0:  # released from the buffer: never read another message in its place
                raise AssertionError(f"message {k} of {topic} was released before its fold")
            st.msgs[topic], st.times[topic], st.now = buf.data[j], buf.times[j], buf.times[j]
            try:
                memo[k] = b.evaluate(st)
            except SignalError as exc:
                raise SignalError(f"{exc} (message of {topic} at log time "
                                  f"{buf.log_times[j]})", variable=exc.variable) from None
        return memo[k]

    empty = EMPTY_FOLD[b.aggregate]  # type: ignore[index]
    with np.errstate(all="ignore"):
        for first, last in zip(window[0].tolist(), window[1].tolist()):
            if last < first:
                out.append(value(last) if empty is None else empty)
            else:
                out.append(fold(b.aggregate, [value(k) for k in range(first, last + 1)]))  # type: ignore[arg-type]
    if all(type(v) is bool for v in out):
        return np.array(out, dtype=np.bool_)
    return np.array(out, dtype=np.float64)


def folded_topics(variables: list[Binding]) -> set[str]:
    """Topics read only by aggregated bindings (``any_of_messages`` ..., windows) among
    ``variables``: every message of them is folded, none goes unsampled."""
    agg = [b.aggregate is not None or b.window is not None for b in variables]
    folded = {t for b, a in zip(variables, agg) if a for t in b.topics}
    return folded - {t for b, a in zip(variables, agg) if not a for t in b.topics}
