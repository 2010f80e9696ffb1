"""Binding values over many ticks at once: the per-message columns of the messages a block of
ticks holds (:class:`MessageColumns`), and what a binding's vectorized evaluation reads
(:class:`HeldColumns`: the held message of each topic at each tick, found by
``np.searchsorted``; :meth:`fretc.signals.bindings.Binding.evaluate_columns`).

Each bound field is extracted once per message, a reduction of one topic's fields
(``min(/scan.ranges)``) is computed once per message (:meth:`HeldColumns.per_message`), and
the values are gathered per tick by index. Values the columns cannot hold (arrays whose length
changes between messages, text, nested messages, a field missing from some message) raise
:class:`Irregular`; the caller then evaluates that binding tick by tick with
:meth:`fretc.signals.bindings.Binding.evaluate`, which gives the same values and the same errors.
"""

from __future__ import annotations

import operator
from typing import Any

import numpy as np

from fretc.common.units import NS_PER_S

from fretc.signals.bindings.compile import EvalError, EvalState
from fretc.signals.bindings.expression import Field, unparse
from fretc.signals.bindings.extract import LASER_SCAN, FieldAccessError, Valid, make_extractor, rep117

__all__ = ["Irregular", "MessageColumns", "HeldColumns", "regular_column", "SegmentList"]


class Irregular(Exception):
    """Values that do not fit a column (ragged arrays, text, messages, extraction errors)."""


def regular_column(values: list[Any], what: str) -> Any:
    """Per-message values as one column: bool or float64 1-D array, or :class:`Valid` of
    messages x items.

    Raises:
        Irregular: values that do not fit one column (``what`` names them).
    """
    if all(type(v) is bool for v in values):
        return np.array(values, dtype=np.bool_)
    if all(type(v) in (bool, float) for v in values):
        return np.array(values, dtype=np.float64)
    if values and all(isinstance(v, Valid) for v in values):
        first = values[0].data
        if any(v.data.shape != first.shape or v.data.dtype != first.dtype for v in values):
            raise Irregular(f"{what}: arrays of different lengths or types")
        data = np.stack([v.data for v in values])
        if all(v.mask is None for v in values):
            return Valid(data, None)
        mask = np.stack([v.mask if v.mask is not None else np.ones(first.shape, np.bool_)
                         for v in values])
        return Valid(data, mask)
    raise Irregular(f"{what}: values that are not numbers or arrays of one length")


class MessageColumns:
    """The messages of each topic that a block of ticks may hold, as columns.

    Args:
        data: topic -> the decoded messages (list), in time order.
    """

    def __init__(self, data: dict[str, list[Any]]) -> None:
        self.data = data
        self._fields: dict[tuple[str, str], Any] = {}  # (topic, field text) -> column
        self._reduced: dict[tuple[str, str], Any] = {}
        #: (topic, field text) -> (the values read from each message, why they are no column):
        #: read once, for every binding and the message-by-message fallback
        self._irregular: dict[tuple[str, Any], tuple[list, str]] = {}

    def field(self, topic: str, path: tuple, node: Field) -> Any:
        """Field ``path`` of every message of ``topic`` (:func:`regular_column`).

        Raises:
            Irregular: values that do not fit a column, or a message without the field.
        """
        key = (topic, node.text())  # the same field at other columns of other bindings
        if key in self._irregular:
            raise Irregular(self._irregular[key][1])
        col = self._fields.get(key)
        if col is None:
            msgs = self.data[topic]
            col = msgs.column(path) if isinstance(msgs, SegmentList) else None
            if col is None:
                col = _plain_column(msgs, path)
            self._fields[key] = col
        if col is None:
            ex = make_extractor(node)
            try:
                values = [ex(d) for d in self.data[topic]]
            except FieldAccessError as exc:
                raise Irregular(str(exc)) from None
            try:
                col = self._fields[key] = regular_column(values, node.text())
            except Irregular as exc:
                self._irregular[key] = (values, str(exc))
                raise
        return col

    def reduced(self, node: Any, topic: str, vector: Any, scalar: Any) -> np.ndarray:
        """The reduction ``node`` (of fields of ``topic`` only) for every message of
        ``topic``: by ``vector`` over all messages at once, or message by message by
        ``scalar`` when the fields do not fit columns.

        Raises:
            Irregular: some message gives an error (the per-tick evaluation reports it, if a
                tick holds that message).
        """
        key = (unparse(node), topic)  # the same reduction in several bindings: computed once
        col = self._reduced.get(key)
        if col is not None:
            return col
        msgs = self.data[topic]
        try:
            out = vector(_OneTopic(self, topic, len(msgs)))
        except (Irregular, EvalError):
            st = EvalState()
            values = []
            known = [(k, v) for k, (v, _why) in self._irregular.items() if k[0] == topic]
            try:
                for i, d in enumerate(msgs):
                    st.msgs[topic] = d
                    for k, v in known:  # fields already read: the evaluators' memo
                        st.values[k] = (d, v[i])
                    values.append(scalar(st))
            except EvalError as exc:
                raise Irregular(exc.message) from None
            out = regular_column([_plain(v) for v in values], "a reduction")
        if isinstance(out, Valid) or not isinstance(out, np.ndarray) or out.ndim != 1:
            raise Irregular("a reduction that is not one number per message")
        self._reduced[key] = out
        return out


