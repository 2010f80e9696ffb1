"""The one read of a CSV trace (:mod:`fretc.logs.csv.read`: plain chunks column by column,
the others row by row) against a plain reading of the format with the :mod:`csv` module, one
row at a time (:func:`_reference`): on random small traces with ``unknown``/``gap``/``cut``
marks, blank and comment lines, empty, unreadable and mixed cells, odd times and rows of the
wrong width, read in chunks of 1 to 6 rows so that chunk edges fall everywhere, the same
first error (its words, line and column), or the same columns, types, marks, rows (line,
time, values, unknowns) and kept columns."""

from __future__ import annotations

import csv
import math
from decimal import Decimal, InvalidOperation

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fretc.logs.csv.read as csv_read
from fretc.common.problems import CsvError
from fretc.logs import CsvSource

WORDS = {"true": True, "false": False, "1": True, "0": False}
PERIOD = 250_000_000


def _time(path, line, cell):
    try:
        value = Decimal(cell)
        if not value.is_finite():
            raise InvalidOperation
    except (InvalidOperation, ValueError):
        raise CsvError(path, line, f"time {cell!r} is not a number of seconds",
                       column="time") from None
    return int((value * 1_000_000_000).to_integral_value())


def _lines(path: str) -> list:
    """The file's rows the format reads, ``(line, stripped cells)``, then
    ``(line, CsvError)`` where it stops being CSV."""
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        lines = []
        try:
            for cells in reader:
                if not cells or all(not c.strip() for c in cells):
                    continue
                if cells[0].lstrip().startswith("#"):
                    continue
                lines.append((reader.line_num, [c.strip() for c in cells]))
        except csv.Error as exc:
            lines.append((reader.line_num, CsvError(path, reader.line_num,
                                                    f"malformed CSV: {exc}")))
    return lines


def _reference(path: str):
    """The format read row by row (a trace of one clock): (columns, types, row count,
    unknown rows, gap rows, cut time, rows as (index, line, time, values, unknown, gap))."""
    lines = _lines(path)
    if not lines:
        raise CsvError(path, 1, "empty file: expected a header row of variable names")
    (_line, header), data = lines[0], lines[1:]
    names = [c for c in header if c != "time"]
    word_at, num_at, unknown_rows, gap_rows = {}, {}, {}, []
    rows, last, cut, cut_line = [], None, None, None
    for line, cells in data:
        if isinstance(cells, CsvError):
            raise cells
        if len(cells) != len(header):
            raise CsvError(path, line, f"expected {len(header)} cells ({', '.join(header)}), "
                           f"got {len(cells)}")
        row = dict(zip(header, cells))
        time = None
        if "time" in row:
            time = _time(path, line, row["time"])
            if last is not None and time < last:
                raise CsvError(path, line, f"time {row['time']} s goes backwards (previous "
                               f"row at {Decimal(last) / 10**9} s)", column="time")
            last = time
        if cut_line is not None:
            raise CsvError(path, line, f"a row after the cut (line {cut_line}): nothing was "
                           "read after it")
        marks = {row[n] for n in names} & {"gap", "cut"}
        if marks and (len(marks) > 1 or any(row[n] not in marks for n in names)):
            raise CsvError(path, line, f"a {'/'.join(sorted(marks))} row has every cell "
                           f"{' or '.join(sorted(marks))}")
        index = len(rows)
        if "cut" in marks:
            cut, cut_line = (time if time is not None else index * PERIOD), line
            continue
        if "gap" in marks:
            gap_rows.append(index)
            rows.append((index, line, time, {n: None for n in names}, frozenset(names), True))
            continue
        values, unknown = {}, []
        for n in names:
            cell = row[n]
            if not cell:
                raise CsvError(path, line, "empty cell", column=n)
            if cell == "unknown":
                unknown_rows.setdefault(n, []).append(index)
                unknown.append(n)
                values[n] = None
                continue
            low = cell.lower()
            if low not in WORDS:
                try:
                    values[n] = float(cell)
                except ValueError:
                    raise CsvError(path, line, f"cannot read {cell!r} as true/false or a "
                                   "number", column=n) from None
                num_at.setdefault(n, line)
            else:
                values[n] = cell
                if low in ("true", "false"):
                    word_at.setdefault(n, line)
            if n in word_at and n in num_at:
                raise CsvError(path, line, f"column mixes true/false (line {word_at[n]}) "
                               f"with numbers (line {num_at[n]})", column=n)
        rows.append((index, line, time, values, frozenset(unknown), False))
    types = {n: "float" if n in num_at else "bool" for n in names}

    def typed(n, v):
        if v is None:
            return 0.0 if types[n] == "float" else False
        if isinstance(v, float):
            return v
        return float(WORDS[v.lower()]) if types[n] == "float" else WORDS[v.lower()]

    rows = [(i, ln, t, {n: typed(n, v) for n, v in vals.items()}, unk, gap)
            for i, ln, t, vals, unk, gap in rows]
    return names, types, len(rows), unknown_rows, gap_rows, cut, rows


