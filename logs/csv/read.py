"""The one read of a CSV trace's data rows (:class:`fretc.logs.csv.source.CsvSource`): each
row checked (cells, marks, the columns of the clock read, the types) and its values kept as
compact columns, in one streaming pass over the file.

Design notes: ARCHITECTURE.md, `logs/csv/read.py`."""

from __future__ import annotations

import re
from array import array
from collections.abc import Callable, Iterator
from decimal import Decimal, InvalidOperation
from itertools import islice

import numpy as np

from fretc.common.problems import CsvError
from fretc.common.units import NS_PER_S

__all__ = ["RowReader", "RowSink", "CHUNK_ROWS", "UNKNOWN_CELL", "GAP_CELL", "CUT_CELL",
           "clean_cells", "csv_time"]

#: A cell whose value is not known at its tick (a gap of the log left the variable unknown).
UNKNOWN_CELL = "unknown"
#: Every cell of a row that stands for the ticks a gap lost (how many is not known): unknown.
GAP_CELL = "gap"
#: Every cell of a clock's last row: the log was cut at its time (nothing after it was read).
CUT_CELL = "cut"
#: the cells of a boolean's two values (any case for true/false)
_BOOL_WORDS = {"true": 1, "false": 0, "1": 1, "0": 0}

#: data rows read, checked and converted at once by :class:`RowReader`
CHUNK_ROWS = 4096

#: What :class:`RowReader` hands a sink after each chunk of rows of the clock read:
#: ``(first, times, columns)``: the 0-based index of the chunk's first row, the rows' times
#: (ns, ``int64``: the ``time`` column, or index x the period without one) and column ->
#: its values at those rows (``bool`` for a column of 0/1 cells so far, else ``float64``;
#: a value not known holds 0, as the kept columns). A chunk may hold no row.
RowSink = Callable[[int, np.ndarray, dict[str, np.ndarray]], None]
#: distinct cells whose kind :class:`RowReader` keeps (a trace repeats its cells)
_KINDS_KEPT = 1 << 16
#: a time in seconds of at most 9 decimals, read exactly without :class:`Decimal`
_PLAIN_TIME = re.compile(r"(-?)([0-9]+)(?:\.([0-9]{1,9}))?\Z")
#: the times a tick time (ns, ``int64``) can hold
_NS_MIN, _NS_MAX = -(1 << 63), (1 << 63) - 1
# a cell's kind: true/false, 1/0 (either type), another number, ``unknown``
_WORD, _BIT, _NUM, _UNKNOWN = range(4)


def clean_cells(cells: list[str]) -> list[str] | None:
    """A row's cells stripped of white space, or None for a row the format ignores (blank,
    or a comment: its first cell starts with ``#``)."""
    if not cells or all(not c.strip() for c in cells):
        return None
    if cells[0].lstrip().startswith("#"):
        return None
    return [c.strip() for c in cells]


def _time_ns(cell: str) -> int | None:
    """A ``time`` cell (seconds, decimal) in ns, rounded half to even past 9 decimals; None
    when it is not a finite number."""
    whole, dot, frac = cell.partition(".")
    if (whole.isascii() and whole.isdigit()
            and (not dot or (frac.isascii() and frac.isdigit() and len(frac) <= 9))):
        return int(whole) * NS_PER_S + (int(frac.ljust(9, "0")) if dot else 0)
    plain = _PLAIN_TIME.match(cell)
    if plain is not None:  # (the same ns as Decimal's, exactly)
        sign, whole, frac = plain.groups()
        ns = int(whole) * NS_PER_S + (int(frac.ljust(9, "0")) if frac else 0)
        return -ns if sign else ns
    try:
        value = Decimal(cell)
        if not value.is_finite():
            return None
        return int((value * NS_PER_S).to_integral_value())
    except (InvalidOperation, ValueError):
        return None


def csv_time(path: str, line: int, cell: str) -> int:
    """The ``time`` cell at ``path:line`` in ns.

    Raises:
        CsvError: not a finite number of seconds."""
    ns = _time_ns(cell)
    if ns is None:
        raise CsvError(path, line, f"time {cell!r} is not a number of seconds", column="time")
    return ns


