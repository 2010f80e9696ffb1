"""CSV traces of FRET variables as a :class:`~fretc.logs.base.LogSource`: a header row
of variable names, one row per tick (format in :class:`CsvSource`)."""

from __future__ import annotations

import csv
import io
import os
import re
from array import array
from bisect import bisect_right
from collections.abc import Iterable, Iterator
from itertools import islice
from types import SimpleNamespace
from typing import Any, NamedTuple, TextIO

import numpy as np

from fretc.common.units import NS_PER_S

from fretc.common.problems import CsvError, LogError
from fretc.logs.base import LogSource, Message
# (the cells' words: UNKNOWN_CELL, GAP_CELL, CUT_CELL, are defined with their reader)
from fretc.logs.csv.read import CUT_CELL, GAP_CELL, UNKNOWN_CELL, RowReader, RowSink, clean_cells

__all__ = ["CsvSource", "CsvRow", "CSV_TOPIC", "CSV_TYPE", "SAMPLED_MARK", "CLOCK_LINE",
           "CLOCK_COLUMN", "UNKNOWN_CELL", "GAP_CELL", "CUT_CELL", "clock_lines", "sampled_trace",
           "NOT_SAMPLED_LINE", "not_sampled_lines", "PER_ENTITY_LINE", "per_entity_lines",
           "SampledHeader", "sampled_header",
           "escape_id", "unescape_id", "column_name_problem"]

#: Pseudo-topic of a CSV trace: one message per row; ``data`` has one attribute per column.
CSV_TOPIC = "/csv"
#: Type name reported by ``CsvSource.topics()``.
CSV_TYPE = "fretc/msg/CsvRow"

#: The first line of a CSV trace written by ``fretc audit --write-csv``: its columns are FRET
#: variables already sampled through the binding files (:mod:`fretc.audit.sampled.csv`).
SAMPLED_MARK = "# fretc sampled trace"
#: A comment line of a sampled trace naming one clock and the requirements sampled on it:
#: ``# fretc clock 2: R5 R6`` (ids written by :func:`escape_id`, separated by spaces).
CLOCK_LINE = "# fretc clock "
#: A comment line of a sampled trace naming a requirement it does not carry and why:
#: ``# fretc not sampled: T: <why>`` (a per-entity requirement; the id written by
#: :func:`escape_id`).
NOT_SAMPLED_LINE = "# fretc not sampled: "
#: A comment line of a sampled trace saying a requirement is judged per entity:
#: ``# fretc per entity: T: track``; the clock and not-sampled lines after it naming
#: ``T[track=...]`` are its entities, in order (:mod:`fretc.audit.sampled.entities`).
PER_ENTITY_LINE = "# fretc per entity: "
#: The column of a sampled trace of several clocks giving the clock of each row (``tick`` is
#: a FRETish reserved word, so never a FRET variable's column).
CLOCK_COLUMN = "tick"

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
#: a column of an uninterpreted function's values, named by its printed call (``sqrt(w)``),
#: as the monitors read it (FRET's ``det_3x3(a,b,c)`` in the case studies)
_CALL = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\(.*\)\Z")
_PLAIN = frozenset(range(0x21, 0x7F)) - {ord("\\"), ord(","), ord('"')}


def escape_id(rid: str) -> str:
    """A requirement id as a word of a :data:`CLOCK_LINE`: its UTF-8 bytes, each outside
    printable ASCII, a backslash, a comma or a double quote as ``\\xNN`` (the C monitors'
    runner compares its ids escaped the same way)."""
    return "".join(chr(b) if b in _PLAIN else f"\\x{b:02x}" for b in rid.encode("utf-8"))


_HEX2 = re.compile(r"[0-9a-f]{2}")


def unescape_id(word: str) -> str:
    """The requirement id :func:`escape_id` wrote as ``word``: each ``\\xNN`` of two
    lowercase hex digits is the byte NN (as the C monitors' runner reads it); anything else
    stands for itself."""
    out = bytearray()
    i = 0
    while i < len(word):
        if word.startswith("\\x", i) and _HEX2.fullmatch(word, i + 2, i + 4):
            out.append(int(word[i + 2:i + 4], 16))
            i += 4
            continue
        out += word[i].encode("utf-8")
        i += 1
    return out.decode("utf-8", errors="replace")


