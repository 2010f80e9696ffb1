"""What an audit found, as plain dataclasses and a stable JSON document.

Design notes: ARCHITECTURE.md, `audit/verdict.py`."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

__all__ = ["TimePoint", "FirstViolation", "Ltl3", "Verdict", "LogAudit", "audit_json",
           "write_audit_json",
           "NO_EVIDENCE", "SharedEmptyDict", "SharedEmptyList", "summary", "exit_code",
           "incomplete", "SCHEMA", "VERDICTS", "EXIT_CODES", "EXIT_OK", "EXIT_VIOLATED",
           "EXIT_INPUT_ERROR", "EXIT_INCOMPLETE", "EXIT_UNDECIDED"]

SCHEMA = "fretc-audit/1"
#: At most this many points of a verdict's margin over time (:attr:`Verdict.margin`).
MARGIN_POINTS = 400
VERDICTS = ("satisfied", "vacuous", "violated", "unknown", "error")


def _t(ns: int | None, start: int | None) -> dict[str, Any]:
    """``{"ns": int, "s": seconds since start}`` (None values when unknown)."""
    if ns is None:
        return {"ns": None, "s": None}
    return {"ns": int(ns), "s": None if start is None else round((ns - start) / 1e9, 9)}


@dataclass(frozen=True)
class TimePoint:
    """A tick: its index, its own time (``time_ns``, ns in the bindings' time base: the
    log clock or header stamps; a fixed-period tick is usually no message's time) and the
    log time of the message that decided it (``log_time_ns``: the newest message held at
    the tick among the requirement's topics - a real MCAP/bag log time, what Foxglove
    seeks to; None when unknown)."""

    tick: int
    time_ns: int
    log_time_ns: int | None = None

    def to_json(self, start: int | None) -> dict:
        """The point as the audit JSON gives it: tick, tick time (ns, and s from ``start``, the
        log's start in ns) and the log time (ns) of the message that decided it."""
        return {"tick": self.tick, "time_ns": self.time_ns,
                "time_s": _t(self.time_ns, start)["s"], "log_time_ns": self.log_time_ns}


@dataclass
class FirstViolation:
    """The evidence of a violation (see :class:`fretc.monitors.interval.Violation`).

    Attributes:
        at: the tick (and time) at which the obligation was definitely missed.
        trigger: the trigger point behind it; None when the interval semantics could not be
            evaluated (then ``at`` is the monitor's earliest definitive violation, or the
            last tick).
        scope: the scope interval ``(first, last)`` holding the trigger.
        window: the ticks the obligation was about (``(lo, hi)``; ``hi`` may lie past the
            end of the log for ``within``-like timings cut short by the log).
        obligation: the timing's obligation in words (``monitors.obligations.OBLIGATIONS``).
        reason: what failed, in tick numbers.
    """

    at: TimePoint
    trigger: TimePoint | None = None
    scope: tuple[TimePoint, TimePoint] | None = None
    window: tuple[int, int] | None = None
    window_time_ns: tuple[int | None, int | None] | None = None
    obligation: str = ""
    reason: str = ""

    def to_json(self, start: int | None, time_base: str | None = None) -> dict:
        """The first violation as the audit JSON gives it (times in ns and in s from ``start``;
        ``time_base`` names the tick clock's base)."""
        lt = self.at.log_time_ns
        out = {"tick": self.at.tick, "log_time_ns": lt, "log_time_s": _t(lt, start)["s"],
               "tick_time_ns": self.at.time_ns, "tick_time_s": _t(self.at.time_ns, start)["s"],
               "tick_time_base": time_base,
               "obligation": self.obligation, "reason": self.reason,
               "trigger": self.trigger.to_json(start) if self.trigger else None,
               "scope_interval": None, "window": None}
        if self.scope is not None:
            out["scope_interval"] = {"start": self.scope[0].to_json(start),
                                     "end": self.scope[1].to_json(start)}
        if self.window is not None:
            lo_ns, hi_ns = self.window_time_ns or (None, None)
            out["window"] = {"start_tick": self.window[0], "end_tick": self.window[1],
                             "start_time_ns": lo_ns, "end_time_ns": hi_ns,
                             "start_time_s": _t(lo_ns, start)["s"],
                             "end_time_s": _t(hi_ns, start)["s"]}
        return out


@dataclass(frozen=True, slots=True)
class Ltl3:
    """The earliest definitive verdict of the infinite-trace formula (LTL3: ``satisfied``,
    ``violated`` or ``unknown``) and the tick at which it was reached (None: unknown, or
    definitive before the first tick). Immutable: verdicts share equal ones (the entities
    judged at once, :mod:`fretc.audit.entities.log`)."""

    status: str = "unknown"
    tick: int | None = None
    time_ns: int | None = None

    def to_json(self, start: int | None) -> dict:
        """The LTL3 verdict as the audit JSON gives it (key ``status``: ``satisfied``,
        ``violated`` or ``unknown``; its tick and time, in ns and in s from ``start``)."""
        return {"status": self.status, "tick": self.tick, "time_ns": self.time_ns,
                "time_s": _t(self.time_ns, start)["s"]}


def _refuse(self, *_args: Any, **_kwargs: Any) -> Any:
    raise TypeError("an empty evidence field shared by the verdicts of entities judged at once "
                    "cannot change: assign the verdict a container of its own")


class SharedEmptyDict(dict):
    """An empty dict that many verdicts share (:data:`NO_EVIDENCE`): any change raises
    TypeError (it would change every verdict sharing it); JSON writes, compares, copies
    (``copy``, ``pickle``: a plain ``{}``) as ``{}``."""

    __slots__ = ()
    __setitem__ = __delitem__ = __ior__ = update = setdefault = pop = popitem = clear = _refuse

    def __reduce__(self) -> tuple:
        return (dict, ())


class SharedEmptyList(list):
    """An empty list that many verdicts share (:data:`NO_EVIDENCE`): as
    :class:`SharedEmptyDict`, a change raises TypeError; copies are a plain ``[]``."""

    __slots__ = ()
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse
    append = extend = insert = remove = pop = clear = sort = reverse = _refuse

    def __reduce__(self) -> tuple:
        return (list, ())


_NO_DICT, _NO_LIST = SharedEmptyDict(), SharedEmptyList()
#: The evidence fields of a :class:`Verdict` that has none, as keyword arguments, their
#: empty containers shared: the verdicts of the entities judged at once
#: (:mod:`fretc.audit.entities.log`), 100,000 of them on a large log, each otherwise carrying
#: seven empty containers of its own (half its memory, and the collector's work)
NO_EVIDENCE: dict[str, Any] = {
    "values": _NO_DICT, "sources": _NO_DICT, "waiting_for": _NO_LIST,
    "unsampled_messages": _NO_DICT, "missed_changes": _NO_DICT, "violation_list": _NO_LIST,
    "margin": _NO_LIST}


@dataclass(slots=True)
class Verdict:
    """One requirement on one log.

    Attributes:
        log, requirement: the log path and the requirement id; ``source`` its file:line.
        verdict: one of :data:`VERDICTS`.
        partial: the log is damaged: judged on the messages read (a gap's ticks are
            unknown, nothing after a cut is read).
        first_violation: evidence when violated.
        ltl3: the earliest definitive LTL3 verdict.
        values: variable -> [(tick, time_ns, value)] around the trigger and the violation.
        sources: topic -> [(tick, time_ns, log_time_ns of the message held)] for the topics
            those variables are bound to, at the same ticks.
        ticks_evaluated, warmup_ticks, first_tick_ns, last_tick_ns, waiting_for: this
            requirement's own clock (the topics of its variables and the bindings' tick;
            never other requirements'): evaluated ticks, warm-up ticks, the times of its
            first evaluated and last tick, the topics it waited for.
        unsampled_messages: topic -> messages of a bound topic that no tick of this clock
            sampled (superseded by a newer one between two ticks: sample-and-hold holds the
            newest), counted from the first evaluated tick on.
        missed_changes: variable -> how many of those messages would have changed its
            value (a boolean binding of one topic without aggregation: its value on the
            skipped message differs from the tick before); such a variable can miss events
            between ticks (bind it with ``any_of_messages``; docs/bindings.md).
        intervals, triggers, violations: counts from the interval semantics (None when it
            could not be evaluated).
        violation_list: (trigger, violation) time points of the failed triggers in order,
            the first :data:`fretc.monitors.interval.MAX_LISTED` of them (``violations`` counts
            all).
        engine: ``"stepwise"`` (the generated monitor's ``step()``), ``"vectorized"``
            (``monitors.vectorized`` over the columns; equal by test) or ``"interval"``
            (no online monitor exists - a future-time function - so FRET's interval
            semantics decided it, :mod:`fretc.monitors.interval`).
        notes: remarks (evidence unavailable, warnings of the formalization).
        error: why the verdict is ``error``.
        robustness: the margin behind the verdict (:mod:`fretc.monitors.robustness`): in
            the unit of the comparison that decides it, negative exactly when violated,
            ``+-inf`` when a boolean decides it; None when ``unknown``, ``error``, or the pt
            formula cannot be evaluated over columns (a note says why).
        robustness_at: the tick where the margin that decides the verdict was reached
            (:class:`fretc.monitors.robustness.Robustness`'s ``tick``): where the pt
            formula is ``H`` of what must hold at every tick (most requirements without a
            scope) the first tick where the margin is that small, else the first tick since
            which the margin has held its final value.
        unknown_ticks: ticks of this requirement's clock at which something it reads is
            unknown (a gap of the log, a comparison with NaN): judged in three-valued
            semantics (:mod:`fretc.audit.unknown_ticks`).
        margin: the margin over time, ``[(tick, time_ns, value)]``: every tick, or on a
            long log the least value (at the first tick where it occurs) of each run of
            ``B`` consecutive ticks from tick 0, ``B`` the least power of two that makes at
            most :data:`MARGIN_POINTS` runs (:func:`fretc.monitors.robustness.margin_ticks`:
            kept a chunk of ticks at a time), so no dip is lost.
        trials: for a requirement with a probability bound, its triggers on this log as
            trials (:class:`fretc.audit.trials.Trials`: satisfied, violated, and the cut and
            unknown ones that are no trials); None for the others, and when it was not
            judged.
        coverage: with ``fretc audit --coverage``, the coverage obligations this log
            exercised (:func:`fretc.audit.coverage.record_coverage`); None without it.
    """

    log: str
    requirement: str
    text: str = ""
    source: str = ""
    verdict: str = "error"
    partial: bool = False
    first_violation: FirstViolation | None = None
    ltl3: Ltl3 = Ltl3()
    values: dict[str, list[tuple[int, int, Any]]] = field(default_factory=dict)
    sources: dict[str, list[tuple[int, int, int | None]]] = field(default_factory=dict)
    ticks_evaluated: int = 0
    warmup_ticks: int = 0
    first_tick_ns: int | None = None
    last_tick_ns: int | None = None
    waiting_for: list[str] = field(default_factory=list)
    unsampled_messages: dict[str, int] = field(default_factory=dict)
    missed_changes: dict[str, int] = field(default_factory=dict)
    intervals: int | None = None
    triggers: int | None = None
    violations: int | None = None
    violation_list: list[tuple[TimePoint, TimePoint]] = field(default_factory=list)
    engine: str | None = None
    notes: list[str] = field(default_factory=list)
    error: str | None = None
    unknown_reason: str | None = None
    robustness: float | None = None
    robustness_at: TimePoint | None = None
    margin: list[tuple[int, int, float]] = field(default_factory=list)
    unknown_ticks: int = 0
    trials: Any = None
    coverage: Any = None

    def to_json(self, start: int | None, time_base: str | None = None) -> dict:
        """The verdict as the audit JSON gives it (``docs/reference/audit.schema.json``): times in
        ns and in s from ``start`` (the log's start, ns); NaN and infinities as strings."""
        def val(v):
            if isinstance(v, float) and v != v:
                return "nan"
            if isinstance(v, float) and v in (float("inf"), float("-inf")):
                return "inf" if v > 0 else "-inf"
            return v

        return {
            "log": self.log, "requirement": self.requirement, "text": self.text,
            "source": self.source, "verdict": self.verdict, "partial": self.partial,
            "first_violation": (self.first_violation.to_json(start, time_base)
                                if self.first_violation else None),
            "ltl3": self.ltl3.to_json(start),
            "values": {k: [{"tick": t, "time_ns": ns, "time_s": _t(ns, start)["s"],
                            "value": val(v)} for t, ns, v in rows]
                       for k, rows in self.values.items()},
            "sources": {k: [{"tick": t, "time_ns": ns, "time_s": _t(ns, start)["s"],
                             "message_log_time_ns": lt} for t, ns, lt in rows]
                        for k, rows in self.sources.items()},
            "ticks_evaluated": self.ticks_evaluated, "warmup_ticks": self.warmup_ticks,
            "first_tick_ns": self.first_tick_ns, "first_tick_s": _t(self.first_tick_ns, start)["s"],
            "last_tick_ns": self.last_tick_ns, "last_tick_s": _t(self.last_tick_ns, start)["s"],
            # (plain copies: never the shared empty containers of NO_EVIDENCE, which a
            # serializer of exact types such as PyYAML's safe dumper refuses)
            "waiting_for": list(self.waiting_for),
            "unsampled_messages": dict(self.unsampled_messages),
            "missed_changes": dict(self.missed_changes),
            "intervals": self.intervals, "triggers": self.triggers,
            "violations": self.violations,
            "violation_list": [{"trigger": t.to_json(start), "violation": w.to_json(start)}
                               for t, w in self.violation_list],
            "engine": self.engine, "notes": self.notes,
            "error": self.error, "unknown_reason": self.unknown_reason,
            "robustness": self._robustness_json(start, val),
            "unknown_ticks": self.unknown_ticks,
            "trials": None if self.trials is None else self.trials.to_json(),
            **({} if self.coverage is None else {"coverage": self.coverage}),
        }

    def _robustness_json(self, start: int | None, val) -> dict:
        """``{"value", "tick", "time_ns", "time_s", "log_time_ns", "margin"}`` (margin:
        ``[[tick, time_s, value]]``; None values and no margin when
        there is no robustness; infinities as the strings inf, -inf)."""
        at = self.robustness_at
        out = {"value": None if self.robustness is None else val(self.robustness),
               "margin": [[t, _t(ns, start)["s"], val(x)] for t, ns, x in self.margin]}
        if at is None:
            return dict(out, tick=None, time_ns=None, time_s=None, log_time_ns=None)
        return dict(out, **at.to_json(start))


@dataclass
class LogAudit:
    """One log: how it was read and the verdicts of every requirement on it.

    Attributes:
        log: the path as given; ``kind`` mcap / bag / rosbag2 / csv.
        partial, damage_time_ns: the log is damaged (truncated, a chunk skipped, its summary
            lost); where the span read completely ends (log time, ns; None when no message
            was lost). Only ticks before it are judged; ``ticks_after_damage`` counts the
            ticks sampled after it and not judged.
        start_time_ns: time of the first tick (evaluated or not); ``first_time_ns`` of the
            first evaluated tick; ``end_time_ns`` the log's end, the log time of its last
            message of any topic (:func:`fretc.audit.log.log_end`; after damage with ticks
            not judged, the last tick judged).
        ticks_evaluated, warmup_ticks: evaluated ticks, and ticks before every bound topic
            had a message (not evaluated); ``waiting_for`` the topics still silent at the
            first tick; ``missing_topics`` bound topics that never had a message.
        tick, time_base: the clock used (``{"period_ns": ...}`` or ``{"topic": ...}``).
        messages: messages read per topic.
        problems: data problems (kind, topic, log_time_ns, end_time_ns, detail);
            ``problem_counts`` counts all of them by ``kind topic`` (the list is capped).
        verdicts: one per requirement, in requirement order.
        error: a log-level input error (unreadable log, no bindings for a ROS log).
        warnings: remarks on how far the audit can be trusted (e.g. the tick topic's
            measured rate differs from its declared nominal rate by more than 10 %).
        gaps: the log's gaps (:func:`fretc.audit.gaps.gap_json`: log-time span, topics,
            cause, bridged): the spans in which messages were lost and the log was read on
            after; their ticks are unknown for the requirements reading those topics, unless
            bridged (``--bridge-gaps``).
        cut_time_ns: where a cut ends what was read (log time, ns: a truncation, nothing
            read after it; None when the log was read to its end).
        integrity: why a changed byte of the log would read as data (a format or a file
            without checksums: :meth:`fretc.logs.base.LogSource.integrity_note`), None when
            every byte read was checked.
        allowance_ns: the reaction allowance it was read with (``--allowance``, ``[audit]
            allowance``: topic -> ns its messages were read earlier, :mod:`fretc.logs.allowance`);
            empty: none. In the JSON (``allowance_ns``, and in each first violation) only
            when given, so that a verdict is never read without it.
    """

    log: str
    kind: str | None = None
    partial: bool = False
    damage_time_ns: int | None = None
    start_time_ns: int | None = None
    first_time_ns: int | None = None
    end_time_ns: int | None = None
    ticks_evaluated: int = 0
    warmup_ticks: int = 0
    waiting_for: list[str] = field(default_factory=list)
    missing_topics: list[str] = field(default_factory=list)
    tick: dict[str, Any] = field(default_factory=dict)
    time_base: str | None = None
    messages: dict[str, int] = field(default_factory=dict)
    problems: list[dict[str, Any]] = field(default_factory=list)
    problem_counts: dict[str, int] = field(default_factory=dict)
    verdicts: list[Verdict] = field(default_factory=list)
    engine: str | None = None
    error: str | None = None
    ticks_after_damage: int = 0
    damage_cut: bool = False
    warnings: list[str] = field(default_factory=list)
    gaps: list[dict[str, Any]] = field(default_factory=list)
    cut_time_ns: int | None = None
    integrity: str | None = None
    allowance_ns: dict[str, int] = field(default_factory=dict)

    def to_json(self) -> dict:
        """The log's audit as the audit JSON gives it (``docs/reference/audit.schema.json``)."""
        out = self.head_json()
        out["verdicts"] = list(self.verdicts_json())
        return out

    def verdicts_json(self) -> Iterator[dict]:
        """The verdicts as :meth:`to_json` gives them, one at a time."""
        st, base = self.start_time_ns, self.time_base
        for v in self.verdicts:
            out = v.to_json(st, base)
            if self.allowance_ns and out.get("first_violation"):
                out["first_violation"]["allowance_ns"] = dict(self.allowance_ns)
            yield out

    def head_json(self) -> dict:
        """:meth:`to_json` but for its ``verdicts``."""
        st = self.start_time_ns
        return {
            "log": self.log, "kind": self.kind, "partial": self.partial,
            "damage_time_ns": self.damage_time_ns,
            "damage_time_s": _t(self.damage_time_ns, st)["s"],
            "start_time_ns": st, "first_time_ns": self.first_time_ns,
            "first_time_s": _t(self.first_time_ns, st)["s"],
            "end_time_ns": self.end_time_ns, "end_time_s": _t(self.end_time_ns, st)["s"],
            "ticks_evaluated": self.ticks_evaluated, "warmup_ticks": self.warmup_ticks,
            "waiting_for": self.waiting_for, "missing_topics": self.missing_topics,
            "tick": self.tick, "time_base": self.time_base, "messages": self.messages,
            "problems": [dict(p, log_time_s=_t(p.get("log_time_ns"), st)["s"])
                         for p in self.problems],
            "problem_counts": self.problem_counts,
            "engine": self.engine, "error": self.error,
            "ticks_after_damage": self.ticks_after_damage, "damage_cut": self.damage_cut,
            "gaps": [dict(g, start_s=_t(g["start_ns"], st)["s"], end_s=_t(g["end_ns"], st)["s"])
                     for g in self.gaps],
            "cut_time_ns": self.cut_time_ns, "cut_time_s": _t(self.cut_time_ns, st)["s"],
            "integrity": self.integrity,
            **({"allowance_ns": dict(self.allowance_ns)} if self.allowance_ns else {}),
        }


#: Exit codes of ``fretc audit`` (docs/guide/audits.md "Exit codes"; ``fretc audit --help``).
EXIT_OK = 0
EXIT_VIOLATED = 1
EXIT_INPUT_ERROR = 2
EXIT_INCOMPLETE = 3
EXIT_UNDECIDED = 5
EXIT_CODES = (
    (EXIT_OK, "every verdict satisfied or vacuous, on complete logs without data problems"),
    (EXIT_VIOLATED, "a requirement is violated on some log, or a probability requirement "
                    "fails statistically over the logs"),
    (EXIT_INPUT_ERROR, "a usage or input error: bad option, requirement or binding, a log "
                       "that cannot be read, a requirement that could not be audited on a log"),
    (EXIT_INCOMPLETE, "no violation found, but a log is partial (truncated, damaged) or had "
                      "data problems, or a verdict is unknown: the audit is incomplete "
                      "(--allow-partial: 0 instead)"),
    (EXIT_UNDECIDED, "no violation, but a probability requirement is undecided: too few "
                     "runs for its bound at the confidence asked (--allow-partial does not "
                     "change it)"),
)


def incomplete(la: LogAudit) -> bool:
    """The log was not audited completely: partial (damaged, cut short), data problems
    found while reading it, or a verdict that is neither satisfied, vacuous, violated nor
    error (e.g. ``unknown`` at damage)."""
    return bool(la.partial or la.problems or la.problem_counts
                or any(v.verdict not in _DECIDED for v in la.verdicts))


#: Verdicts that say the requirement was checked to the end of the log.
_DECIDED = ("satisfied", "vacuous", "violated", "error")


def summary(logs: list[LogAudit], allow_partial: bool = False,
            statistics: list | None = None) -> dict[str, int]:
    """Counts of verdicts over all logs, and the exit code they give (:func:`exit_code`)."""
    out = {k: 0 for k in VERDICTS}
    for la in logs:
        for v in la.verdicts:
            out[v.verdict] = out.get(v.verdict, 0) + 1
    out["partial_logs"] = sum(1 for la in logs if la.partial)
    out["incomplete_logs"] = sum(1 for la in logs if incomplete(la))
    out["log_errors"] = sum(1 for la in logs if la.error)
    out["exit_code"] = exit_code(logs, allow_partial=allow_partial, statistics=statistics)
    return out


def exit_code(logs: list[LogAudit], input_errors: bool = False,
              allow_partial: bool = False, statistics: list | None = None) -> int:
    """The exit code of an audit (:data:`EXIT_CODES`), first that applies: 2 anything could
    not be audited (an input error, an ``error`` verdict); 1 a requirement is violated; 3
    (0 with ``allow_partial``) no violation but some log is incomplete (:func:`incomplete`:
    partial, data problems, unknown verdicts - a CI gate must not pass a recording that lost
    its last minutes); else 0.

    ``statistics`` (:class:`fretc.audit.fleet.statistics.RequirementStatistics` list): a requirement
    with a probability bound is judged by its statistical verdict, not by its runs: 1 when
    it ``fails``, 5 (:data:`EXIT_UNDECIDED`, after 1 and before 3) when ``undecided``; its
    violated runs alone do not give 1."""
    bounded = {s.id for s in statistics or () if s.bound is not None}
    failed = any(s.verdict == "fails" for s in statistics or ())
    undecided = any(s.verdict == "undecided" for s in statistics or ())
    if input_errors or any(la.error for la in logs) or any(
            v.verdict == "error" for la in logs for v in la.verdicts):
        return EXIT_INPUT_ERROR
    if failed or any(v.verdict == "violated" and v.requirement not in bounded
                     for la in logs for v in la.verdicts):
        return EXIT_VIOLATED
    if undecided:
        return EXIT_UNDECIDED
    if not allow_partial and any(incomplete(la) for la in logs):
        return EXIT_INCOMPLETE
    return EXIT_OK


def audit_json(logs: list[LogAudit], requirements: list[dict], bindings: dict | None,
               input_errors: bool = False, allow_partial: bool = False,
               extra: dict | None = None, statistics: list | None = None) -> str:
    """The ``--json`` document (module docstring), as text with sorted keys. ``extra``: more
    top-level members (``not_formalized``, :meth:`fretc.audit.model.AuditPlan.sources_json`);
    the ``statistics`` list when ``statistics`` is given (None: no key). Each verdict of a
    requirement read from a tool (its ``origin``) names the tool's identifier as
    ``tool_id``. The text of :func:`write_audit_json`."""
    parts: list[str] = []
    write_audit_json(parts.append, logs, requirements, bindings, input_errors, allow_partial,
                     extra, statistics)
    return "".join(parts)


def write_audit_json(write: Callable[[str], Any], logs: list[LogAudit],
                     requirements: list[dict], bindings: dict | None,
                     input_errors: bool = False, allow_partial: bool = False,
                     extra: dict | None = None, statistics: list | None = None) -> None:
    """:func:`audit_json`'s document given to ``write`` piece by piece: the verdicts one at a
    time (each made, written and let go), so that writing it holds one verdict's JSON, not
    every verdict's (10^6 entities' verdicts are gigabytes as one tree of dicts and its
    text). The same text as ``json.dumps(doc, indent=2, sort_keys=True, allow_nan=False)``
    of the whole document, and a new line.

    Raises:
        ValueError: a NaN or an infinity in the document (``allow_nan=False``)."""
    s = summary(logs, allow_partial, statistics)
    s["exit_code"] = exit_code(logs, input_errors, allow_partial, statistics)
    tool_ids = {r["id"]: r["origin"]["tool_id"] for r in requirements
                if isinstance(r.get("origin"), dict)}

    def verdicts(la: LogAudit) -> Iterator[dict]:
        for v in la.verdicts_json():
            if v["requirement"] in tool_ids:
                v["tool_id"] = tool_ids[v["requirement"]]
            yield v

    logs_json = _Stream(_Tree({**la.head_json(), "verdicts": _Stream(verdicts(la))})
                        for la in logs)
    doc = _Tree({"schema": SCHEMA, "requirements": requirements, "bindings": bindings,
                 "logs": logs_json, "summary": s, **(extra or {})})
    if statistics is not None:
        doc["statistics"] = [st.to_json() for st in statistics]
    _write_json(write, doc, 0)
    write("\n")


class _Tree(dict):
    """A dict of the document written member by member (it holds a :class:`_Stream`)."""


class _Stream:
    """A list of the document whose items are made one at a time, as it is written."""

    def __init__(self, items: Iterable[Any]) -> None:
        self.items = items


_INDENT = "  "


def _write_json(write: Callable[[str], Any], obj: Any, depth: int) -> None:
    """``obj`` as ``json.dumps(obj, indent=2, sort_keys=True, allow_nan=False)`` writes it
    at nesting ``depth``: a :class:`_Tree` member by member, a :class:`_Stream` item by
    item, anything else in one piece."""
    pad = "\n" + _INDENT * (depth + 1)
    if isinstance(obj, _Stream):
        first = True
        for item in obj.items:
            write(("[" if first else ",") + pad)
            _write_json(write, item, depth + 1)
            first = False
        write("[]" if first else "\n" + _INDENT * depth + "]")
    elif isinstance(obj, _Tree):
        if not obj:
            write("{}")
            return
        for k, key in enumerate(sorted(obj)):
            write(("{" if not k else ",") + pad + json.dumps(key) + ": ")
            _write_json(write, obj[key], depth + 1)
        write("\n" + _INDENT * depth + "}")
    else:
        out: list[str] = []
        _encode(obj, _INDENT * depth, out)
        write("".join(out))


_ESCAPE = json.encoder.encode_basestring_ascii  # (C or Python)


def _encode(obj: Any, pad: str, out: list[str]) -> None:
    """``obj`` into ``out`` as ``json.dumps(obj, indent=2, sort_keys=True,
    allow_nan=False)`` writes it at indentation ``pad`` (the same text, tested over random
    documents), in one pass of appends rather than :mod:`json`'s generators (which its
    C encoder does not replace when indenting), scalars inside a list or dict written with
    it: the audit JSON of 10^6 verdicts in about a third of the time. A dict with a key that
    is not a string is left to :mod:`json` (how it converts and sorts such keys).

    Raises:
        ValueError: a NaN or an infinity.
        TypeError: a value JSON has no form for."""
    leaf = _leaf(obj)
    if leaf is not None:
        out.append(leaf)
    elif isinstance(obj, (list, tuple)):
        if not obj:
            out.append("[]")
            return
        inner = pad + _INDENT
        sep = "[\n" + inner
        for x in obj:
            leaf = _leaf(x)
            if leaf is not None:
                out.append(sep + leaf)
            else:
                out.append(sep)
                _encode(x, inner, out)
            sep = ",\n" + inner
        out.append("\n" + pad + "]")
    elif isinstance(obj, dict) and all(type(k) is str for k in obj):
        if not obj:
            out.append("{}")
            return
        inner = pad + _INDENT
        sep = "{\n" + inner
        for k in sorted(obj):
            x = obj[k]
            leaf = _leaf(x)
            if leaf is not None:
                out.append(sep + _ESCAPE(k) + ": " + leaf)
            else:
                out.append(sep + _ESCAPE(k) + ": ")
                _encode(x, inner, out)
            sep = ",\n" + inner
        out.append("\n" + pad + "}")
    else:
        text = json.dumps(obj, indent=2, sort_keys=True, allow_nan=False)
        out.append(text.replace("\n", "\n" + pad))


def _leaf(x: Any) -> str | None:
    """The JSON text of a scalar ``x`` (as :mod:`json` writes it), else None.

    Raises:
        ValueError: a NaN or an infinity."""
    t = type(x)
    if t is str:
        return _ESCAPE(x)
    if x is None:
        return "null"
    if t is bool:
        return "true" if x else "false"
    if t is int:
        return int.__repr__(x)
    if t is float:
        if x != x or x in (_INF, -_INF):
            raise ValueError(f"Out of range float values are not JSON compliant: {x!r}")
        return float.__repr__(x)
    if isinstance(x, str):
        return _ESCAPE(x)
    if isinstance(x, bool):  # (json's order: a bool before an int)
        return "true" if x else "false"
    if isinstance(x, int):
        return int.__repr__(x)
    if isinstance(x, float):
        return _leaf(float(x))
    return None


_INF = float("inf")
