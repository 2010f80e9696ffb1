"""Finalization: one requirement's verdict and evidence from the pass over its clock
(:func:`finalize`).

The verdict, the LTL3 verdict and the evidence come from one judge,
:func:`fretc.monitors.judge.judge`, over the columns of the requirement's clock: FRET's
interval semantics gives the finite-trace verdict, the vacuity, the first violated trigger,
its scope interval and response window; the monitor automata give the earliest definite
(LTL3) verdict. The values of the requirement's variables and the log times of the messages
behind them are taken around the trigger and the violation. On a damaged log the verdict is
the one the intact span decides (:mod:`fretc.audit.damage`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from fretc.signals.bindings import Bindings
from fretc.signals.clock import unsampled_of
from fretc.audit.damage import OpenObligation, open_obligations, verdict_at_damage
from fretc.monitors.interval import OBLIGATIONS, Evidence, EvidenceUnsupported
from fretc.monitors.judge import judge, nan_ticks
from fretc.monitors.unknowns import Unknowns
from fretc.monitors.stepwise import to_python
from fretc.audit.verdict import MARGIN_POINTS, FirstViolation, Ltl3, TimePoint
from fretc.audit.model import AuditPlan, RequirementPlan
from fretc.audit.columns import ClockPass
from fretc.audit.passes import clock_key
from fretc.audit.trials import trigger_trials
from fretc.audit.unknown_ticks import gap_ticks, judge_three
from fretc.audit.streams import with_streams
from fretc.common.problems import NAN
from fretc.monitors.vectorized import supports
from fretc.monitors.robustness import TINY

if TYPE_CHECKING:
    from fretc.signals.clock import Sampling
    from fretc.audit.verdict import LogAudit, Verdict

__all__ = ["finalize", "between_ticks", "prepare", "unknown_of", "NAN_FALSE_NOTE",
           "vacuous_note", "judged", "decided", "shown_ticks", "StreamTicks"]

#: The note of every verdict judged under a binding file's ``[tick] nan = "false"``.
NAN_FALSE_NOTE = ("NaN policy of the binding file ([tick] nan = \"false\"): a comparison "
                  "with NaN is false")


def vacuous_note(intervals: int) -> str:
    """The note of a vacuous verdict whose interval semantics found ``intervals`` scope
    intervals (none: the scope was never entered; else no trigger fired)."""
    return "vacuous: " + ("the scope was never entered" if intervals == 0
                          else "the trigger never fired")


def between_ticks(v: Verdict, s: Sampling, r: RequirementPlan, bindings: Bindings | None) -> None:
    """Set ``v.unsampled_messages`` and ``v.missed_changes`` from requirement ``r``'s clock
    ``s`` (:class:`fretc.signals.clock.Sampling`), with a note per variable that could miss events
    between ticks (never silently)."""
    v.unsampled_messages = unsampled_of(s, r.variables, bindings)
    v.missed_changes = {n: s.missed_changes[n] for n in r.variables
                        if s.missed_changes.get(n)}
    for n, k in v.missed_changes.items():
        b = bindings.variables[n] if bindings is not None else None
        topic = ", ".join(sorted(b.topics)) if b is not None else "its topic"
        v.notes.append(f"{n}: {k} message{'s' if k != 1 else ''} of {topic} that no tick "
                       f"sampled would have changed its value (events between ticks); "
                       f"bind it as any_of_messages({b.expr if b else '...'}) to see them")


def finalize(plan: AuditPlan, r: RequirementPlan, res: ClockPass, bindings: Bindings | None,
             v: Verdict, la: LogAudit, rob: Any = None,
             ltl3: tuple[str, int | None, int] | None = None) -> None:
    """Set the verdict ``v`` (:class:`fretc.audit.verdict.Verdict`) of requirement ``r``
    from its clock's pass ``res``: engine, LTL3 verdict, interval counts, and for a
    violation the first violation with the values and message log times around it. Ticks
    a gap or a NaN leaves unknown are judged in three-valued semantics
    (:mod:`fretc.audit.unknown_ticks`); the stream variables it reads are computed first
    (:func:`fretc.audit.streams.with_streams`). ``la`` is the log's
    :class:`fretc.audit.verdict.LogAudit`. A requirement with a probability bound also gets
    its triggers as trials (:mod:`fretc.audit.trials`). ``rob``: the pt formula's robustness
    over the pass's ticks when computed already (:func:`fretc.monitors.judge.judge`);
    ``ltl3``: its LTL3 verdict and tick over the pass's ticks, and how many ticks that was,
    when computed already (:func:`fretc.monitors.judge.ltl3_verdicts`)."""
    if r.streams is not None:  # (the columns of the stream variables it reads)
        res = with_streams(r, res, _nan_unknown(bindings))
    res, nan_unknown = prepare(r, res, bindings, v, la)
    n = len(res.times)
    if n == 0:
        _no_tick(res, v, la, _windows_of(r, bindings))
        return
    if rob is not None and rob.n != n:  # (computed over other ticks: not these)
        rob = None
    known = ltl3[:2] if ltl3 is not None and ltl3[2] == n else None
    _verdict(plan, r, res, bindings, v, nan_unknown, rob, known)
    if plan.coverage:
        from fretc.audit.coverage import record_coverage  # lazy: only with --coverage

        record_coverage(r, res, v, unknown_of(r, res, nan_unknown))
    if getattr(r.compiled, "probability", None) is not None and v.error is None:
        _trials(r, res, v, nan_unknown)


def _trials(r, res: ClockPass, v, nan_unknown: bool) -> None:
    """``v.trials`` of a probability requirement (:func:`fretc.audit.trials.trigger_trials`),
    with a note when a trigger may have fired in unknown ticks; a note when the interval
    semantics cannot count them (an uninterpreted function)."""
    n = len(res.times)
    unknown = unknown_of(r, res, nan_unknown)
    parts = (Unknowns.of(r.requirement, res.unknown, res.columns, n, nan_unknown,
                         gap_ticks(res))
             if unknown.any() else None)
    try:
        v.trials = trigger_trials(r.requirement, res.columns, n, r.formalization.ticks,
                                  parts, damaged=res.intact_end is not None)
    except (EvidenceUnsupported, KeyError) as exc:
        v.notes.append(f"its triggers cannot be counted as trials ({exc}): the fleet "
                       "statistics count this run as unknown")
        return
    t = v.trials
    if t.hidden:
        v.notes.append("a trigger may have fired in unknown ticks: not seen, not counted as "
                       "a trial")
    if t.cut or t.unknown:
        v.notes.append(f"triggers that are no trials: {t.cut} cut by the end of the log "
                       f"inside their timing window, {t.unknown} with an outcome unknown "
                       "ticks or the damage hide")


def _verdict(plan: AuditPlan, r: RequirementPlan, res: ClockPass, bindings: Bindings | None,
             v, nan_unknown: bool, rob: Any = None,
             ltl3: tuple[str, int | None] | None = None) -> None:
    """The verdict of :func:`finalize` over the prepared pass ``res`` (at least one tick)."""
    n = len(res.times)
    f = r.formalization
    assert r.requirement is not None and f is not None  # (judged: formalized)
    online = not r.offline
    try:
        j = judge(r.requirement, f, res.columns, n,
                  monitor_source=r.monitor_source if online else None,
                  monitor_cls=r.monitor_cls if online else None, rob=rob, ltl3=ltl3,
                  times=res.times, points=MARGIN_POINTS)
    except EvidenceUnsupported as exc:
        v.error = f"no online monitor and no interval semantics for it: {exc}"
        return
    v.engine = j.engine
    if j.note is not None:
        v.notes.append(j.note)
    holds: bool | None
    ev, holds, status, st_tick = j.evidence, j.holds, j.ltl3, j.ltl3_tick
    if ev is not None:
        v.intervals, v.triggers, v.violations = ev.intervals, ev.triggers, ev.violations
    unknown = unknown_of(r, res, nan_unknown)
    three = bool(unknown.any())
    if three:
        holds, ev, status, st_tick = judge_three(r, res, v, j, nan_unknown, unknown)
    v.ltl3 = Ltl3(status, st_tick, int(res.times[st_tick]) if st_tick is not None else None)
    if three:
        if holds is None:
            return
        v.notes.append(f"robustness unavailable: {v.unknown_ticks} of its ticks are unknown")
    else:
        assert holds is not None  # (the two-valued judge decides)
        if res.intact_end is not None:
            holds = _judge_at_damage(r, res, v, holds, ev, status, st_tick, n)
            if holds is None:
                return
        _robustness(r, res, bindings, v, j.robustness, holds)
    decided(plan, r, v, holds, ev, status, st_tick, n, lambda: _own_ticks(r, res, bindings))
    if v.verdict == "violated":
        _values_around(plan.config.window, r, res, bindings, v)


def judged(plan: AuditPlan, r: RequirementPlan, v: Verdict, ticks: StreamTicks,
           ev: Evidence, ltl3: tuple[str, int | None, int | None],
           rob: tuple[float, int, int, list[tuple[int, int, float]]],
           held: int | None | str = "row", at_cut: bool = False,
           opened: list[OpenObligation] | None = None) -> None:
    """Set the verdict ``v`` of ``r`` as :func:`finalize` sets it on a trace without
    unknown ticks or damage, from what was decided over its ``ticks.n`` ticks without
    their columns (:mod:`fretc.audit.streamed`): the interval semantics' evidence ``ev``,
    the LTL3 verdict ``(status, tick, time)`` and the robustness ``(value, tick, time of
    that tick, margin points (tick, time, value))``. The values around a violation
    (``v.values``, ``v.sources``) are the caller's: at :func:`shown_ticks`. ``held``: the
    log time (ns) of the message held at the robustness's tick (None: none); ``"row"``, a
    CSV trace's: the tick's own time when not negative. ``at_cut``: the trace ends at a
    cut, the verdict the one its ticks decide (:func:`fretc.audit.damage.verdict_at_damage`;
    ``opened`` the obligations open at the cut)."""
    v.engine = "interval"
    v.intervals, v.triggers, v.violations = ev.intervals, ev.triggers, ev.violations
    status, tick, time = ltl3
    v.ltl3 = Ltl3(status, tick, time)
    holds = ev.holds
    if at_cut:
        word, why = verdict_at_damage(holds, ev.vacuous, status, tick, ticks.n, ev,
                                      opened or [], has_ltl3=not r.offline)
        if word == "unknown":
            v.verdict, v.unknown_reason = "unknown", why
            return
        holds = word != "violated"
    value, at, at_time, points = rob
    shown = (at_time if at_time >= 0 else None) if held == "row" else held
    assert not isinstance(shown, str)  # (a CSV row's, or a held log time)
    _robustness_fields(v, holds, value, TimePoint(at, at_time, shown), points)
    decided(plan, r, v, holds, ev, status, tick, ticks.n, lambda: ticks)


def decided(plan: AuditPlan, r: RequirementPlan, v: Verdict, holds: bool,
            ev: Evidence | None, status: str, st_tick: int | None, n: int,
            ticks: Callable[[], _Ticks | StreamTicks]) -> None:
    """The verdict word of a decided requirement (``holds``), its vacuity's note, and a
    violation's evidence (:func:`_first_violation`, over the ticks ``ticks()`` gives)."""
    if holds:
        v.verdict = "vacuous" if (ev is not None and ev.vacuous) else "satisfied"
        if v.verdict == "vacuous" and ev is not None:
            v.notes.append(vacuous_note(ev.intervals))
        return
    v.verdict = "violated"
    _first_violation(r, v, ev, status, st_tick, n, ticks())


