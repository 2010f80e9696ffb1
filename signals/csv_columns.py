"""A CSV trace without bindings as the columns of its one clock, straight from what its
source kept when it read the file (:meth:`fretc.logs.CsvSource.column_pass`): the ticks,
values and figures :func:`fretc.signals.sample` then :func:`fretc.signals.blocks_of_ticks`
give it (tested), without a Python object per row."""

from __future__ import annotations

import numpy as np

from fretc.logs import CSV_TOPIC, CsvSource
from fretc.signals.clock import Sampling

__all__ = ["csv_columns", "csv_streamed_pass"]


def csv_columns(source: CsvSource, names: list[str]
                ) -> tuple[Sampling, np.ndarray, dict[str, np.ndarray]]:
    """One pass over the rows of ``source`` as the columns of the variables ``names`` (the
    columns of the same names: the variables of a CSV trace without bindings).

    Returns:
        ``(sampling, times, columns)``: the pass's :class:`~fretc.signals.Sampling`, its
        figures final (ticks, start, first and end time; the source's message count and
        damage as :func:`~fretc.signals.sample` leaves them); the rows' times (ns,
        ``int64``: the ``time`` column or index × the source's period); variable -> values
        (``bool`` or ``float64``, read-only views of the source's columns, one item per
        row; a variable that is no column reads false).
    """
    source._begin_pass()
    times, columns = source.column_pass(names)
    n = len(times)
    s = _sampling(source, n, int(times[0]) if n else None, int(times[-1]) if n else None)
    return s, times, columns


def csv_streamed_pass(source: CsvSource, n: int, first_time: int | None,
                      last_time: int | None) -> Sampling:
    """The pass :func:`csv_columns` makes, for a trace whose values went to a sink as the
    file was read (:class:`~fretc.logs.CsvSource`'s ``sink``): the same
    :class:`~fretc.signals.Sampling` figures and source figures (messages, ``partial``, a
    ``cut`` row's gap) from the ``n`` rows handed over and their first and last times
    (ns), with no column."""
    source._begin_pass()
    source.mark_pass()
    return _sampling(source, n, first_time, last_time)


def _sampling(source: CsvSource, n: int, first: int | None, last: int | None) -> Sampling:
    """The pass's :class:`~fretc.signals.Sampling` of ``n`` rows from time ``first`` to
    ``last`` (ns), the rows counted as messages of the source."""
    s = Sampling(source, None)
    if n:
        source.counts[CSV_TOPIC] = source.counts.get(CSV_TOPIC, 0) + n
        s.ticks = n
        s.start_time = s.first_time = first
        s.end_time = last
    return s
