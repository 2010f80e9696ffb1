"""The entities of one per-entity requirement judged at once (:func:`judge_at_once`): their
traces laid end to end, a chunk of at most :data:`CHUNK_TICKS` ticks at a time, the
requirement's pt formula and its trigger formula evaluated over all of them in one pass that
restarts at each trace's first tick (:func:`fretc.monitors.vectorized.pt_series` with
``starts``), and its LTL3 automata run over each (:func:`fretc.monitors.judge.ltl3_verdicts`).

Design notes: ARCHITECTURE.md, `audit/entities/batch.py`."""

from __future__ import annotations

from typing import Any

import numpy as np

from fretc.audit.entities.verdicts import LTL3_STATUS, EntityBlock
from fretc.audit.finalize import NAN_FALSE_NOTE
from fretc.audit.gaps import inner_gaps
from fretc.common.streams import base_topic
from fretc.compiler.trigger import trigger_pt
from fretc.monitors.expressions import EvidenceUnsupported
from fretc.monitors.interval import evaluate_requirement
from fretc.monitors.interval_traces import interval_counts
from fretc.monitors.judge import ltl3_verdicts
from fretc.monitors.robustness import ROBUSTNESS_CHUNK, robustness_columns, summary_of
from fretc.audit.verdict import MARGIN_POINTS
from fretc.monitors.vectorized import VectorizeError, pt_series, supports

__all__ = ["batchable", "batch_verdicts", "judge_at_once", "CHUNK_TICKS", "BATCH_NOTE"]

#: Ticks of the traces judged at once in one evaluation (the robustness' bound, so that a
#: chunk's temporaries are a few arrays of that many values whatever the entities); a
#: longer trace is judged alone.
CHUNK_TICKS = ROBUSTNESS_CHUNK

#: The note of an entity judged with the others.
BATCH_NOTE = ("judged with the requirement's other entities at once (its pt formula, "
              "robustness and interval counts over their ticks)")


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


def judge_at_once(j: Any, trig: Any, robs: bool = True) -> np.ndarray:
    """The entities of :class:`fretc.audit.entities.log._Judge` ``j`` judged at once (module
    docstring; ``trig``: the requirement's trigger formula, :func:`batchable`): the satisfied
    and vacuous ones as records of ``j.block``; returns entity -> its record (int64, -1:
    judged one at a time: the violated ones with the LTL3 verdict found here in ``j.ltl3s``,
    and with ``robs`` their robustness in ``j.robs``). None judged on a log with damage, or
    when the formulas cannot be evaluated over columns."""
    src, c, r = j.source, j.c, j.r
    record = np.full(len(c.table.keys), -1, np.int64)
    if src.partial or src.lost or inner_gaps(src):
        return record
    judged = [i for i in range(len(c.table.keys))
              if (i not in c.table.errors or c.kind.stream) and i not in j.unread]
    n = len(j.times)
    i0s, i1s = j._ranges(judged)
    lengths = i1s - i0s + 1
    keep = (i0s < n) & (lengths <= CHUNK_TICKS)
    ents = np.asarray(judged, np.int64)[keep]
    i0s, lengths = i0s[keep], lengths[keep]
    if not len(ents):
        return record
    b = j.bindings
    j.block = block = EntityBlock(
        j.ents.path, r.id, r.text, r.source, j.name, c.kind.key, c.table.keys,
        np.asarray(c.table.first, np.int64), np.asarray(c.table.last, np.int64), j.times,
        tuple(r.notes), (NAN_FALSE_NOTE,) if b.tick.nan == "false" else (), BATCH_NOTE)
    ends = np.cumsum(lengths)
    a = 0
    while a < len(ents):  # (chunks of at most CHUNK_TICKS ticks)
        z = int(np.searchsorted(ends, (ends[a - 1] if a else 0) + CHUNK_TICKS, side="right"))
        got = _chunk(j, trig, block, ents[a:z], i0s[a:z], lengths[a:z], robs)
        if got is None:
            record[:] = -1
            return record
        record[got[0]] = got[1]
        a = z
    block.seal()
    return record