def _plain_column(msgs: list[Any], path: tuple) -> Any:
    """The column of a path of field names (no index) read with one ``attrgetter`` per
    message when every value is a number or a bool (bool or float64 array), or LaserScan
    ranges of one length (REP 117 applied to all messages at once); None otherwise (the
    caller then extracts message by message, with its errors)."""
    if not msgs or not path or not all(isinstance(p, str) for p in path):
        return None
    if path[-1] == "ranges":
        parents = msgs if len(path) == 1 else _values(msgs, path[:-1])
        if parents is None or any(getattr(p, "__msgtype__", None) != LASER_SCAN
                                  for p in parents):
            return None
        rows = [p.ranges for p in parents]
        if len({len(r) for r in rows}) != 1:
            return None
        limits = np.array([(p.range_min, p.range_max) for p in parents], dtype=np.float64)
        return rep117(np.array(rows, dtype=np.float64), limits[:, :1], limits[:, 1:])
    raw = _values(msgs, path)
    if raw is None:
        return None
    try:
        arr = np.array(raw)
    except ValueError:  # arrays of different lengths
        return None
    if arr.ndim != 1:
        return None
    if arr.dtype == np.bool_:
        return arr
    return arr.astype(np.float64) if arr.dtype.kind in "iuf" else None


def _values(msgs: list[Any], path: tuple) -> list[Any] | None:
    get = operator.attrgetter(".".join(path))
    try:
        return [get(d) for d in msgs]
    except AttributeError:
        return None


def _plain(v: Any) -> Any:
    if isinstance(v, np.generic):
        v = v.item()
    return float(v) if type(v) is int else v


class _OneTopic:
    """The messages of one topic as the "ticks" of a vectorized evaluation (one per message)."""

    def __init__(self, cols: MessageColumns, topic: str, n: int) -> None:
        self.cols, self.topic, self.n = cols, topic, n

    def field(self, topic: str, path: tuple, node: Field) -> Any:
        return self.cols.field(topic, path, node)

    def age(self, topic: str) -> np.ndarray:  # pragma: no cover - excluded by per_message_topic
        raise Irregular("age() of a message")

    def per_message(self, node: Any, topic: str, vector: Any, scalar: Any) -> np.ndarray:
        return self.cols.reduced(node, topic, vector, scalar)


