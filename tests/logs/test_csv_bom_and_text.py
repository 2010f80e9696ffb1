"""CSV traces as spreadsheets write them (hostile round 9): a UTF-8 byte order mark
before the header (Excel's "CSV UTF-8") was read into the first column's name and refused
the file; a free-text column no requirement reads (a note, a comment) refused the whole
file. Now the mark is skipped and an unread column is not read; the verdicts are those of
the same trace without them (metamorphic), and a column a requirement does read is still
checked."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.audit import AuditConfig, audit_log, load_plan

FRET = "R: the robot shall always satisfy x > 0\n"
BOM = b"\xef\xbb\xbf"


def _verdicts(tmp: Path, name: str, data: bytes) -> dict:
    (tmp / "r.fret").write_text(FRET)
    (tmp / name).write_bytes(data)
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp / "r.fret"),))),
                   str(tmp / name))
    return {v.requirement: (v.verdict, v.error,
                            None if v.first_violation is None else v.first_violation.at.tick)
            for v in la.verdicts}


def test_a_bom_before_the_header_is_skipped(tmp_path):
    """The smallest input that failed: BOM + ``time,x`` (column '\\ufefftime')."""
    got = _verdicts(tmp_path, "bom.csv", BOM + b"time,x\n0,1\n1,2\n")
    assert got == {"R": ("satisfied", None, None)}


def test_a_free_text_column_nothing_reads_does_not_refuse_the_file(tmp_path):
    """The smallest input that failed: a ``comment`` column with ``hello world``."""
    got = _verdicts(tmp_path, "t.csv", b"time,x,comment\n0,1,hello world\n1,-2,ok\n")
    assert got == {"R": ("violated", None, 1)}


def test_a_column_a_requirement_reads_is_still_checked(tmp_path):
    got = _verdicts(tmp_path, "t.csv", b"time,x,comment\n0,1,a\n1,oops,b\n")
    assert got["R"][0] == "error" and "oops" in got["R"][1] and "t.csv:3" in got["R"][1]


_TEXT = st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=12).map(
    lambda s: '"' + s.replace('"', '""') + '"')


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(xs=st.lists(st.integers(-3, 3), min_size=1, max_size=12), bom=st.booleans(),
       notes=st.none() | st.lists(_TEXT, min_size=12, max_size=12), first=st.booleans())
def test_a_bom_and_an_unread_text_column_leave_the_verdicts_unchanged(tmp_path_factory, xs,
                                                                      bom, notes, first):
    tmp = tmp_path_factory.mktemp("csv")
    plain = "time,x\n" + "".join(f"{k},{x}\n" for k, x in enumerate(xs))
    want = _verdicts(tmp, "plain.csv", plain.encode())
    if notes is None:
        text = plain
    elif first:
        text = "note,time,x\n" + "".join(f"{n},{k},{x}\n" for k, (x, n) in
                                         enumerate(zip(xs, notes)))
    else:
        text = "time,x,note\n" + "".join(f"{k},{x},{n}\n" for k, (x, n) in
                                         enumerate(zip(xs, notes)))
    got = _verdicts(tmp, "other.csv", (BOM if bom else b"") + text.encode())
    assert got == want, (text, got, want)


@pytest.mark.parametrize("data", [BOM + b"time,x\n0,1\n", b"time,x\n0,1\n"])
def test_the_reader_gives_the_same_columns_with_or_without_the_mark(tmp_path, data):
    from fretc.logs.csv.source import CsvSource

    (tmp_path / "a.csv").write_bytes(data)
    src = CsvSource(tmp_path / "a.csv")
    assert src.columns == ["x"] and src.has_time
