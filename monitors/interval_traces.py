"""FRET's interval semantics' counts over many traces at once: the scope intervals and the
trigger points of each of many traces laid end to end in columns
(:func:`interval_counts`), as :func:`fretc.monitors.interval.evaluate_requirement` counts
them one trace at a time (``intervals``, ``triggers``; ``../shared/fretish/README.md``
sections 2-3, :mod:`fretc.monitors.interval`'s points 1 and 2).

Design notes: ARCHITECTURE.md, `monitors/interval_traces.py`."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fretc.fretish import ast as A
from fretc.monitors.expressions import ColumnExpressions

__all__ = ["interval_counts", "per_tick"]


def per_tick(e: A.Expr | None) -> bool:
    """Whether expression ``e`` (None: none) has a value at a tick read from that tick's
    columns alone: no function call (FRET's temporal functions, ``ite``, uninterpreted
    ones) and no ``FTP``."""
    if e is None:
        return True
    if isinstance(e, A.Call):
        return False
    if isinstance(e, A.Var):
        return e.name != "FTP"
    if isinstance(e, A.Unary):
        return per_tick(e.operand)
    if isinstance(e, A.Binary):
        return per_tick(e.left) and per_tick(e.right)
    return True


def interval_counts(req: A.Requirement, columns: Mapping[str, np.ndarray],
                    firsts: np.ndarray, lengths: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray] | None:
    """The scope intervals and the trigger points of each of ``len(firsts)`` traces laid
    end to end in ``columns`` (FRET variable -> array of ``lengths.sum()`` values; trace
    ``e`` its ``lengths[e] >= 1`` ticks from ``firsts[e]``).

    Returns:
        ``(intervals, triggers)``: two int64 arrays, one count per trace; None when the
        scope's mode or the condition reads a temporal function or ``FTP``
        (:func:`per_tick`), or for a free-form requirement.

    Raises:
        EvidenceUnsupported: what the interval semantics does not take (an arithmetic
            minus where a condition is expected).
        KeyError: a variable missing from ``columns``."""
    if req.freeform or req.response is None:
        return None
    scope, cond = req.scope.kind, req.condition.kind
    if not per_tick(req.scope.mode) or not per_tick(req.condition.expr):
        return None
    n, k = int(lengths.sum()), len(firsts)
    trace = np.repeat(np.arange(k, dtype=np.int64), lengths)
    start = np.zeros(n, np.bool_)
    start[firsts] = True
    ex = ColumnExpressions(columns, n, free=True)
    m = ex.bool(req.scope.mode)[:n] if scope != "null" else None  # type: ignore[arg-type]
    inside = _inside(scope, m, start, trace, firsts)
    istart = inside & (start | ~_prev(inside, start))
    intervals = np.bincount(trace[istart], minlength=k).astype(np.int64)
    if cond == "null":
        return intervals, intervals.copy()
    C = ColumnExpressions(columns, n).bool(req.condition.expr)[:n]  # type: ignore[arg-type]
    fired = inside & C
    if cond != "holding":  # regular: becomes true, or holds at the interval's first tick
        fired &= istart | ~_prev(C, start)
    return intervals, np.bincount(trace[fired], minlength=k).astype(np.int64)


def _prev(x: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``x`` at the tick before, within each trace (False at a trace's first tick)."""
    out = np.empty(len(x), np.bool_)
    out[0] = False
    out[1:] = x[:-1]
    out[start] = False
    return out


def _ever(x: np.ndarray, trace: np.ndarray, firsts: np.ndarray) -> np.ndarray:
    """Whether ``x`` held at some tick up to and including each tick, within its trace."""
    c = np.cumsum(x, dtype=np.int64)
    before = c[firsts] - x[firsts]  # (the count before each trace's first tick)
    return c - before[trace] > 0


def _inside(scope: str, m: np.ndarray | None, start: np.ndarray, trace: np.ndarray,
            firsts: np.ndarray) -> np.ndarray:
    """The ticks inside a scope interval of ``scope`` (module docstring), ``m`` the mode."""
    if scope == "null" or m is None:
        return np.ones(len(start), np.bool_)
    if scope == "in":
        return m.copy()
    if scope in ("notin", "onlyIn"):
        return ~m
    if scope == "before":
        return ~_ever(m, trace, firsts)
    if scope == "onlyBefore":
        return _ever(m, trace, firsts)
    fall = ~m & _prev(m, start)  # (the first tick after a run of the mode)
    if scope == "after":
        return _ever(fall, trace, firsts)
    if scope == "onlyAfter":
        return ~_ever(fall, trace, firsts)
    raise ValueError(f"unknown scope kind {scope!r}")
