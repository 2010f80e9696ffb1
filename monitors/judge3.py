"""The offline judge over a trace with unknown ticks (a gap in the log, a comparison with
NaN): the verdict every way of filling them agrees on, and evidence that lies in the ticks
read (../shared/DESIGN.md, "Damage is a gap: never evidence, never the end").

* **The verdict** is FRET's finite-trace verdict three-valued (:func:`fretc.monitors.
  completions.pt_verdict`): violated when every completion of the unknown ticks violates
  the requirement, satisfied when every one satisfies it, unknown otherwise. An invariant
  broken at a tick read is violated, whatever a gap elsewhere held; one that held on every
  tick read but has unknown ticks is unknown.
* **The evidence** of a violation is FRET's interval semantics
  (:func:`fretc.monitors.interval.evaluate_requirement`) over the ticks as sampled, keeping
  only the failed triggers that are *definite*: their scope interval's bounds, the trigger
  and the response (and stop condition) from the trigger to the tick the obligation was
  missed are all known. Where none is, the evidence is the tick from which the pt formula is
  false in every completion.
* **Triggers** counted are the definite ones (the trigger and the part of its scope
  interval up to it known: the interval's end does not make a trigger); a requirement that holds in every completion
  with no definite trigger is vacuous (a note says when a trigger may have fired in unknown
  ticks).

Where the parts of a requirement are unknown is :mod:`fretc.monitors.unknowns`'s.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from fretc.compiler.ir import Node
from fretc.fretish import ast as A
from fretc.monitors.interval import Evidence, Violation, every_trigger
from fretc.monitors.unknowns import Unknowns

__all__ = ["definite_evidence", "verdict_under_nan", "nan_rule_judge"]


def nan_rule_judge(compiled: Any) -> Callable[..., str]:
    """A :data:`fretc.check.witness.Judge` (``judge(requirement, columns, n,
    duration_ticks)``) giving :func:`verdict_under_nan` for the requirements of
    ``compiled`` (:class:`fretc.compiler.build.Compiled`, their pt formulas found by the
    requirement), the interval verdict for another: the expected verdicts ``fretc check``
    writes in its witnesses are the audit's, a comparison reading NaN included."""
    pts = {}
    for c in compiled:
        f = getattr(c, "formalization", None)
        if f is not None and c.requirement is not None:
            pts[c.requirement] = f.pt

    def judge(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
              duration_ticks: int | None) -> str:
        return verdict_under_nan(req, pts.get(req), columns, n, duration_ticks)

    return judge


def verdict_under_nan(req: A.Requirement, pt: Node | None, columns: Mapping[str, np.ndarray],
                      n: int, duration_ticks: int | None) -> str:
    """The audit's verdict of ``req`` on a finite trace of ``n`` ticks (``columns``: FRET
    variable -> array of ``n`` values; ``pt`` its pt formula, ``duration_ticks`` as
    ``Formalization.ticks``) under fretc's NaN rule: a comparison that reads NaN is unknown
    at its tick (:func:`fretc.monitors.judge.nan_ticks`), and the verdict is the one every
    completion of those ticks agrees on (module docstring), else ``"unknown"``; with no
    NaN tick, FRET's interval verdict (:func:`fretc.monitors.interval.verdict_of`).
    ``"unknown"`` too when the interval semantics cannot evaluate ``req``, or it reads NaN
    and has no pt formula or one past the completions' bounds. What ``fretc testgen``
    writes as a test's expected verdict, so that it is the audit's."""
    from fretc.monitors.completions import decide
    from fretc.monitors.interval import EvidenceUnsupported, evaluate_requirement, verdict_of
    from fretc.monitors.judge import nan_ticks
    from fretc.monitors.three_valued import ThreeValued
    from fretc.monitors.vectorized import VectorizeError

    if not nan_ticks(req, columns, n).any():
        return verdict_of(req, columns, n, duration_ticks)
    if pt is None:
        return "unknown"
    try:
        holds, _pair, _why = decide(pt, ThreeValued(columns, {}, n, True))
        if holds is not True:
            return "violated" if holds is False else "unknown"
        parts = Unknowns.of(req, {}, columns, n, True)
        ev = evaluate_requirement(req, columns, n, duration_ticks, favour=parts)
    except (EvidenceUnsupported, VectorizeError):
        return "unknown"
    return "vacuous" if definite_evidence(req, ev, parts, columns).triggers == 0 \
        else "satisfied"


def definite_evidence(req: A.Requirement, ev: Evidence, u: Unknowns,
                      columns: Mapping[str, np.ndarray]) -> Evidence:
    """``ev`` (the interval semantics over the ticks as sampled) with only the definite
    failed triggers listed and counted, and the definite triggers counted (module
    docstring). Its ``holds`` and ``vacuous`` are left to the caller (the three-valued
    verdict decides them)."""
    scope, cond = req.scope.kind, req.condition.kind
    negate = scope.startswith("only")
    listed: list[Violation] = []
    for w in ev.listed:
        s, e = w.interval
        if (u.scope_known(s, e, scope) and u.trigger_known(w.trigger_tick, s, cond)
                and u.missed_known(w.trigger_tick, w.window[0], w.violation_tick,
                                   req.timing.kind, negate)):
            listed.append(w)
    triggers = 0
    first_trigger = None
    got = every_trigger(req, columns, u.n, 0)
    for (s, _e), points in zip(got.intervals, got.triggers):
        for t in points:
            if u.in_scope_known(t, s, scope) and u.trigger_known(t, s, cond):
                triggers += 1
                first_trigger = t if first_trigger is None else first_trigger
    return Evidence(holds=ev.holds, vacuous=ev.vacuous, intervals=ev.intervals,
                    triggers=triggers, violations=len(listed),
                    violation=listed[0] if listed else None, ticks=ev.ticks,
                    first_interval=ev.first_interval, first_trigger=first_trigger,
                    listed=listed)