def _nan_unknown(bindings) -> bool:
    return bindings is None or bindings.tick.nan != "false"


def unknown_of(r: RequirementPlan, res: ClockPass, nan_unknown: bool) -> np.ndarray:
    """The ticks of ``res`` at which ``r`` reads something unknown: a gap leaves one of its
    variables unknown, or (``nan_unknown``) one of its comparisons reads NaN."""
    n = len(res.times)
    out = np.zeros(n, np.bool_)
    for name in r.judged_variables:
        m = res.unknown.get(name)
        if m is not None:
            out |= m[:n]
    if nan_unknown and n and r.requirement is not None:  # (judged: parsed)
        try:
            out[_nan_index(r, res)] = True
        except (EvidenceUnsupported, KeyError, ValueError):
            pass
    return out


def _nan_index(r: RequirementPlan, res: ClockPass) -> np.ndarray:
    """The ticks (indexes, ``int64``, ascending) of :func:`fretc.monitors.judge.nan_ticks`
    of ``r`` over ``res``, computed once for the pass (its NaN problem, the ticks it reads
    unknown and its trials all read it) and kept as indexes: a pass of many requirements
    keeps a few bytes per NaN tick each, not a byte per tick. Raises what that raises."""
    req, n = r.requirement, len(res.times)
    assert req is not None  # (judged: parsed)
    kept = res.nan_ticks.get(id(req))
    if kept is None or kept[0] is not req or kept[1] is not res.columns or kept[3] != n:
        kept = res.nan_ticks[id(req)] = (req, res.columns,
                                         np.flatnonzero(nan_ticks(req, res.columns, n)), n)
    return kept[2]


