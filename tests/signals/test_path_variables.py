"""FoxQL's message path variables (docs/bindings.md, "FoxQL"): ``$name`` in a filter or a
slice takes its value from the binding file's ``[path_variables]`` table, so a path copied
from a Foxglove panel that uses a variable binds unchanged; it binds exactly as the path with
the value written in its place."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fretc.common.problems import BindingError
from fretc.signals.bindings.files import parse_bindings

HEAD = '[tick]\nperiod = "100 ms"\n'


def _ast(path_vars: str, expr: str):
    b = parse_bindings(HEAD + path_vars + f"[variables]\nv = '{expr}'\n", "b.toml")
    return b.variables["v"].ast


def _same(a, b) -> bool:
    """Trees equal but for columns (a value is written at another column than ``$name``)."""
    import dataclasses

    if dataclasses.is_dataclass(a) and dataclasses.is_dataclass(b):
        return type(a) is type(b) and all(
            f.name == "col" or _same(getattr(a, f.name), getattr(b, f.name))
            for f in dataclasses.fields(a))
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


@given(name=st.text("abcdefghij_", min_size=1, max_size=8),
       level=st.integers(-5, 5), lo=st.integers(-4, 4), hi=st.integers(-4, 8))
def test_a_variable_binds_as_its_value_written_in_its_place(name, level, lo, hi):
    got = _ast(f'[path_variables]\nrobot = "{name}"\nlevel = {level}\nlo = {lo}\nhi = {hi}\n',
               "count(/d.status[:]{name==$robot}{level>=$level}.level) + "
               "min(/scan.ranges[$lo:$hi])")
    want = _ast("", f'count(/d.status[:]{{name=="{name}"}}{{level>={level}}}.level) + '
                f"min(/scan.ranges[{lo}:{hi}])")
    assert _same(got, want)


@pytest.mark.parametrize("tables, expr, message", [
    ("", "max(/d.s[:]{name==$who}.level)", r"\$who has no value"),
    ("[path_variables]\nlo = 1.5\n", "min(/scan.ranges[$lo:])", "slice bound is an integer"),
    ("[path_variables]\nx = [1]\n", "max(/d.s[:]{level==$x}.level)", "a number, a string"),
    ("[path_variables]\n\"a b\" = 1\n", "max(/d.s[:]{level==1}.level)", "is not a name"),
])
def test_bad_variables_are_errors_naming_where(tables, expr, message):
    with pytest.raises(BindingError, match=message) as info:
        _ast(tables, expr)
    assert "b.toml:" in str(info.value)
