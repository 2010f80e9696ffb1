"""Robustness (the margin behind a verdict): quantitative semantics of a requirement's pt
formula over the columns of a trace.

FRET's pt formula at the last tick is the requirement's finite-trace verdict
(../shared/fretish/README.md); this module evaluates the same formula with Donze and Maler's
space robustness (Donze, Maler, FORMATS 2010; Fainekos, Pappas, TCS 2009) instead of truth
values, operator by operator over the same columns :mod:`fretc.monitors.vectorized` reads:

Design notes: ARCHITECTURE.md, `monitors/robustness.py`."""

from __future__ import annotations

import math
from typing import Any
from collections.abc import Hashable, Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from fretc.compiler.ir import Node, name_of, walk

from fretc.monitors.vectorized import VectorizeError, node_series

_FUTURE = ("X", "F", "G", "U", "V", "LAST", "future")

__all__ = ["RobustnessStream", "RobustnessSummary", "TINY", "POINTS", "ROBUSTNESS_CHUNK",
           "chunkable", "margin_ticks", "past_truth", "robustness", "robustness_columns",
           "robustness_series", "stateful", "summary_of"]

#: The smallest positive double: ``-TINY`` is the robustness of a comparison false at
#: distance 0 (the module docstring's sign convention).
TINY = math.ulp(0.0)
_INF = math.inf

Columns = Mapping[str, np.ndarray]


#: ticks evaluated at a time (a long trace's formula is evaluated a chunk at a time,
#: carrying each temporal operator's state: the memory is the margin's points and a few
#: arrays of a chunk, not a few arrays of the whole trace)
ROBUSTNESS_CHUNK = 1 << 16
#: the margin points :func:`robustness` keeps by default (the audit keeps its own count)
POINTS = 400


def robustness(pt: Node, columns: Columns, n: int, chunk: int | None = None, *,
               times: np.ndarray | None = None, points: int = POINTS) -> RobustnessSummary:
    """The robustness of the pt formula ``pt`` over a whole trace of ``n >= 1`` ticks: a
    :class:`RobustnessStream` fed it as one chunk (``chunk`` ticks, default
    :data:`ROBUSTNESS_CHUNK`, evaluated at a time when ``n`` is longer; a formula whose
    comparisons read a past-time operator or ``pre``, or whose window is longer than a
    chunk, over the whole trace at once). ``times``: the ticks' times (int64 ns; default
    each tick's index); ``points``: the margin points kept.

    Raises:
        VectorizeError: a future-time operator or function in ``pt``, or a missing or
            mis-shaped column (as :func:`fretc.monitors.vectorized.pt_series`).
        ValueError: ``n < 1``.
    """
    if n < 1:
        raise ValueError("robustness needs at least one tick")
    chunk = ROBUSTNESS_CHUNK if chunk is None else chunk
    stream = RobustnessStream(pt, points, chunk if n > chunk else n, whole=True)
    stream.feed(columns, n, np.arange(n, dtype=np.int64) if times is None else times)
    return stream.finish()


#: operators :class:`_Rho` evaluates itself (carrying their state from chunk to chunk);
#: any other node is evaluated by :func:`fretc.monitors.vectorized.node_series`
_OWN = frozenset(("!", "&", "|", "->", "<->", "xor", "Y", "Z", "O", "H", "S", "T", "ite",
                  "past", "FTP"))
#: operators whose value at a tick depends on earlier ticks
_STATEFUL = frozenset(("Y", "Z", "O", "H", "S", "T", "FTP", "pre"))


def _chunkable(body: Node, chunk: int) -> bool:
    """Whether ``body`` can be evaluated a chunk at a time: every node
    :func:`~fretc.monitors.vectorized.node_series` evaluates (comparisons, atoms) depends on
    its own tick only, and no bounded window reaches back further than a chunk."""
    for node in walk(body):
        if node.op in ("O", "H") and node.hi is not None and node.hi > chunk:
            return False
        if node.op not in _OWN and any(x.op in _STATEFUL for x in walk(node)):
            return False
    return True