def _three_valued_takes(r) -> str | None:
    """None when the three-valued judge can take ``r``, else why not."""
    f = r.formalization
    if not f.pt_causal or not supports(f.pt):
        return "its pt formula has a future-time function"
    return None


def prepare(r: RequirementPlan, res: ClockPass, bindings: Bindings | None, v: Verdict,
            la: LogAudit) -> tuple[ClockPass, bool]:
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
        v.notes.append(NAN_FALSE_NOTE)
    elif n:
        _nan_problem(r, res, la)
    unknown = unknown_of(r, res, nan_unknown)
    why = _three_valued_takes(r) if unknown.any() else None
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
    try:
        bad = _nan_index(r, res)
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



def _windows_of(r: RequirementPlan, bindings: Bindings | None) -> list[str]:
    """The window bindings among ``r``'s variables, over messages (``mean(x, 2s)`` ...) or
    over the requirement's ticks (``count_ticks(c, 1min)``), as ``name = expression``."""
    if bindings is None:
        return []
    return [f"{n} = {b.expr}" for n in r.variables
            if (b := bindings.variables.get(n)) is not None
            and (b.window is not None or b.tick_window is not None)]


def _no_tick(res: ClockPass, v, la, windows: Sequence[str] = ()) -> None:
    """No tick evaluated: unknown when the damage came first, else an error saying what the
    clock waited for (its topics, or windows that never filled: ``windows``)."""
    if res.intact_end is not None:
        v.verdict = "unknown"
        v.unknown_reason = ("the log is damaged before its first evaluated tick: nothing was "
                            "read completely to judge")
        if res.lost:
            v.unknown_reason = ("what it reads could not be read before its first "
                                f"evaluated tick ({res.lost}): nothing was read to judge")
        return
    waiting = la.missing_topics or la.waiting_for
    if not waiting and windows and v.warmup_ticks:
        v.error = (f"no tick evaluated: the window of {'; '.join(windows)} is never complete "
                   f"in the {v.warmup_ticks} ticks of the log (a window is complete once it "
                   "starts at or after its topic's first message, or holds its count of "
                   "messages; a count_ticks window once it starts at or after the "
                   "requirement's first tick): a shorter window, or a longer log")
        return
    v.error = ("no tick evaluated" + (f": waiting for {', '.join(waiting)}" if waiting
                                      else ": the log has no message on the bound topics"))


