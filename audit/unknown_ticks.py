"""A requirement's verdict over a clock with unknown ticks: ticks a gap of the log leaves
unknown (:mod:`fretc.audit.gaps`) and ticks at which a comparison reads NaN
(:mod:`fretc.monitors.nan`), judged over the whole log in three-valued semantics
(:mod:`fretc.monitors.judge3`; ../shared/DESIGN.md, "Damage is a gap: never evidence, never
the end").

Design notes: ARCHITECTURE.md, `audit/unknown_ticks.py`."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from fretc.logs.recorded_gaps import SILENT_CAUSES
from fretc.audit.damage import open_obligations, verdict_at_damage
from fretc.audit.columns import ClockPass
from fretc.monitors.interval import EvidenceUnsupported
from fretc.monitors.judge3 import judge_three as judged_three

if TYPE_CHECKING:
    from fretc.monitors.interval import Evidence
    from fretc.monitors.judge import Judgement
    from fretc.audit.verdict import Verdict
    from fretc.audit.model import RequirementPlan

__all__ = ["judge_three", "gap_ticks", "gap_words", "pt_decides_note", "unknown_reason",
           "outgrew_words", "COMPLETED_NOTE"]


def judge_three(r: RequirementPlan, res: ClockPass, v: Verdict, j: Judgement, nan_unknown: bool,
                unknown: np.ndarray) -> tuple[bool | None, Evidence | None, str, int | None]:
    """The verdict of ``r`` over ``res`` with unknown ticks ``unknown`` (bool array over its
    ticks: :func:`fretc.audit.finalize.unknown_of`; module docstring), from the judge's
    result ``j`` over the ticks as sampled (its interval evidence).

    Returns:
        ``(holds, evidence, status, status_tick)``: ``holds`` True (satisfied or vacuous),
        False (violated; ``evidence`` has only definite failed triggers), or None when the
        verdict (``unknown``) was set here; the three-valued LTL3 verdict and its tick.
    """
    assert r.requirement is not None and r.formalization is not None  # (judged: formalized)
    n = len(res.times)
    online = not r.offline and r.monitor_source is not None
    # (the definite evidence where the judge found the interval semantics' over the ticks)
    three = judged_three(r.requirement, r.formalization, res.columns, res.unknown, n,
                         nan_unknown=nan_unknown, stretch=gap_ticks(res),
                         monitor_source=r.monitor_source if online else None,
                         evidence=j.evidence is not None)
    holds, why = three.holds, three.why
    outgrew = outgrew_words(why)
    status, st_tick = three.ltl3
    v.unknown_ticks = int(unknown.sum())
    ev = three.evidence
    if ev is not None:
        v.intervals, v.triggers, v.violations = ev.intervals, ev.triggers, ev.violations
    if res.intact_end is not None:  # and a cut at the end: a definite LTL3 verdict decides
        holds = _at_cut(r, res, v, holds, ev, status, st_tick, n)
    elif holds is None:
        v.verdict = "unknown"
        v.unknown_reason = _why(res, unknown, n, outgrew, r.judged_variables)
    if holds is True and ev is not None and ev.triggers == 0:
        ev.vacuous = True
        if three.possible_trigger:
            v.notes.append("vacuous on the ticks read: a trigger may have fired in unknown "
                           "ticks, and the requirement holds whichever way")
    elif ev is not None:
        ev.vacuous = False
    if holds is False and ev is not None and ev.violation is None:
        v.notes.append(_COMPLETED if three.completed else pt_decides_note(three.reading[2]))
    return holds, ev, status, st_tick


def gap_ticks(res: ClockPass) -> np.ndarray | None:
    """The gap ticks of ``res`` (bool array over its ticks: each one tick or more, how many
    not known, docs/guide/ticks.md), or None without one."""
    n = len(res.times)
    at = [i for i in res.tick_gaps if i < n]
    if not at:
        return None
    out = np.zeros(n, np.bool_)
    out[at] = True
    return out


def outgrew_words(why: str) -> str:
    """The words an unknown reason adds when the completions were not all followed
    (``why``: :class:`fretc.monitors.completions.TooManyStates`' message; empty: none)."""
    return f" (not every way of filling them was followed: {why})" if why else ""


#: the note of a violation every completion makes, no single failed trigger shown
COMPLETED_NOTE = ("violated whatever the unknown ticks held: its pt formula is false at the "
                  "last tick in every way of filling them (each followed through the "
                  "formula's states; no single failed trigger lies wholly in ticks read)")
_COMPLETED = COMPLETED_NOTE


def pt_decides_note(last_hi: int | None) -> str:
    """Why a requirement is violated without a definite failed trigger to show, its pt
    formula false in every completion after tick ``last_hi`` (None: at every tick)."""
    d = last_hi + 1 if last_hi is not None else 0
    return (f"violated whatever the unknown ticks held: its pt formula is false from tick "
            f"{d} on in every way of filling them (no single failed trigger lies wholly in "
            "ticks read)")


def _cause(g) -> str:
    """A gap's cause in the reason of an unknown verdict: a silence (a publisher away,
    :data:`fretc.logs.recorded_gaps.SILENT_CAUSES`) says whose publisher left."""
    if g.cause in SILENT_CAUSES and g.topics:
        return f"the publisher of {', '.join(sorted(g.topics))} left ({g.cause})"
    return g.cause or "gap"


def _why(res: ClockPass, unknown: np.ndarray, n: int, outgrew: str = "",
         variables: tuple[str, ...] | list[str] = ()) -> str:
    """The unknown verdict's reason: its unknown ticks and the gaps behind them (and
    ``outgrew``: why the ways of filling them were not all followed). With no gap, what
    the unknown ticks read: the ``variables`` (the requirement's) whose values the log
    marks unknown (a CSV trace's ``unknown`` cells and ``gap`` rows: ``unknown values of
    x``), and comparisons that read NaN at the other unknown ticks."""
    k = int(unknown.sum())
    first = int(np.argmax(unknown)) if k else 0
    causes = sorted({_cause(g) for g in res.gaps})
    if not causes:
        marked = [name for name in variables
                  if (m := res.unknown.get(name)) is not None and m[:n].any()]
        rest = unknown.copy()
        for name in marked:
            rest &= ~res.unknown[name][:n]
        causes = ([f"unknown values of {', '.join(marked)}"] if marked else []) + \
            (["comparisons with NaN"] if rest.any() or not marked else [])
    what = ", ".join(causes)
    if res.lost_words:
        what += f": {res.lost_words}"
    what += gap_words(sum(1 for i in res.tick_gaps if i < n))
    return unknown_reason(k, n, what, first, int(res.times[first]), outgrew)


def gap_words(stretched: int) -> str:
    """The words an unknown reason adds for its ``stretched`` gap ticks (empty: none)."""
    if not stretched:
        return ""
    return (f"; {stretched} of them " + ("a gap tick" if stretched == 1 else
                                          "gap ticks, each") + " standing for one tick or more")


def unknown_reason(k: int, n: int, what: str, first: int, first_time: int,
                   outgrew: str = "") -> str:
    """The reason of a verdict left unknown by ``k`` of its ``n`` ticks (``what`` makes
    them unknown; the first at tick ``first``, ``first_time`` ns; ``outgrew``: why not
    every way of filling them was followed, with its leading space, or empty)."""
    depends = "may depend" if outgrew else "depends"
    return (f"{k} of its {n} ticks are unknown ({what}; the first at tick {first}, "
            f"{first_time} ns), and the verdict {depends} on them{outgrew}: no "
            "violation in the ticks read, but one could lie in the ticks not read")


def _at_cut(r, res: ClockPass, v, holds, ev, status, st_tick, n: int) -> bool | None:
    """The verdict on a log cut at the end, with unknown ticks before the cut
    (:func:`fretc.audit.damage.verdict_at_damage` with the three-valued inputs)."""
    opened = []
    try:
        opened = open_obligations(r.requirement, res.columns, n, r.formalization.ticks)
    except (EvidenceUnsupported, KeyError) as exc:
        if holds:
            v.verdict = "unknown"
            v.unknown_reason = (f"the log is damaged and whether an obligation is open at "
                                f"the damage cannot be decided ({exc})")
            return None
    verdict, why = verdict_at_damage(holds is True, bool(ev is not None and ev.triggers == 0),
                                     status, st_tick, n, ev, opened,
                                     has_ltl3=not r.offline)
    if verdict == "unknown":
        v.verdict = "unknown"
        v.unknown_reason = why
        return None
    return verdict != "violated"
