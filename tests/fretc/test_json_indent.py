"""fretc.compile.json_indent2 (the ``--emit ltl --json`` writer) against ``json.dumps(...,
indent=2)``: the same text for any JSON value, including values it hands back to json."""

from __future__ import annotations

import json

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compile import json_indent2

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
    from compiler.build import compile_entries
    from fretish.files import load_requirements
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    objs = [c.to_json() for c in compile_entries(load_requirements([root / "requirements"]))]
    assert objs and json_indent2(objs) == json.dumps(objs, indent=2)