def _same(a, b) -> bool:
    """Equal values, NaN equal to NaN, a float never equal to a bool."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float) and math.isnan(a):
        return math.isnan(b)
    return a == b


BOOL_CELLS = ["0", "1", "true", "FALSE", " 1 ", "True"]
NUM_CELLS = ["0", "1", "2.5", "-1e3", "nan", "inf", " -0.25", "1_0", "0.1"]
ODD_CELLS = ["unknown", "", "x", "gap", "cut", "true", "3.5", "Unknown"]


@st.composite
def traces(draw):
    """A small CSV trace: a header of 1 to 3 variables and maybe ``time``, rows mostly
    plain, some odd (a mark, an empty or unreadable cell, the other type, a row of marks, a
    blank or comment line, a wrong width, a time backwards or written oddly, a quoted cell
    over two lines)."""
    kinds = draw(st.lists(st.sampled_from(["bool", "num"]), min_size=1, max_size=3))
    names = [f"v{i}" for i in range(len(kinds))]
    timed = draw(st.booleans())
    header = (["time"] if timed else []) + names
    if timed and draw(st.booleans()):
        header = names[:1] + ["time"] + names[1:]
    odd = draw(st.sampled_from([0.0, 0.0, 0.02, 0.2]))
    marked = draw(st.sampled_from([0.0, 0.1]))  # unknown cells, gap rows
    n = draw(st.integers(0, 30))
    cut = draw(st.sampled_from([None, n - 1, n // 2])) if n else None
    lines = [",".join(header)]
    t = draw(st.integers(0, 10**7)) / 1000
    for j in range(n):
        r = draw(st.floats(0, 1))
        if r < odd / 4:
            lines.append(draw(st.sampled_from(["", "# note", " ,", "  # x,y"])))
            continue
        if j == cut or r < marked / 2 or r < odd / 2:
            mark = ("cut" if j == cut else "gap" if r < marked / 2
                    else draw(st.sampled_from(["gap", "cut"])))
            cells = {n: mark for n in names}
        else:
            cells = {}
            for n, k in zip(names, kinds):
                pool = ODD_CELLS if draw(st.floats(0, 1)) < odd else (
                    ["unknown"] if draw(st.floats(0, 1)) < marked else
                    BOOL_CELLS if k == "bool" else NUM_CELLS)
                cells[n] = draw(st.sampled_from(pool))
        t += draw(st.sampled_from([0.1, 0.1, 0.25, 0.0, 0.001, -0.5 if odd else 0.1]))
        stamp = f"{t:.3f}"
        if draw(st.floats(0, 1)) < odd:
            stamp = draw(st.sampled_from([f"{t:.1f}e0", f"{t}0000000009", "soon", "",
                                          f" {t:.2f} ", "1e40", f"{t:.3f}."]))
        cells["time"] = stamp
        row = [cells[h] for h in header]
        if draw(st.floats(0, 1)) < odd / 4:
            row = row + ["1"] if draw(st.booleans()) else row[:-1]
        if row and draw(st.floats(0, 1)) < odd / 4:
            row[-1] = f'"{row[-1]}\n"'
        lines.append(",".join(row))
    return "\n".join(lines) + "\n"


def _read(path: str):
    try:
        src = CsvSource(path, period_ns=PERIOD)
    except CsvError as exc:
        return ("error", str(exc)), None
    rows = [(r.index, r.line, r.time, r.values, r.unknown, r.gap) for r in src.rows()]
    return (src.columns, src.types, src.row_count, src.unknown_rows, src.gap_rows,
            src.cut_time, rows), src


@settings(max_examples=400, deadline=None)
@given(traces(), st.integers(1, 6), st.sets(st.sampled_from(["v0", "v1", "v2", "x"])))
def test_the_one_read_equals_a_plain_reading(tmp_path_factory, text, chunk, keep):
    path = str(tmp_path_factory.mktemp("r") / "t.csv")
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(text)
    try:
        want = _reference(path)
    except CsvError as exc:
        want = ("error", str(exc))
    mp = pytest.MonkeyPatch()
    try:
        mp.setattr(csv_read, "CHUNK_ROWS", chunk)
        got, src = _read(path)
    finally:
        mp.undo()
    if got[0] == "error" and "is out of range" in got[1]:
        return  # (a time past int64 ns: the plain reading keeps it, an audit could not)
    if got[0] == "error" or want[0] == "error":
        assert got == want
        return
    *figures, rows = got
    *want_figures, want_rows = want
    assert figures == want_figures
    assert len(rows) == len(want_rows)
    for r, w in zip(rows, want_rows):
        assert r[:3] == w[:3] and r[4:] == w[4:]
        assert r[3].keys() == w[3].keys()
        assert all(_same(r[3][n], w[3][n]) for n in r[3]), (r, w)
    assert src is not None
    times = src.row_times()
    assert times.dtype == np.int64 and times.tolist() == [
        r[2] if r[2] is not None else r[0] * PERIOD for r in want_rows]
    for n in src.columns:
        col = src.column_values(n)
        assert col.dtype == (np.float64 if src.types[n] == "float" else np.bool_)
        assert all(_same(v, w[3][n]) for v, w in zip(col.tolist(), want_rows))
        assert not col.flags.writeable
    assert [src.row_line(i) for i in range(src.row_count)] == [r[1] for r in want_rows]
    # keeping some columns: the same checks and figures, the kept columns alone
    mp = pytest.MonkeyPatch()
    try:
        mp.setattr(csv_read, "CHUNK_ROWS", chunk)
        part = CsvSource(path, period_ns=PERIOD, keep=keep)
    finally:
        mp.undo()
    assert (part.columns, part.types, part.row_count, part.unknown_rows, part.gap_rows,
            part.cut_time) == tuple(want_figures)
    for n in src.columns:
        if n in keep:
            assert np.array_equal(part.column_values(n), src.column_values(n), equal_nan=True)
        else:
            with pytest.raises(KeyError):
                part.column_values(n)
            with pytest.raises(KeyError):
                part.column_pass([n])
    if set(src.columns) <= keep:
        assert len(list(part.rows())) == src.row_count
    else:
        with pytest.raises(RuntimeError, match="rows.. gives every column"):
            list(part.rows())


def test_the_plain_chunks_are_read_column_by_column(tmp_path, monkeypatch):
    """The relation above is not vacuous: a plain trace is read by chunks (no row read
    one by one), and one odd row sends only its chunk row by row."""
    rows = [f"{k / 10:.1f},{k % 2},{0.5 * k}" for k in range(20)]
    path = tmp_path / "t.csv"
    path.write_text("time,a,x\n" + "\n".join(rows) + "\n")
    calls = []
    original = csv_read.RowReader._row
    monkeypatch.setattr(csv_read, "CHUNK_ROWS", 4)
    monkeypatch.setattr(csv_read.RowReader, "_row",
                        lambda self, line, cells: calls.append(line) or original(self, line, cells))
    src = CsvSource(path)
    assert calls == [] and src.row_count == 20 and src.types == {"a": "bool", "x": "float"}
    rows[9] = "0.9,unknown,gap"  # (a gap cell beside a value: an error, row by row)
    path.write_text("time,a,x\n" + "\n".join(rows) + "\n")
    with pytest.raises(CsvError, match=r"t.csv:11: a gap row has every cell gap"):
        CsvSource(path)
    assert calls == [10, 11]  # (the chunk of lines 10..13 up to its error)


@pytest.mark.parametrize("cell, ns", [
    ("0.1", 100_000_000), ("999999.999999999", 999_999_999_999_999),
    ("1700000000.123456789", 1_700_000_000_123_456_789), (".5", 500_000_000),
    ("2.", 2_000_000_000), ("1e3", 10**12), ("-0.25", -250_000_000),
    ("0.0000000005", 0), ("0.0000000015", 2), ("1_0", None), ("nan", None), ("", None),
])
def test_chunk_times_read_exactly(cell, ns):
    """A chunk's times equal the row by row reading's, exactly (the float path under
    10^6 s, the integer one above, Decimal for the rest)."""
    got = csv_read._chunk_times([cell, cell])
    if ns is None:
        assert got is None or got.tolist() == [csv_read._time_ns(cell)] * 2
        return
    assert got is not None and got.tolist() == [ns, ns]
    assert csv_read._time_ns(cell) == ns


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 10**15 - 1), st.integers(0, 9))
def test_float_path_times_are_exact(ns, decimals):
    """Every time under 10^6 s of at most 9 decimals (at most 10 characters, as the float
    path takes them) reads to its exact ns."""
    ns -= ns % 10 ** (9 - decimals)
    cell = f"{ns // 10**9}" + (f".{ns % 10**9:09d}"[:decimals + 1] if decimals else "")
    if len(cell) > 10:
        cell = cell[:10].rstrip(".")
    want = int(Decimal(cell) * 10**9)
    got = csv_read._chunk_times([cell])
    assert got is not None and got.tolist() == [want]
