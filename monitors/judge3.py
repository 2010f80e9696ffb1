"""The offline judge over a whole trace with unknown ticks (a gap in the log, a comparison with
NaN, a gap tick standing for one tick or more): the verdict every way of filling them agrees
on, and evidence that lies in the ticks read (../shared/DESIGN.md, "Damage is a gap: never
evidence, never the end"), from the three-valued streams each fed the trace as one chunk
(:func:`judge_three`).

Design notes: ARCHITECTURE.md, `monitors/judge3.py`."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from fretc.compiler.ir import Node
from fretc.fretish import ast as A
from fretc.monitors.completions import Reading, decide
from fretc.monitors.definite import definite_evidence
from fretc.monitors.interval import Evidence, EvidenceUnsupported, verdict_of
from fretc.monitors.judge import nan_ticks
from fretc.monitors.three_valued import ltl3_verdict
from fretc.monitors.vectorized import VectorizeError

if TYPE_CHECKING:
    from fretc.compiler.codegen import MonitorSource
    from fretc.compiler.semantics import Formalization

__all__ = ["ThreeJudgement", "judge_three", "verdict_under_nan", "nan_rule_judge"]


@dataclass
class ThreeJudgement:
    """What :func:`judge_three` decided about one requirement over a trace with unknown
    ticks.

    Attributes:
        holds: True (every completion satisfies it), False (every one violates it), None
            (they differ, or the search outgrew its bounds: ``why``).
        reading: Kleene's reading of the pt formula at the last tick
            (:data:`fretc.monitors.completions.Reading`); ``completed``: the verdict was
            decided by following every completion (Kleene's reading left it open).
        ltl3: the three-valued LTL3 verdict and its tick.
        evidence: the definite evidence (None where the interval semantics cannot take the
            requirement); ``possible_trigger``: a trigger may have fired in unknown ticks.
    """

    holds: bool | None
    reading: Reading
    why: str
    ltl3: tuple[str, int | None]
    evidence: Evidence | None
    possible_trigger: bool

    @property
    def completed(self) -> bool:
        """The verdict was decided by following every completion."""
        return self.holds is not None and not self.reading[0] and self.reading[1]


def judge_three(requirement: A.Requirement, formalization: Formalization,
                columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray], n: int,
                *, nan_unknown: bool = True, stretch: np.ndarray | None = None,
                monitor_source: MonitorSource | None = None, evidence: bool = True
                ) -> ThreeJudgement:
    """Judge ``requirement`` over a whole trace of ``n >= 1`` ticks whose variables are
    unknown at ``unknown`` (variable -> bool array of ``n``) and whose gap ticks are
    ``stretch`` (module docstring); ``monitor_source``: its LTL3 automata (None: no online
    monitor, LTL3 ``"unknown"``); ``evidence``: make the definite evidence.

    Raises:
        VectorizeError: the pt formula cannot be evaluated over the columns.
    """
    holds, reading, why = decide(formalization.pt, columns, unknown, n, nan_unknown, stretch)
    ltl3: tuple[str, int | None] = ("unknown", None)
    if monitor_source is not None:
        try:
            ltl3 = ltl3_verdict(monitor_source, columns, unknown, n, nan_unknown, stretch)
        except VectorizeError:
            pass
    ev, possible = None, False
    if evidence:
        ev, possible = definite_evidence(requirement, columns, unknown, n,
                                         formalization.ticks, nan_unknown, stretch)
    return ThreeJudgement(holds, reading, why, ltl3, ev, possible)


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
    if not nan_ticks(req, columns, n).any():
        return verdict_of(req, columns, n, duration_ticks)
    if pt is None:
        return "unknown"
    try:
        holds, _reading, _why = decide(pt, columns, {}, n)
        if holds is not True:
            return "violated" if holds is False else "unknown"
        ev, _possible = definite_evidence(req, columns, {}, n, duration_ticks)
    except (EvidenceUnsupported, VectorizeError):
        return "unknown"
    return "vacuous" if ev.triggers == 0 else "satisfied"
