"""One verdict per entity (docs/bindings.md, "One verdict per entity"): a requirement whose
variables read an entity of the binding file's ``[entities]`` table (``$track`` in a filter,
``{id==$track}``) is judged once for every value of the entity's key that appears in the log
(first-order monitoring's universal quantifier over the trace's objects, as DejaVu and
MonPoly have it; FRET's parameterised requirements over N identical components). Each
instance is an ordinary verdict named ``R[track=7]`` with its evidence, judged on the
entity's life (:mod:`fretc.audit.entities.read`: every entity of every per-entity requirement
in one read of the log); a summary over the entities is added to each instance's notes.

Design notes: ARCHITECTURE.md, `audit/entities/log.py`."""

from __future__ import annotations

import dataclasses
import re
from typing import Any, cast

import numpy as np

from fretc.audit.entities.batch import batchable, judge_at_once
from fretc.audit.entities.columns import EntityColumns, column as _column
from fretc.audit.entities.kinds import entity_kind
from fretc.audit.entities.read import ENTITIES, EntityClock, read_entities
from fretc.audit.entities.runs import TickRuns
from fretc.audit.entities.summary import summary_note, summary_verdict
from fretc.audit.entities.verdicts import EntityVerdict
from fretc.audit.finalize import finalize
from fretc.audit.gaps import inner_gaps, merged_gaps, split_bridged
from fretc.audit.log_problems import collect_problems, problem_json
from fretc.audit.columns import ClockPass
from fretc.audit.passes import cut_at_damage, lost_in_words, mark_gaps
from fretc.audit.verdict import LogAudit, Verdict
from fretc.common.problems import FretcInputError
from fretc.common.streams import base_topic, log_topics
from fretc.logs import open_log
from fretc.logs.allowance import with_allowance
from fretc.signals.bindings import Bindings
from fretc.signals.bindings.expression import TF_TOPICS, EntityParam

__all__ = ["MAX_ENTITIES", "DEFAULT_MAX_ENTITIES", "entity_of_requirements", "audit_entities",
           "entity_passes", "summary_verdict", "summary_note"]

#: Entities of one key that ``fretc watch`` steps live (their messages replayed into a
#: monitor of their own while watching); its final verdicts are the audit's, unbounded.
MAX_ENTITIES = 1000
#: Entities of one per-entity requirement judged in one log unless ``--max-entities`` says
#: otherwise (each costs a few hundred bytes while the log is read).
DEFAULT_MAX_ENTITIES = 1_000_000

#: The start of the error of every per-entity requirement when the log cannot be opened.
NOT_AUDITED = "log not audited: "

#: Whether the robustness of the entities the batch finds violated is passed to their
#: judgement one at a time (False: computed again there, the reference the tests compare
#: it with)
BATCH_ROBUSTNESS = True


_DOLLAR = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


def _entities_read(bindings: Any, name: str, seen: set[str]) -> set[str]:
    """The entities a per-entity variable reads, directly (``$track``) or through the
    per-entity variables it refers to."""
    if name in seen:
        return set()
    seen.add(name)
    expr = bindings.per_entity[name][0]
    out = set(_DOLLAR.findall(expr)) & set(bindings.entities)
    for other in bindings.per_entity:
        if other != name and re.search(rf"(?<![\w/.$]){re.escape(other)}(?!\w)", expr):
            out |= _entities_read(bindings, other, seen)
    return out


def entity_of_requirements(plan: Any) -> dict[int, list[str]]:
    """Requirement index -> the entities its variables read (sorted), for the requirements
    of ``plan`` that read one."""
    b = plan.bindings
    if b is None or not b.per_entity:
        return {}
    out = {}
    for r in plan.requirements:
        names: set[str] = set()
        for v in r.variables:
            if v in b.per_entity:
                names |= _entities_read(b, v, set())
        if names:
            out[r.index] = sorted(names)
    return out