class HeldColumns:
    """What :meth:`fretc.signals.bindings.Binding.evaluate_columns` reads for ``n`` ticks: the field
    values and ages of the message each topic holds at each tick.

    Args:
        messages: the block's :class:`MessageColumns`.
        tick_times: int64 tick times (ns), length ``n``.
        times: topic -> int64 times (ns, time base) of its messages in ``messages``.
        idx: topic -> int64 index of the message held at each tick (length ``n``, >= 0).
    """

    def __init__(self, messages: MessageColumns, tick_times: np.ndarray,
                 times: dict[str, np.ndarray], idx: dict[str, np.ndarray]) -> None:
        self.messages = messages
        self.n = len(tick_times)
        self.tick_times = tick_times
        self.times = times
        self.idx = idx

    def field(self, topic: str, path: tuple, node: Field) -> Any:
        """Field ``path`` of ``topic`` at each tick (1-D array or :class:`Valid`).

        Raises:
            Irregular: as :meth:`MessageColumns.field`.
        """
        col = self.messages.field(topic, path, node)
        i = self.idx[topic]
        if isinstance(col, Valid):
            return Valid(col.data[i], None if col.mask is None else col.mask[i])
        return col[i]

    @property
    def tf(self) -> Any:
        """``tf()`` reads every message of /tf and /tf_static, not the held ones.

        Raises:
            Irregular: always (the binding is evaluated tick by tick).
        """
        raise Irregular("tf() reads every message of /tf and /tf_static")

    def age(self, topic: str) -> np.ndarray:
        """``age(topic)`` at each tick: seconds since the held message (float64)."""
        held = self.times[topic][self.idx[topic]]
        return (self.tick_times - held).astype(np.float64) / NS_PER_S

    def per_message(self, node: Any, topic: str, vector: Any, scalar: Any) -> np.ndarray:
        """A reduction of ``topic``'s fields at each tick, computed once per message
        (:meth:`MessageColumns.reduced`) and gathered."""
        return self.messages.reduced(node, topic, vector, scalar)[self.idx[topic]]


class SegmentList:
    """The messages of one topic as a list (indexing decodes a message on demand), held as
    :class:`~fretc.logs.ros.columnar.Segment` s whose columns :meth:`column` joins: what the
    columnar MCAP pass (:mod:`fretc.logs.mcap.columns`) gives the block sampler."""

    def __init__(self) -> None:
        self.segments: list[Any] = []
        self._n = 0

    def add(self, segment: Any) -> None:
        """Append the messages of ``segment``."""
        if len(segment):
            self.segments.append(segment)
            self._n += len(segment)

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, k: int) -> Any:
        if k < 0:
            k += self._n
        if not 0 <= k < self._n:
            raise IndexError(k)
        for seg in self.segments:
            if k < len(seg):
                return seg.message(k)
            k -= len(seg)
        raise IndexError(k)  # pragma: no cover

    def __iter__(self):
        for seg in self.segments:
            for k in range(len(seg)):
                yield seg.message(k)

    def __delitem__(self, s: slice) -> None:
        """``del messages[:k]``: drop the first ``k`` messages."""
        k = s.stop if isinstance(s, slice) and s.start is None and s.step is None else None
        if k is None:
            raise TypeError("only del messages[:k]")
        k = min(max(k, 0), self._n)
        self._n -= k
        while k:
            seg = self.segments[0]
            if k >= len(seg):
                self.segments.pop(0)
                k -= len(seg)
            else:
                self.segments[0] = seg.dropped(k)
                k = 0

    def column(self, path: tuple) -> Any:
        """The column of field ``path`` of every message, as :func:`_plain_column` gives it
        from the messages, when every segment holds it (LaserScan ``ranges``: REP 117 applied,
        :func:`~fretc.signals.bindings.extract.rep117`); None otherwise (read the messages)."""
        segs = self.segments
        if not segs or any(seg.columns is None for seg in segs):
            return None
        if path == ("ranges",):
            if any(seg.typename != LASER_SCAN for seg in segs):
                return None
            need = (path, ("range_min",), ("range_max",))
            if any(p not in seg.columns for seg in segs for p in need) or len(
                    {seg.columns[path].shape[1] for seg in segs}) != 1:
                return None
            rows, lo, hi = (np.concatenate([seg.columns[p] for seg in segs]) for p in need)
            return rep117(rows.astype(np.float64), lo[:, None], hi[:, None])
        if any(path not in seg.columns for seg in segs):
            return None
        if len(segs) == 1:
            return segs[0].columns[path]
        return np.concatenate([seg.columns[path] for seg in segs])
