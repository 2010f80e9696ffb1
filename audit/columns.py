"""The per-tick columns an audit keeps for the evidence and the vectorized engine, and one
clock's pass over a log that holds them (:class:`ClockPass`).

Memory: messages are streamed (:mod:`fretc.logs`), never kept. What grows with the
length of the log is only these columns: per evaluated tick, 8 bytes of time, 8 bytes per
bound topic (log time of the held message), 1 byte per boolean and 8 per numeric variable -
about 80 bytes a tick for the Safe-ROS set, 3 MB for an hour at 10 Hz (kept in chunks of
:data:`CHUNK` ticks). A topic whose held log time is the tick's time at every tick (a CSV
trace's rows) keeps no column of its own: its column is the times' array.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from fretc.signals.blocks import TickBlock

__all__ = ["CHUNK", "TickColumns", "column_array", "ClockPass"]

#: Ticks per column chunk.
CHUNK = 4096
#: a block :meth:`TickColumns.drain` gave, released
_RELEASED = np.zeros(0, np.int64)


class TickColumns:
    """Per-tick columns of one clock (module docstring): values of ``names``, tick times, and
    log times (ns; -1 when none yet) of the messages of ``topics`` held at each tick; kept
    as the blocks of :func:`fretc.signals.sample_blocks`."""

    def __init__(self, names: list[str], topics: list[str]):
        self.names = names
        self.topics = topics
        self.n = 0
        self._vchunks: list[list[np.ndarray]] = [[] for _ in names]
        self._lchunks: list[list[np.ndarray]] = [[] for _ in topics]
        self._tchunks: list[np.ndarray] = []
        #: per topic: its held log times equal the ticks' times so far (no chunk kept)
        self._same = [True for _ in topics]

    def append_block(self, block: TickBlock) -> None:
        """Add a block of ticks (:class:`fretc.signals.TickBlock`); a variable absent
        from it (its evaluation failed: its requirements are errors) reads False."""
        k = len(block.times)
        for name, chunks in zip(self.names, self._vchunks):
            v = block.values.get(name)
            chunks.append(v if v is not None else np.zeros(k, dtype=np.bool_))
        for i, (topic, chunks) in enumerate(zip(self.topics, self._lchunks)):
            lt = block.log_times.get(topic)
            lt = lt if lt is not None else np.full(k, -1, dtype=np.int64)
            if self._same[i]:
                if lt.dtype == block.times.dtype and np.array_equal(lt, block.times):
                    continue
                self._same[i] = False  # the chunks so far were the times'
                chunks.extend(c.copy() for c in self._tchunks)
            chunks.append(lt)
        self._tchunks.append(block.times)
        self.n += k

    def drain(self) -> Iterator[tuple[np.ndarray, dict[str, np.ndarray],
                                      dict[str, np.ndarray]]]:
        """The blocks kept, in order, as (times, variable -> values, topic -> held log
        times), each released once given; the columns are then empty."""
        for i, times in enumerate(self._tchunks):
            yield (times, {n: c[i] for n, c in zip(self.names, self._vchunks)},
                   {t: times if same else c[i]
                    for t, c, same in zip(self.topics, self._lchunks, self._same)})
            for c in (self._tchunks, *self._vchunks, *self._lchunks):
                if i < len(c):
                    c[i] = _RELEASED
        self.n = 0
        self._tchunks = []
        self._vchunks = [[] for _ in self.names]
        self._lchunks = [[] for _ in self.topics]
        self._same = [True for _ in self.topics]

    def finish(self) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """(times, variable -> values, topic -> held log times), each of length ``n``.
        Chunks are joined one column at a time and released, so the peak is the columns
        plus one column."""

        def cat(chunks: list[np.ndarray], dtype) -> np.ndarray:
            if not chunks:
                return np.zeros(0, dtype=dtype)
            if any(c.dtype != chunks[0].dtype for c in chunks):
                out = np.concatenate([c.astype(np.float64) for c in chunks])
            else:
                out = np.concatenate(chunks) if len(chunks) > 1 else chunks[0]
            chunks.clear()
            return out

        times = cat(self._tchunks, np.int64)
        cols = {n: cat(c, np.bool_) for n, c in zip(self.names, self._vchunks)}
        lts = {t: times if same else cat(c, np.int64)
               for t, c, same in zip(self.topics, self._lchunks, self._same)}
        return times, cols, lts


def column_array(values: list) -> np.ndarray:
    """A column of values: booleans as ``bool``, anything else as ``float64``."""
    if all(type(x) is bool for x in values):
        return np.array(values, dtype=np.bool_)
    return np.array(values, dtype=np.float64)


@dataclass
class ClockPass:
    """The ticks of one clock: its sampling (:class:`fretc.signals.Sampling`), tick
    times (ns) and the columns (variable -> values, topic -> held log times)."""

    sampling: Any
    times: np.ndarray
    columns: dict[str, np.ndarray]
    log_times: dict[str, np.ndarray]
    cut: int = 0  # ticks dropped after the damage (:func:`fretc.audit.passes.cut_at_damage`)
    intact_end: int | None = None  # exclusive bound of the judged ticks' times (a cut)
    #: when the judged span ends where something could not be read - messages of the
    #: clock's topics present but not decoded (topic, count, channel, first and last log
    #: time), or a comparison with NaN (audit.finalize) - that, in words
    lost: str | None = None
    #: variable -> bool array over the ticks: where a gap leaves it unknown (only variables
    #: with an unknown tick; :func:`mark_gaps`)
    unknown: dict[str, np.ndarray] = field(default_factory=dict)
    #: the log's gaps that may hold messages of this clock's topics (:class:`fretc.logs.Gap`)
    gaps: list = field(default_factory=list)
    #: ticks inserted for gaps of a tick topic (indexes), unknown for every variable
    tick_gaps: list[int] = field(default_factory=list)
    #: the messages of its topics present but not decoded, in words (for reasons)
    lost_words: str = ""
    #: id of a requirement's AST -> (that AST, the columns, the indexes of its NaN ticks over
    #: them, the ticks), as :mod:`fretc.audit.finalize` computed them (never copied by
    #: ``dataclasses.replace``)
    nan_ticks: dict[int, tuple[Any, dict, np.ndarray, int]] = field(
        default_factory=dict, init=False, repr=False, compare=False)
