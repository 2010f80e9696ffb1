"""CSV traces of FRET variables as a :class:`~fretc.logs.base.LogSource`: a header row
of variable names, one row per tick (format in :class:`CsvSource`)."""

from __future__ import annotations

import csv
import os
import re
from collections.abc import Iterator
from decimal import Decimal, InvalidOperation
from types import SimpleNamespace
from typing import NamedTuple

from fretc.common.units import NS_PER_S

from fretc.common.problems import CsvError, LogError
from fretc.logs.base import LogSource, Message

__all__ = ["CsvSource", "CsvRow", "CSV_TOPIC", "CSV_TYPE", "SAMPLED_MARK", "column_name_problem"]

#: Pseudo-topic of a CSV trace: one message per row; ``data`` has one attribute per column.
CSV_TOPIC = "/csv"
#: Type name reported by ``CsvSource.topics()``.
CSV_TYPE = "fretc/msg/CsvRow"

#: The first line of a CSV trace written by ``fretc audit --write-csv``: its columns are FRET
#: variables already sampled through the binding files (:mod:`fretc.audit.sampled_csv`).
SAMPLED_MARK = "# fretc sampled trace"

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
#: a column of an uninterpreted function's values, named by its printed call (``sqrt(w)``),
#: as the monitors read it (FRET's ``det_3x3(a,b,c)`` in the case studies)
_CALL = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\(.*\)\Z")
_BOOL_WORDS = {"true": True, "false": False, "1": True, "0": False}


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
        values: column name → bool (boolean column) or float (numeric column).
    """

    index: int  # type: ignore[assignment]  # the field shadows tuple.index, as documented
    line: int
    time: int | None
    values: dict[str, bool | float]


class CsvSource(LogSource):
    """A CSV trace of FRET variables.

    Format: a header row of variable names (identifiers), then one row per tick.  Blank lines
    and lines starting with ``#`` are ignored.  Cells hold ``true``/``false`` (any case),
    ``1``/``0`` or numbers (``nan``/``inf`` allowed).  A column whose every cell is
    true/false/1/0 is boolean (values ``bool``); any other column is numeric (values
    ``float``) and then must not hold true/false.  An optional ``time`` column gives each row's
    time in seconds (decimal, non-decreasing); without it row *k* is at ``k * period_ns``
    (default 1 s: one tick is one time unit).

    The file is checked completely when opened (two streaming passes: types, then rows).

    As a LogSource it yields one :class:`Message` per row on topic :data:`CSV_TOPIC` whose
    ``data`` has one attribute per column (so bindings may say ``/csv.speed``); the tick clock (:mod:`fretc.signals`)
    uses :meth:`rows` directly so columns are variables without bindings.

    Raises:
        CsvError: bad header (empty, duplicate or non-identifier name), a row with the wrong
            number of cells, an unreadable cell, or time going backwards; the message names
            ``file:line`` and the column.
    """

    kind = "csv"

    def __init__(self, path: str | os.PathLike, *, period_ns: int = NS_PER_S) -> None:
        super().__init__(path)
        if period_ns <= 0:
            raise ValueError("period_ns must be positive")
        self.period_ns = period_ns
        self.columns: list[str] = []
        self.types: dict[str, str] = {}
        self.has_time = False
        self.row_count = 0
        #: the file starts with :data:`SAMPLED_MARK`: its columns are sampled FRET variables
        self.sampled = False
        self._check()

    def _lines(self) -> Iterator[tuple[int, list[str]]]:
        try:
            f = open(self.path, newline="", encoding="utf-8")
        except OSError as exc:
            raise LogError(self.path, f"cannot read: {exc.strerror or exc}") from None
        with f:
            reader = csv.reader(f)
            try:
                for cells in reader:
                    line = reader.line_num
                    if not cells or all(not c.strip() for c in cells):
                        continue
                    if cells[0].lstrip().startswith("#"):
                        continue
                    yield line, [c.strip() for c in cells]
            except csv.Error as exc:
                raise CsvError(self.path, reader.line_num, f"malformed CSV: {exc}") from None
            except UnicodeDecodeError as exc:
                line, what = _bad_utf8(self.path, exc)
                raise CsvError(self.path, line, f"not UTF-8 text: {what}") from None

    def _first_line(self) -> str:
        with open(self.path, encoding="utf-8", errors="replace") as f:
            return f.readline()

    def _check(self) -> None:
        lines = self._lines()
        try:
            line, header = next(lines)
        except StopIteration:
            raise CsvError(self.path, 1, "empty file: expected a header row of variable names") from None
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
        self.has_time = "time" in header
        self.columns = [c for c in header if c != "time"]
        numeric_at: dict[str, int] = {}  # first line with a non-boolean cell
        word_at: dict[str, int] = {}  # first line with true/false
        count = 0
        last_time: int | None = None
        for line, cells in lines:
            if len(cells) != len(header):
                raise CsvError(self.path, line,
                               f"expected {len(header)} cells ({', '.join(header)}), got {len(cells)}")
            for name, cell in zip(header, cells):
                if name == "time":
                    t = _csv_time(self.path, line, cell)
                    if last_time is not None and t < last_time:
                        raise CsvError(self.path, line, f"time {cell} s goes backwards "
                                       f"(previous row at {last_time / NS_PER_S} s)", column="time")
                    last_time = t
                    continue
                if not cell:
                    raise CsvError(self.path, line, "empty cell", column=name)
                low = cell.lower()
                if low in ("true", "false"):
                    word_at.setdefault(name, line)
                elif low not in _BOOL_WORDS:
                    try:
                        float(cell)
                    except ValueError:
                        raise CsvError(self.path, line, f"cannot read {cell!r} as true/false or a "
                                       "number", column=name) from None
                    numeric_at.setdefault(name, line)
                if name in word_at and name in numeric_at:
                    raise CsvError(self.path, max(word_at[name], numeric_at[name]),
                                   f"column mixes true/false (line {word_at[name]}) with numbers "
                                   f"(line {numeric_at[name]})", column=name)
            count += 1
        self.row_count = count
        self.types = {c: ("float" if c in numeric_at else "bool") for c in self.columns}

    def topics(self) -> dict[str, str]:
        """``{CSV_TOPIC: CSV_TYPE}``."""
        return {CSV_TOPIC: CSV_TYPE}

    def rows(self) -> Iterator[CsvRow]:
        """The data rows, typed (see the class docstring), in file order."""
        lines = self._lines()
        next(lines)  # header, checked in __init__
        header = self._header
        types = self.types
        for index, (line, cells) in enumerate(lines):
            time = None
            values: dict[str, bool | float] = {}
            for name, cell in zip(header, cells):
                if name == "time":
                    time = _csv_time(self.path, line, cell)
                elif types[name] == "bool":
                    values[name] = _BOOL_WORDS[cell.lower()]
                else:
                    values[name] = float(cell)
            yield CsvRow(index, line, time, values)

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


def _csv_time(path: str, line: int, cell: str) -> int:
    try:
        value = Decimal(cell)
        if not value.is_finite():
            raise InvalidOperation
        return int((value * NS_PER_S).to_integral_value())
    except (InvalidOperation, ValueError):
        raise CsvError(path, line, f"time {cell!r} is not a number of seconds", column="time") from None


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