def audit_entities(plan: Any, path: str, progress: Any, run: Any) -> LogAudit:
    """Audit ``plan`` on the log at ``path`` with its per-entity requirements instantiated per
    entity (module docstring); ``run(plan, path, progress)`` audits a plan (the plain audit).

    Returns:
        the log's audit: the other requirements' verdicts, then per requirement its verdict
        over all entities (named as the requirement: violated when one entity violates it,
        satisfied when all satisfy it) and one verdict per entity in order of first
        appearance (none appeared: one ``vacuous`` verdict saying so; an error: one ``error``
        verdict naming it).
    """
    groups = entity_of_requirements(plan)
    plain = [r for r in plan.requirements if r.index not in groups]
    la = run(dataclasses.replace(plan, requirements=plain), path, progress) if plain else None
    if la is None:
        la = LogAudit(log=path)
    extra = _Entities(plan, path, la).judge([r for r in plan.requirements
                                             if r.index in groups], groups)
    la.verdicts = la.verdicts + extra
    return la


def entity_passes(plan: Any, path: str, keep: Any) -> tuple[LogAudit, dict[str, Any]]:
    """The audit of the per-entity requirements of ``plan`` on the log at ``path`` and what
    each entity was judged on: ``keep(r, pass)`` of its :class:`~fretc.audit.columns.ClockPass`
    by the entity's verdict's name (``R[track=7]``; none for an entity with no tick). For
    ``--write-csv`` (:mod:`fretc.audit.sampled.entities`).

    Returns:
        (the log's audit of the per-entity requirements alone, what ``keep`` returned); the
        audit's verdicts are :func:`audit_entities`' (per requirement its summary, then its
        entities).
    """
    groups = entity_of_requirements(plan)
    la = LogAudit(log=path)
    ents = _Entities(plan, path, la, keep=keep)
    la.verdicts = ents.judge([r for r in plan.requirements if r.index in groups], groups)
    return la, ents.kept


