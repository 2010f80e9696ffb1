"""Tests of requirement files (fretish.files): the .fret format and FRET JSON exports."""

from __future__ import annotations

import json
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

from fretc.fretish import (FretishError, FretishFileError, FretishSyntaxError, RequirementEntry,
                     load_requirements)
from fretc.fretish import ast as A
from fretc.fretish.files import parse_tick_period

R1 = "whenever too_close agilex_agent shall eventually satisfy stopped"


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def file_error(path) -> FretishFileError:
    with pytest.raises(FretishFileError) as info:
        load_requirements(path)
    return info.value


# --------------------------------------------------------------------------- .fret
def test_fret_basic(tmp_path):
    p = write(tmp_path, "r.fret", f"""# Safe-ROS requirements
@tick_period 100 ms

R1: {R1}   # the paper's R1
    rationale: stop when an obstacle is too close
      and stay stopped
    parent: SAFE-1
R-2.b: upon p the sw
    shall always satisfy q & "a#b"   # quoted '#' is text
    tick_period: 50 ms
""")
    e1, e2 = load_requirements(p)
    assert isinstance(e1, RequirementEntry)
    assert (e1.id, e1.text, e1.line, e1.column) == ("R1", R1, 4, 5)
    assert e1.rationale == "stop when an obstacle is too close and stay stopped"
    assert e1.parent == "SAFE-1" and e1.tick_period == Fraction(1, 10)
    assert e1.error is None and e1.requirement.key == "null,holding,eventually,satisfaction"
    assert e1.requirement.component == "agilex_agent" and e1.source == str(p)
    assert e2.id == "R-2.b" and e2.tick_period == Fraction(1, 20)
    assert e2.text == 'upon p the sw\n    shall always satisfy q & "a#b"'
    r = e2.requirement
    assert r.response == A.Binary("&", A.Var("q"), A.Var("a#b"))
    # spans are file positions: "q" is on line 9, column 26
    q = r.response.left
    assert (q.span.line, q.span.column) == (9, 26)
    assert e2.text[q.span.start:q.span.end] == "q"
    assert (r.component_span.line, r.component_span.column) == (8, 15)


def test_fret_sentence_starting_on_next_line_and_blank_lines(tmp_path):
    p = write(tmp_path, "r.fret", "R1:\n    the sw shall\n\n    # comment\n      always satisfy p\n")
    (e,) = load_requirements(p)
    assert (e.line, e.column) == (2, 5)
    assert e.requirement.response == A.Var("p")
    assert e.requirement.response.span.line == 5 and e.requirement.response.span.column == 22


def test_fret_defaults(tmp_path):
    (e,) = load_requirements(write(tmp_path, "r.fret", "R1: the sw shall satisfy p\n"))
    assert e.rationale is None and e.parent is None and e.tick_period is None
    assert e.extra == {}


def test_fret_parse_error_is_an_entry_in_file_coordinates(tmp_path):
    p = write(tmp_path, "r1.fret", f"""# header
R1: {R1}
R2: the sw shall always satisfy p and q
R3:   upon p
        the sw shall always satisfy x == 3
R4: the sw shall always satisfy p
""")
    entries = load_requirements(p)
    assert [e.id for e in entries] == ["R1", "R2", "R3", "R4"]
    assert entries[0].error is None and entries[3].error is None
    e2 = entries[1].error
    assert isinstance(e2, FretishSyntaxError) and entries[1].requirement is None
    assert (e2.source, e2.line, e2.column) == (str(p), 3, 35)
    lines = str(e2).split("\n")
    assert lines[0] == f"{p}:3:35: error: unexpected 'and' in an expression"
    assert lines[1] == "R2: the sw shall always satisfy p and q"
    assert lines[2] == " " * 34 + "^"
    assert any(l.startswith("hint: ") for l in lines)
    e3 = entries[2].error
    assert (e3.line, e3.column) == (5, 39) and "'=='" in e3.message
    assert e3.text_line == "        the sw shall always satisfy x == 3"
    assert str(e3).split("\n")[2] == " " * 38 + "^"


