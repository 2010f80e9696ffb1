"""A clock of a sampled trace (``fretc audit --write-csv``, :mod:`fretc.audit.sampled.csv`):
its ticks and the cells of its variables as the audit judged them (:class:`SampledClock`,
:func:`pass_cells`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fretc.audit.columns import ClockPass
from fretc.logs.csv.source import GAP_CELL, UNKNOWN_CELL

__all__ = ["SampledClock", "pass_cells", "seconds"]


def seconds(ns: int) -> str:
    """Integer nanoseconds as exact decimal seconds (``1700000000.1``)."""
    sign = "-" if ns < 0 else ""
    whole, frac = divmod(abs(int(ns)), 1_000_000_000)
    return f"{sign}{whole}" + (f".{frac:09d}".rstrip("0") if frac else "")


@dataclass
class SampledClock:
    """One clock of a sampled trace.

    Attributes:
        ids: the requirements judged on it.
        times: its tick times (ns).
        columns: variable -> its cells, one per tick (text, marks included).
        cut: the time (ns) where the damage ends the span read, or None.
        entity_of: the per-entity requirement whose entity it is (``ids`` is that
            entity's verdict's name), or None.
    """

    ids: list[str]
    times: np.ndarray
    columns: dict[str, list[str]] = field(default_factory=dict)
    cut: int | None = None
    entity_of: str | None = None

    def agrees(self, other: SampledClock) -> bool:
        """The same ticks and cut, and the same cells of the variables both have."""
        return (self.cut == other.cut and np.array_equal(self.times, other.times)
                and all(self.columns[n] == other.columns[n]
                        for n in self.columns.keys() & other.columns.keys()))


def pass_cells(res: ClockPass, name: str) -> list[str]:
    """The cells of variable ``name`` over the ticks of ``res``: values, ``unknown`` where a
    gap leaves it unknown, ``gap`` at the ticks standing for a gap's lost ticks."""
    col = res.columns[name]
    if col.dtype == np.bool_:
        out = ["true" if x else "false" for x in col.tolist()]
    else:
        out = [repr(float(x)) for x in col.tolist()]
    mask = res.unknown.get(name)
    if mask is not None:
        for i in np.flatnonzero(mask[:len(out)]).tolist():
            out[i] = UNKNOWN_CELL
    for i in res.tick_gaps:
        if i < len(out):
            out[i] = GAP_CELL
    return out