class _Entities:
    """The per-entity requirements of one log: checked, read once, judged (``keep``: what
    :func:`entity_passes` keeps of each entity's pass, in :attr:`kept`)."""

    def __init__(self, plan: Any, path: str, la: LogAudit, keep: Any = None) -> None:
        self.plan, self.path, self.la = plan, path, la
        self.bound = getattr(plan.config, "max_entities", None) or DEFAULT_MAX_ENTITIES
        self.keep = keep
        self.kept: dict[str, Any] = {}

    def alone(self, r: Any, verdict: str, **kw: Any) -> list[Verdict]:
        return [Verdict(log=self.path, requirement=r.id, text=r.text, source=r.source,
                        verdict=verdict, **kw)]

    def judge(self, rs: list, groups: dict[int, list[str]]) -> list[Verdict]:
        """Every per-entity requirement's verdicts, in ``rs`` order."""
        out: dict[int, list[Verdict]] = {}
        try:
            b = self.plan.bindings
            source = with_allowance(open_log(self.path, msg_path=self.plan.config.msg_path),
                                    b.allowance if b is not None else None)
            available = source.topics()
        except (FretcInputError, OSError) as exc:
            return [v for r in rs for v in self.alone(r, "error", error=f"{NOT_AUDITED}{exc}")]
        clocks: dict[int, tuple[str, list[str]]] = {}
        for r in rs:
            why = self._cannot(r, groups[r.index], available, source)
            if why is not None:
                out[r.index] = why
            else:
                clocks[r.index] = (groups[r.index][0], list(r.variables))
        if clocks:
            self._read(source, rs, clocks, out)
        return [v for r in rs for v in out[r.index]]

    def _cannot(self, r: Any, names: list[str], available: Any, source: Any
                ) -> list[Verdict] | None:
        """The verdicts of a requirement that cannot be read (else None): an error before
        the log (its own), two kinds of entity, a topic not in the log (``unknown`` when
        the damage may have taken it)."""
        if r.error is not None:
            return self.alone(r, "error", error=r.error)
        if len(names) != 1:
            return self.alone(r, "error", error=f"{r.id} reads the entities {', '.join(names)}"
                              ": a requirement is judged per entity of one key")
        b = self.plan.bindings
        missing = [v for v in r.variables if v not in b.variables and v not in b.per_entity]
        if missing:
            return self.alone(r, "error", error=f"no binding for {', '.join(map(repr, missing))}"
                              f" in bindings ({b.source})")
        try:
            key_topics = _key_topics(b, names[0])
            own = b.for_entity({names[0]: EntityParam(names[0])}).variables
        except Exception as exc:  # noqa: BLE001 - a binding that does not compile: its error
            return self.alone(r, "error", error=str(exc))
        has = f"(it has {', '.join(available) or 'no topics'})"
        absent = sorted(t for t in log_topics(key_topics) if t not in available)
        if absent:
            why = (f"topic {', '.join(absent)} (the key {b.entities[names[0]][0]} of entity "
                   f"{names[0]}) is not in the log {has}: no entity was looked for")
        else:
            tf = set(TF_TOPICS) if set(TF_TOPICS) & set(available) else set()  # (one of
            # them is enough: a log from before tf2 has no /tf_static)
            absent = sorted({t for v in r.variables for t in log_topics(own[v].topics)
                             if t not in available and t not in tf})
            if not absent:
                return None
            why = f"topic {', '.join(absent)} (bound to {r.id}'s variables) is not in the log {has}"
        if source.partial:
            return self.alone(r, "unknown", unknown_reason=f"{why}; the log is damaged: "
                              "the damage may have taken it", partial=True)
        return self.alone(r, "error", error=why)

    def _read(self, source: Any, rs: list, clocks: dict[int, tuple[str, list[str]]],
              out: dict[int, list[Verdict]]) -> None:
        """One read for the requirements of ``clocks``, then each judged into ``out``."""
        try:
            made, ticks, errors = read_entities(source, self.plan.bindings, clocks, self.bound)
        except Exception as exc:  # noqa: BLE001 - a binding or signal error: every one's error
            for r in rs:
                out.setdefault(r.index, self.alone(r, "error", error=str(exc)))
            return
        self._record(source, made)
        gaps, _bridged = split_bridged(inner_gaps(source), self.plan.config.bridge_gaps_ns)
        for r in rs:
            if r.index not in clocks:
                continue
            c = made[r.index]
            err = errors.get(r.index) or next(iter(c.failed.values()), None)
            if err is not None:
                out[r.index] = self.alone(r, "error", error=str(err))
                continue
            out[r.index] = _Judge(self, r, clocks[r.index][0], c, ticks[r.index], source,
                                  gaps).verdicts()

    def _record(self, source: Any, made: dict[int, EntityClock]) -> None:
        """The log's figures from the read (when no plain requirement read it already)."""
        la = self.la
        la.kind = la.kind or source.kind
        la.partial = la.partial or bool(source.partial)
        if la.damage_time_ns is None:
            la.damage_time_ns = source.damage_time
        la.damage_cut = la.damage_cut or bool(source.damage_cut)
        la.cut_time_ns = la.cut_time_ns if la.cut_time_ns is not None else source.cut_start
        for t, n in source.counts.items():
            la.messages[t] = max(la.messages.get(t, 0), n)
        problems: dict = {}
        counts: dict[str, int] = {}
        for c in made.values():
            collect_problems(source, c.s, problems, counts)
        seen = {(p["kind"], p["topic"], p["log_time_ns"], p["detail"]) for p in la.problems}
        la.problems += [problem_json(p) for k, p in problems.items() if k not in seen]
        for k, n in counts.items():
            la.problem_counts[k] = max(la.problem_counts.get(k, 0), n)
        if not la.gaps:
            kept, bridged = split_bridged(inner_gaps(source),
                                          self.plan.config.bridge_gaps_ns)
            la.gaps = merged_gaps(kept, bridged)
        starts = [t for t in (la.start_time_ns, source.start_time) if t is not None]
        la.start_time_ns = min(starts) if starts else None
        la.end_time_ns = la.end_time_ns if la.end_time_ns is not None else source.end_time
        if not la.tick and self.plan.bindings is not None:
            b = self.plan.bindings
            la.tick = ({"period_ns": b.tick.period_ns} if b.tick.period_ns
                       else {"topic": b.tick.topic})
            la.time_base = b.time_base
        if self.plan.bindings is not None and self.plan.bindings.allowance:
            la.allowance_ns = dict(sorted(self.plan.bindings.allowance.items()))


def _key_topics(bindings: Bindings, name: str) -> frozenset[str]:
    return entity_kind(bindings, name).binding.topics