def robustness_columns(pt: Node, columns: Columns, firsts: np.ndarray, lengths: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The robustness of each of ``len(firsts)`` traces laid end to end in ``columns``
    (trace ``e`` its ``lengths[e] >= 1`` ticks from ``firsts[e]``), in one evaluation of the
    formula that restarts every temporal operator at each trace's first tick, as columns:
    ``(margin, values, ticks)``, the margin of every tick of the traces (float array of
    ``lengths.sum()``), and per trace its value and tick (0-based in the trace; ``0`` when
    the value is NaN) as :class:`RobustnessSummary` defines them for one trace: what
    :func:`robustness` gives each trace alone (equal by test). None when that evaluation
    cannot restart (a comparison's operand holds a past-time operator or ``pre``) or the
    traces hold more than :data:`ROBUSTNESS_CHUNK` ticks in all: judge them one at a time.

    Raises:
        VectorizeError: as :func:`robustness`."""
    n = int(lengths.sum())
    top = pt.op == "H" and pt.hi is None
    body = pt.args[0] if top else pt
    if n > ROBUSTNESS_CHUNK or not _chunkable(body, 1 << 62):  # (any window: no chunks)
        return None
    margin = _Traces(columns, n, body, np.repeat(firsts, lengths)).rho(body)
    trace = np.repeat(np.arange(len(firsts), dtype=np.int64), lengths)
    local = np.arange(n, dtype=np.int64) - firsts[trace]  # (each tick's, in its trace)
    if top:  # the least, at its first tick (the value that tick's bits, as RobustnessStream reads it)
        values = np.minimum.reduceat(margin, firsts)
        far = np.iinfo(np.int64).max
        ticks = np.minimum.reduceat(np.where(margin == values[trace], local, far), firsts)
        found = ticks != far
        ticks[~found] = 0  # (NaN: no tick equals it)
        values[found] = margin[(firsts + ticks)[found]]
    else:  # the last tick's, from the tick after the last one that differs from it
        values = margin[firsts + lengths - 1]
        ticks = np.maximum.reduceat(np.where(margin != values[trace], local + 1, 0), firsts)
        ticks[np.isnan(values)] = 0
    return margin, values, ticks


def robustness_series(node: Node, columns: Columns, n: int) -> np.ndarray:
    """The robustness of a past-time formula ``node`` at every tick (float array ``(n,)``).

    Raises:
        VectorizeError: as :func:`robustness`.
    """
    return _Rho(columns, n, node).rho(node)


def past_truth(node: Node, columns: Columns, k: int, start: int, carry: dict) -> np.ndarray:
    """The truth (bool array ``(k,)``) of the past-time formula ``node`` at the ticks
    ``start..start+k-1`` (``k >= 1``) of a trace fed a chunk at a time: the sign of its
    robustness (``>= 0`` exactly where true, the module docstring's induction), each
    temporal operator's state carried in ``carry`` (one dict per formula, empty at tick 0,
    given again with the next chunk). Equal to
    :func:`fretc.monitors.vectorized.node_series` over the whole trace (by test) where
    :func:`chunkable` says so.

    Raises:
        VectorizeError: as :func:`robustness`."""
    return _Rho(columns, k, node, start, carry).rho(node) >= 0


def chunkable(node: Node) -> bool:
    """Whether the past-time formula ``node`` can be evaluated a chunk of ticks at a time
    (:func:`past_truth`, :class:`RobustnessStream`): no comparison, arithmetic or call of
    it reads a past-time operator or ``pre`` (bounded windows of any length)."""
    return _chunkable(node, 1 << 62)


def stateful(node: Node) -> bool:
    """Whether ``node``'s value at a tick depends on earlier ticks (a past-time operator,
    ``pre``, ``FTP`` in it)."""
    return any(x.op in _STATEFUL for x in walk(node))


def margin_ticks(margin: np.ndarray, points: int) -> list[int]:
    """The ticks (ascending) the audit reports the margin at: the ticks cut into runs of
    ``B`` consecutive ticks from tick 0, ``B`` the least power of two with ``ceil(n / B) <=
    points`` (``B = 1``, every tick, when ``n <= points``), and of each run the tick of its
    least value, the first at ties (NaN counts as least, as ``np.argmin``). A power of two
    from tick 0 so that a stream keeps them without knowing ``n`` (:class:`_MarginRuns`:
    two runs merge into one when the ticks outgrow ``points`` runs). At most ``points``
    ticks, so no dip of the margin is lost.

    Args:
        margin: float array ``(n,)``.
        points: the most ticks given (``>= 1``)."""
    n, size = len(margin), _run_size(len(margin), points)
    if size == 1:
        return list(range(n))
    whole = n - n % size
    ticks = (np.argmin(margin[:whole].reshape(-1, size), axis=1)
             + np.arange(0, whole, size, dtype=np.int64)).tolist()
    if whole < n:
        ticks.append(whole + int(np.argmin(margin[whole:])))
    return ticks


def _run_size(n: int, points: int) -> int:
    """:func:`margin_ticks`' ``B`` for ``n`` ticks."""
    if points < 1:
        raise ValueError(f"margin points must be at least 1, not {points}")
    size = 1
    while -(-n // size) > points:
        size *= 2
    return size


class _MarginRuns:
    """:func:`margin_ticks` of a margin fed a chunk at a time, with each tick's time and
    value: per run of ``size`` ticks (run ``j`` from tick ``j * size``) the least value,
    its tick and time; when the ticks would need more than ``points`` runs, runs ``2j``
    and ``2j + 1`` merge into run ``j`` of twice the size. Memory: three arrays of at most
    ``points`` runs, and one chunk's while it is added."""

    def __init__(self, points: int) -> None:
        self.points, self.size = points, _run_size(0, points)
        self.values: np.ndarray = np.empty(0, np.float64)
        self.ticks: np.ndarray = np.empty(0, np.int64)
        self.times: np.ndarray = np.empty(0, np.int64)

    def add(self, margin: np.ndarray, start: int, times: np.ndarray) -> None:
        """The margin (float ``(k,)``) and times (int64 ns ``(k,)``) of ticks
        ``start..start+k-1``, ``start`` the ticks added before."""
        end = start + len(margin)
        while -(-end // self.size) > self.points:
            self._merge_pairs()
        size, at = self.size, 0
        if start % size:  # the rest of the last run, begun by the chunk before
            at = min(len(margin), size - start % size)
            i = int(np.argmin(margin[:at]))
            self._append(margin[i:i + 1], np.array([start + i], np.int64), times[i:i + 1])
            self._merge_last()
        whole = at + (len(margin) - at) // size * size
        if whole > at:
            i = np.argmin(margin[at:whole].reshape(-1, size), axis=1) + np.arange(
                at, whole, size, dtype=np.int64)
            self._append(margin[i], start + i, times[i])
        if whole < len(margin):
            i = whole + int(np.argmin(margin[whole:]))
            self._append(margin[i:i + 1], np.array([start + i], np.int64), times[i:i + 1])

    def _append(self, values: np.ndarray, ticks: np.ndarray, times: np.ndarray) -> None:
        self.values = np.concatenate((self.values, values))
        self.ticks = np.concatenate((self.ticks, ticks))
        self.times = np.concatenate((self.times, np.asarray(times, np.int64)))

    @staticmethod
    def _later(first: np.ndarray, second: np.ndarray) -> np.ndarray:
        """Where the later of two runs holds the least of both (``np.argmin``'s choice:
        the first NaN, else the first least)."""
        return (second < first) | (np.isnan(second) & ~np.isnan(first))

    def _merge_last(self) -> None:
        """The last two entries as one run (the rest of a run added to its beginning)."""
        drop = -2 if self._later(self.values[-2:-1], self.values[-1:])[0] else -1
        self.values = np.delete(self.values, drop)
        self.ticks = np.delete(self.ticks, drop)
        self.times = np.delete(self.times, drop)

    def _merge_pairs(self) -> None:
        """Runs ``2j`` and ``2j + 1`` as run ``j`` of twice the size."""
        even = len(self.values) - len(self.values) % 2
        take = self._later(self.values[0:even:2], self.values[1:even:2])

        def merged(x: np.ndarray) -> np.ndarray:
            return np.concatenate((np.where(take, x[1:even:2], x[0:even:2]), x[even:]))

        self.values, self.ticks, self.times = (merged(self.values), merged(self.ticks),
                                               merged(self.times))
        self.size *= 2

    def points_list(self) -> list[tuple[int, int, float]]:
        """``[(tick, time_ns, value)]`` of the runs, ascending."""
        return list(zip(self.ticks.tolist(), self.times.tolist(), self.values.tolist()))


@dataclass(frozen=True)
class RobustnessSummary:
    """A requirement's robustness on one trace of ``n`` ticks, as :class:`RobustnessStream`
    keeps it (the *margin* at a tick is the robustness of the body of a top-level unbounded
    ``H``, what must hold at every tick, else of the pt formula at that tick).

    Attributes:
        value: the robustness of the pt formula at the last tick (the whole trace), in the
            unit of the comparison that decides it; ``+-inf`` when a boolean decides it.
            Negative exactly when FRET's finite-trace verdict is false.
        tick: the 0-based tick where the margin that decides the verdict was reached (0
            when ``value`` is NaN). For a pt formula whose top is an unbounded ``H`` (the
            value is the least margin) the first tick whose margin equals ``value`` (where
            the trace came closest to violating, or violated most); for any other pt
            formula (the value is the margin at the last tick) the first tick of the last
            run of consecutive ticks whose margin equals ``value``: the tick since which
            the margin has held its final value.
        tick_time: the time of that tick (int ns, as the fed ``times``).
        points: the margin at :func:`margin_ticks`' ticks, ``[(tick, time_ns, value)]``
            ascending: ``[(i, times[i], margin[i]) for i in margin_ticks(margin, points)]``.
        n: the ticks it was judged over.
    """

    value: float
    tick: int
    tick_time: int
    points: list[tuple[int, int, float]]
    n: int = 0


def summary_of(margin: np.ndarray, value: float, tick: int, times: np.ndarray, points: int
               ) -> RobustnessSummary:
    """The :class:`RobustnessSummary` of a margin computed already (``(n,)`` floats, ``n >=
    1``; ``value`` and ``tick`` as defined there, ``times`` the ticks' times): the margin
    of traces laid end to end (:func:`robustness_columns`)."""
    kept = [(i, int(times[i]), float(margin[i])) for i in margin_ticks(margin, points)]
    return RobustnessSummary(value, tick, int(times[tick]), kept, len(margin))


class _Recorder(Mapping):
    """Columns that record the names read (each a tick of zeros)."""

    def __init__(self) -> None:
        self.names: list[str] = []

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self.names:
            self.names.append(name)
        return np.zeros(1, np.float64)

    def __iter__(self) -> Iterator[str]:
        return iter(self.names)

    def __len__(self) -> int:
        return len(self.names)


def _columns_read(node: Node) -> list[str]:
    """The columns the evaluation of the past-time formula ``node`` reads (found by
    evaluating it over one tick of zeros)."""
    rec = _Recorder()
    with np.errstate(all="ignore"):
        _Rho(rec, 1, node).rho(node)
    return rec.names


class RobustnessStream:
    """:func:`robustness` of a pt formula over a trace fed a chunk of ticks at a time
    (Donze, Maler, FORMATS 2010's space robustness, the module docstring's table), kept as
    a :class:`RobustnessSummary`: the value and tick :func:`robustness` gives over the whole
    trace, and the margin at :func:`margin_ticks`' ticks, the same bits.

    The fed ticks are buffered into blocks of ``chunk`` ticks (default
    :data:`ROBUSTNESS_CHUNK`), each evaluated as :func:`robustness` evaluates its chunks
    (each temporal operator's state carried to the next block), so the margins are the
    same floats. Memory: the formula's columns over one block and a few float arrays of
    it, and three arrays of at most ``points`` runs (:class:`_MarginRuns`): independent of
    the trace's length.

    A column may change dtype from chunk to chunk (a boolean read as ``bool``, ``uint8``
    0/1 or ``float64`` 0/1: a CSV reader decides a column's type at the end of the file):
    a block holds the common type of its pieces (``np.result_type``), which reads as the
    same truth (``bool(x)``) and the same number. A whole block fed at once is evaluated
    where it lies (no copy).
    """

    def __init__(self, pt: Node, points: int, chunk: int | None = None,
                 whole: bool = False) -> None:
        """Args:
            pt: the requirement's pt formula.
            points: the most margin points kept (``>= 1``, the audit's ``MARGIN_POINTS``).
            chunk: ticks per block (:func:`robustness`'s ``chunk``).
            whole: a formula that cannot be evaluated a chunk at a time is taken, fed the
                whole trace as one chunk (evaluated at once: :func:`robustness`).

        Raises:
            VectorizeError: a future-time operator or function; without ``whole``, a
                formula that cannot be evaluated a chunk at a time: a comparison,
                arithmetic or call over a past-time operator or ``pre``, or a bounded
                window longer than ``chunk``.
            ValueError: ``points < 1``.
        """
        self.chunk = ROBUSTNESS_CHUNK if chunk is None else chunk
        self.top = pt.op == "H" and pt.hi is None
        self.body = pt.args[0] if self.top else pt
        if any(x.op in _FUTURE for x in walk(self.body)):
            raise VectorizeError("future-time operator or function in a past-time formula")
        #: fed the whole trace as one block (a formula not evaluated a chunk at a time)
        self.at_once = not _chunkable(self.body, self.chunk)
        if self.at_once and not whole:
            raise VectorizeError("the pt formula compares a past-time value, or has a window "
                                 f"longer than {self.chunk} ticks: not a chunk at a time")
        self.names = _columns_read(self.body)
        self.runs = _MarginRuns(points)
        self.carry: dict[Node, object] = {}
        self.blocks: dict[str, np.ndarray] = {}  # name -> the block's values (``chunk``)
        self.times = np.empty(self.chunk, np.int64)
        self.fill = 0  # ticks in the block
        self.start = 0  # the trace's tick of the block's first
        self.first_time = 0  # the time of tick 0
        #: the value so far (NaN before a tick), its tick (None before) and that tick's time
        self.value = math.nan
        self.tick: int | None = None
        self.tick_time = 0
        self.done: RobustnessSummary | None = None

    def feed(self, columns: Columns, k: int, times: np.ndarray) -> None:
        """The next ``k >= 0`` ticks: ``columns`` every column the formula reads (FRET
        variable, or the text of an uninterpreted call -> a 1-D array whose first ``k``
        values are these ticks'), ``times`` their times (int64 ns, at least ``k``).

        Raises:
            VectorizeError: a column missing or shorter than ``k``.
            ValueError: fed after :meth:`finish`; a second chunk of a formula fed at once.
        """
        if self.done is not None:
            raise ValueError("the robustness stream was finished")
        if k <= 0:
            return
        pieces = {name: _piece(columns, name, k) for name in self.names}
        times = np.asarray(times)[:k]
        if len(times) != k:
            raise VectorizeError(f"{len(times)} times for {k} ticks")
        if self.at_once:
            if self.start or self.fill:
                raise ValueError("the pt formula compares a past-time value: its robustness "
                                 "is fed the whole trace as one chunk")
            self._evaluate(pieces, k, times)
            return
        at = 0
        while at < k:
            if not self.fill and k - at >= self.chunk:  # (a whole block: where it lies)
                b = at + self.chunk
                self._evaluate({name: p[at:b] for name, p in pieces.items()}, self.chunk,
                               times[at:b])
                at = b
                continue
            take = min(k - at, self.chunk - self.fill)
            for name, piece in pieces.items():
                self._put(name, piece[at:at + take])
            self.times[self.fill:self.fill + take] = times[at:at + take]
            self.fill += take
            at += take
            if self.fill == self.chunk:
                self._evaluate_block()

    def finish(self) -> RobustnessSummary:
        """The summary of the ticks fed (the block begun evaluated); the same on every call.

        Raises:
            ValueError: no tick was fed (:func:`robustness` needs one).
        """
        if self.done is None:
            if self.fill:
                self._evaluate_block()
            if self.start == 0:
                raise ValueError("robustness needs at least one tick")
            if self.value != self.value:  # (NaN: no tick equals it: tick 0)
                self.tick, self.tick_time = 0, self.first_time
            assert self.tick is not None  # (a value not NaN was met at a tick)
            self.done = RobustnessSummary(self.value, self.tick, self.tick_time,
                                          self.runs.points_list(), self.start)
            self.blocks = {}
        return self.done

    def _put(self, name: str, piece: np.ndarray) -> None:
        """``piece`` into the block of ``name`` from :attr:`fill` (the block widened to the
        common type when the piece's differs)."""
        block = self.blocks.get(name)
        if block is None:
            block = self.blocks[name] = np.empty(self.chunk, piece.dtype)
        elif block.dtype != piece.dtype:
            common = np.result_type(block.dtype, piece.dtype)
            if common != block.dtype:
                block = self.blocks[name] = block.astype(common)
        block[self.fill:self.fill + len(piece)] = piece

    def _evaluate_block(self) -> None:
        """:meth:`_evaluate` of the block filled; the block emptied."""
        k = self.fill
        self._evaluate({name: block[:k] for name, block in self.blocks.items()}, k,
                       self.times[:k])
        self.fill = 0

    def _evaluate(self, columns: Columns, k: int, times: np.ndarray) -> None:
        """The margin of the next ``k`` ticks (``columns``, ``times``: theirs), each temporal
        operator's state carried, read into the value, tick and margin points."""
        a = self.start
        margin = _Rho(columns, k, self.body, a, self.carry).rho(self.body)
        if a == 0:
            self.first_time = int(times[0])
        if self.top:
            self._least(margin, a, times)
        else:
            self._last_run(margin, a, times)
        self.runs.add(margin, a, times)
        self.start = a + k

    def _least(self, margin: np.ndarray, a: int, times: np.ndarray) -> None:
        """A top ``H``: the least margin so far at its first tick (NaN: stays NaN)."""
        least = margin.min()
        if least != least:
            self.value, self.tick = math.nan, 0
        elif self.tick is None or least < self.value:  # (False once NaN)
            i = int(np.argmax(margin == least))
            self.value, self.tick, self.tick_time = float(margin[i]), a + i, int(times[i])

    def _last_run(self, margin: np.ndarray, a: int, times: np.ndarray) -> None:
        """Any other pt formula: the last tick's margin, and the first tick of the last
        run of ticks at it (a run the block before began continues)."""
        value = float(margin[-1])
        differs = margin[::-1] != value
        back = int(np.argmax(differs))
        if not differs[back]:  # (the whole block at it: the run goes on, or begins here)
            if self.tick is None or not self.value == value:
                self.tick, self.tick_time = a, int(times[0])
        elif back:  # (back 0: the value NaN, which differs from itself: no tick)
            i = len(margin) - back
            self.tick, self.tick_time = a + i, int(times[i])
        self.value = value


def _piece(columns: Columns, name: str, k: int) -> np.ndarray:
    """The first ``k`` values of column ``name`` (1-D).

    Raises:
        VectorizeError: no such column, or fewer values."""
    col = columns.get(name)
    if col is None:
        raise VectorizeError(f"no column for variable {name!r}")
    col = np.asarray(col)
    if col.ndim != 1 or len(col) < k:
        raise VectorizeError(f"column {name!r} has shape {col.shape}, expected ({k},)")
    return col[:k]


def _neg(x: np.ndarray) -> np.ndarray:
    """``-x``, with 0 (true) mapped to ``-TINY`` (false)."""
    return np.where(x == 0, -TINY, -x)


def _fix_sign(rho: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """``rho`` with its sign forced to the comparison's truth (equality of a strict
    comparison, NaN): ``0.0`` where true but not ``>= 0``, ``-TINY`` where false but not
    ``< 0``."""
    with np.errstate(invalid="ignore"):
        rho = np.where(truth & ~(rho >= 0), 0.0, rho)
        return np.where(~truth & ~(rho < 0), -TINY, rho)


#: ticks of a since (``S``, ``T``) recurrence run at a time (:meth:`_Rho._since`)
SINCE_CHUNK = 1 << 14


class _Rho:
    """Per-node robustness arrays over ``n`` ticks of the formula ``root``; a node read by
    several parents is kept until its last parent read it, any other array only while it
    is used (the memory is a few arrays of ``n`` floats, not one per node)."""

    def __init__(self, columns: Columns, n: int, root: Node, start: int = 0,
                 carry: dict | None = None):
        self.columns = columns
        self.n = n
        #: the trace's tick of index 0 here, and the temporal operators' state at the end of
        #: the ticks before it (node -> value), when the trace is evaluated in chunks
        self.start = start
        self.carry = carry
        self.memo: dict[Node, np.ndarray] = {}
        self.uses: dict[Node, int] = {}  # node -> reads by its parents still to come
        seen, stack = {root}, [root]
        while stack:
            for child in stack.pop().args:
                self.uses[child] = self.uses.get(child, 0) + 1
                if child not in seen:
                    seen.add(child)
                    stack.append(child)

    def rho(self, node: Node) -> np.ndarray:
        got = self.memo.get(node)
        if got is None:
            got = self._compute(node)
            if self.uses.get(node, 0) > 1:
                self.memo[node] = got
        left = self.uses.get(node, 0) - 1
        self.uses[node] = left
        if left <= 0:
            self.memo.pop(node, None)
        return got

    def _compute(self, node: Node) -> np.ndarray:
        op, a, n = node.op, node.args, self.n
        if op in _FUTURE:
            raise VectorizeError(f"future-time operator {op!r} in a past-time formula")
        if op == "cmp":
            return self._comparison(node)
        if op == "!":
            return _neg(self.rho(a[0]))
        if op in ("&", "|", "->", "<->", "xor"):
            return self._connective(op, a[0], a[1])
        if op in ("Y", "Z"):
            x = self.rho(a[0])
            out = np.empty(n)
            out[0] = self._carried(node, -_INF if op == "Y" else _INF)
            out[1:] = x[:-1]
            self._keep(node, float(x[-1]))
            return out
        if op == "FTP":
            out = np.full(n, -_INF)
            if self.start == 0:
                out[0] = _INF
            return out
        if op in ("O", "H"):
            return self._once(node)
        if op in ("S", "T"):
            return self._since(node)
        if op == "ite":  # a boolean if-then-else: (c & t) | (!c & e)
            c = self.rho(a[0])
            return np.maximum(np.minimum(c, self.rho(a[1])),
                              np.minimum(_neg(c), self.rho(a[2])))
        if op == "past":
            return self.rho(a[0])
        # constants, FTP, boolean variables and calls: +-inf by their truth
        truth = node_series(node, self.columns, n)
        return np.where(truth, _INF, -_INF)

    def _carried(self, node: Hashable, initial):
        """The state ``node`` carried from the chunk before (``initial`` at the start)."""
        if self.carry is None or node not in self.carry:
            return initial
        return self.carry[node]

    def _keep(self, node: Hashable, state) -> None:
        if self.carry is not None:
            self.carry[node] = state

    def _comparison(self, node: Node) -> np.ndarray:
        x = node_series(node.args[0], self.columns, self.n, numeric=True)
        y = node_series(node.args[1], self.columns, self.n, numeric=True)
        truth = node_series(node, self.columns, self.n)
        with np.errstate(invalid="ignore", over="ignore"):
            d = {"<": y - x, "<=": y - x, ">": x - y, ">=": x - y,
                 "=": -np.abs(x - y), "!=": np.abs(x - y)}[name_of(node)]
        return _fix_sign(d, truth)

    def _connective(self, op: str, p: Node, q: Node) -> np.ndarray:
        x, y = self.rho(p), self.rho(q)
        if op == "&":
            return np.minimum(x, y)
        if op == "|":
            return np.maximum(x, y)
        if op == "->":
            return np.maximum(_neg(x), y)
        iff = np.minimum(np.maximum(_neg(x), y), np.maximum(x, _neg(y)))
        return iff if op == "<->" else _neg(iff)

    def _once(self, node: Node) -> np.ndarray:
        """``O`` / ``H``: running max / min, or over the window ``[i-hi, i-lo]``."""
        if node.hi is not None:  # (the operand's values held by _bounded alone)
            return self._bounded(node, self.rho(node.args[0]))
        x = self.rho(node.args[0])
        pick = np.maximum if node.op == "O" else np.minimum
        out = pick.accumulate(x)
        before = self._carried(node, None)
        if before is not None:
            out = pick(out, before)
        self._keep(node, float(out[-1]))
        return out

    def _bounded(self, node: Node, x: np.ndarray) -> np.ndarray:
        """``O[lo,hi]`` / ``H[lo,hi]`` of the operand's values ``x``: the max / min over the
        window ``[i-hi, i-lo]`` (``-inf`` / ``+inf`` where it is empty), the last ``hi``
        values carried to the next chunk."""
        is_once = node.op == "O"
        pick = np.maximum if is_once else np.minimum
        lo, hi = node.lo or 0, node.hi
        assert hi is not None  # (a bounded operator)
        tail = self._carried(node, x[:0])  # the last ``hi`` ticks before, where they exist
        if len(tail):
            x = np.concatenate((tail, x))
        m = len(x)
        out = np.full(m, -_INF if is_once else _INF)
        for d in range(lo, min(hi, m - 1) + 1):  # the value d ticks back, where it exists
            out[d:] = pick(out[d:], x[:m - d])
        self._keep(node, x[max(0, m - hi):].copy() if hi else x[:0])
        return out[len(tail):]

    def _since(self, node: Node) -> np.ndarray:
        """``a S b``: ``s[i] = max(b[i], min(a[i], s[i-1]))`` from ``s[-1] = -inf``; its dual
        ``a T b``: ``s[i] = min(b[i], max(a[i], s[i-1]))`` from ``+inf``. The recurrence
        runs over :data:`SINCE_CHUNK` ticks at a time as Python floats, so its memory is the
        output array and one chunk, not Python objects for every tick."""
        op = node.op
        a, b = self.rho(node.args[0]), self.rho(node.args[1])
        out = np.empty(self.n, dtype=np.float64)
        s = self._carried(node, -_INF if op == "S" else _INF)
        for k in range(0, self.n, SINCE_CHUNK):
            chunk = []
            if op == "S":
                for ai, bi in zip(a[k:k + SINCE_CHUNK].tolist(), b[k:k + SINCE_CHUNK].tolist()):
                    s = max(bi, min(ai, s))
                    chunk.append(s)
            else:
                for ai, bi in zip(a[k:k + SINCE_CHUNK].tolist(), b[k:k + SINCE_CHUNK].tolist()):
                    s = min(bi, max(ai, s))
                    chunk.append(s)
            out[k:k + len(chunk)] = chunk
        self._keep(node, s)
        return out


class _Traces(_Rho):
    """:class:`_Rho` over traces laid end to end: ``seg[i]`` the first tick of tick ``i``'s
    trace; the temporal operators start again at each trace's first tick (no carry)."""

    def __init__(self, columns: Columns, n: int, root: Node, seg: np.ndarray) -> None:
        super().__init__(columns, n, root)
        self.seg = seg
        self.first = np.arange(n, dtype=np.int64) == seg

    def _compute(self, node: Node) -> np.ndarray:
        op = node.op
        if op in ("Y", "Z"):
            out = np.empty(self.n)
            out[1:] = self.rho(node.args[0])[:-1]
            out[self.first] = -_INF if op == "Y" else _INF
            return out
        if op == "FTP":
            return np.where(self.first, _INF, -_INF)
        return super()._compute(node)

    def _scan(self, x: np.ndarray, combine: Any) -> np.ndarray:
        """The inclusive scan of ``x`` by ``combine(earlier, later)`` (associative) within
        each trace, by doubling (Hillis and Steele): ``log2`` of the longest trace numpy
        steps over all ticks, rather than a step per trace or per tick."""
        n, idx = self.n, np.arange(self.n, dtype=np.int64)
        longest = int((idx - self.seg).max()) + 1 if n else 0
        out, d = x, 1
        while d < longest:
            ok = idx[d:] - d >= self.seg[d:]  # (tick i - d in tick i's trace)
            new = out.copy() if out is x else out
            new[d:] = np.where(ok, combine(out[:-d], out[d:]), out[d:])
            out, d = new, d * 2
        return out.copy() if out is x else out

    def _once(self, node: Node) -> np.ndarray:
        x, is_once = self.rho(node.args[0]), node.op == "O"
        pick = np.maximum if is_once else np.minimum
        if node.hi is None:  # (max and min: exact whatever the order of the steps)
            return self._scan(x, pick)
        lo, hi, m = node.lo or 0, node.hi, self.n
        out = np.full(m, -_INF if is_once else _INF)
        idx = np.arange(m, dtype=np.int64)
        for d in range(lo, min(hi, m - 1) + 1):  # the value d ticks back, in the same trace
            inside = idx[d:] - d >= self.seg[d:]
            out[d:] = np.where(inside, pick(out[d:], x[:m - d]), out[d:])
        return out

    def _since(self, node: Node) -> np.ndarray:
        """``a S b`` and ``a T b`` (:meth:`_Rho._since`'s recurrences) restarting at each
        trace: each tick's step ``s -> max(b, min(a, s))`` (``S``) is the clamp of ``s`` to
        ``[b, max(a, b)]`` (``T``'s ``min(b, max(a, s))`` to ``[min(a, b), b]``), clamps
        compose into clamps, so the recurrence is a scan of clamps (:meth:`_scan`) read at
        the start value (``-inf``: the low end; ``+inf``: the high end). The values are
        the inputs' (no arithmetic): those of the tick by tick loop, which runs instead
        where an input is NaN or a negative zero (Python's ``max`` and ``min`` order
        them as it meets them)."""
        op = node.op
        a, b = self.rho(node.args[0]), self.rho(node.args[1])
        if not (np.isnan(a).any() or np.isnan(b).any()
                or ((a == 0) & np.signbit(a)).any() or ((b == 0) & np.signbit(b)).any()):
            lo, hi = (b, np.maximum(a, b)) if op == "S" else (np.minimum(a, b), b)
            both = np.stack((lo, hi))

            def compose(earlier: np.ndarray, later: np.ndarray) -> np.ndarray:
                return np.minimum(np.maximum(earlier, later[0]), later[1])

            got = self._scan_pairs(both, compose)
            return got[0] if op == "S" else got[1]
        return self._since_loop(op, a.tolist(), b.tolist())

    def _scan_pairs(self, x: np.ndarray, combine: Any) -> np.ndarray:
        """:meth:`_scan` of pairs (``x`` of shape ``(2, n)``, ``combine`` of such arrays)."""
        n, idx = self.n, np.arange(self.n, dtype=np.int64)
        longest = int((idx - self.seg).max()) + 1 if n else 0
        out, d = x, 1
        while d < longest:
            ok = idx[d:] - d >= self.seg[d:]
            new = out.copy()
            new[:, d:] = np.where(ok, combine(out[:, :-d], out[:, d:]), out[:, d:])
            out, d = new, d * 2
        return out

    def _since_loop(self, op: str, a: list, b: list) -> np.ndarray:
        """:meth:`_since` tick by tick (Python floats)."""
        start = -_INF if op == "S" else _INF
        out, s = [], start
        for ai, bi, first in zip(a, b, self.first.tolist()):
            if first:
                s = start
            s = max(bi, min(ai, s)) if op == "S" else min(bi, max(ai, s))
            out.append(s)
        return np.array(out, dtype=np.float64)
