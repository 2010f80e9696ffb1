"""The per-entity variables of one per-entity requirement as columns
(:class:`EntityColumns`): what :mod:`fretc.audit.entities` judges, one entity's trace at a
time or every entity's laid end to end.

At each tick a per-entity variable reads, for an entity present in the held key message, its
row's value, else the variable's absent value at that tick (:mod:`fretc.audit.entity_read`).
A trace's column is bool when every value in it is a bool (the absent values count as bools
only when all of them are, at every tick), else float (True 1.0, False 0.0, NaN unknown), as
:func:`column` types one; the rows are kept as numpy arrays (entity, tick,
value, whether a bool) sorted by entity, so that gathering a trace is a few numpy steps
rather than a loop over its ticks.
"""

from __future__ import annotations

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
    """The rows of a batch of held key messages (:mod:`fretc.audit.entity_read`, vectorized):
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
        self._build(names, absent, [(k, 1, t.values[entities][1]) for k, t in enumerate(ticks)],
                    len(ticks), n_entities)

    @classmethod
    def of_runs(cls, names: list[str], absent: tuple, runs: list[tuple[int, int, Any]],
                n_ticks: int, n_entities: int) -> EntityColumns:
        """The columns of ``n_ticks`` ticks given as runs ``(first tick, ticks, rows)`` of
        ticks holding the same rows (:mod:`fretc.audit.entity_runs`), ``absent`` the
        variables' absent values at every tick."""
        out = cls.__new__(cls)
        cols = {}
        for j, n in enumerate(names):
            f, b = floats([absent[j]])
            cols[n] = (np.repeat(f, n_ticks), np.repeat(b, n_ticks))
        out._build(names, cols, runs, n_ticks, n_entities)
        return out

    def _build(self, names: list[str], absent: dict[str, tuple[np.ndarray, np.ndarray]],
               runs: list[tuple[int, int, Any]], n_ticks: int, n_entities: int) -> None:
        """The columns from the absent values (per variable, at each tick) and the rows of
        runs ``(first tick, ticks, rows)`` of ticks holding the same rows."""
        self.names = names
        self.absent = {n: (f, b if b.all() else np.zeros(len(b), np.bool_))
                       for n, (f, b) in absent.items()}
        flat: list[tuple] = []
        counts = np.zeros(n_ticks, np.int64)
        held: dict[int, tuple[RowBlock, list[int], list[int]]] = {}
        for k, m, rows in runs:
            if type(rows) is list:
                counts[k:k + m] = len(rows)
                flat.extend(rows * m)
                continue
            blk = rows.block
            assert blk is not None  # (every batch is evaluated by the end of the read)
            got = held.get(id(blk))
            if got is None:
                got = held[id(blk)] = (blk, [], [])
            if m == 1:
                got[1].append(k)
                got[2].append(rows.at)
            else:
                got[1].extend(range(k, k + m))
                got[2].extend([rows.at] * m)
        vals = [r[1] for r in flat]
        parts = [(np.array([r[0] for r in flat], np.int64),
                  np.repeat(np.arange(n_ticks, dtype=np.int64), counts),
                  {n: floats([v[j] for v in vals]) for j, n in enumerate(names)})]
        for blk, ks, ats in held.values():
            at = np.array(ats, np.int64)
            starts = blk.offsets[at]
            lengths = blk.offsets[at + 1] - starts
            pos = (np.repeat(starts - (np.cumsum(lengths) - lengths), lengths)
                   + np.arange(int(lengths.sum()), dtype=np.int64))
            parts.append((blk.entity[pos], np.repeat(np.array(ks, np.int64), lengths),
                          {n: (blk.values[n][0][pos], blk.values[n][1][pos]) for n in names}))
        entity = np.concatenate([p[0] for p in parts])
        self.order = np.argsort(entity, kind="stable")
        self.entity = entity[self.order]
        self.tick = np.concatenate([p[1] for p in parts])[self.order]
        self.starts = np.searchsorted(self.entity, np.arange(n_entities + 1))
        self.rows: dict[str, tuple[np.ndarray, np.ndarray]] = {
            n: (np.concatenate([p[2][n][0] for p in parts])[self.order],
                np.concatenate([p[2][n][1] for p in parts])[self.order]) for n in names}

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