class _Judge:
    """One per-entity requirement's verdicts from its clock's read: each entity's trace
    (its life, :mod:`fretc.audit.entities.read`) judged as a plain requirement's clock."""

    def __init__(self, ents: _Entities, r: Any, name: str, c: EntityClock, ticks: list,
                 source: Any, gaps: list) -> None:
        self.ents, self.r, self.name, self.c, self.source, self.gaps = (
            ents, r, name, c, source, gaps)
        c.table.index = {}  # (the keys' index served the read: let go before the columns)
        own = [b.name for b in c.own]
        self.rows: EntityColumns | None = None
        if c.lean:  # (its ticks are runs: no plain variable, an array key)
            self.times = c.runs.times()
            self.plain: dict[str, np.ndarray] = {}
            self.log_times = c.runs.log_time_columns()
            self.rows = (c.runs.columns(own, c.absent_once, len(c.table.keys))
                         if c.absent_once is not None else
                         EntityColumns([], own, ENTITIES, len(c.table.keys)))
        else:
            self.times = np.array([t.time for t in ticks], dtype=np.int64)
            self.plain = {b.name: _column([t.values.get(b.name) for t in ticks])
                          for b in c.variables}
            topics = sorted({tp for t in ticks for tp in t.log_times})
            self.log_times = {tp: np.array([t.log_times.get(tp, -1) for t in ticks],
                                           np.int64) for tp in topics}
            if not c.kind.stream:
                self.rows = EntityColumns(ticks, own, ENTITIES, len(c.table.keys))
        # (what the read kept that the columns now hold, and the keys' index, are let go
        # before the judgement: 10^6 entities' runs, rows and index are hundreds of MB)
        c.runs = TickRuns(c.period or 0)
        self.lives: tuple[np.ndarray, np.ndarray] | None = None  # first, last times
        #: entity -> the robustness of its trace computed with the others' (the batch), and
        #: its LTL3 verdict, tick and ticks
        self.robs: dict[int, Any] = {}
        self.ltl3s: dict[int, tuple[str, int | None, int]] = {}
        #: entity -> its messages (one-value keys; array keys held on their own): (time,
        #: its values (one-value keys), log time)
        self.records: dict[int, list[tuple[int, tuple, int]]] = {}
        for i, tm, vals, lt in c.table.rows:
            self.records.setdefault(i, []).append((tm, vals, lt))
        self.held = c.kind.held
        #: entities of an array key read at no tick of their life (each message that
        #: carried them superseded before a tick): their values were never read
        self.unread = self._unread()
        #: the records of the entities judged at once (:mod:`fretc.audit.entities.verdicts`)
        self.block: Any = None
        self.bindings = Bindings({**{b.name: b for b in c.variables},
                                  **{b.name: b for b in c.own}},
                                 ents.plan.bindings.tick, ents.plan.bindings.time_base,
                                 ents.plan.bindings.header_lag_ns, ents.plan.bindings.source)

    def verdicts(self) -> list[Verdict]:
        ents, r, c = self.ents, self.r, self.c
        table, key = c.table, c.kind.key
        if not table.keys:
            return ents.alone(r, "vacuous", notes=[f"no entity {self.name} ({key}) appeared in "
                                                   "the log: the requirement holds of none"])
        fast = self._batch()  # (entity -> its record, -1: judged alone)
        block = self.block
        out: list[Verdict] = [  # (a record reads as a Verdict: audit/entities/verdicts.py)
            self._one(i) if k < 0 else cast(Verdict, EntityVerdict(block, k))
            for i, k in enumerate(fast.tolist())]
        if ents.keep is not None:  # (what the entities judged at once were judged on)
            for i in np.flatnonzero(fast >= 0).tolist():
                i0, i1 = self._range(i)
                ents.kept[out[i].requirement] = ents.keep(r, self._pass(i, i0, i1))
        summary = summary_note(r.id, self.name, out)
        if self.block is not None:  # (the records' notes end with it)
            self.block.summary = summary
        for v in out:
            if type(v) is Verdict:
                v.notes.append(summary)
        if table.cut:  # the entities left unjudged: a verdict of their own, never named r.id
            rest = ents.alone(r, "error", error=(
                f"more than {ents.bound:,} entities {self.name} ({key}) in the log: only the "
                f"first {ents.bound:,} are judged (raise the bound with --max-entities)"))
            rest[0].requirement = f"{r.id}[{self.name}=...]"
            out += rest
        return [summary_verdict(r, ents.path, out, summary)] + out

    def _new(self, i: int) -> Verdict:
        """Entity ``i``'s verdict, not yet judged."""
        r, table, value = self.r, self.c.table, self.c.table.keys[i]
        seen = (f"entity {self.name} = {value!r} ({self.c.kind.key}): first seen at "
                f"log time {table.first[i]}, last at {table.last[i]}")
        rid = f"{r.id}[{self.name}={value}]"
        return Verdict(self.ents.path, rid, r.text, r.source, notes=[*r.notes, seen])

    def _own_log_times(self, i: int, times: np.ndarray, log_times: dict) -> None:
        """The log time held at each tick of ``times`` on the key's topic, for entity ``i``
        read in its own messages (one-value keys; held on their own): its newest message's,
        not the topic's newest (another entity's), so that its evidence names the message
        that decided it."""
        rec = self.records.get(i)
        if not rec:
            return
        rt = np.array([r[0] for r in rec], dtype=np.int64)
        lt = np.array([r[2] for r in rec], dtype=np.int64)
        k = np.searchsorted(rt, times, side="right") - 1
        own = np.where(k >= 0, lt[np.maximum(k, 0)], -1)
        key = base_topic(self.c.kind.topic)  # (the topic, and its streams the variables
        # read: "PARM"{Name==$param})
        names = ({t for t in log_times if base_topic(t) == key}
                 | {t for b in self.c.own for t in b.topics if base_topic(t) == key})
        for name in names or {key}:
            log_times[name] = own

    def _unread(self) -> set[int]:
        """The entities (indexes) of an array key read in the message held at the tick
        that no tick of their life read (:attr:`unread`): none for one-value keys and
        entities read at every tick (held on their own, ``tf()``)."""
        c = self.c
        rows = self.rows
        n, m = len(self.times), len(c.table.keys)
        if c.kind.stream or self.held or rows is None or not m or not n or any(
                b.uses_tf for b in c.own):
            return set()
        i0, i1 = self._ranges(list(range(m)))
        e, k = rows.entity, rows.tick
        inside = (k >= i0[e]) & (k <= i1[e])
        read = np.bincount(e[inside], minlength=m)
        return set(np.flatnonzero((read == 0) & (i0 < n)).tolist())

    def _range(self, i: int) -> tuple[int, int]:
        """Entity ``i``'s ticks ``i0..i1`` (its life; ``i0`` past the end: none)."""
        i0, i1 = self._ranges([i])
        return int(i0[0]), int(i1[0])

    def _ranges(self, which: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """The ticks ``i0..i1`` of the entities ``which`` (:meth:`_range`), as arrays."""
        n = len(self.times)
        at = np.asarray(which, np.int64)
        if self.lives is None:
            self.lives = (np.asarray(self.c.table.first, np.int64),
                          np.asarray(self.c.table.last, np.int64))
        first, last = self.lives[0][at], self.lives[1][at]
        i0 = np.searchsorted(self.times, first, side="left").astype(np.int64)
        if self.held:  # (held to the clock's last tick)
            return i0, np.full(len(at), n - 1, np.int64)
        return (i0, np.minimum(np.searchsorted(self.times, last, side="left"),
                               n - 1).astype(np.int64))

    def _batch(self) -> np.ndarray:
        """The entities judged at once (:func:`fretc.audit.entities.batch.judge_at_once`):
        satisfied or vacuous ones on a log without damage, as records of :attr:`block`;
        entity -> its record (-1: judged one at a time)."""
        trig = batchable(self.ents.plan, self.r)
        if trig is None:
            return np.full(len(self.c.table.keys), -1, np.int64)
        return judge_at_once(self, trig, BATCH_ROBUSTNESS)

    def _own_columns(self, judged: list[int], i0s: np.ndarray, firsts: np.ndarray,
                     lengths: np.ndarray, idx: np.ndarray) -> dict[str, np.ndarray]:
        """The per-entity variables of the entities ``judged`` laid end to end."""
        c = self.c
        own = [b.name for b in c.own]
        if c.kind.stream:
            vals: list[list] = [[] for _ in own]
            for e, i in enumerate(judged):
                rec = self.records[i]
                rt = np.array([r[0] for r in rec], dtype=np.int64)
                a, m = int(i0s[e]), int(lengths[e])
                at = np.maximum(np.searchsorted(rt, self.times[a:a + m], side="right") - 1, 0)
                for j in range(len(own)):
                    vals[j] += [rec[k][1][j] for k in at.tolist()]
            return {name: _column(vals[j]) for j, name in enumerate(own)}
        assert self.rows is not None  # (an array key)
        return self.rows.end_to_end(judged, i0s, firsts, lengths, idx)

    def _one(self, i: int) -> Verdict:
        """Entity ``i``'s verdict."""
        r, c, ents = self.r, self.c, self.ents
        v = self._new(i)
        first = c.table.first[i]
        if i in c.table.errors and not c.kind.stream:
            v.verdict, v.error = "error", str(c.table.errors[i])
            return v
        n = len(self.times)
        i0, i1 = self._range(i)
        if i0 >= n:
            v.verdict = "error"
            v.error = (f"no tick evaluated at or after its first message (log time {first})"
                       + (f": waiting for {', '.join(c.s.missing_topics)}"
                          if c.s.missing_topics else ""))
            return v
        res = self._pass(i, i0, i1)
        unread = i in self.unread
        if unread:  # (its values unknown at every tick: never read)
            for b in c.own:
                res.unknown[b.name] = np.ones(len(res.times), np.bool_)
        if ents.keep is not None:
            ents.kept[v.requirement] = ents.keep(r, res)
        v.ticks_evaluated = len(res.times)
        v.first_tick_ns, v.last_tick_ns = int(self.times[i0]), int(self.times[i1])
        if res.cut:
            v.last_tick_ns = int(res.times[-1]) if len(res.times) else None
        ri = dataclasses.replace(r, id=v.requirement)
        finalize(ents.plan, ri, res, self.bindings, v, ents.la, rob=self.robs.get(i),
                 ltl3=self.ltl3s.get(i))
        if v.error is not None:
            v.verdict = "error"
        v.partial = ents.la.partial and v.error is None
        if unread:
            self._unread_said(i, v)
        return v

    def _unread_said(self, i: int, v: Verdict) -> None:
        """What ``v``, the verdict of entity ``i`` read at no tick (:attr:`unread`), says of
        it: its reason when unknown, else a note (decided whatever its values)."""
        c = self.c
        why = (f"entity {self.name} = {c.table.keys[i]!r} was read at no tick: the messages "
               f"of {c.kind.topic} that carried it ({c.kind.key}, from log time "
               f"{c.table.first[i]} to {c.table.last[i]}) were each superseded before a "
               "tick, and a tick reads the message held; to read each entity in its own "
               f"newest message, write [entities] {self.name} = {{ key = \"{c.kind.key}\", "
               "hold = \"entity\" }")
        if v.verdict == "unknown":
            v.unknown_reason = why
        else:
            v.notes.append(why + f": {v.verdict} whatever its values")

    def _pass(self, i: int, i0: int, i1: int) -> ClockPass:
        """Entity ``i``'s clock pass over ticks ``i0..i1`` (the damage's cut and gaps)."""
        c, sl = self.c, slice(i0, i1 + 1)
        times = self.times[sl]
        columns = {k: col[sl] for k, col in self.plain.items()}
        own = [b.name for b in c.own]
        if c.kind.stream:
            rec = self.records[i]
            rt = np.array([r[0] for r in rec], dtype=np.int64)
            at = np.maximum(np.searchsorted(rt, times, side="right") - 1, 0)
            for j, name in enumerate(own):
                columns[name] = _column([rec[k][1][j] for k in at.tolist()])
        else:
            assert self.rows is not None  # (an array key)
            columns.update(self.rows.trace(i, i0, i1))
        log_times = {k: lt[sl] for k, lt in self.log_times.items()}
        if c.kind.stream or self.held:
            self._own_log_times(i, times, log_times)
        res = ClockPass(c.s, times, columns, log_times)
        topics = frozenset(t for b in self.bindings.variables.values() for t in b.topics)
        cut_at_damage(res, self.source, self.bindings, topics)
        mark_gaps(res, list(columns), self.bindings, self.gaps, topics,
                  lost_in_words(self.source, log_topics(topics)))
        return res
