"""The cache's JSON of fretc's dataclasses (:mod:`fretc.common.cache_json`): what it writes it
reads back equal and of the same types, it makes only the classes it is given, and anything
else is refused (a value it has no form for when written, a layout it does not know when
read)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.common import cache_json
from fretc.fretish import ast, entry


class Pos(NamedTuple):
    line: int
    column: int


@dataclass(frozen=True)
class Leaf:
    value: object
    pos: Pos = Pos(0, 0)


@dataclass
class Node:
    name: str
    kids: tuple
    extra: dict = field(default_factory=dict)


CLASSES = {"Pos": Pos, "Leaf": Leaf, "Node": Node}
scalars = st.one_of(st.none(), st.booleans(), st.integers(), st.text(),
                    st.floats(allow_nan=False), st.fractions())
trees = st.recursive(
    scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.tuples(inner, inner),
        st.frozensets(st.one_of(st.integers(), st.text()), max_size=3),
        st.dictionaries(st.one_of(st.integers(), st.text(), st.tuples(st.integers())), inner,
                        max_size=3),
        st.builds(Leaf, inner, st.builds(Pos, st.integers(), st.integers())),
        st.builds(Node, st.text(), st.tuples(inner, inner),
                  st.dictionaries(st.text(), inner, max_size=2))),
    max_leaves=20)


def _shape(v):
    """``v`` with the type of every value spelled out (``==`` says 1 == 1.0 == True)."""
    if isinstance(v, (list, tuple, frozenset)):
        items = sorted(map(repr, map(_shape, v))) if type(v) is frozenset else list(map(_shape, v))
        return (type(v).__name__, items)
    if isinstance(v, dict):
        return ("dict", [(_shape(k), _shape(x)) for k, x in v.items()])
    if isinstance(v, (Leaf, Node)):
        return (type(v).__name__, _shape(tuple(vars(v).values())))
    return (type(v).__name__, repr(v))


@settings(max_examples=300, deadline=None)
@given(trees)
def test_what_is_written_reads_back_equal_and_of_the_same_types(tree):
    got = cache_json.loads(cache_json.dumps(tree, CLASSES), CLASSES)
    assert got == tree and _shape(got) == _shape(tree)


def test_floats_keep_their_kind_and_special_values():
    values = [1.0, -0.0, math.inf, -math.inf, 1e308, 5e-324, 1, True]
    got = cache_json.loads(cache_json.dumps(values, CLASSES), CLASSES)
    assert [(type(v), repr(v)) for v in got] == [(type(v), repr(v)) for v in values]
    (nan,) = cache_json.loads(cache_json.dumps([math.nan], CLASSES), CLASSES)
    assert math.isnan(nan)


def test_a_class_not_listed_is_refused_both_ways():
    data = cache_json.dumps(Leaf(1), CLASSES)
    with pytest.raises(ValueError):
        cache_json.loads(data, {"Pos": Pos})
    with pytest.raises(TypeError):
        cache_json.dumps(Leaf(1), {"Pos": Pos})
    with pytest.raises(TypeError):
        cache_json.dumps({1, 2}, CLASSES)  # a set has no form (a frozenset has)
    with pytest.raises(TypeError):
        cache_json.dumps(object(), CLASSES)


@pytest.mark.parametrize("data", [
    b'{"x": 1}', b'{"c": "Leaf", "v": [1]}', b'{"c": "os.system", "v": ["true"]}',
    b'{"q": [1, 0]}', b'{"q": ["1", 2]}', b'{"p": "k"}', b'{"d": [[[1], 2]]}', b"not json",
    b'{"t": [1], "f": [2]}', b'{"c": "Pos", "v": [1, 2, 3]}', b"[" * 100000 + b"]" * 100000])
def test_a_layout_it_does_not_know_is_a_value_error(data):
    with pytest.raises(ValueError):
        cache_json.loads(data, CLASSES)


def test_persistent_objects_are_the_callers_own():
    key = object()
    data = cache_json.dumps([key, (key,)], CLASSES, lambda o: "k" if o is key else None)
    got = cache_json.loads(data, CLASSES, {"k": key}.__getitem__)
    assert got[0] is key and got[1][0] is key


def test_classes_of_lists_the_modules_own_dataclasses_and_named_tuples():
    found = cache_json.classes_of(ast, entry)
    assert {"Requirement", "Span", "Var", "RequirementEntry", "Origin"} <= set(found)
    assert "FretishError" not in found and "Fraction" not in found
    assert all(c.__module__ in (ast.__name__, entry.__name__) for c in found.values())
