"""A CSV trace still being written during its audit is judged over one extent: the bytes the
audit's first read found (:attr:`fretc.logs.CsvSource.extent`), for every requirement and
every read (hostile round 9, W1).

The audit reads a CSV trace more than once: the streams judge while the rows are read, a
requirement whose ticks turn out unknown is judged whole from a second read, and the values
shown around a streamed violation are read again. A logger appending rows between two reads
had one requirement judged on more rows than another, both claiming the same last tick.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fretc.audit.streamed as streamed
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.common.problems import CsvError
from fretc.logs.csv.source import CsvSource

REQUIREMENTS = """\
R1: the s shall always satisfy x <= 1
R2: the s shall always satisfy y <= 1
R3: the s shall always satisfy z <= 1
"""


def _grows_after_the_first_read(monkeypatch, path, text: str) -> list[int]:
    """Append ``text`` to ``path`` once the streams' read is over (before the second read);
    the sizes the reads met are returned as they happen."""
    sizes: list[int] = []
    close = streamed.CsvStreams.close

    def close_then_grow(self, source):
        close(self, source)
        sizes.append(path.stat().st_size)
        with open(path, "a", encoding="ascii") as f:
            f.write(text)

    monkeypatch.setattr(streamed.CsvStreams, "close", close_then_grow)
    return sizes


@pytest.mark.tor("TOR-LOG-002")
def test_rows_appended_between_reads_are_judged_by_no_requirement(tmp_path, monkeypatch):
    """R1 is streamed; R2 reads a NaN at its first row (judged whole, from the second read);
    R3 is streamed and violated at row 500 (its values read again). The rows appended after
    the first read would violate R2 and R3 and push R2's ticks to 2000: every requirement is
    judged on the first read's 1000 rows, with one last tick."""
    (tmp_path / "r.fret").write_text(REQUIREMENTS, encoding="utf-8")
    rows = ["x,y,z", "0,nan,0"] + ["0,0,0"] * 998 + ["0,0,0"]
    rows[501] = "0,0,7"
    path = tmp_path / "t.csv"
    path.write_text("\n".join(rows) + "\n", encoding="ascii")
    size = path.stat().st_size
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    sizes = _grows_after_the_first_read(monkeypatch, path, "5,5,5\n" * 1000)
    la = audit_log(plan, str(path))
    assert sizes == [size]  # (the file did grow during the audit)
    assert path.stat().st_size > size
    by_id = {v.requirement: v for v in la.verdicts}
    assert [by_id[r].verdict for r in ("R1", "R2", "R3")] == ["satisfied", "unknown",
                                                              "violated"]
    assert {v.ticks_evaluated for v in la.verdicts} == {1000}
    assert {v.last_tick_ns for v in la.verdicts} == {999 * 10**9}
    assert la.ticks_evaluated == 1000
    # the values shown around R3's violation: rows of the first extent, as written then
    shown = by_id["R3"].values["z"]
    assert shown and all(t < 1000 for t, _time, _value in shown)
    assert {t: val for t, _time, val in shown}[500] == 7.0


def test_the_audit_of_a_grown_file_equals_the_audit_of_the_file_as_first_read(
        tmp_path, monkeypatch):
    """Metamorphic: rows appended during the audit change no verdict, tick or time from the
    audit of the file as it was when the audit began."""
    (tmp_path / "r.fret").write_text(REQUIREMENTS, encoding="utf-8")
    rows = ["x,y,z"] + [f"{(k % 3) / 2},{'nan' if k == 7 else 0},{k % 2}" for k in range(300)]
    path = tmp_path / "t.csv"
    path.write_text("\n".join(rows) + "\n", encoding="ascii")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    before = [(v.requirement, v.verdict, v.ticks_evaluated, v.first_tick_ns,
               v.last_tick_ns, v.violations) for v in audit_log(plan, str(path)).verdicts]
    _grows_after_the_first_read(monkeypatch, path, "9,9,9\n" * 300)
    after = [(v.requirement, v.verdict, v.ticks_evaluated, v.first_tick_ns,
              v.last_tick_ns, v.violations) for v in audit_log(plan, str(path)).verdicts]
    assert after == before


@settings(max_examples=40)
@given(rows=st.lists(st.tuples(st.integers(-5, 5), st.booleans()), min_size=0, max_size=60),
       more=st.lists(st.tuples(st.integers(-5, 5), st.booleans()), min_size=1, max_size=30),
       half=st.booleans())
@pytest.mark.tor("TOR-LOG-002")
def test_a_source_reads_its_extent_alone(tmp_path_factory, rows, more, half):
    """Property: a CsvSource given the file's size before rows were appended (or half a row
    more, a writer caught mid-row: refused naming the row's line) reads the rows of
    the file as it was then, and its ``extent`` is that size."""
    path = tmp_path_factory.mktemp("extent") / "t.csv"
    text = "a,b\n" + "".join(f"{a},{int(b)}\n" for a, b in rows)
    path.write_text(text, encoding="ascii")
    size = path.stat().st_size
    whole = CsvSource(path)
    assert whole.extent == size
    extra = "".join(f"{a},{int(b)}\n" for a, b in more)
    with open(path, "a", encoding="ascii") as f:
        f.write(extra)
    got = CsvSource(path, extent=size)
    assert got.extent == size
    assert got.row_count == len(rows) == whole.row_count
    for name in ("a", "b"):
        if rows:
            assert got.column_values(name).tolist() == whole.column_values(name).tolist()
    if half:
        # a writer caught mid-row: the row cut short at the extent is refused, naming its
        # line (never read as a shorter row, nor as the whole row written since)
        with pytest.raises(CsvError) as err:
            CsvSource(path, extent=size + 1)
        assert f"t.csv:{len(rows) + 2}" in str(err.value)