@pytest.mark.parametrize("text,line,col,needle", [
    ("R1: the sw shall satisfy p\nthe sw shall satisfy q\n", 2, 1, "ID:"),
    ("R1: the sw shall satisfy p\nR1: the sw shall satisfy q\n", 2, 1, "duplicate"),
    ("R1: the sw shall satisfy p\n  tick_period: 3 ticks\n", 2, 16, "tick"),
    ("R1: the sw shall satisfy p\n  tick_period: fast\n", 2, 16, "tick_period"),
    ("@tick_period 0 ms\nR1: the sw shall satisfy p\n", 1, 14, "positive"),
    ("@tick_period 1 ms\n@tick_period 2 ms\n", 2, 1, "second"),
    ("@tickperiod 1 ms\n", 1, 1, "unknown directive"),
    ("  R1: the sw shall satisfy p\n", 1, 3, "outside a requirement"),
    ("R1: the sw shall satisfy p\n  parent: A\n  parent: B\n", 3, 3, "duplicate attribute"),
    ("R1: the sw shall\n  parent: A\n  satisfy p\n", 3, 3, "before its attributes"),
    ("R 1: the sw shall satisfy p\n", 1, 1, "ID:"),
])
def test_fret_structural_errors(tmp_path, text, line, col, needle):
    p = write(tmp_path, "bad.fret", text)
    e = file_error(p)
    assert isinstance(e, FretishError)
    assert (e.source, e.line, e.column) == (str(p), line, col)
    assert needle in e.message
    assert str(e).startswith(f"{p}:{line}:{col}: error: ")


def test_fret_empty_sentence_is_an_entry_error(tmp_path):
    e, e2 = load_requirements(write(tmp_path, "r.fret",
                                    "R1:   # nothing\nR2: the sw shall satisfy p\n"))
    assert e.error is not None and e.error.message == "empty requirement"
    assert e.error.line == 1 and e2.error is None


def test_fret_freeform_with_hash(tmp_path):
    (e,) = load_requirements(write(tmp_path, "r.fret",
                                   'R1: "The robot shall be polite # always."  # comment\n'))
    assert e.requirement.freeform and e.text == '"The robot shall be polite # always."'


# --------------------------------------------------------------------------- tick periods
@pytest.mark.parametrize("text,seconds", [
    ("100 ms", Fraction(1, 10)), ("0.1 s", Fraction(1, 10)), ("2.5 ms", Fraction(1, 400)),
    ("1 millisecond", Fraction(1, 1000)), ("3 secs", Fraction(3)), ("1 min", Fraction(60)),
    ("2 hours", Fraction(7200)), ("20 us", Fraction(1, 50000)), ("20 µs", Fraction(1, 50000)),
    ("1 microsec", Fraction(1, 10 ** 6)), ("0.333 s", Fraction(333, 1000)), ("50ms", Fraction(1, 20)),
])
def test_tick_period_units(text, seconds):
    assert parse_tick_period(text) == seconds


@pytest.mark.parametrize("text", ["", "ms", "1", "1 tick", "2 ticks", "1 fortnight", "-1 ms",
                                  "0 s", "1 ms 2", "0 Hz", "1 ms2"])
def test_tick_period_errors(text):
    with pytest.raises(ValueError):
        parse_tick_period(text)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 10 ** 6), st.integers(0, 10 ** 4),
       st.sampled_from([("us", Decimal("1e-6")), ("ms", Decimal("1e-3")),
                        ("seconds", Decimal(1)), ("minutes", Decimal(60)),
                        ("h", Decimal(3600))]))
def test_tick_period_is_exact(whole, frac, unit):
    text = f"{whole}.{frac}" if frac else str(whole)
    name, scale = unit
    expected = Fraction(Decimal(text) * scale)
    if expected == 0:
        with pytest.raises(ValueError):
            parse_tick_period(f"{text} {name}")
    else:
        assert parse_tick_period(f"{text} {name}") == expected


# --------------------------------------------------------------------------- JSON exports
FRET_EXPORT = [
    {"reqid": "FSM-001", "parent_reqid": "", "project": "FSM", "rationale": "pull up",
     "fulltext": "FSM shall always satisfy (limits & !standby) => pullup",
     "semantics": {"type": "nasa"}, "_id": "abc"},
    {"reqid": "FSM-002", "parent_reqid": "FSM-001", "project": "FSM", "rationale": "",
     "fulltext": "FSM shall always satisfy p and q"},
]


