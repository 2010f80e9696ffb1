"""A requirement's verdict over a clock with unknown ticks: ticks a gap of the log leaves
unknown (:mod:`fretc.audit.gaps`) and ticks at which a comparison reads NaN
(:mod:`fretc.monitors.nan`), judged over the whole log in three-valued semantics
(:mod:`fretc.monitors.judge3`; ../shared/DESIGN.md, "Damage is a gap: never evidence, never
the end").

* A violation in the ticks read is **violated** (exit 1); a verdict an unknown tick could
  change is **unknown**, naming the gaps (and NaN ticks) that make it so; one that every way
  of filling them agrees on is satisfied or vacuous.
* A cut at the end of the log (nothing read after it) is judged as before
  (:mod:`fretc.audit.damage`): only a definite LTL3 verdict decides, now over every letter an
  unknown tick may be.
* The three-valued judge needs the requirement's pt formula over columns. Requirements
  without it (a future-time function, FRET leaves those unexpanded in pt) and, on a clock
  that ticks on a topic's messages, requirements that count ticks (a duration, a bounded
  operator) across a gap of that topic (how many ticks it lost is not known) are judged
  as on a cut log instead: up to their first unknown tick.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fretc.audit.damage import open_obligations, verdict_at_damage
from fretc.audit.passes import ClockPass
from fretc.common.problems import NAN
from fretc.compiler.ir import walk
from fretc.monitors.interval import EvidenceUnsupported
from fretc.monitors.judge import nan_ticks
from fretc.monitors.judge3 import Unknowns, definite_evidence, possible_trigger
from fretc.monitors.three_valued import ThreeValued, ltl3_verdict
from fretc.monitors.vectorized import VectorizeError, supports

__all__ = ["prepare", "judge_three", "unknown_of"]


def _nan_unknown(bindings) -> bool:
    return bindings is None or bindings.tick.nan != "false"


def unknown_of(r, res: ClockPass, nan_unknown: bool) -> np.ndarray:
    """The ticks of ``res`` at which ``r`` reads something unknown: a gap leaves one of its
    variables unknown, or (``nan_unknown``) one of its comparisons reads NaN."""
    n = len(res.times)
    out = np.zeros(n, np.bool_)
    for name in r.variables:
        m = res.unknown.get(name)
        if m is not None:
            out |= m[:n]
    if nan_unknown and n:
        try:
            out |= nan_ticks(r.requirement, res.columns, n)
        except (EvidenceUnsupported, KeyError, ValueError):
            pass
    return out


def _three_valued_takes(r, res: ClockPass) -> str | None:
    """None when the three-valued judge can take ``r`` on ``res``, else why not."""
    f = r.formalization
    if not f.pt_causal or not supports(f.pt):
        return "its pt formula has a future-time function"
    if res.tick_gaps and (r.requirement.timing.kind in ("within", "for", "after")
                          or any(getattr(x, "hi", None) is not None for x in walk(f.pt))):
        return ("it counts ticks on a clock that ticks on a topic's messages, and a gap of "
                "that topic lost an unknown number of them")
    return None


def prepare(r, res: ClockPass, bindings, v, la) -> tuple[ClockPass, bool]:
    """Before judging ``r``: its NaN ticks reported as a ``nan`` data problem of ``la`` (or
    the binding file's IEEE 754 policy noted); a requirement the three-valued judge cannot
    take is cut at its first unknown tick (judged as on a cut log, a note says why).

    Returns:
        ``(res, nan_unknown)``: the clock's pass to judge, and whether a comparison with NaN
        is unknown (fretc's NaN rule) rather than IEEE 754's false.
    """
    nan_unknown = _nan_unknown(bindings)
    n = len(res.times)
    if not nan_unknown:
        v.notes.append("NaN policy of the binding file ([tick] nan = \"false\"): a "
                       "comparison with NaN is false")
    elif n:
        _nan_problem(r, res, la)
    unknown = unknown_of(r, res, nan_unknown)
    why = _three_valued_takes(r, res) if unknown.any() else None
    if why is None:
        return res, nan_unknown
    first = int(np.argmax(unknown))
    t = int(res.times[first])
    v.notes.append(f"judged up to its first unknown tick ({first}, {t} ns): {why}")
    cut = replace(res, times=res.times[:first],
                  columns={k: c[:first] for k, c in res.columns.items()},
                  log_times={k: c[:first] for k, c in res.log_times.items()},
                  unknown={}, tick_gaps=[],
                  intact_end=t if res.intact_end is None else min(t, res.intact_end),
                  lost="; ".join(x for x in (res.lost, f"tick {first} is unknown ({why})")
                                 if x))
    return cut, nan_unknown


def _nan_problem(r, res: ClockPass, la) -> None:
    """A ``nan`` data problem in ``la`` for the ticks at which ``r`` compares NaN."""
    n = len(res.times)
    try:
        bad = np.flatnonzero(nan_ticks(r.requirement, res.columns, n))
    except (EvidenceUnsupported, KeyError, ValueError):
        return
    if len(bad) == 0:
        return
    first, t = int(bad[0]), int(res.times[bad[0]])
    what = (f"{len(bad)} tick{'s' if len(bad) != 1 else ''} of {r.id} compare NaN (first "
            f"at tick {first}, {t} ns; last at tick {int(bad[-1])}, "
            f"{int(res.times[bad[-1]])} ns): a comparison with NaN is neither true nor "
            "false, so those ticks are unknown")
    la.problems.append({"kind": NAN, "topic": None, "log_time_ns": t,
                        "end_time_ns": int(res.times[bad[-1]]), "detail": what})
    la.problem_counts[f"{NAN} {r.id}"] = len(bad)


def judge_three(r, res: ClockPass, v, j, nan_unknown: bool):
    """The verdict of ``r`` over ``res`` with unknown ticks (module docstring), from the
    judge's result ``j`` over the ticks as sampled (its interval evidence).

    Returns:
        ``(holds, evidence, status, status_tick)``: ``holds`` True (satisfied or vacuous),
        False (violated; ``evidence`` has only definite failed triggers), or None when the
        verdict (``unknown``) was set here; the three-valued LTL3 verdict and its tick.
    """
    n = len(res.times)
    ev3 = ThreeValued(res.columns, res.unknown, n, nan_unknown)
    lo, hi = ev3.pair(r.formalization.pt)
    holds = True if lo[-1] else (False if not hi[-1] else None)
    status, st_tick = "unknown", None
    if not r.offline and r.monitor_source is not None:
        try:
            status, st_tick = ltl3_verdict(r.monitor_source, ev3)
        except VectorizeError:
            status, st_tick = "unknown", None
    unknown = unknown_of(r, res, nan_unknown)
    v.unknown_ticks = int(unknown.sum())
    ev = j.evidence
    parts = None
    if ev is not None:
        parts = Unknowns.of(r.requirement, res.unknown, res.columns, n, nan_unknown)
        ev = definite_evidence(r.requirement, ev, parts, res.columns)
        v.intervals, v.triggers, v.violations = ev.intervals, ev.triggers, ev.violations
    if res.intact_end is not None:  # and a cut at the end: a definite LTL3 verdict decides
        holds = _at_cut(r, res, v, holds, ev, status, st_tick, n)
    elif holds is None:
        v.verdict = "unknown"
        v.unknown_reason = _why(res, unknown, n)
    if holds is True and ev is not None and ev.triggers == 0:
        ev.vacuous = True
        if parts is not None and possible_trigger(parts):
            v.notes.append("vacuous on the ticks read: a trigger may have fired in unknown "
                           "ticks, and the requirement holds whichever way")
    elif ev is not None:
        ev.vacuous = False
    if holds is False and ev is not None and ev.violation is None:
        v.notes.append(_pt_decides(hi))
    return holds, ev, status, st_tick


def _pt_decides(hi: np.ndarray) -> str:
    """Why a requirement is violated without a definite failed trigger to show."""
    still = np.flatnonzero(hi)
    d = int(still[-1]) + 1 if len(still) else 0
    return (f"violated whatever the unknown ticks held: its pt formula is false from tick "
            f"{d} on in every way of filling them (no single failed trigger lies wholly in "
            "ticks read)")


def _why(res: ClockPass, unknown: np.ndarray, n: int) -> str:
    """The unknown verdict's reason: its unknown ticks and the gaps behind them."""
    k = int(unknown.sum())
    first = int(np.argmax(unknown)) if k else 0
    causes = sorted({g.cause or "gap" for g in res.gaps})
    what = ", ".join(causes) if causes else "comparisons with NaN"
    if res.lost_words:
        what += f": {res.lost_words}"
    return (f"{k} of its {n} ticks are unknown ({what}; the first at tick {first}, "
            f"{int(res.times[first])} ns), and the verdict depends on them: no violation "
            "in the ticks read, but one could lie in the ticks not read")


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
