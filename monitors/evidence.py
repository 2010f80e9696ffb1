"""The evidence behind a requirement's verdict under FRET's interval semantics
(:mod:`fretc.monitors.interval`): the first violated trigger (:class:`Violation`) and the
counts and violations of one trace (:class:`Evidence`), as the audit reports them."""

from __future__ import annotations

from dataclasses import dataclass, field

from fretc.monitors.obligations import Interval

__all__ = ["Violation", "Evidence", "MAX_LISTED"]

#: How many failed triggers an :class:`Evidence` lists (all are counted).
MAX_LISTED = 100


@dataclass(frozen=True)
class Violation:
    """A trigger whose obligation failed (all ticks 0-based, inclusive).

    Attributes:
        trigger_tick: the trigger point ``t``.
        interval: the scope interval ``(s, e)`` holding it.
        window: ``(lo, hi)``: the ticks the obligation was about (e.g. ``[t, t+k]`` for
            ``within k``); ``hi`` may exceed ``e`` only where FRET looks past it.
        violation_tick: the tick at which the obligation was definitely missed (for
            ``eventually`` the interval end; for ``always`` the first point where the
            response failed).
        reason: one sentence for a person, in tick numbers.
    """

    trigger_tick: int
    interval: Interval
    window: Interval
    violation_tick: int
    reason: str


@dataclass
class Evidence:
    """The interval-semantics verdict of one requirement on one trace.

    Attributes:
        holds: FRET's finite-trace verdict (equals the monitor's ``finish()``).
        vacuous: ``holds`` and there was no scope interval or no trigger.
        intervals: number of scope intervals; ``first_interval`` the first one.
        triggers: number of trigger points over all intervals.
        violations: number of triggers whose obligation failed.
        violation: the first of them, or None.
        listed: the failed triggers in order, at most :data:`MAX_LISTED` of them.
        ticks: trace length.
    """

    holds: bool
    vacuous: bool
    intervals: int
    triggers: int
    violations: int
    violation: Violation | None
    ticks: int
    first_interval: Interval | None = None
    first_trigger: int | None = None
    listed: list[Violation] = field(default_factory=list)
