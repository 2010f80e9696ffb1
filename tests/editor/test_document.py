"""What the language server knows of a document (:mod:`fretc.editor.document`), without the
protocol: diagnostics for bad durations, undeclared constants and unbound variables, and no
exception on any document."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.editor.document import analyse


def test_durations_constants_and_unbound_variables(tmp_path):
    (tmp_path / "x.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                              'p = "/a.data > 0"\n')
    text = ("@tick_period 100 ms\n"
            "R1: the sw shall within 150 milliseconds satisfy p\n"
            "R2: the sw shall within T_go satisfy p\n"
            "R3: the sw shall always satisfy q\n")
    a = analyse(text, str(tmp_path / "x.fret"))
    got = {(p.line, p.severity): p.message for p in a.problems}
    assert "not a whole number of ticks" in got[(1, 1)]
    assert "T_go is not declared" in got[(2, 1)]
    assert "'q' is not bound" in got[(3, 2)]
    assert len(a.problems) == 3


@settings(max_examples=60, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("R1: theswhalyfrin@_ 0123\n\t&|!()<>=\"#\x00")),
               max_size=120))
def test_no_document_makes_the_analysis_raise(text):
    a = analyse(text, "/nonexistent/dir/x.fret")
    for p in a.problems:
        assert p.line >= 0 and p.col >= 0 and p.end_col >= p.col


def test_on_save_check_finds_a_conflict(tmp_path):
    from fretc.editor.document import check_problems

    text = ("R1: the sw shall always satisfy p\n"
            "R2: the sw shall always satisfy !p\n"
            "R3: the sw shall always satisfy q\n")
    a = analyse(text, str(tmp_path / "c.fret"))
    got = check_problems(a)
    assert {p.line for p in got} == {0, 1}  # R1 and R2, not R3
    assert all("conflict" in p.message and p.severity == 1 for p in got)


def test_completion_offers_what_the_grammar_accepts_there(tmp_path):
    (tmp_path / "x.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                              'p = "/a.data > 0"\n')
    lines = ["R1: upon p the robot shall within 3 ticks satisfy p",
             "R2: the robot shall ", "R3: the robot shall within 3 "]
    a = analyse("\n".join(lines) + "\n", str(tmp_path / "x.fret"))
    after_shall = [label for label, _k in a.completions(1, len(lines[1]))]
    assert "within" in after_shall and "satisfy" in after_shall
    assert "upon" not in after_shall and "p" not in after_shall  # no name comes there
    units = [label for label, _k in a.completions(2, len(lines[2]))]
    assert set(units) == {"ticks", "microseconds", "milliseconds", "seconds", "minutes",
                          "hours"}
    after_cond = a.completions(0, len("R1: upon p "))
    assert after_cond[0] == ("robot", "component") and ("p", "variable") in after_cond