def sampled_trace(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a CSV trace whose first line is :data:`SAMPLED_MARK` (its columns
    the FRET variables, bindings applied: ``--write-csv``, ``fretc testgen``)."""
    if not str(path).lower().endswith(".csv"):
        return False
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as f:
            return f.readline().startswith(SAMPLED_MARK)
    except OSError:
        return False


class SampledHeader(NamedTuple):
    """What a sampled trace (:data:`SAMPLED_MARK` on its first line) says before its header
    (:func:`sampled_header`).

    Attributes:
        clocks: clock label -> the ids of the requirements sampled on it (its
            :data:`CLOCK_LINE` comment).
        not_sampled: requirement id -> why the trace does not carry it (its
            :data:`NOT_SAMPLED_LINE` comment).
        per_entity: requirement id -> (the entity's name, the ids of its entities' verdicts
            ``T[track=7]`` in the order the clock and not-sampled lines after its
            :data:`PER_ENTITY_LINE` name them).
    """

    clocks: dict[str, list[str]]
    not_sampled: dict[str, str]
    per_entity: dict[str, tuple[str, list[str]]]


def sampled_header(path: str | os.PathLike) -> SampledHeader:
    """The comment lines of the sampled trace ``path`` before its header, read once and
    parsed (:class:`SampledHeader`); every part empty for any other CSV trace, or a file that
    cannot be read as text."""
    clocks: dict[str, list[str]] = {}
    not_sampled: dict[str, str] = {}
    per_entity: dict[str, tuple[str, list[str]]] = {}
    for line in _sampled_comments(path):
        if line.startswith(PER_ENTITY_LINE):
            word, _, name = line[len(PER_ENTITY_LINE):].partition(": ")
            per_entity[unescape_id(word)] = (name.strip(), [])
            continue
        if line.startswith(CLOCK_LINE) and ":" in line:
            label, _, words = line[len(CLOCK_LINE):].partition(":")
            ids = clocks[label.strip()] = [unescape_id(w) for w in _words(words)]
        elif line.startswith(NOT_SAMPLED_LINE):
            word, _, why = line[len(NOT_SAMPLED_LINE):].partition(": ")
            ids = [unescape_id(word)]
            not_sampled[ids[0]] = why.strip()
        else:
            continue
        for i in ids:
            owner, bracket, _rest = i.partition("[")
            if bracket and owner in per_entity and i.endswith("]"):
                per_entity[owner][1].append(i)
    return SampledHeader(clocks, not_sampled, per_entity)


def clock_lines(path: str | os.PathLike) -> dict[str, list[str]]:
    """The clocks of a sampled trace: :attr:`SampledHeader.clocks` of
    :func:`sampled_header`."""
    return sampled_header(path).clocks


def not_sampled_lines(path: str | os.PathLike) -> dict[str, str]:
    """The requirements a sampled trace does not carry: :attr:`SampledHeader.not_sampled`
    of :func:`sampled_header`."""
    return sampled_header(path).not_sampled


def per_entity_lines(path: str | os.PathLike) -> dict[str, tuple[str, list[str]]]:
    """The per-entity requirements of a sampled trace: :attr:`SampledHeader.per_entity` of
    :func:`sampled_header`."""
    return sampled_header(path).per_entity


def _words(ids: str) -> list[str]:
    """The ids of a comment line's list, as :func:`escape_id` writes them: separated by
    spaces (an id holds none; a tab or another byte is part of the word, as the C runner
    reads it)."""
    return [w for w in ids.rstrip("\r\n").split(" ") if w]


def _sampled_comments(path: str | os.PathLike) -> list[str]:
    """The comment lines after a sampled trace's first line, before its header (none for
    any other file, or one that cannot be read as text)."""
    out: list[str] = []
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as f:
            if not f.readline().startswith(SAMPLED_MARK):
                return []
            for line in f:
                if not line.startswith("#"):
                    break
                out.append(line)
    except OSError:
        return []
    return out


def column_name_problem(name: str) -> str | None:
    """Why a CSV trace cannot carry the FRET variable ``name`` as a column of its own (a
    header cell reads as a name only when it is an identifier or a function call's printed
    text, and ``time`` is the rows' time), or None when it can."""
    if name == "time":
        return "'time' is the column of the rows' time in a CSV trace"
    if not (_IDENT.match(name) or _CALL.match(name)):
        return "a CSV trace's column names are identifiers or a function call's printed text"
    return None


class CsvRow(NamedTuple):
    """One CSV row.

    Attributes:
        index: 0-based row number among data rows (the tick index).
        line: 1-based line number in the file.
        time: ns from the ``time`` column (seconds, decimal), or None without one.
        values: column name → bool (boolean column) or float (numeric column); a value not
            known (``unknown``, ``gap``) holds a placeholder (false, 0.0).
        unknown: the columns whose value is not known at this tick.
        gap: the row stands for the ticks a gap lost (every column unknown).
    """

    index: int  # type: ignore[assignment]  # the field shadows tuple.index, as documented
    line: int
    time: int | None
    values: dict[str, bool | float]
    unknown: frozenset[str] = frozenset()
    gap: bool = False


class CsvSource(LogSource):
    """A CSV trace of FRET variables.

    Format: a header row of variable names (identifiers), then one row per tick.  Blank lines
    and lines starting with ``#`` are ignored.  Cells hold ``true``/``false`` (any case),
    ``1``/``0`` or numbers (``nan``/``inf`` allowed).  A column whose every cell is
    true/false/1/0 is boolean (values ``bool``); any other column is numeric (values
    ``float``) and then must not hold true/false.  An optional ``time`` column gives each row's
    time in seconds (decimal, non-decreasing); without it row *k* is at ``k * period_ns``
    (default 1 s: one tick is one time unit).

    What a log's damage left unknown (docs/guide/ticks.md "CSV traces"): a cell ``unknown``
    is a value not known at its tick (judged three-valued, as a gap of a log); a row whose
    cells are all ``gap`` stands for the ticks a gap of a tick topic lost (unknown, how many
    not known); a last row whose cells are all ``cut`` ends the trace where the log was cut
    (a gap to its end: only the ticks before it are judged, ``partial``).

    A sampled trace (:data:`SAMPLED_MARK`) names its clocks in :data:`CLOCK_LINE` comments;
    with several, its :data:`CLOCK_COLUMN` gives each row's clock and a row's cells of the
    columns of other clocks are empty. ``clock`` selects one clock: the source is then its
    rows and columns alone (the audit reads such a trace clock by clock,
    :mod:`fretc.audit.sampled.audit`); a trace of several clocks read whole has no rows.

    The file is UTF-8; a UTF-8 byte order mark before its first line (as Excel and other
    spreadsheets write "CSV UTF-8") is skipped, not read as part of the first column's name
    (``utf-8-sig``; issue 91). A column that no requirement or binding reads (``keep``
    naming it not) is not read at all: a free-text column beside the variables does not
    refuse the file (:class:`~fretc.logs.csv.read.RowReader`).

    The file is read once, when opened (:mod:`fretc.logs.csv.read`): checked completely, its
    values kept as compact columns (a byte a row for a boolean column, eight for a numeric
    one or the time); :meth:`rows`, :meth:`messages`, :meth:`column_values` and
    :meth:`column_pass` read those, not the file. ``keep`` names the columns whose values are
    kept (None: all): the others are checked and typed but not kept, and :meth:`rows` and
    :meth:`messages`, which give every column, then raise RuntimeError (an audit without
    bindings keeps its requirements' variables alone). ``max_rows``: a reader with a bound
    of its own (``fretc simulate``'s 2,000 ticks) stops reading the file a chunk of rows past
    it (:attr:`over_max_rows`), in bounded memory.

    ``extent``: the bytes of the file read, from its start (None: its size when opened,
    kept in :attr:`extent`). Rows past it are never read, so a file still being written (a
    logger appending rows during an audit) is read over the same rows by every pass of one
    audit: the audit opens the file again for requirements judged whole, and reads values
    around a violation again, each with the first open's :attr:`extent` (issue 91, W1: a
    CSV appended to during the audit had one requirement judged on 3,001,000 rows and
    another on 3,000,000, both claiming the same last tick). A last row the writer had not
    finished at the extent reads as a row cut short (its error names its line).

    ``sink`` (:data:`fretc.logs.csv.read.RowSink`): while the file is read, the values of the
    columns named in ``streamed`` are handed to it a chunk of rows at a time, with the rows'
    times, and kept only when ``keep`` names them too (an audit judges requirements as the
    rows pass: :mod:`fretc.audit.streamed`); ``keep_times`` False keeps no ``time`` column
    (:meth:`row_times` then raises RuntimeError for a trace that has one).

    As a LogSource it yields one :class:`Message` per row on topic :data:`CSV_TOPIC` whose
    ``data`` has one attribute per column (so bindings may say ``/csv.speed``); the tick clock (:mod:`fretc.signals`)
    uses :meth:`rows` directly so columns are variables without bindings.

    Raises:
        CsvError: bad header (empty, duplicate or non-identifier name), a row with the wrong
            number of cells, an unreadable cell, time going backwards, or marks out of place
            (``cut`` not last, ``gap`` beside values, a row of no clock); the message names
            ``file:line`` and the column.
    """

    kind = "csv"

    def __init__(self, path: str | os.PathLike, *, period_ns: int = NS_PER_S,
                 clock: str | None = None, keep: Iterable[str] | None = None,
                 max_rows: int | None = None, sink: RowSink | None = None,
                 streamed: Iterable[str] = (), keep_times: bool = True,
                 extent: int | None = None) -> None:
        super().__init__(path)
        if period_ns <= 0:
            raise ValueError("period_ns must be positive")
        if extent is not None and extent < 0:
            raise ValueError("extent must be at least 0 bytes")
        #: the bytes of the file read (class docstring): its size when first opened, or the
        #: ``extent`` given
        self.extent: int | None = extent
        self.period_ns = period_ns
        self.columns: list[str] = []
        self.types: dict[str, str] = {}
        self.has_time = False
        self.row_count = 0
        #: the file starts with :data:`SAMPLED_MARK`: its columns are sampled FRET variables
        self.sampled = False
        #: a sampled trace's clocks: label -> requirement ids (:func:`clock_lines`)
        self.clocks: dict[str, list[str]] = {}
        #: the clock read (None: every row of a trace of one clock)
        self.clock = clock
        #: column -> the data rows (indexes) where its value is ``unknown``
        self.unknown_rows: dict[str, list[int]] = {}
        #: the data rows (indexes) that are ``gap`` rows
        self.gap_rows: list[int] = []
        #: the time (ns) of the ``cut`` row, or None
        self.cut_time: int | None = None
        self._grouped = False  # several clocks: a CLOCK_COLUMN gives each row's
        self._gap_set: frozenset[int] = frozenset()
        self._header: list[str] = []
        #: column -> its values at the rows of the clock read (:meth:`column_values`)
        self._values: dict[str, array] = {}
        self._times: array | None = None  # the ``time`` column's ns, kept with it
        #: (row index, its line): the rows from it to the next are on consecutive lines
        self._line_runs: list[tuple[int, int]] = []
        #: the columns whose values are kept (None: every one)
        self.keep: frozenset[str] | None = frozenset(keep) if keep is not None else None
        #: ``max_rows`` given and passed: the file was read only up to a chunk past it
        #: (:attr:`row_count` rows, more than ``max_rows``), the rest neither read nor checked
        self.over_max_rows = False
        self._max_rows = max_rows
        self._sink, self._streamed, self._keep_times = sink, frozenset(streamed), keep_times
        self._check()

    def _raw(self) -> Iterator[tuple[int, list[str] | CsvError]]:
        """The file's rows as the :mod:`csv` module reads them: ``(line, cells)``, then
        ``(line, CsvError)`` where it stops being UTF-8 CSV (:class:`_FileRows`, which
        also gives them a chunk at a time).

        Only the first :attr:`extent` bytes are read (the file's size now when it is None,
        which then becomes the extent).

        Raises:
            LogError: the file cannot be opened."""
        try:
            raw = open(self.path, "rb", buffering=0)
        except OSError as exc:
            raise LogError(self.path, f"cannot read: {exc.strerror or exc}") from None
        if self.extent is None:
            self.extent = os.fstat(raw.fileno()).st_size
        bounded = io.BufferedReader(_Extent(raw, self.extent), buffer_size=1 << 16)
        f = io.TextIOWrapper(bounded, encoding="utf-8-sig", newline="")
        return _FileRows(self.path, f)

    def _clock_lines(self) -> dict[str, list[str]]:
        """The trace's clocks (:func:`clock_lines`)."""
        return clock_lines(self.path)

    def _first_line(self) -> str:
        with open(self.path, encoding="utf-8-sig", errors="replace") as f:
            return f.readline()

    def _check(self) -> None:
        raw = self._raw()
        for at, cells in raw:
            if isinstance(cells, CsvError):
                raise cells
            got = clean_cells(cells)
            if got is not None:
                line, header = at, got
                break
        else:
            raise CsvError(self.path, 1, "empty file: expected a header row of variable names")
        self._header_line = line
        seen: set[str] = set()
        for name in header:
            if not name:
                raise CsvError(self.path, line, "empty column name in the header")
            if not (_IDENT.match(name) or _CALL.match(name)):
                raise CsvError(self.path, line, f"column name {name!r} is not an identifier "
                               "(nor a function call's printed text)",
                               column=name)
            if name in seen:
                raise CsvError(self.path, line, f"column {name!r} appears twice", column=name)
            seen.add(name)
        self._header = header
        self.sampled = self._first_line().startswith(SAMPLED_MARK)
        self.clocks = self._clock_lines() if self.sampled else {}
        self._grouped = bool(self.clocks) and CLOCK_COLUMN in header
        if len(self.clocks) > 1 and not self._grouped:
            raise CsvError(self.path, line, f"{len(self.clocks)} clocks but no column "
                           f"{CLOCK_COLUMN!r} giving each row's clock")
        if self.clock is None and len(self.clocks) == 1:
            self.clock = next(iter(self.clocks))
        if self.clock is not None and self.clock not in self.clocks:
            raise CsvError(self.path, line, f"no clock {self.clock!r} in this trace")
        self.has_time = "time" in header
        self.columns = [c for c in header
                        if c != "time" and not (self._grouped and c == CLOCK_COLUMN)]
        reader = RowReader(self.path, header, self.columns, has_time=self.has_time,
                           keep=self.keep, grouped=self._grouped, own=self._own,
                           clock=self.clock, period_ns=self.period_ns,
                           max_rows=self._max_rows, sink=self._sink,
                           streamed=self._streamed, keep_times=self._keep_times)
        reader.run(raw)
        self.over_max_rows = reader.over
        self.columns, self.types, self.row_count = reader.columns, reader.types, reader.count
        self.gap_rows, self.unknown_rows = reader.gap_rows, reader.unknown_rows
        self.cut_time, self._gap_set = reader.cut_time, frozenset(reader.gap_rows)
        self._values, self._times = reader.kept_values, reader.kept_times
        self._line_runs = reader.runs

    def _own(self, cells: list[str], line: int) -> bool:
        """Whether a data row belongs to the clock read (its :data:`CLOCK_COLUMN` cell)."""
        if not self._grouped:
            return True
        label = cells[self._header.index(CLOCK_COLUMN)]
        if label not in self.clocks:
            raise CsvError(self.path, line, f"clock {label!r} is not named by a "
                           f"{CLOCK_LINE.strip()!r} line", column=CLOCK_COLUMN)
        return label == self.clock

    def topics(self) -> dict[str, str]:
        """``{CSV_TOPIC: CSV_TYPE}``."""
        return {CSV_TOPIC: CSV_TYPE}

    def column_values(self, name: str) -> np.ndarray:
        """The values of column ``name`` at the :attr:`row_count` rows of the clock read, as
        kept when the file was read (no copy; read-only): ``bool`` for a boolean column,
        ``float64`` for a numeric one; a value not known (``unknown``, a ``gap`` row) holds
        the placeholder (false, 0.0).

        Raises:
            KeyError: ``name`` is not a column of the clock read, or one not kept."""
        col = self._values[name]
        out = np.frombuffer(col, np.float64 if col.typecode == "d" else np.uint8)
        if col.typecode != "d":
            out = out.view(np.bool_)
        out.flags.writeable = False
        return out

    def row_times(self, period_ns: int | None = None) -> np.ndarray:
        """The time of each row of the clock read, ns (``int64``): its ``time`` cell, or
        without a ``time`` column the row's index × ``period_ns`` (default
        :attr:`period_ns`).

        Raises:
            RuntimeError: the trace has a ``time`` column and its times were not kept
                (``keep_times`` False)."""
        if self.has_time and self._times is None:
            raise RuntimeError(f"{self.path}: the rows' times were not kept")
        if self._times is not None:
            out = np.frombuffer(self._times, np.int64)
            out.flags.writeable = False
            return out
        return np.arange(self.row_count, dtype=np.int64) * (period_ns or self.period_ns)

    def row_line(self, index: int) -> int:
        """The 1-based line of the file where the data row ``index`` (0-based, of the clock
        read) ends.

        Raises:
            IndexError: no such row."""
        if not 0 <= index < self.row_count:
            raise IndexError(f"row {index} of {self.row_count}")
        at = bisect_right(self._line_runs, (index, 1 << 62)) - 1
        first, line = self._line_runs[at]
        return line + index - first

    def column_pass(self, names: list[str]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """One pass over the rows of the clock read as columns, what :meth:`rows` gives as
        arrays: (:meth:`row_times`, ``names`` -> :meth:`column_values`; a name that is no
        column reads false; every column ``bool`` when there is no row). As :meth:`rows`,
        marks make the pass ``partial`` and a ``cut`` row is recorded as a gap to the end
        (start the pass with ``_begin_pass``).

        Raises:
            KeyError: a name of a column not kept (``keep``)."""
        n = self.row_count
        times = self.row_times()

        def column(name: str) -> np.ndarray:
            if name not in self.types:
                return np.zeros(n, np.bool_)
            values = self.column_values(name)  # (KeyError: not kept)
            return values if n else np.zeros(0, np.bool_)

        cols = {name: column(name) for name in names}
        self.mark_pass()
        return times, cols

    def mark_pass(self) -> None:
        """What a pass over the rows records besides their values (:meth:`column_pass`, and
        a pass whose values went to a sink as the file was read): ``unknown`` cells and
        ``gap`` rows make it ``partial``; a ``cut`` row is a gap from its time to the end
        of the log (start the pass with ``_begin_pass``)."""
        if self.unknown_rows or self.gap_rows:
            self.partial = True
        if self.cut_time is not None:
            self._gap(self.cut_time, None, topics=frozenset((CSV_TOPIC,)), cause="cut")

    def rows(self) -> Iterator[CsvRow]:
        """The data rows of the clock read, typed (see the class docstring), in file order.
        A ``cut`` row ends them: the pass records a gap from its time to the end of the log
        (:attr:`fretc.logs.LogSource.cut_start`); marks make the pass ``partial``.

        Raises:
            RuntimeError: some column's values were not kept (``keep``)."""
        if self._values.keys() != set(self.columns):
            raise RuntimeError(f"{self.path}: rows() gives every column; kept only "
                               f"{', '.join(sorted(self._values)) or 'none'}")
        if self.unknown_rows or self.gap_rows:
            self.partial = True
        names = self.columns
        every = frozenset(names)
        unknown_at: dict[int, list[str]] = {}
        for name in names:
            for i in self.unknown_rows.get(name, ()):
                unknown_at.setdefault(i, []).append(name)
        cols = [(name, self.column_values(name)) for name in names]
        times = self.row_times() if self.has_time else None
        runs = self._line_runs
        run = 0
        step = 4096
        for lo in range(0, self.row_count, step):
            hi = min(self.row_count, lo + step)
            chunk = [(name, col[lo:hi].tolist()) for name, col in cols]
            ts = times[lo:hi].tolist() if times is not None else None
            for k in range(hi - lo):
                i = lo + k
                while run + 1 < len(runs) and runs[run + 1][0] <= i:
                    run += 1
                gap = i in self._gap_set
                unknown = every if gap else frozenset(unknown_at.get(i, ()))
                yield CsvRow(i, runs[run][1] + i - runs[run][0],
                             ts[k] if ts is not None else None,
                             {name: vals[k] for name, vals in chunk}, unknown, gap)
        if self.cut_time is not None:
            self._gap(self.cut_time, None, topics=frozenset((CSV_TOPIC,)), cause="cut")

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """One Message per row on :data:`CSV_TOPIC`; log time = ``time`` column or index × period."""
        self._begin_pass()
        if topics is not None and CSV_TOPIC not in topics:
            return
        first = last = None
        for row in self.rows():
            t = row.time if row.time is not None else row.index * self.period_ns
            first = t if first is None else first
            last = t
            self.counts[CSV_TOPIC] = self.counts.get(CSV_TOPIC, 0) + 1
            yield Message(CSV_TOPIC, t, t, None, SimpleNamespace(**row.values))
        self._start_time, self._end_time = first, last


class _Extent(io.RawIOBase):
    """The first ``extent`` bytes of an open binary file (:attr:`CsvSource.extent`): reads
    end there, whatever was written after."""

    def __init__(self, f: io.FileIO, extent: int) -> None:
        super().__init__()
        self.f, self.left = f, extent

    def readable(self) -> bool:
        return True

    def readinto(self, b: Any) -> int:
        if self.left <= 0:
            return 0
        view = memoryview(b)
        got = self.f.readinto(view[:min(len(view), self.left)]) or 0
        self.left -= got
        return got

    def close(self) -> None:
        self.f.close()
        super().close()


class _FileRows:
    """The rows of an open CSV file as the :mod:`csv` module reads them, ``(line, cells)``,
    then ``(line, CsvError)`` where it stops being UTF-8 CSV; closed at its end. Iterate
    it, or take rows :meth:`chunk` at a time (no Python frame per row)."""

    def __init__(self, path: str, f: TextIO) -> None:
        self.path, self.f = path, f
        self.reader = csv.reader(f)

    def __iter__(self) -> _FileRows:
        return self

    def __next__(self) -> tuple[int, list[str] | CsvError]:
        got = self.chunk(1)
        if not got:
            raise StopIteration
        return got[0]

    def chunk(self, n: int) -> list[tuple[int, list[str] | CsvError]]:
        """The next ``n`` rows (fewer at the end, the error last where there is one)."""
        out: list[tuple[int, list[str] | CsvError]] = []
        if self.f.closed:
            return out
        reader, append = self.reader, out.append
        try:
            for cells in islice(reader, n):
                append((reader.line_num, cells))
            if len(out) == n:
                return out
        except csv.Error as exc:
            append((reader.line_num, CsvError(self.path, reader.line_num,
                                              f"malformed CSV: {exc}")))
        except UnicodeDecodeError as exc:
            line, what = _bad_utf8(self.path, exc)
            append((line, CsvError(self.path, line, f"not UTF-8 text: {what}")))
        self.f.close()
        return out


def _bad_utf8(path: str, exc: UnicodeDecodeError) -> tuple[int, str]:
    """The 1-based line of the first byte of ``path`` that is not UTF-8, and the error in
    words naming the byte's column there (the text decoder reads ahead of the CSV reader,
    so the reader's line number is not the byte's)."""
    with open(path, "rb") as f:
        for n, raw in enumerate(f, 1):
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError as e:
                return n, f"byte 0x{raw[e.start]:02x} at column {e.start + 1}: {e.reason}"
    return 1, str(exc)