def _chunk_times(cells: list[str]) -> np.ndarray | None:
    """The ``time`` cells of a chunk in ns (``int64``), or None when one is not a number
    or does not fit. Cells of at most 10 characters of digits and dots under 10^6 s are
    read as floats: float64 keeps ``s * 1e9`` within 0.2 ns of its integer there, so
    rounding gives it exactly."""
    try:
        text = "".join(cells).encode("ascii")
    except UnicodeEncodeError:
        text = b"-"
    if not text.translate(None, b"0123456789.") and max(map(len, cells)) <= 10:
        try:
            f = np.frombuffer(array("d", map(float, cells)), np.float64)
        except ValueError:
            return None
        if f.max() < 1e6:
            return np.rint(f * 1e9).astype(np.int64)
    ns = list(map(_time_ns, cells))
    if None in ns:
        return None
    try:
        return np.array(ns, dtype=np.int64)
    except OverflowError:
        return None


def _stripped(cells: tuple[str, ...]) -> list[str]:
    """A column's cells stripped of white space (copied as they are when none has any)."""
    text = "".join(cells)
    if text and text.split() == [text]:
        return list(cells)
    return list(map(str.strip, cells))


def _kind(cell: str) -> tuple[int, float] | None:
    """(kind, value) of a variable's cell (value 1/0 for true/false and 1/0, 0 for
    ``unknown``), or None when it is empty or unreadable (a ``gap``/``cut`` mark too)."""
    if not cell:
        return None
    if cell == UNKNOWN_CELL:
        return _UNKNOWN, 0
    low = cell.lower()
    if low in ("true", "false"):
        return _WORD, _BOOL_WORDS[low]
    if low in _BOOL_WORDS:
        return _BIT, _BOOL_WORDS[low]
    try:
        return _NUM, float(cell)
    except ValueError:
        return None


def _widened(col: array) -> array:
    """A column of 0/1 bytes as ``float64`` values."""
    out = array("d")
    if len(col):
        out.frombytes(np.frombuffer(col, np.uint8).astype(np.float64).tobytes())
    return out


