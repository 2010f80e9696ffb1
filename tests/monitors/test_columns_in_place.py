"""Comparisons of a variable with a number or another variable, and their NaN ticks, read
the columns in place (no copy with FRET's absorbing state appended): the same arrays as the
definition over ``n + 1`` positions (the absorbing state: every number 0), on random columns
with NaN, infinities, booleans and columns longer than the trace."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.fretish import ast as A
from fretc.monitors.arrays import COMPARISONS
from fretc.monitors.expressions import ColumnExpressions
from fretc.monitors.nan import nan_ticks_of

VALUES = [0.0, 0.5, -1.0, 2.0, float("nan"), float("inf"), -0.0]


@st.composite
def cases(draw):
    n = draw(st.integers(1, 12))
    extra = draw(st.integers(0, 2))  # a column longer than the trace
    columns = {
        "x": np.array(draw(st.lists(st.sampled_from(VALUES), min_size=n + extra,
                                    max_size=n + extra)), np.float64),
        "y": np.array(draw(st.lists(st.sampled_from(VALUES), min_size=n + extra,
                                    max_size=n + extra)), np.float64),
        "b": np.array(draw(st.lists(st.booleans(), min_size=n + extra, max_size=n + extra)),
                      np.bool_),
    }
    leaf = st.sampled_from([A.Var("x"), A.Var("y"), A.Var("b"), A.NumLit("0.5"),
                            A.NumLit("0"), A.NumLit("-2")])
    op = draw(st.sampled_from(sorted(COMPARISONS)))
    return n, columns, A.Binary(op, draw(leaf), draw(leaf))


def _definition(e: A.Expr, columns, n: int) -> np.ndarray:
    """An operand at the ``n`` ticks and the absorbing state (0 there), float64."""
    if isinstance(e, A.NumLit):
        return np.full(n + 1, float(e.value))
    return np.concatenate((columns[e.name][:n].astype(np.float64), [0.0]))


@settings(max_examples=300, deadline=None)
@given(cases())
def test_leaf_comparisons_and_their_nan_ticks(case):
    n, columns, e = case
    x, y = _definition(e.left, columns, n), _definition(e.right, columns, n)
    with np.errstate(invalid="ignore"):
        want = COMPARISONS[e.op](x, y)
    got = ColumnExpressions(columns, n).bool(e)
    assert got.dtype == np.bool_ and got.tolist() == want.tolist()
    nan = nan_ticks_of([e], columns, n)
    assert nan.tolist() == (np.isnan(x[:n]) | np.isnan(y[:n])).tolist()
    assert nan_ticks_of([A.Var("x")], columns, n).tolist() == np.isnan(columns["x"][:n]).tolist()
