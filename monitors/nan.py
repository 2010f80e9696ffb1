"""Where a requirement's comparisons read NaN: such a tick's value is neither true nor false.

IEEE 754 makes every ordered comparison with NaN false (and ``!=`` true), so ``x < 5`` and
``!(x >= 5)`` - one requirement spelled twice - would get opposite verdicts on a NaN. fretc
gives NaN one meaning instead (docs/guide/ticks.md, "NaN"): a comparison of a FRETish
expression with a NaN operand (a NaN in a column, or ``0/0`` in the requirement's
arithmetic), and a number read as a condition that is NaN, make that tick *unread* for the
requirement; the audit judges only the ticks before the first unread one
(:mod:`fretc.audit.damage`), as it does before a cut (:func:`fretc.monitors.judge.nan_ticks`). LaserScan ranges under REP 117 never get
here: the bindings drop their NaN before any comparison (:mod:`fretc.signals.bindings`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from fretc.fretish import ast as A

from fretc.monitors.expressions import ColumnExpressions, EvidenceUnsupported

__all__ = ["nan_ticks_of"]


def nan_ticks_of(exprs: list[A.Expr], columns: Mapping[str, np.ndarray], n: int
                 ) -> np.ndarray:
    """The ticks (of ``n``) at which a comparison inside ``exprs`` (a requirement's scope
    mode, condition, stop condition and response: :func:`fretc.monitors.judge.nan_ticks`) has a
    NaN operand, or a number read as a condition is NaN.

    Args:
        exprs: FRETish expressions, each read as a condition.
        columns: FRET variable -> 1-D array of at least ``n`` values.
        n: ticks of the trace.

    Returns:
        A bool array of ``n`` items, True where the tick's value is unread. Parts that
        cannot be evaluated over columns (an uninterpreted function, a missing column) add
        nothing here; the judge reports them.
    """
    out = np.zeros(n, dtype=np.bool_)
    if n == 0:
        return out
    ev = ColumnExpressions(columns, n)
    for e in exprs:
        _walk(e, ev, out, as_condition=True)
    return out


def _nan(e: A.Expr, ev: ColumnExpressions, n: int) -> np.ndarray | None:
    """Where the numeric expression ``e`` is NaN at the ``n`` ticks (None: nowhere); a
    variable's column read in place (no copy with the absorbing state)."""
    if isinstance(e, A.NumLit):
        return np.ones(n, np.bool_) if math.isnan(float(e.value)) else None
    if isinstance(e, A.Var) and e.name != "FTP":
        col = ev.ticks(e.name)
        if col.dtype.kind in "biu":
            return None
        if col.dtype.kind == "f":
            return np.isnan(col)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        return np.isnan(ev.num(e)[:n])


def _walk(e: A.Expr, ev: ColumnExpressions, out: np.ndarray, as_condition: bool) -> None:
    """OR into ``out`` the NaN ticks of the comparisons inside ``e``."""
    n = len(out)
    try:
        if isinstance(e, A.Binary) and e.op in A.COMPARISON_OPS:
            x, y = _nan(e.left, ev, n), _nan(e.right, ev, n)
            for nan in (x, y):
                if nan is not None:
                    out |= nan
        elif isinstance(e, A.Var) and as_condition and e.name in ev.columns:
            col = ev.ticks(e.name)
            if col.dtype.kind == "f":
                out |= np.isnan(col)
    except (EvidenceUnsupported, KeyError, ValueError, TypeError):
        pass
    if isinstance(e, A.Binary):
        cond = e.op not in A.COMPARISON_OPS and e.op not in A.ARITH_OPS
        _walk(e.left, ev, out, cond)
        _walk(e.right, ev, out, cond)
    elif isinstance(e, A.Unary):
        _walk(e.operand, ev, out, e.op == "!")
    elif isinstance(e, A.Call):
        for a in e.args:
            _walk(a, ev, out, True)