def test_json_list(tmp_path):
    p = write(tmp_path, "export.json", json.dumps(FRET_EXPORT, indent=2))
    a, b = load_requirements(p)
    assert (a.id, a.rationale, a.parent) == ("FSM-001", "pull up", None)
    assert a.extra == {"project": "FSM", "semantics": {"type": "nasa"}, "_id": "abc"}
    assert a.requirement.key == "null,null,always,satisfaction"
    assert (b.parent, b.rationale, b.requirement) == ("FSM-001", None, None)
    raw = p.read_text().split("\n")
    # positions point at the fulltext string in the file
    assert raw[a.line - 1][a.column - 1:].startswith(FRET_EXPORT[0]["fulltext"])
    err = b.error
    assert isinstance(err, FretishSyntaxError) and err.line == b.line
    assert err.column == b.column + FRET_EXPORT[1]["fulltext"].index(" and ") + 1
    assert str(err).split("\n")[1] == FRET_EXPORT[1]["fulltext"]
    assert str(err).split("\n")[2].index("^") == FRET_EXPORT[1]["fulltext"].index(" and ") + 1


def test_json_object_with_variables(tmp_path):
    p = write(tmp_path, "export.json",
              json.dumps({"requirements": FRET_EXPORT[:1], "variables": [{"name": "x"}]}))
    (e,) = load_requirements(p)
    assert e.id == "FSM-001" and e.error is None and e.line == 1


@pytest.mark.parametrize("content,needle", [
    ('[{"reqid": "a", "fulltext": "x"}', "invalid JSON"),
    ('{"reqs": []}', "list of FRET requirements"),
    ('[{"fulltext": "the sw shall satisfy p"}]', "reqid"),
    ('[{"reqid": "a"}]', "fulltext"),
    ('[1]', "not a JSON object"),
    ('[{"reqid": "a", "fulltext": "s shall satisfy p"},'
     ' {"reqid": "a", "fulltext": "s shall satisfy q"}]', "duplicate"),
])
def test_json_errors(tmp_path, content, needle):
    e = file_error(write(tmp_path, "bad.json", content))
    assert needle in e.message and e.source.endswith("bad.json")


def test_json_syntax_error_position(tmp_path):
    e = file_error(write(tmp_path, "bad.json", '[\n  {"reqid": "a",, "fulltext": "x"}\n]'))
    assert (e.line, e.column) == (2, 17)


def test_json_same_reqid_in_two_projects_is_an_error_naming_both(tmp_path):
    """Ids are unique across a run, whatever their FRET project (the generated
    module's MONITORS would hold the id twice)."""
    data = [{"reqid": "a", "project": "P1", "fulltext": "s shall satisfy p"},
            {"reqid": "a", "project": "P2", "fulltext": "s shall satisfy q"}]
    with pytest.raises(FretishFileError) as e:
        load_requirements(write(tmp_path, "x.json", json.dumps(data)))
    msg = str(e.value)
    assert "'P1'" in msg and "'P2'" in msg and msg.count("x.json:1:") == 2


# --------------------------------------------------------------------------- folders
def test_folder_sorted_by_name(tmp_path):
    write(tmp_path, "b.fret", "B1: the sw shall satisfy p\n")
    write(tmp_path, "a.json", json.dumps([{"reqid": "A1", "fulltext": "s shall satisfy p"}]))
    write(tmp_path, "c.fret", "C1: the sw shall satisfy p\nC2: bad bad\n")
    write(tmp_path, "notes.txt", "not requirements")
    (tmp_path / "sub").mkdir()
    write(tmp_path / "sub", "d.fret", "D1: the sw shall satisfy p\n")
    entries = load_requirements(tmp_path)
    assert [e.id for e in entries] == ["A1", "B1", "C1", "C2"]
    assert entries[3].error is not None
    # several paths, in the order given; a single file of any other extension is .fret
    other = write(tmp_path, "reqs.txt", "X1: the sw shall satisfy p\n")
    ids = [e.id for e in load_requirements([other, tmp_path / "sub"])]
    assert ids == ["X1", "D1"]


def test_missing_path(tmp_path):
    e = file_error(tmp_path / "nope.fret")
    assert "no such file" in e.message