def _judge_at_damage(r: RequirementPlan, res: ClockPass, v, holds: bool, ev, status, st_tick,
                     n: int) -> bool | None:
    """The verdict over the intact span of a damaged log (:mod:`fretc.audit.damage`): True /
    False for the usual satisfied-or-vacuous / violated paths of :func:`finalize`, None
    when the verdict (``unknown``) is set here."""
    opened = []
    assert r.requirement is not None and r.formalization is not None  # (judged: formalized)
    try:
        opened = open_obligations(r.requirement, res.columns, n, r.formalization.ticks)
    except (EvidenceUnsupported, KeyError) as exc:
        if holds:  # cannot tell whether an obligation is open at the damage
            v.verdict = "unknown"
            v.unknown_reason = (f"the log is damaged and whether an obligation is open at "
                                f"the damage cannot be decided ({exc})")
            return None
    verdict, why = verdict_at_damage(holds, bool(ev is not None and ev.vacuous), status,
                                     st_tick, n, ev, opened, has_ltl3=not r.offline)
    if res.lost:
        why = (f"the judged span ends at log time {res.intact_end} ns, where what it reads "
               f"could not be read ({res.lost}); " + (why or ""))
        if verdict != "unknown":
            v.notes.append(f"decided before log time {res.intact_end} ns, where what it "
                           f"reads could not be read ({res.lost})")
    if verdict == "unknown":
        v.verdict = "unknown"
        v.unknown_reason = why
        return None
    return verdict != "violated"


