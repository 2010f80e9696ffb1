"""FRET's rules on names (../shared/fretish/README.md sections 5 and 6b): NuSMV's and R2U2's
reserved words are refused as bare names with FRET's message; a quoted name keeps every
backslash but the one before a quote."""

from __future__ import annotations

import pytest

from fretc.common.errors import FretishSyntaxError
from fretc.compiler.printers import to_smv
from fretc.compiler.semantics import formalize
from fretc.fretish.parser import parse


@pytest.mark.parametrize("sentence, name", [
    ("whenever count > 3 the sw shall immediately satisfy q", "count"),
    ("the sw shall always satisfy abs(x) < 1", "abs"),
    ("the sw shall always satisfy min(x, y) < 1", "min"),
    ("the sw shall always satisfy E", "E"),
    ("upon R the sw shall eventually satisfy q", "R"),
    ("in init mode the sw shall always satisfy int > 0", "init"),
    ("the sw shall always satisfy MODULE | q", "MODULE"),
])
def test_reserved_names_are_refused_with_frets_message(sentence, name):
    with pytest.raises(FretishSyntaxError) as err:
        parse(sentence)
    text = str(err.value)
    assert f"These reserved letter combinations cannot be used: {name}" in text
    col = sentence.index(name) + 1
    assert f":1:{col}:" in text  # the name's own position


@pytest.mark.parametrize("sentence, printed", [
    ('the sw shall always satisfy "count" > 0', "_DQT_count_DQT_"),
    ("the sw shall always satisfy a.count > 0", "a_DOT_count"),
    ("the sw shall always satisfy counter > 0", "counter"),
    ("the sw shall always satisfy Count > 0", "Count"),  # case sensitive
])
def test_names_that_only_contain_a_reserved_word_are_accepted(sentence, printed):
    assert printed in to_smv(formalize(parse(sentence)).ft_inf)


def test_backslashes_in_quoted_names_stay_as_written():
    f = formalize(parse('the sw shall always satisfy "back\\\\slash" > 0'))
    assert "_DQT_back_BSL__BSL_slash_DQT_" in to_smv(f.ft_inf)
    g = formalize(parse('the sw shall always satisfy "say \\"hi\\"" > 0'))
    assert g.variables == ['say "hi"']