class RowReader:
    """The one pass of :meth:`CsvSource._check <fretc.logs.csv.source.CsvSource>` over the
    data rows (module docstring): checks, the columns of the clock read, the types; after
    :meth:`run`, what it read is in its fields (the source takes them).

    Args:
        path: the file (for errors). header: its header row's names. columns: the variables'
            columns (the header without ``time`` and the clock column).
        has_time: the header has a ``time`` column. keep: the columns whose values are kept
            (None: all). grouped: the rows of several clocks, each row's clock in its clock
            column; ``own(cells, line)`` tells whether a row is of the clock read (``clock``,
            its label); ``period_ns``: the tick period, the time of a row without ``time``.

    ``max_rows``: stop after the chunk (:data:`CHUNK_ROWS` rows) where the rows of the clock
    read pass it, ``over`` then True (the rows after it neither read nor checked).

    A column that nothing reads (``keep`` given and naming it not, nor ``streamed``: no
    requirement or binding reads it) in a trace of one clock may hold text (issue 91: a
    free-text column, a comment or an operator's note beside the variables, refused the
    whole file): at its first cell that is neither true/false nor a number it is a text
    column, listed in ``text`` and left out of ``columns`` and ``types``, its cells no
    longer read. With ``keep`` None (every column read) each is checked as before.

    ``sink``: called after each chunk of rows with the rows it read (:data:`RowSink`): the
    columns named in ``streamed`` are handed over a chunk at a time and kept only when
    ``keep`` names them too; ``keep_times`` False keeps no ``time`` column either
    (``kept_times`` then None). The rows reach the sink before the file's later rows are
    checked: a later error still raises, and a column's type is only known at the end (a
    column of 0/1 cells reaches it as ``bool`` until its first other number, ``float64``
    from that chunk on).

    Fields after :meth:`run`: ``columns`` (of the clock read), ``types`` (column -> ``bool``
    or ``float``), ``count`` (rows of the clock read), ``kept_values`` (column -> its values,
    :class:`array.array`), ``kept_times`` (the ``time`` column, ns; None without one), ``runs``
    ((row index, line) where rows stop being on consecutive lines), ``gap_rows`` (the
    indexes of ``gap`` rows), ``unknown_rows`` (column -> indexes of its ``unknown`` cells)
    and ``cut_time`` (the time of the ``cut`` row, ns; None without one).
    """

    def __init__(self, path: str, header: list[str], columns: list[str], *, has_time: bool,
                 keep: frozenset[str] | None, grouped: bool,
                 own: Callable[[list[str], int], bool], clock: str | None,
                 period_ns: int, max_rows: int | None = None,
                 sink: RowSink | None = None, streamed: frozenset[str] = frozenset(),
                 keep_times: bool = True) -> None:
        self.path, self.has_time, self.grouped, self.own_row = path, has_time, grouped, own
        #: stop once more rows than this were read (None: read them all); ``over`` says so
        self.max_rows, self.over = max_rows, False
        self.clock, self.period_ns = clock, period_ns
        self.types: dict[str, str] = {}
        self.gap_rows: list[int] = []
        self.unknown_rows: dict[str, list[int]] = {}
        self.cut_time: int | None = None
        self.kept_times: array | None = None
        self.kept_values: dict[str, array] = {}
        self.header = header
        self.time_at = header.index("time") if has_time else None
        #: the columns nothing reads, and those of them found to hold text (class docstring)
        self.unread = (frozenset(c for c in columns if c not in keep and c not in streamed)
                       if keep is not None and not grouped else frozenset())
        self.text: list[str] = []
        self.columns = list(columns)
        self.variables = frozenset(columns)
        #: (position, name) of the variables' columns in the header
        self.var_at = [(i, n) for i, n in enumerate(header) if n in self.variables]
        self.numeric_at: dict[str, int] = {}  # first line with a non-boolean cell
        self.word_at: dict[str, int] = {}  # first line with true/false
        self.own: list[str] | None = None  # the columns of the clock read (grouped traces)
        self.cut_line: int | None = None
        #: cell text -> (kind, value), for the first :data:`_KINDS_KEPT` distinct cells
        self.kinds: dict[str, tuple[int, float]] = {}
        self.count = 0
        self.last_time: int | None = None
        self.values: dict[str, array] = {}
        self.times = array("q")
        #: (row index, its line): the rows from it to the next run's are on consecutive lines
        self.runs: list[tuple[int, int]] = []
        self.next_line = -1
        self.kept = keep  # the columns whose values are kept (None: all)
        #: the sink, the columns it is handed, and whether the times are kept
        self.sink, self.keep_times = sink, keep_times
        self.streamed = frozenset(streamed) & self.variables if sink is not None else frozenset()
        self.flushed = 0  # the rows handed to the sink so far
        self.flushed_times = 0  # (the times kept before the rows not yet handed)

    def run(self, raw: Iterator[tuple[int, list[str] | CsvError]]) -> None:
        """Read the rows after the header: ``(line, cells)`` as the :mod:`csv` module reads
        them, or ``(line, CsvError)`` where the file stops being CSV (raised in its turn).

        Raises:
            CsvError: as :class:`~fretc.logs.csv.source.CsvSource`, the first in file order.
        """
        fast = not self.grouped
        take = getattr(raw, "chunk", None)  # (a file's rows: a chunk without a frame a row)
        while True:
            chunk = take(CHUNK_ROWS) if take is not None else list(islice(raw, CHUNK_ROWS))
            if not chunk:
                break
            if not (fast and self._chunk(chunk)):
                for line, cells in chunk:
                    if isinstance(cells, CsvError):
                        raise cells
                    kept = clean_cells(cells)
                    if kept is not None:
                        self._row(line, kept)
            if self.sink is not None:
                self._flush()
            if self.max_rows is not None and self.count > self.max_rows:
                self.over = True  # (the rest of the file is not read)
                break
        self._finish()

    # ------------------------------------------------------------------ row by row
    def _row(self, line: int, cells: list[str]) -> None:
        path, header = self.path, self.header
        if len(cells) != len(header):
            raise CsvError(path, line,
                           f"expected {len(header)} cells ({', '.join(header)}), got {len(cells)}")
        time, cell = None, ""
        if self.time_at is not None:
            cell = cells[self.time_at]
            time = csv_time(path, line, cell)
            if self.last_time is not None and time < self.last_time:
                raise CsvError(path, line, f"time {cell} s goes backwards "
                               f"(previous row at {Decimal(self.last_time) / NS_PER_S} s)", column="time")
            self.last_time = time
        if not self.own_row(cells, line):
            return
        if self.cut_line is not None:
            raise CsvError(path, line, f"a row after the cut (line {self.cut_line}): "
                           "nothing was read after it")
        index = self.count
        values = self._cells(line, cells, index)
        if values is None:  # the cut row
            self.cut_time = time if time is not None else index * self.period_ns
            return
        if time is not None:
            if not _NS_MIN <= time <= _NS_MAX:
                raise CsvError(path, line, f"time {cell} s is out of range "
                               "(a tick time is at most 2^63 - 1 ns)", column="time")
            self.times.append(time)
        for name, value in values.items():
            if not self._keeps(name):
                continue
            self._column_of(name).append(value)  # (0/1 in a column of bytes)
        if line != self.next_line:
            self.runs.append((index, line))
        self.next_line = line + 1
        self.count = index + 1

    def _keeps(self, name: str) -> bool:
        """Whether the values of column ``name`` are collected (kept, or streamed)."""
        return self.kept is None or name in self.kept or name in self.streamed

    def _flush(self) -> None:
        """Hand the rows read since the last flush to the sink (the class docstring): the
        streamed columns' values and the rows' times; a column or the times that are not
        kept are dropped after."""
        first, count = self.flushed, self.count
        k = count - first
        if self.has_time:
            at = first - self.flushed_times
            times = np.frombuffer(self.times, np.int64)[at:at + k].copy()
            if not self.keep_times:
                self.times = array("q")
                self.flushed_times = count
        else:
            times = np.arange(first, count, dtype=np.int64) * self.period_ns
        cols: dict[str, np.ndarray] = {}
        for name in sorted(self.streamed):
            col = self._column_of(name)
            kept = self.kept is None or name in self.kept
            at = first if kept else 0
            if col.typecode == "d":
                cols[name] = np.frombuffer(col, np.float64)[at:at + k].copy()
            else:
                cols[name] = np.frombuffer(col, np.uint8)[at:at + k].view(np.bool_).copy()
            if not kept:
                self.values[name] = array(col.typecode)
        self.flushed = count
        assert self.sink is not None  # (flushed only with a sink)
        self.sink(first, times, cols)

    def _column_of(self, name: str) -> array:
        """The kept column of ``name`` (new: bytes), widened to ``float64`` once a number
        was read in it."""
        col = self.values.get(name)
        if col is None:
            col = self.values[name] = array("B")
        if col.typecode == "B" and name in self.numeric_at:
            col = self.values[name] = _widened(col)
        return col

    def _cells(self, line: int, cells: list[str], index: int) -> dict[str, float] | None:
        """Check one data row of the clock read: its variables' values (0 where not known),
        or None for the ``cut`` row."""
        path = self.path
        named = {n: c for n, c in zip(self.header, cells) if n in self.variables}
        if self.grouped:  # the clock's columns: the cells its first row fills
            filled = [n for n, c in named.items() if c]
            if self.own is None:
                self.own = filled
            elif filled != self.own:
                raise CsvError(path, line, f"the cells of clock {self.clock} fill "
                               f"{', '.join(filled) or 'no column'}, its first row "
                               f"{', '.join(self.own) or 'no column'}")
            named = {n: named[n] for n in self.own}
        marks = {c for c in named.values() if c in (GAP_CELL, CUT_CELL)}
        if marks and (len(marks) > 1 or any(c not in marks for c in named.values())):
            raise CsvError(path, line, f"a {'/'.join(sorted(marks))} row has every cell "
                           f"{' or '.join(sorted(marks))}")
        if CUT_CELL in marks:
            self.cut_line = line
            return None
        if GAP_CELL in marks:
            self.gap_rows.append(index)
            return dict.fromkeys(named, 0)
        return {name: self._cell(line, name, cell, index) for name, cell in named.items()}

    def _cell(self, line: int, name: str, cell: str, index: int) -> float:
        got = self.kinds.get(cell)
        if got is None:
            got = _kind(cell)
            if got is None and name in self.unread:  # (text nothing reads: class docstring)
                self._text(name)
                return 0
            if got is None:
                raise CsvError(self.path, line, "empty cell" if not cell else
                               f"cannot read {cell!r} as true/false or a number", column=name)
            if len(self.kinds) < _KINDS_KEPT:
                self.kinds[cell] = got
        kind, value = got
        if kind == _BIT:  # either type (a column of mixed types was refused at its second)
            return value
        if kind == _UNKNOWN:
            self.unknown_rows.setdefault(name, []).append(index)
            return 0
        if kind == _WORD:
            self.word_at.setdefault(name, line)
        else:
            self.numeric_at.setdefault(name, line)
        if name in self.word_at and name in self.numeric_at:
            raise CsvError(self.path, line,
                           f"column mixes true/false (line {self.word_at[name]}) with numbers "
                           f"(line {self.numeric_at[name]})", column=name)
        return value

    def _text(self, name: str) -> None:
        """Column ``name``, which nothing reads, holds text: its cells are no longer read
        (class docstring)."""
        self.text.append(name)
        self.variables = self.variables - {name}
        self.var_at = [(i, n) for i, n in self.var_at if n != name]
        self.values.pop(name, None)

    # ------------------------------------------------------------------ a chunk at once
    def _chunk(self, chunk: list[tuple[int, list[str] | CsvError]]) -> bool:
        """Check and keep a chunk of plain rows column by column (module docstring); False,
        with nothing kept, when it is not plain."""
        if self.cut_line is not None or isinstance(chunk[-1][1], CsvError):
            return False
        rows: list[list[str]] = [cells for _line, cells in chunk]  # type: ignore[misc]
        if set(map(len, rows)) != {len(self.header)}:
            return False
        cols = [_stripped(c) for c in zip(*rows)]
        if min(cols[0]) < "$":  # a blank or comment line, or an odd first cell
            return False
        times = None
        if self.time_at is not None:
            times = _chunk_times(cols[self.time_at])
            if times is None or (self.last_time is not None and times[0] < self.last_time) \
                    or bool((times[1:] < times[:-1]).any()):
                return False
        got = []
        for i, name in self.var_at:
            c = self._column(name, cols[i])
            if c is None:
                return False
            got.append((name, c))
        lines = [line for line, _cells in chunk]
        base = self.count
        for name, (vals, unknown, first_word, first_num) in got:
            if first_word is not None:
                self.word_at[name] = lines[first_word]
            if first_num is not None:
                self.numeric_at[name] = lines[first_num]
            if unknown:
                self.unknown_rows.setdefault(name, []).extend(base + k for k in unknown)
            if not self._keeps(name):
                continue
            col = self._column_of(name)
            want = np.float64 if col.typecode == "d" else np.uint8
            col.frombytes(vals.astype(want, copy=False).tobytes())
        if times is not None:
            self.times.frombytes(times.tobytes())
            self.last_time = int(times[-1])
        if lines[0] != self.next_line:
            self.runs.append((base, lines[0]))
        if lines[-1] - lines[0] != len(lines) - 1:  # (rows over several lines: quoted cells)
            self.runs.extend((base + k, lines[k]) for k in range(1, len(lines))
                             if lines[k] != lines[k - 1] + 1)
        self.next_line = lines[-1] + 1
        self.count = base + len(lines)
        return True

    def _column(self, name: str, cells: list[str]
                ) -> tuple[np.ndarray, list[int], int | None, int | None] | None:
        """A variable's cells in a chunk: (values, as ``float64`` when a number is among
        them, else 0/1 ``uint8``; the positions of ``unknown`` cells; the position of the
        first true/false and of the first number where the column has none yet), or None
        when a cell is empty, unreadable or a mark of a row, or the column would mix
        true/false with numbers."""
        n = len(cells)
        distinct = set(cells)
        if len(distinct) * 4 > n and name not in self.word_at:  # many values: each a number?
            try:
                vals = np.frombuffer(array("d", map(float, cells)), np.float64)
            except ValueError:
                vals = None
            if vals is not None:
                numeric = cells.count("0") + cells.count("1") < n
                first_num = None
                if numeric and name not in self.numeric_at:
                    first_num = next(k for k, c in enumerate(cells) if c != "0" and c != "1")
                return (vals if numeric else vals.astype(np.uint8)), [], None, first_num
        table: dict[str, tuple[int, float]] = {}
        kinds = self.kinds
        for cell in distinct:
            got = kinds.get(cell)
            if got is None:
                got = _kind(cell)
                if got is None:
                    return None
                if len(kinds) < _KINDS_KEPT:
                    kinds[cell] = got
            table[cell] = got
        seen = {k for k, _v in table.values()}
        word, numeric = _WORD in seen, _NUM in seen
        if (word or name in self.word_at) and (numeric or name in self.numeric_at):
            return None
        value = {c: v for c, (_k, v) in table.items()}
        if numeric:
            vals = np.frombuffer(array("d", map(value.__getitem__, cells)), np.float64)
        else:
            vals = np.frombuffer(bytes(map(value.__getitem__, cells)), np.uint8)  # type: ignore[arg-type]  # (0/1)
        unknown = ([k for k, c in enumerate(cells) if c == UNKNOWN_CELL]
                   if _UNKNOWN in seen else [])
        first_word = first_num = None
        if word and name not in self.word_at:
            first_word = next(k for k, c in enumerate(cells) if table[c][0] == _WORD)
        if numeric and name not in self.numeric_at:
            first_num = next(k for k, c in enumerate(cells) if table[c][0] == _NUM)
        return vals, unknown, first_word, first_num

    def _finish(self) -> None:
        if self.text:
            self.columns = [c for c in self.columns if c not in self.text]
        if self.own is not None:
            self.columns = [c for c in self.columns if c in self.own]
        elif self.grouped:
            self.columns = []
        self.types = {c: ("float" if c in self.numeric_at else "bool") for c in self.columns}
        self.kept_values = {c: self.values.get(c, array("B")) for c in self.columns
                            if self.kept is None or c in self.kept}
        self.kept_times = self.times if self.has_time and self.keep_times else None
