"""fretc.compile.json_indent2 (the ``--emit ltl --json`` writer) against ``json.dumps(...,
indent=2)``: the same text for any JSON value, including values it hands back to json."""

from __future__ import annotations

import json

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli.compile import json_indent2

SCALARS = st.one_of(st.none(), st.booleans(), st.integers(), st.text(max_size=6),
                    st.floats(allow_nan=True))
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=4), inner, max_size=4),
    st.dictionaries(st.integers(), inner, max_size=2)), max_leaves=20)


@settings(max_examples=400, deadline=None)
@given(VALUES)
def test_same_text_as_json_dumps(value):
    assert json_indent2(value) == json.dumps(value, indent=2)


def test_compiled_requirements():
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    objs = [c.to_json() for c in compile_entries(load_requirements([root / "requirements"]))]
    assert objs and json_indent2(objs) == json.dumps(objs, indent=2)


# Same-shaped objects (the per-requirement layout is computed once per key tuple and depth
# and reused): keys and values drawn with quotes, backslashes, control and non-ASCII
# characters, so a wrong key, separator, indentation or escape in a reused layout differs.
NASTY = st.text(alphabet=st.sampled_from('a"\\\n\t\x00\x1f\x7fé€😀 '), max_size=5)
LEAVES = st.one_of(st.none(), st.booleans(), st.integers(), NASTY,
                   st.lists(NASTY, max_size=3), st.lists(st.one_of(NASTY, st.integers()),
                                                         max_size=3))


@settings(max_examples=300, deadline=None)
@given(st.lists(NASTY, min_size=1, max_size=5, unique=True), st.data())
def test_same_shaped_objects_reuse_one_layout(keys, data):
    rows = [{k: data.draw(LEAVES) for k in keys} for _ in range(data.draw(st.integers(1, 4)))]
    nested = {"outer": rows, "again": [{"x": rows}]}
    for value in (rows, nested, [rows, rows[0]]):
        assert json_indent2(value) == json.dumps(value, indent=2)


def test_requirement_shaped_rows_with_escapes():
    keys = ("id", "text", "source", "line", "parent", "rationale", "key", "ft", "ft_inf",
            "pt", "ft_spot", "ft_inf_spot", "variables", "variables_fret", "ticks",
            "warnings", "pt_causal")
    row = dict.fromkeys(keys, 'G"1\\\u00e9\n')
    row.update(line=3, parent=None, ticks=None, pt_causal=False, warnings=[],
               variables=["a", 'w"x'], variables_fret=["_DQT_w_DQT_"])
    rows = [row, dict(row, id="G2", pt_causal=True, ticks=7), {"id": "E", "error": {}}]
    assert json_indent2(rows) == json.dumps(rows, indent=2)
