"""The verdicts of the entities of one per-entity requirement judged at once, kept as columns
(:class:`EntityBlock`: one compact record per entity) and read through a small object per
entity (:class:`EntityVerdict`) that has every field of
:class:`fretc.audit.verdict.Verdict`, computed from its record when read.

Design notes: ARCHITECTURE.md, `audit/entities/verdicts.py`."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from fretc.audit.finalize import vacuous_note
from fretc.audit.verdict import MARGIN_POINTS, NO_EVIDENCE, Ltl3, TimePoint, Verdict
from fretc.monitors.robustness import margin_ticks

__all__ = ["EntityBlock", "EntityVerdict", "LTL3_STATUS"]

#: LTL3 statuses by their code in :attr:`EntityBlock.ltl3_status`
LTL3_STATUS = ("unknown", "satisfied", "violated")
_NO_TICK = -1


class EntityBlock:
    """The entities of requirement ``rid`` (kind ``name``) judged at once on the log ``log``
    (:mod:`fretc.audit.entities.batch`), one record each, added chunk by chunk
    (:meth:`add`) and read by :class:`EntityVerdict`.

    Attributes:
        keys: the entities' keys (the entity table's, by entity index); ``first``, ``last``
            their first and last message times (ns, int64 arrays by entity index).
        times: the clock's tick times (ns, int64): a record's ticks are its trace's, from
            ``i0`` for ``length`` ticks.
        head: the notes every verdict starts with (the requirement's); ``tail`` those after
            its own (the block's note and, once all entities are judged, the summary).
    """

    def __init__(self, log: str, rid: str, text: str, source: str, name: str, key: str,
                 keys: list, first: np.ndarray, last: np.ndarray, times: np.ndarray,
                 head: tuple[str, ...], extra: tuple[str, ...], note: str) -> None:
        self.log, self.rid, self.text, self.source = log, rid, text, source
        self.name, self.key, self.keys, self.first, self.last = name, key, keys, first, last
        self.times, self.head, self.extra, self.note = times, head, extra, note
        self.summary: str | None = None
        self._parts: list[dict[str, np.ndarray]] = []
        self.cols: dict[str, np.ndarray] = {}
        self.words: list[str] = []
        self.size = 0

    def add(self, **cols: np.ndarray) -> range:
        """Records of one chunk: the columns ``entity``, ``i0``, ``length``, ``vacuous``,
        ``ltl3_status``, ``ltl3_tick`` (-1: none), ``rob`` (NaN with ``rob_tick`` -1: none),
        ``rob_tick``, ``rob_log_time`` (-1: none), ``intervals``, ``triggers`` (-1: none)
        and ``margin`` (the margin at every tick of the chunk's traces laid end to end, in
        record order). Returns the records' numbers."""
        n = len(cols["entity"])
        self._parts.append(cols)
        a = self.size
        self.size += n
        return range(a, a + n)

    def seal(self) -> None:
        """Join the chunks' columns (after the last :meth:`add`)."""
        if not self._parts:
            return
        names = [k for k in self._parts[0] if k != "margin"]
        self.cols = {k: np.concatenate([p[k] for p in self._parts]) for k in names}
        self.cols["margin"] = np.concatenate([p["margin"] for p in self._parts])
        lengths = self.cols["length"]
        self.cols["margin_at"] = np.cumsum(lengths) - lengths
        self._parts = []
        # (each record's verdict as one of two shared strings: the field read most)
        self.words = [("satisfied", "vacuous")[x] for x in self.cols["vacuous"].tolist()]

    def json(self, k: int, start: int | None) -> dict:
        """Record ``k``'s verdict as :meth:`fretc.audit.verdict.Verdict.to_json` gives it
        (``start``: the log's start, ns), made from the columns at once rather than field
        by field (the audit JSON of 10^6 entities; equal by test to the verdict's)."""
        cols, times = self.cols, self.times
        i0, m = int(cols["i0"][k]), cols["length"].item(k)
        first, last = times.item(i0), times.item(i0 + m - 1)
        intervals, triggers = cols["intervals"].item(k), cols["triggers"].item(k)
        counted = intervals >= 0

        def s(ns: int) -> float | None:
            return None if start is None else round((ns - start) / 1e9, 9)

        return {
            "log": self.log, "requirement": self._f_requirement(k), "text": self.text,
            "source": self.source, "verdict": self.words[k], "partial": False,
            "first_violation": None, "ltl3": self._f_ltl3(k).to_json(start),
            "values": {}, "sources": {}, "ticks_evaluated": m, "warmup_ticks": 0,
            "first_tick_ns": first, "first_tick_s": s(first),
            "last_tick_ns": last, "last_tick_s": s(last), "waiting_for": [],
            "unsampled_messages": {}, "missed_changes": {},
            "intervals": intervals if counted else None,
            "triggers": triggers if counted else None, "violations": 0 if counted else None,
            "violation_list": [], "engine": "vectorized", "notes": list(self._f_notes(k)),
            "error": None, "unknown_reason": None, "robustness": self._robustness_json(k, start),
            "unknown_ticks": 0, "trials": None}

    def _robustness_json(self, k: int, start: int | None) -> dict:
        """Record ``k``'s ``robustness`` member of the audit JSON."""
        at = self._f_robustness_at(k)
        if at is None:
            return {"value": None, "margin": [], "tick": None, "time_ns": None,
                    "time_s": None, "log_time_ns": None}
        margin = [[t, None if start is None else round((ns - start) / 1e9, 9), _val(x)]
                  for t, ns, x in self._f_margin(k)]
        return {"value": _val(self.cols["rob"].item(k) + 0.0), "margin": margin,
                **at.to_json(start)}

    # --- one record's fields --------------------------------------------------------------
    def field(self, name: str, k: int) -> Any:
        """The field ``name`` of :class:`~fretc.audit.verdict.Verdict` of record ``k``."""
        get = getattr(self, "_f_" + name, None)
        if get is not None:
            return get(k)
        return _CONSTANT[name]

    def _f_log(self, k: int) -> str:
        return self.log

    def _f_requirement(self, k: int) -> str:
        return f"{self.rid}[{self.name}={self.keys[self.cols['entity'].item(k)]}]"

    def _f_text(self, k: int) -> str:
        return self.text

    def _f_source(self, k: int) -> str:
        return self.source

    def _f_verdict(self, k: int) -> str:
        return self.words[k]

    def _f_ltl3(self, k: int) -> Ltl3:
        status, tick = int(self.cols["ltl3_status"][k]), int(self.cols["ltl3_tick"][k])
        if tick == _NO_TICK:
            return Ltl3(LTL3_STATUS[status], None, None)
        return Ltl3(LTL3_STATUS[status], tick, self.times.item(self._i0(k) + tick))

    def _i0(self, k: int) -> int:
        return int(self.cols["i0"][k])

    def _f_ticks_evaluated(self, k: int) -> int:
        return self.cols["length"].item(k)

    def _f_first_tick_ns(self, k: int) -> int:
        return int(self.times[self._i0(k)])

    def _f_last_tick_ns(self, k: int) -> int:
        return int(self.times[self._i0(k) + self.cols["length"].item(k) - 1])

    def _count(self, name: str, k: int) -> int | None:
        x = self.cols[name].item(k)
        return None if x < 0 else x

    def _f_intervals(self, k: int) -> int | None:
        return self._count("intervals", k)

    def _f_triggers(self, k: int) -> int | None:
        return self._count("triggers", k)

    def _f_violations(self, k: int) -> int | None:
        return None if self._count("intervals", k) is None else 0

    def _f_notes(self, k: int) -> tuple[str, ...]:
        i = self.cols["entity"].item(k)
        seen = (f"entity {self.name} = {self.keys[i]!r} ({self.key}): first seen at log time "
                f"{int(self.first[i])}, last at {int(self.last[i])}")
        own: tuple[str, ...] = ()
        if self.cols["vacuous"].item(k) and self._count("intervals", k) is not None:
            own = (vacuous_note(self.cols["intervals"].item(k)),)
        return (*self.head, seen, *self.extra, *own, self.note,
                *((self.summary,) if self.summary is not None else ()))

    def _f_robustness(self, k: int) -> float | None:
        return None if self.cols["rob_tick"].item(k) == _NO_TICK else self.cols["rob"].item(k) + 0.0

    def _f_robustness_at(self, k: int) -> TimePoint | None:
        tick = self.cols["rob_tick"].item(k)
        if tick == _NO_TICK:
            return None
        lt = self.cols["rob_log_time"].item(k)
        return TimePoint(tick, self.times.item(self._i0(k) + tick), lt if lt >= 0 else None)

    def _f_margin(self, k: int) -> list[tuple[int, int, float]]:
        """The margin over time as :func:`fretc.audit.finalize` gives it (every tick, or the
        least of each run of ticks: :func:`fretc.monitors.robustness.margin_ticks`)."""
        if self.cols["rob_tick"].item(k) == _NO_TICK:
            return NO_EVIDENCE["margin"]
        a, m, i0 = self.cols["margin_at"].item(k), self.cols["length"].item(k), self._i0(k)
        margin = self.cols["margin"][a:a + m]
        times = self.times
        return [(i, int(times[i0 + i]), float(margin[i]))
                for i in margin_ticks(margin, MARGIN_POINTS)]


def _val(x: float) -> float | str:
    """A margin value as the audit JSON writes it (infinities and NaN as strings)."""
    if x != x:
        return "nan"
    if x in (math.inf, -math.inf):
        return "inf" if x > 0 else "-inf"
    return x


#: The fields an entity judged at once has as every other such entity has them
_CONSTANT: dict[str, Any] = {
    "partial": False, "first_violation": None, "warmup_ticks": 0, "engine": "vectorized",
    "error": None, "unknown_reason": None, "unknown_ticks": 0, "trials": None,
    "coverage": None, **NO_EVIDENCE}
_FIELDS = tuple(f.name for f in dataclasses.fields(Verdict))


class EntityVerdict:
    """The verdict of record ``i`` of ``block`` (module docstring): reads as a
    :class:`~fretc.audit.verdict.Verdict`; a change makes it one of its own
    (:meth:`verdict_of`) that every later read and change goes to."""

    # (``verdict`` kept as an attribute: the field every summary reads, several times a
    # verdict; one of two shared strings)
    __slots__ = ("_b", "_i", "_own", "verdict")
    _b: EntityBlock
    _i: int
    _own: Verdict | None
    verdict: str

    def __init__(self, block: EntityBlock, i: int) -> None:
        object.__setattr__(self, "_b", block)
        object.__setattr__(self, "_i", i)
        object.__setattr__(self, "_own", None)
        object.__setattr__(self, "verdict", block.words[i])

    def verdict_of(self) -> Verdict:
        """This verdict as a :class:`~fretc.audit.verdict.Verdict` (its own once changed,
        else a new one each call); the notes a list of its own."""
        if self._own is not None:
            return self._own
        b, i = self._b, self._i
        values = {name: b.field(name, i) for name in _FIELDS}
        values["notes"] = list(values["notes"])
        return Verdict(**values)

    def __setattr__(self, name: str, value: Any) -> None:
        if self._own is None:
            own = self.verdict_of()
            for k, v in NO_EVIDENCE.items():  # (containers of its own: it may change them)
                setattr(own, k, {} if isinstance(v, dict) else [])
            own.margin = list(self._b.field("margin", self._i))
            object.__setattr__(self, "_own", own)
        setattr(self._own, name, value)
        if name == "verdict":
            object.__setattr__(self, "verdict", value)

    def to_json(self, start: int | None, time_base: str | None = None) -> dict:
        """As :meth:`fretc.audit.verdict.Verdict.to_json` (:meth:`EntityBlock.json`: no
        verdict made whole)."""
        if self._own is not None:
            return self._own.to_json(start, time_base)
        return self._b.json(self._i, start)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, EntityVerdict):
            other = other.verdict_of()
        return self.verdict_of() == other

    __hash__ = None  # type: ignore[assignment]  # (as Verdict: equal by value, mutable)

    def __repr__(self) -> str:
        return repr(self.verdict_of())

    def __reduce__(self) -> tuple:
        return (_rebuild, (self._b, self._i, self._own))


def _rebuild(block: EntityBlock, i: int, own: Verdict | None) -> EntityVerdict:
    v = EntityVerdict(block, i)
    if own is not None:
        object.__setattr__(v, "_own", own)
    return v


def _reader(name: str) -> property:
    """The property of field ``name`` (the block's record, or the verdict of its own once
    changed): a constant returned as it is, a computed field by its block's method bound
    once (no lookup by name at each read: a summary reads 10^6 verdicts' fields)."""
    doc = f"The verdict's ``{name}`` (:class:`~fretc.audit.verdict.Verdict`)."
    if not hasattr(EntityBlock, "_f_" + name):
        value = _CONSTANT[name]

        def constant(self: EntityVerdict) -> Any:
            own = self._own
            return value if own is None else getattr(own, name)
        return property(constant, doc=doc)
    compute = getattr(EntityBlock, "_f_" + name)

    def get(self: EntityVerdict) -> Any:
        own = self._own
        return compute(self._b, self._i) if own is None else getattr(own, name)
    return property(get, doc=doc)


for _name in _FIELDS:
    if _name != "verdict":  # (a slot of its own)
        setattr(EntityVerdict, _name, _reader(_name))
