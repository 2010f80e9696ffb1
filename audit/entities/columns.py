"""The per-entity variables of one per-entity requirement as columns
(:class:`EntityColumns`): what :mod:`fretc.audit.entities.log` judges, one entity's trace at a
time or every entity's laid end to end.

At each tick a per-entity variable reads, for an entity present in the held key message, its
row's value, else the variable's absent value at that tick (:mod:`fretc.audit.entities.read`).
A trace's column is bool when every value in it is a bool (the absent values count as bools
only when all of them are, at every tick), else float (True 1.0, False 0.0, NaN unknown), as
:func:`column` types one; the rows are kept as numpy arrays (entity, tick,
value, whether a bool) sorted by entity, so that gathering a trace is a few numpy steps
rather than a loop over its ticks.
"""

from __future__ import annotations

from collections.abc import Sequence
from operator import attrgetter
from typing import Any

import numpy as np

__all__ = ["column", "floats", "EntityColumns", "RowBlock", "HeldRows"]


def column(values: list) -> np.ndarray:
    """Values of one variable as a column: booleans as bool, else float (NaN unknown)."""
    f, b = floats(values)
    return f.astype(np.bool_) if len(f) and b.all() else f


def floats(values: list) -> tuple[np.ndarray, np.ndarray]:
    """``values`` as float64 (bools 1.0 and 0.0; None and what is no number NaN) and whether
    each is a bool."""
    n = len(values)
    isbool = np.array([type(x) is bool or type(x) is np.bool_ for x in values], np.bool_)
    try:
        return np.array(values, dtype=np.float64).reshape(n), isbool
    except (TypeError, ValueError):
        pass
    out = np.empty(n, np.float64)
    for k, x in enumerate(values):
        try:
            out[k] = float(x) if x is not None else np.nan
        except (TypeError, ValueError):
            out[k] = np.nan
    return out, isbool


