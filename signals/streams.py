"""Streams: the messages of a topic that pass a FoxQL filter written right after the topic
(``/track{id==3}.x``; :mod:`fretc.common.streams`, docs/bindings.md "FoxQL").

The sampling reads a stream as a topic of its own: every message of the topic read from the
log is also given to the clocks as a message of each of its streams whose filters it passes
(:meth:`Streams.fan_out`), so the stream's held message is the newest passing one, its
first message ends the warm-up as a topic's first message does, and a window over the
stream counts only passing messages.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

from fretc.common.problems import SignalError
from fretc.common.streams import base_topic, is_stream
from fretc.signals.bindings.compile import EvalError
from fretc.signals.bindings.expression import Field, walk
from fretc.signals.bindings.extract import FieldAccessError, message_filter

__all__ = ["Streams"]


class Streams:
    """The streams read by some bindings, by their topic.

    ``by_topic`` maps a topic to ``[(stream, test, fail)]``: ``test(data)`` says whether a
    message passes the stream's filters (raising :class:`FieldAccessError` on a message
    without the filtered field), ``fail(exc, log_time)`` turns that error into a
    :class:`SignalError` naming the binding's file:line:col, the topic and the log time.
    """

    def __init__(self, bindings: Iterable[Any]) -> None:
        self.by_topic: dict[str, list[tuple[str, Callable[[Any], bool], Any]]] = {}
        self.failed: set[str] = set()
        seen: set[str] = set()
        for b in bindings:
            for node in _stream_fields(b):
                if node.topic in seen:
                    continue
                seen.add(node.topic)
                test = message_filter(node.filters, b.constants, node.text())
                self.by_topic.setdefault(base_topic(node.topic), []).append(
                    (node.topic, test, _failure(b, node)))

    def __bool__(self) -> bool:
        return bool(self.by_topic)

    def fan_out(self, topic: str, log_time: int, data: Any, wanted: Any = None,
                on_error: Callable[[str, SignalError], None] | None = None) -> list[str]:
        """The streams of ``topic`` (of ``wanted`` only, when given) that message ``data``
        passes. A stream whose filter fails on a message is given to ``on_error`` and read
        no more (its clocks stop with the error); without ``on_error`` the error is raised.

        Raises:
            SignalError: a filtered field the message does not have (binding file:line:col,
                topic, log time).
        """
        out = []
        for stream, test, fail in self.by_topic.get(topic, ()):
            if (wanted is not None and stream not in wanted) or stream in self.failed:
                continue
            try:
                if test(data):
                    out.append(stream)
            except FieldAccessError as exc:
                err = fail(exc, log_time)
                if on_error is None:
                    raise err from None
                self.failed.add(stream)
                on_error(stream, err)
        return out

    def messages(self, messages: Iterable[Any], wanted: Any,
                 on_error: Callable[[str, SignalError], None] | None = None) -> Iterator[Any]:
        """``messages`` (log :class:`~fretc.logs.base.Message` s) with, after each, a copy
        renamed to each stream in ``wanted`` it passes; a message of a topic not in
        ``wanted`` (read only for its streams) is left out. ``on_error``: as
        :meth:`fan_out`."""
        if not self.by_topic:
            yield from messages
            return
        for m in messages:
            if m.topic in wanted:
                yield m
            for s in self.fan_out(m.topic, m.log_time, m.data, wanted, on_error):
                yield m._replace(topic=s)


def _stream_fields(b: Any) -> Iterator[Field]:
    for tree in [b.ast] + [p.ast for p in getattr(b, "parts", ())]:
        for n in walk(tree):
            if isinstance(n, Field) and n.filters and is_stream(n.topic):
                yield n


def _failure(b: Any, node: Field) -> Callable[[FieldAccessError, int], SignalError]:
    def fail(exc: FieldAccessError, log_time: int) -> SignalError:
        return b._fail(EvalError(node, f"{exc} (topic {base_topic(node.topic)}, message at "
                                 f"log time {log_time} ns)"), "")
    return fail