def test_not_utf8(tmp_path):
    p = tmp_path / "r.fret"
    p.write_bytes(b"R1: the sw shall satisfy \xff\n")
    assert "UTF-8" in file_error(p).message


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.from_regex(r"[A-Za-z0-9_.-]{1,8}", fullmatch=True),
                          st.sampled_from(["p", "q & r", "x > 3", "p and q", "x ==", "(p"]),
                          st.integers(0, 6)),
                min_size=1, max_size=6, unique_by=lambda t: t[0]))
def test_fret_positions_property(tmp_path_factory, reqs):
    """Whatever the indentation, an error or the response span points at the right place
    in the file."""
    d = tmp_path_factory.mktemp("prop")
    lines = []
    for rid, resp, pad in reqs:
        lines.append(f"{rid}:{' ' * (pad + 1)}the sw shall")
        lines.append(f"{' ' * (pad + 2)}always satisfy {resp}   # c")
    p = d / "r.fret"
    p.write_text("\n".join(lines) + "\n")
    entries = load_requirements(p)
    for k, ((rid, resp, _pad), e) in enumerate(zip(reqs, entries)):
        assert e.id == rid and e.line == 2 * k + 1
        if e.requirement is not None:
            s = e.requirement.response_span
            line = lines[s.line - 1]
            assert line[s.column - 1:s.end_column - 1] == f"satisfy {resp}"
        else:
            err = e.error
            assert err.text_line == lines[err.line - 1]
            assert err.line == 2 * k + 2
            assert 1 <= err.column <= len(lines[err.line - 1]) + 1


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(["", ".", "..", "a", "b.fret", ".json", "x.", "r1.JSON",
                                 "a.b.c", " "]), min_size=1, max_size=6),
       st.sampled_from(["", "/", "//", "///"]), st.sampled_from(["", "/", "//"]))
def test_path_text_and_suffix_are_pathlibs(parts, lead, trail):
    """files.py names files without importing pathlib (start-up): the same text as
    ``str(Path(p))`` and the same ``suffix``."""
    from pathlib import Path

    from fretc.fretish.files import _path_text, _suffix
    p = lead + "/".join(parts) + trail
    if not p:
        return
    assert _path_text(p) == str(Path(p))
    assert _suffix(_path_text(p)) == Path(p).suffix


def test_entry_fields_in_the_order_the_reader_passes_them():
    """The .fret reader (files._FretReader._entry) makes each RequirementEntry with
    positional arguments in this order: it must be the dataclass's field order."""
    import dataclasses

    from fretc.fretish import files
    assert tuple(f.name for f in dataclasses.fields(files.RequirementEntry)) == (
        "id", "text", "source", "line", "column", "rationale", "parent", "tick_period",
        "requirement", "error", "extra", "inputs", "outputs", "origin", "variables",
        "streams")


def test_inputs_and_outputs_name_quoted_variables_as_the_requirements_write_them(tmp_path):
    """``@inputs``/``@outputs`` and ``--inputs``/``--outputs`` take a name that is no
    identifier in double quotes (``"wheel speed"``, ``"it's safe"``, ``"path #3"``), as
    FRETish writes it: such a requirement could be given to no shield, and an unclosed
    quote is refused with its column."""
    from fretc.fretish.files import load_requirements, split_names

    assert split_names('"wheel speed", ok ROS.ok,"it\'s safe" "path #3"') == [
        "wheel speed", "ok", "ROS.ok", "it's safe", "path #3"]
    for bad in ('"abc', '""', 'a"b'):
        with pytest.raises(ValueError):
            split_names(bad)
    f = tmp_path / "q.fret"
    f.write_text('@inputs "wheel speed", "path #3" # a comment\n@outputs o\n'
                 'R1: whenever "wheel speed" > 2 & "path #3" c shall immediately satisfy o\n',
                 encoding="utf-8")
    (e,) = load_requirements([f])
    assert e.inputs == ("wheel speed", "path #3") and e.outputs == ("o",)
    f.write_text('@inputs ok, "wheel speed\nR1: whenever ok c shall immediately satisfy o\n',
                 encoding="utf-8")
    with pytest.raises(FretishError, match=r"q.fret:1:13: .*bad variable name '\"wheel' in @inputs \(its double quote is not closed"):
        load_requirements([f])
