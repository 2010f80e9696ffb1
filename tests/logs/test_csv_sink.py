"""A CSV trace read with a sink (:class:`fretc.logs.CsvSource`'s ``sink``: the audit judges its
requirements as the rows pass, audit/streamed.py) hands over exactly the rows the source keeps
when it keeps every column: the same times and values, chunk after chunk in row order,
whatever the reader's chunk size, with comment lines, a time column or none, a column of 0/1
cells that becomes a number column late in the file, and any of the columns also kept; and
it keeps nothing it was not asked to keep."""

from __future__ import annotations

import random

import numpy as np
import pytest

import fretc.logs.csv.read as csv_read
from fretc.logs.csv.source import CsvSource


def _write(path, rnd: random.Random, n: int, timed: bool) -> None:
    late = rnd.randint(0, n) if n else 0
    lines = ["time,a,b,x" if timed else "a,b,x"]
    for i in range(n):
        if rnd.random() < 0.01:
            lines.append("# a comment")
        a = rnd.choice(["0", "1", "true", "false"])
        b = rnd.choice(["0", "1"]) if i < late else rnd.choice(["0", "1", "2.5"])
        lines.append((f"{i / 10:.1f}," if timed else "") + f"{a},{b},{rnd.random()!r}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


@pytest.mark.parametrize("seed", range(12))
def test_the_sink_gets_the_rows_the_source_keeps(tmp_path, monkeypatch, seed):
    rnd = random.Random(seed)
    monkeypatch.setattr(csv_read, "CHUNK_ROWS", rnd.choice([1, 3, 64, 4096]))
    path = tmp_path / "t.csv"
    _write(path, rnd, rnd.randint(0, 3000), timed=seed % 3 != 0)
    whole = CsvSource(path)
    got: dict[str, list[np.ndarray]] = {}
    times: list[np.ndarray] = []

    def sink(first, ts, cols):
        assert first == sum(map(len, times))
        assert all(len(c) == len(ts) for c in cols.values())
        times.append(ts)
        for name, col in cols.items():
            assert col.dtype in (np.bool_, np.float64)
            got.setdefault(name, []).append(col)

    keep = rnd.choice([set(), {"a"}, {"a", "b", "x"}])
    keep_times = rnd.random() < 0.5
    src = CsvSource(path, keep=keep, sink=sink, streamed={"a", "b", "x"}, keep_times=keep_times)
    assert src.types == whole.types and src.row_count == whole.row_count
    handed = np.concatenate(times) if times else np.zeros(0, np.int64)
    assert np.array_equal(handed, whole.row_times())
    for name in "abx":
        col = (np.concatenate([c.astype(np.float64) for c in got[name]]) if got.get(name)
               else np.zeros(0))
        assert np.array_equal(col, whole.column_values(name).astype(np.float64)), name
        if name in keep:
            assert np.array_equal(src.column_values(name), whole.column_values(name))
        else:
            with pytest.raises(KeyError):
                src.column_values(name)
    if keep_times or not src.has_time:
        assert np.array_equal(src.row_times(), whole.row_times())
    else:
        with pytest.raises(RuntimeError):
            src.row_times()


def test_a_bad_row_after_the_sink_read_the_rows_before_still_raises(tmp_path):
    """The sink sees the rows before a bad one, and the file is still refused."""
    from fretc.common.problems import CsvError

    lines = ["time,a"] + [f"{i},1" for i in range(10_000)] + ["10000,x"]
    path = tmp_path / "t.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    seen = []
    with pytest.raises(CsvError, match=r"t\.csv:10002 "):
        CsvSource(path, keep=(), sink=lambda first, ts, cols: seen.append(len(ts)),
                  streamed={"a"}, keep_times=False)
    assert sum(seen) >= 4096