class StreamTicks:
    """The ticks of a CSV trace judged as it was read (:mod:`fretc.audit.streamed`), as
    :class:`_Ticks` gives a clock's ticks: ``times`` the times (ns) of the ticks the
    evidence names, ``n`` ticks, the last at ``last_time``. A row's message is the row:
    its log time the tick's time (None when negative, as a held log time)."""

    def __init__(self, times: Mapping[int, int], n: int, last_time: int) -> None:
        self.times, self.n, self.last_time = times, n, last_time

    def point(self, i: int) -> TimePoint:
        """Tick ``i`` (the nearest tick's time outside ``0..n-1``) as a TimePoint.

        Raises:
            KeyError: a tick the evidence did not name."""
        j = min(max(i, 0), self.n - 1)
        t = self.last_time if j == self.n - 1 else self.times[j]
        return TimePoint(int(i), t, t if t >= 0 else None)

    def time_at(self, i: int) -> int | None:
        """The time of tick ``i`` (None past the trace: a CSV trace has no bindings'
        period to count on with)."""
        if i == self.n - 1:
            return self.last_time
        return self.times[i] if 0 <= i < self.n else None


class _Ticks:
    """Tick indexes of one clock as :class:`fretc.audit.verdict.TimePoint` and times."""

    def __init__(self, res: ClockPass, held: list, bindings: Bindings | None) -> None:
        self.times = res.times
        self.n = len(res.times)
        self.held = held
        self.bindings = bindings

    def point(self, i: int) -> TimePoint:
        j = min(max(i, 0), self.n - 1)
        lts = [int(h[j]) for h in self.held if h[j] >= 0]
        # the message that decided the tick: the newest one held among its topics
        return TimePoint(int(i), int(self.times[j]), max(lts) if lts else None)

    def time_at(self, i: int) -> int | None:
        n, b = self.n, self.bindings
        if 0 <= i < n:
            return int(self.times[i])
        if i >= n and b is not None and b.tick.period_ns:
            return int(self.times[-1]) + (i - n + 1) * b.tick.period_ns
        return None


def _own_ticks(r: RequirementPlan, res: ClockPass, bindings: Bindings | None) -> _Ticks:
    """The ticks of ``r``'s clock, with the log times of the messages its own topics held."""
    own_topics = sorted(clock_key(r, bindings).topics) if bindings is not None else []
    held = [res.log_times[t] for t in own_topics if t in res.log_times] or \
        list(res.log_times.values())
    return _Ticks(res, held, bindings)


def _robustness(r: RequirementPlan, res: ClockPass, bindings: Bindings | None, v, rob,
                holds: bool) -> None:
    """``v.robustness`` and ``v.robustness_at`` from the judge's robustness ``rob`` (None:
    the pt formula cannot be evaluated over columns; a note says so). A value whose sign
    disagrees with the verdict is never reported, nor a violation's ``-TINY`` (a comparison
    false at distance 0: ``x != c`` with ``x == c``, :mod:`fretc.monitors.robustness`'s
    sign convention), which tells no distance (a note says so instead)."""
    if rob is None:
        v.notes.append("robustness unavailable: the pt formula has a future-time function")
        return
    # the message that decided the tick: the newest held among the clock's topics
    at = _Ticks(res, list(res.log_times.values()), bindings).point(rob.tick)
    _robustness_fields(v, holds, rob.value, at, rob.points)