def _merged(absent: tuple[np.ndarray, np.ndarray], slots: np.ndarray,
            rows: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The absent values with the rows' values put at ``slots``, typed as :func:`column`."""
    f, b = absent[0].copy(), absent[1].copy()
    f[slots] = rows[0]
    b[slots] = rows[1]
    return f.astype(np.bool_) if len(f) and b.all() else f


class RowBlock:
    """The rows of a batch of held key messages (:mod:`fretc.audit.entities.read`, vectorized):
    ``entity`` the entity of each row, message ``q``'s rows ``offsets[q]..offsets[q+1]``,
    ``values`` variable -> (float64 values, whether each is a bool) over the rows."""

    __slots__ = ("entity", "offsets", "values")

    def __init__(self, entity: np.ndarray, offsets: np.ndarray,
                 values: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
        self.entity, self.offsets, self.values = entity, offsets, values


class HeldRows:
    """The rows of one held key message, shared by the ticks that hold it: message ``at``
    of ``block``, set when its batch is evaluated."""

    __slots__ = ("block", "at")

    def __init__(self) -> None:
        self.block: RowBlock | None = None
        self.at = 0


class EntityColumns:
    """The per-entity variables ``names`` of an array key's clock: per variable the absent
    value at each tick and the rows ``(entity, tick, value)`` of the ticks ``ticks``
    (each tick's ``values[entities]`` is ``(absent values, rows)``, the rows a list of
    ``(entity, values)`` or a :class:`HeldRows`)."""

    def __init__(self, ticks: list, names: list[str], entities: str, n_entities: int) -> None:
        absent = {}
        for j, n in enumerate(names):
            absent[n] = floats([t.values[entities][0][j] for t in ticks])
        n_ticks = len(ticks)
        self._build(names, absent, list(range(n_ticks)), [1] * n_ticks,
                    [t.values[entities][1] for t in ticks], n_ticks, n_entities)

    @classmethod
    def of_runs(cls, names: list[str], absent: tuple, firsts: list[int], counts: Sequence[int],
                rows: list, n_ticks: int, n_entities: int) -> EntityColumns:
        """The columns of ``n_ticks`` ticks given as runs (run ``r``: ``counts[r]`` ticks from
        tick ``firsts[r]``, each holding the rows ``rows[r]``; :mod:`fretc.audit.entities.runs`),
        ``absent`` the variables' absent values at every tick."""
        out = cls.__new__(cls)
        cols = {}
        for j, n in enumerate(names):
            f, b = floats([absent[j]])
            cols[n] = (np.repeat(f, n_ticks), np.repeat(b, n_ticks))
        out._build(names, cols, firsts, counts, rows, n_ticks, n_entities)
        return out

    def _build(self, names: list[str], absent: dict[str, tuple[np.ndarray, np.ndarray]],
               firsts: list[int], counts: Sequence[int], rows: list, n_ticks: int,
               n_entities: int) -> None:
        """The columns from the absent values (per variable, at each tick) and the rows of
        runs (:meth:`of_runs`): rows given as a list of ``(entity, values)``, or as a
        :class:`HeldRows` (gathered from their blocks by numpy, run by run)."""
        self.names = names
        self.absent = {n: (f, b if b.all() else np.zeros(len(b), np.bool_))
                       for n, (f, b) in absent.items()}
        is_list = np.array([type(r) is list for r in rows], np.bool_)
        parts = [self._listed(names, firsts, counts, rows, n_ticks, bool(is_list.any()))]
        if not is_list.all():
            at = np.flatnonzero(~is_list)
            parts.append(_held_rows(names, [rows[j] for j in at.tolist()],
                                    np.asarray(firsts, np.int64)[at],
                                    np.asarray(counts, np.int64)[at]))
        parts = [p for p in parts if len(p[0])] or parts[:1]
        small = max(n_entities, n_ticks) < 2 ** 31  # (int32 indexes: half the memory)
        entity = _joined([p[0] for p in parts])
        if small:
            entity = entity.astype(np.int32)
        order = np.argsort(entity, kind="stable")
        self.entity = entity[order]
        del entity
        tick = _joined([p[1] for p in parts])
        self.tick = (tick.astype(np.int32) if small else tick)[order]
        del tick
        self.starts = np.searchsorted(self.entity, np.arange(n_entities + 1))
        self.rows: dict[str, tuple[np.ndarray, np.ndarray]] = {
            n: (_joined([p[2][n][0] for p in parts])[order],
                _joined([p[2][n][1] for p in parts])[order]) for n in names}

    @staticmethod
    def _listed(names: list[str], firsts: list[int], counts: Sequence[int], rows: list,
                n_ticks: int, any_list: bool) -> tuple:
        """The rows given as lists, as (entity, tick, variable -> (values, bools))."""
        flat: list[tuple] = []
        per_tick = np.zeros(n_ticks, np.int64)
        if any_list:
            for k, m, got in zip(firsts, counts, rows):
                if got and type(got) is list:
                    per_tick[k:k + m] = len(got)
                    flat.extend(got * m)
        vals = [r[1] for r in flat]
        return (np.array([r[0] for r in flat], np.int64),
                np.repeat(np.arange(n_ticks, dtype=np.int64), per_tick),
                {n: floats([v[j] for v in vals]) for j, n in enumerate(names)})

    def trace(self, i: int, i0: int, i1: int) -> dict[str, np.ndarray]:
        """Entity ``i``'s columns over ticks ``i0..i1``."""
        a, z = int(self.starts[i]), int(self.starts[i + 1])
        k = self.tick[a:z]
        inside = (k >= i0) & (k <= i1)
        slots = k[inside] - i0
        return {n: _merged((self.absent[n][0][i0:i1 + 1], self.absent[n][1][i0:i1 + 1]), slots,
                           (self.rows[n][0][a:z][inside], self.rows[n][1][a:z][inside]))
                for n in self.names}

    def end_to_end(self, judged: list[int], i0s: np.ndarray, firsts: np.ndarray,
                   lengths: np.ndarray, idx: np.ndarray) -> dict[str, Any]:
        """The columns of the entities ``judged`` laid end to end: entity ``judged[e]``'s
        ticks ``i0s[e]..i0s[e] + lengths[e] - 1`` at ``firsts[e]``; ``idx`` the tick of
        each place."""
        at = np.full(len(self.starts) - 1, -1, np.int64)
        at[np.asarray(judged, np.int64)] = np.arange(len(judged))
        e = at[self.entity]
        k = self.tick
        ok = e >= 0
        e, k = e[ok], k[ok]
        inside = (k >= i0s[e]) & (k < i0s[e] + lengths[e])
        slots = firsts[e[inside]] + k[inside] - i0s[e[inside]]
        return {n: _merged((self.absent[n][0][idx], self.absent[n][1][idx]), slots,
                           (self.rows[n][0][ok][inside], self.rows[n][1][ok][inside]))
                for n in self.names}


def _joined(arrays: list[np.ndarray]) -> np.ndarray:
    """``arrays`` end to end (one array: itself, not a copy)."""
    return arrays[0] if len(arrays) == 1 else np.concatenate(arrays)


def _held_rows(names: list[str], held: list[HeldRows], firsts: np.ndarray,
               counts: np.ndarray) -> tuple:
    """The rows of runs holding :class:`HeldRows` (run ``r``: ``counts[r]`` ticks from
    ``firsts[r]``, each the rows of message ``held[r].at`` of ``held[r].block``), as
    (entity, tick, variable -> (values, bools)): the blocks laid end to end, each tick's
    rows gathered by numpy."""
    of = list(map(attrgetter("block"), held))
    blocks: list[RowBlock] = list(dict.fromkeys(of))
    assert None not in blocks  # (every batch is evaluated by the end of the read)
    number = {b: q for q, b in enumerate(blocks)}
    sizes = np.array([len(b.offsets) - 1 for b in blocks], np.int64)
    rows_in = np.array([int(b.offsets[-1]) for b in blocks], np.int64)
    row_base = np.cumsum(rows_in) - rows_in
    # every message of every block: where its rows start and end in the blocks end to end
    starts = np.concatenate([b.offsets[:-1] + r for b, r in zip(blocks, row_base.tolist())])
    ends = np.concatenate([b.offsets[1:] + r for b, r in zip(blocks, row_base.tolist())])
    message = ((np.cumsum(sizes) - sizes)[np.fromiter(map(number.__getitem__, of), np.int64,
                                                      len(held))]
               + np.fromiter(map(attrgetter("at"), held), np.int64, len(held)))
    total = int(counts.sum())
    tick = np.repeat(firsts, counts) + (np.arange(total, dtype=np.int64)
                                        - np.repeat(np.cumsum(counts) - counts, counts))
    message = np.repeat(message, counts)
    first, lengths = starts[message], ends[message] - starts[message]
    pos = (np.repeat(first - (np.cumsum(lengths) - lengths), lengths)
           + np.arange(int(lengths.sum()), dtype=np.int64))
    entity = np.concatenate([b.entity for b in blocks])[pos]
    return (entity, np.repeat(tick, lengths),
            {n: (np.concatenate([b.values[n][0] for b in blocks])[pos],
                 np.concatenate([b.values[n][1] for b in blocks])[pos]) for n in names})
