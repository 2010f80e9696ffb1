"""The clocks of a sampled trace (``fretc audit --write-csv``, :mod:`fretc.audit.sampled.csv`)
read in one pass (:func:`split_clocks`): each clock's rows kept apart, so that the audit of a
trace of many clocks (a per-entity requirement has one per entity) reads the file once, not
once per clock. Each clock is then a :class:`~fretc.logs.csv.source.CsvSource` of its rows
(:class:`ClockRows`), with the lines of the file, so its errors name them as the source read
from the file does."""

from __future__ import annotations

import csv
import os
from collections.abc import Callable, Iterator

from fretc.common.problems import CsvError
from fretc.common.units import NS_PER_S
from fretc.logs.csv.read import clean_cells, csv_time
from fretc.logs.csv.source import CLOCK_COLUMN, CsvSource, clock_lines

__all__ = ["ClockRows", "split_clocks"]

#: Rows as the :mod:`csv` module reads them: (line, cells)
Rows = list[tuple[int, list[str]]]


class ClockRows(CsvSource):
    """One clock of a sampled trace from rows already read (:func:`split_clocks`): the
    header's row and the clock's own, with their lines; otherwise a
    :class:`~fretc.logs.csv.source.CsvSource` of ``path`` reading ``clock``.

    Raises:
        CsvError: as :class:`~fretc.logs.csv.source.CsvSource` for the clock's rows."""

    def __init__(self, path: str | os.PathLike, rows: Rows, clocks: dict[str, list[str]],
                 first_line: str, *, period_ns: int = NS_PER_S, clock: str) -> None:
        self._given, self._given_clocks, self._given_first = rows, clocks, first_line
        super().__init__(path, period_ns=period_ns, clock=clock)

    def _raw(self) -> Iterator[tuple[int, list[str] | CsvError]]:
        return iter(self._given)  # (rows only: a split file has no error left)

    def _clock_lines(self) -> dict[str, list[str]]:
        return self._given_clocks

    def _first_line(self) -> str:
        return self._given_first


def split_clocks(path: str | os.PathLike, period_ns: int = NS_PER_S,
                 clocks: dict[str, list[str]] | None = None
                 ) -> dict[str, Callable[[], CsvSource]] | None:
    """The clocks of the sampled trace ``path`` (label -> a function making its source),
    from one read of the file: its rows split by their :data:`CLOCK_COLUMN` cell.
    ``clocks``: the trace's clock lines when the caller read them
    (:func:`fretc.logs.csv.source.clock_lines`; None: read here).

    Returns None when the file's rows are not those of a trace of several clocks (a row of
    another length, a time not read or going backwards, a clock no line names, not UTF-8
    CSV): the caller reads each clock from the file, which says what is wrong where."""
    if clocks is None:
        clocks = clock_lines(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            first = f.readline()
            f.seek(0)
            return _split(str(path), csv.reader(f), clocks, first, period_ns)
    except (OSError, csv.Error, UnicodeDecodeError, CsvError):
        return None


def _split(path: str, reader, clocks: dict[str, list[str]], first: str, period_ns: int
           ) -> dict[str, Callable[[], CsvSource]] | None:
    header: tuple[int, list[str]] | None = None
    rows: dict[str, Rows] = {label: [] for label in clocks}
    at = time_at = -1
    last = None
    for cells in reader:
        line = reader.line_num
        kept = clean_cells(cells)
        if kept is None:
            continue
        if header is None:
            if CLOCK_COLUMN not in kept:
                return None
            header, at = (line, cells), kept.index(CLOCK_COLUMN)
            time_at = kept.index("time") if "time" in kept else -1
            continue
        if len(kept) != len(header[1]) or kept[at] not in rows:
            return None
        if time_at >= 0:
            t = csv_time(path, line, kept[time_at])
            if last is not None and t < last:
                return None
            last = t
        rows[kept[at]].append((line, cells))
    if header is None:
        return None
    h = header

    def source(label: str) -> Callable[[], CsvSource]:
        return lambda: ClockRows(path, [h] + rows[label], clocks, first, period_ns=period_ns,
                                 clock=label)

    return {label: source(label) for label in clocks}
