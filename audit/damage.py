"""Verdicts on a damaged log: what the span read completely decides, and nothing more.

../shared/DESIGN.md, "Damage is never evidence": only the span of a log that was read completely
is judged (the ticks strictly before :attr:`fretc.logs.LogSource.intact_end`); an
obligation still open where that span ends (a cut, or the first gap) is *unknown*, not
violated; a violation decided entirely before the damage stands.

Design notes: ARCHITECTURE.md, `audit/damage.py`."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fretc.fretish import ast as A

from fretc.monitors.interval import Evidence, EvidenceUnsupported, IntervalStream
from fretc.monitors.obligations import OpenObligation

__all__ = ["OpenObligation", "open_obligations", "verdict_at_damage"]


def open_obligations(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                     duration_ticks: int | None = None, limit: int = 1
                     ) -> list[OpenObligation]:
    """Triggers of ``req`` whose obligation is neither met nor missed at the end of a trace
    of ``n`` ticks that a damage cut short: an :class:`IntervalStream` fed the trace as one
    chunk, its triggers still waiting at the end
    (:meth:`fretc.monitors.interval.IntervalStream.open_at_end`).

    Args:
        req: a parsed, not free-form requirement.
        columns: FRET variable -> 1-D array of ``n`` values.
        n: ticks of the intact span (>= 1).
        duration_ticks: the timing's duration in ticks (``Formalization.ticks``).
        limit: stop after this many.

    Returns:
        Up to ``limit`` :class:`OpenObligation`, earliest trigger first.

    Raises:
        EvidenceUnsupported: as :func:`fretc.monitors.interval.evaluate_requirement`.
    """
    if req.freeform or req.response is None:
        raise EvidenceUnsupported("a free-form requirement has no semantics")
    if n < 1:
        return []
    s = IntervalStream(req, duration_ticks, limit=max(limit, 1))
    s.feed(columns, n, np.arange(n, dtype=np.int64))
    s.finish()
    return s.open_at_end(limit)


def verdict_at_damage(holds: bool, vacuous: bool, status: str | None,
                      status_tick: int | None, n: int, evidence: Evidence | None,
                      opened: list[OpenObligation], has_ltl3: bool
                      ) -> tuple[str, str | None]:
    """The verdict of a requirement over the intact span of a damaged log (module
    docstring).

    Args:
        holds: FRET's finite-trace verdict over the ``n`` intact ticks.
        vacuous: it holds because no scope interval or trigger occurred.
        status, status_tick: the earliest definitive LTL3 verdict over the intact ticks
            (``"violated"``, ``"satisfied"``, ``"unknown"``) and its tick.
        evidence: the interval semantics over the intact ticks (None if unavailable).
        opened: :func:`open_obligations` over the intact ticks.
        has_ltl3: the requirement has an online monitor (``status`` is meaningful).

    Returns:
        ``(verdict, why)``: verdict one of ``satisfied``, ``vacuous``, ``violated``,
        ``unknown``; ``why`` a sentence for ``unknown`` (else None).
    """
    if has_ltl3:
        if status == "violated" and status_tick is not None and status_tick < n:
            return "violated", None
        if status == "satisfied":
            return ("vacuous" if vacuous else "satisfied"), None
    elif not holds and evidence is not None:
        decided = [w for w in evidence.listed if w.interval[1] < n - 1]
        if decided:
            return "violated", None
    if not holds:
        where = ""
        if evidence is not None and evidence.violation is not None:
            where = (f" (trigger at tick {evidence.violation.trigger_tick}: "
                     f"{evidence.violation.reason})")
        return "unknown", ("the intact span ends at the damage with an obligation still "
                           "open" + where + "; a violation only because the log was cut short "
                           "is not evidence")
    if opened:
        o = opened[0]
        return "unknown", (f"an obligation is open at the damage: trigger at tick "
                           f"{o.trigger_tick}, {o.what}")
    if not has_ltl3:
        return "unknown", ("the intact span " + ("never fires the requirement"
                                                 if vacuous else "satisfies it")
                           + ", but it has no LTL3 verdict (no online monitor) to tell "
                           "whether the rest of the run could still violate it")
    return "unknown", ("the intact span " + ("never fires the requirement" if vacuous
                                             else "satisfies it")
                       + " so far, but its LTL3 verdict at the damage is not definite: the "
                       "part of the run after the damage could still violate it")
