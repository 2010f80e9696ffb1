"""The entities of one per-entity requirement judged at once (:func:`batch_verdicts`): their
traces laid end to end, the requirement's pt formula and its trigger formula evaluated over
all of them in one pass that restarts at each trace's first tick
(:func:`fretc.monitors.vectorized.pt_series` with ``starts``), and its LTL3 automata run
over each (:func:`fretc.monitors.judge.ltl3_verdicts`).

FRET's finite-trace verdict of a trace is its pt formula at its last tick; it is vacuous
when the trigger formula (:func:`fretc.compiler.trigger.trigger_pt`: no trigger in any
scope interval) holds there too; the LTL3 verdict is the first rejection of the automata.
These are the verdicts the judge gives one trace at a time (the tests compare them on
random traces). The entities it finds violated get their robustness over their traces at
once too (:func:`fretc.monitors.robustness.robustness_of_traces`, in
:mod:`fretc.audit.entities.log`) and the rest of their evidence (the interval semantics' first
violation and counts) one at a time from the plain judge; so do the traces this pass cannot
take: a value NaN (unknown ticks), and every trace of a log with damage (a cut or gaps).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fretc.compiler.trigger import trigger_pt
from fretc.monitors.judge import ltl3_verdicts
from fretc.monitors.vectorized import VectorizeError, pt_series, supports

__all__ = ["batchable", "batch_verdicts"]


def batchable(plan: Any, r: Any) -> Any:
    """The trigger formula of requirement ``r`` when its entities can be judged at once,
    else None: a pt formula over columns, LTL3 automata as tables, a trigger formula, no
    probability bound, no coverage asked."""
    f = r.formalization
    if (f is None or r.offline or not f.pt_causal or not supports(f.pt) or plan.coverage
            or getattr(r.compiled, "probability", None) is not None):
        return None
    ms = r.monitor_source
    if ms is None or any(a is not None and not a.empty and not a.complete and a.table is None
                         for a in (ms.bad, ms.good)):
        return None
    return trigger_pt(r.compiled)


def batch_verdicts(r: Any, trig: Any, columns: dict[str, np.ndarray], firsts: np.ndarray,
                   lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray, list] | None:
    """The verdicts of ``len(firsts)`` traces of requirement ``r`` laid end to end in
    ``columns`` (variable -> values; trace ``e`` at ``firsts[e]``, ``lengths[e] >= 1``
    ticks).

    Returns:
        ``(holds, vacuous, ltl3)``: per trace FRET's finite-trace verdict, whether it holds
        for want of a trigger, and the LTL3 verdict ``(status, tick)`` (tick 0-based in the
        trace, None when unknown); None when the formulas cannot be evaluated over the
        columns (a missing column: judge one at a time)."""
    n = int(lengths.sum())
    starts = np.repeat(firsts, lengths)
    ends = firsts + lengths - 1
    try:
        holds = pt_series(r.formalization.pt, columns, n, starts)[ends]
        vacuous = pt_series(trig, columns, n, starts)[ends] & holds
        ltl3 = ltl3_verdicts(r.monitor_source, columns, n, starts, firsts, lengths)
    except (VectorizeError, KeyError):
        return None
    return holds, vacuous, ltl3


def nan_traces(columns: dict[str, np.ndarray], firsts: np.ndarray, lengths: np.ndarray
               ) -> set[int]:
    """The traces (indexes) with a NaN value in ``columns``: judged one at a time (their
    NaN ticks are unknown)."""
    which = np.repeat(np.arange(len(firsts)), lengths)
    out: set[int] = set()
    for col in columns.values():
        if col.dtype.kind == "f":
            bad = np.isnan(col)
            if bad.any():
                out |= set(np.unique(which[bad]).tolist())
    return out