def _robustness_fields(v, holds: bool, value: float, at: TimePoint,
                       points: list[tuple[int, int, float]]) -> None:
    """``v.robustness`` (``value``), ``v.robustness_at`` (``at``) and ``v.margin``
    (``points``), unless the value's sign disagrees with the verdict or it is a
    violation's ``-TINY`` (notes say so; :func:`_robustness`)."""
    if (value < 0) == holds:
        v.notes.append(f"robustness unavailable: its sign disagrees with the verdict "
                       f"({value!r})")
        return
    if value == -TINY:
        v.notes.append("robustness: none: the violation is decided at distance 0 from its "
                       "threshold (an `!=` met by equality, a strict comparison met at its "
                       "threshold, or a comparison with NaN), where a margin tells no "
                       "distance")
        return
    v.robustness = value + 0.0  # never -0.0: its sign is the verdict's
    v.robustness_at = at
    v.margin = points


def _first_violation(r: RequirementPlan, v, ev, status: str, st_tick: int | None, n: int,
                     ticks: _Ticks | StreamTicks) -> None:
    """The first violation of a violated requirement (``v.first_violation``) and the
    violations listed (``v.violation_list``), over its ``n`` ticks (``ticks``)."""
    assert r.requirement is not None and r.formalization is not None  # (judged: formalized)
    scope_kind = r.requirement.scope.kind
    timing = r.requirement.timing.kind
    obligation = OBLIGATIONS.get(timing, ("", ""))[1 if scope_kind.startswith("only") else 0]
    k = r.formalization.ticks
    tp = ticks.point
    if ev is not None and ev.violation is not None:
        w = ev.violation
        vt = min(w.violation_tick, n - 1)
        fv = FirstViolation(
            at=tp(vt), trigger=tp(w.trigger_tick), scope=(tp(w.interval[0]), tp(w.interval[1])),
            window=w.window, window_time_ns=(ticks.time_at(w.window[0]),
                                             ticks.time_at(w.window[1])),
            obligation=obligation.replace("t+k", f"t+{k}") if k is not None else obligation,
            reason=w.reason)
        v.violation_list = [(tp(x.trigger_tick), tp(min(x.violation_tick, n - 1)))
                            for x in ev.listed]
    else:
        vt = st_tick if (status == "violated" and st_tick is not None) else n - 1
        fv = FirstViolation(at=tp(vt), obligation=obligation,
                            reason="the monitor's verdict (no interval evidence)")
    v.first_violation = fv


def shown_ticks(window: int, v: Verdict, n: int) -> list[int]:
    """The ticks (of ``n``) whose values a violation's evidence shows: those within
    ``window`` of its first violation's trigger and of the tick it was missed at
    (``v.first_violation``), ascending."""
    fv = v.first_violation
    assert fv is not None  # (a violation's evidence is set before its values)
    centres = [fv.at.tick] if fv.trigger is None else [fv.trigger.tick, fv.at.tick]
    return sorted({i for c in centres for i in range(c - window, c + window + 1)
                   if 0 <= i < n})


def _values_around(window: int, r: RequirementPlan, res: ClockPass, bindings: Bindings | None,
                   v) -> None:
    """``v.values`` and ``v.sources``: the requirement's variables and its topics' held log
    times at the ticks within ``window`` of its first violation (:func:`shown_ticks`)."""
    times = res.times
    ticks = shown_ticks(window, v, len(times))
    for name in (*r.variables, *r.stream_names):
        col = res.columns.get(name)
        if col is None:
            continue
        unknown = res.unknown.get(name)  # a value a gap left unknown is shown as None
        v.values[name] = [(i, int(times[i]), None if unknown is not None and unknown[i]
                           else to_python(col[i])) for i in ticks]
    if bindings is not None:
        topics = sorted({t for name in r.variables if name in bindings.variables
                         for t in bindings.variables[name].topics})
    else:
        topics = sorted(res.log_times)
    for t in topics:
        lt = res.log_times.get(t)
        if lt is None:
            continue
        v.sources[t] = [(i, int(times[i]), int(lt[i]) if lt[i] >= 0 else None) for i in ticks]