def _chunk(j: Any, trig: Any, block: EntityBlock, ents: np.ndarray, i0s: np.ndarray,
           lengths: np.ndarray, robs: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`judge_at_once` of the entities ``ents`` (their ticks from ``i0s``, ``lengths``
    of them): their records added to ``block``, returned as (entities, their records); None
    when the formulas cannot be evaluated over their columns."""
    r = j.r
    firsts = (np.cumsum(lengths) - lengths).astype(np.int64)
    idx = np.arange(int(lengths.sum()), dtype=np.int64) - np.repeat(firsts - i0s, lengths)
    columns = {k: col[idx] for k, col in j.plain.items()}
    columns.update(j._own_columns(ents.tolist(), i0s, firsts, lengths, idx))
    got = batch_verdicts(r, trig, columns, firsts, lengths)
    try:
        rob = robustness_columns(r.formalization.pt, columns, firsts, lengths)
    except (VectorizeError, KeyError):
        rob = None
    if got is None or rob is None:
        return None
    holds, vacuous, ltl3 = got
    margin, values, ticks = rob
    fast = np.ones(len(ents), np.bool_)
    fast[list(nan_traces(columns, firsts, lengths))] = False
    holds = np.asarray(holds, np.bool_)
    for e in np.flatnonzero(fast & ~holds).tolist():  # (violated: judged alone, with the
        i, a, m = int(ents[e]), int(firsts[e]), int(lengths[e])  # LTL3 verdict, ticks and
        j.ltl3s[i] = (*ltl3[e], m)  # robustness known)
        if robs:
            j.robs[i] = summary_of(margin[a:a + m], float(values[e]), int(ticks[e]),
                                   j.times[int(i0s[e]):int(i0s[e]) + m], MARGIN_POINTS)
    sel = np.flatnonzero(fast & holds & ~(values < 0))  # (a value that disagrees: alone)
    if not len(sel):
        return sel, sel
    counts = _counts(j, block, columns, firsts, lengths, sel)
    status = np.array([LTL3_STATUS.index(ltl3[e][0]) for e in sel.tolist()], np.int8)
    st_tick = np.array([-1 if ltl3[e][1] is None else ltl3[e][1] for e in sel.tolist()],
                       np.int64)
    vac = np.asarray(vacuous, np.bool_)[sel] & (counts[0] >= 0)  # (no interval evidence:
    # satisfied, as the judge alone says it)
    ms = lengths[sel]
    at = np.repeat(firsts[sel] - (np.cumsum(ms) - ms), ms) + np.arange(int(ms.sum()),
                                                                     dtype=np.int64)
    rows = block.add(entity=ents[sel], i0=i0s[sel], length=ms, vacuous=vac,
                     ltl3_status=status, ltl3_tick=st_tick, rob=values[sel],
                     rob_tick=ticks[sel], rob_log_time=_deciding(j, ents[sel],
                                                                 i0s[sel] + ticks[sel]),
                     intervals=counts[0], triggers=counts[1], margin=margin[at])
    return ents[sel], np.arange(rows.start, rows.stop, dtype=np.int64)


def _counts(j: Any, block: EntityBlock, columns: dict[str, np.ndarray], firsts: np.ndarray,
            lengths: np.ndarray, sel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The scope intervals and triggers of the traces ``sel`` (-1 each: the interval
    semantics does not take the requirement, a note in ``block.extra`` says why, as the
    judge alone notes it)."""
    req, f = j.r.requirement, j.r.formalization
    try:
        got = interval_counts(req, columns, firsts, lengths)
        if got is not None:
            return got[0][sel], got[1][sel]
        out = np.empty((2, len(sel)), np.int64)
        for k, e in enumerate(sel.tolist()):  # (a temporal function: one at a time)
            a, m = int(firsts[e]), int(lengths[e])
            ev = evaluate_requirement(req, {x: col[a:a + m] for x, col in columns.items()},
                                      m, f.ticks)
            out[0, k], out[1, k] = ev.intervals, ev.triggers
        return out[0], out[1]
    except EvidenceUnsupported as exc:
        note = f"interval evidence unavailable: {exc}"
        if note not in block.extra:
            block.extra = (*block.extra, note)
        return np.full(len(sel), -1, np.int64), np.full(len(sel), -1, np.int64)


def _deciding(j: Any, ents: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The log time (ns; -1: none) of the message that decided tick ``at[e]`` (of the
    clock) for entity ``ents[e]``: the newest held among the clock's topics, an entity read
    in its own messages (one-value keys, held on their own) its own message on the key's
    topic (:meth:`fretc.audit.entities.log._Judge._own_log_times`)."""
    c = j.c
    own = c.kind.stream or j.held
    key = base_topic(c.kind.topic)
    cols = [col[at] for t, col in j.log_times.items() if not (own and base_topic(t) == key)]
    out = np.max(np.stack(cols), axis=0) if cols else np.full(len(at), -1, np.int64)
    if own:
        times = j.times
        for e, (i, g) in enumerate(zip(ents.tolist(), at.tolist())):
            rec = j.records.get(i) or []
            k = int(np.searchsorted([x[0] for x in rec], times[g], side="right")) - 1
            if k >= 0:
                out[e] = max(int(out[e]), rec[k][2])
    return out
