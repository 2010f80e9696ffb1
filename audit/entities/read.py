"""One read of a log for every per-entity requirement and every entity
(docs/bindings.md, "One verdict per entity"): :func:`read_entities`.

Design notes: ARCHITECTURE.md, `audit/entities/read.py`."""

from __future__ import annotations

from collections.abc import Iterator
from fnmatch import fnmatchcase
from itertools import chain
from typing import Any, cast

import numpy as np

from fretc.audit.entities import runs as entity_runs
from fretc.audit.entities.columns import HeldRows, RowBlock, floats
from fretc.audit.entities.kinds import (EntityKind, EntityTable, check_stream, clock_topics,
                                        entity_kind, key_items, own_bindings)
from fretc.audit.entities.rows import (item_values, key_reader, reads_items_of, row_fields,
                                       row_values)
from fretc.audit.entities.runs import TickRuns, grid_run, lean_messages
from fretc.common.problems import SignalError
from fretc.common.streams import base_topic, log_topics
from fretc.logs.ros.selective import install as install_selective
from fretc.signals.bindings import Bindings
from fretc.signals.bindings.binding import Binding
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.expression import EntityParam, Filter
from fretc.signals.bindings.extract import by_entity
from fretc.signals.bindings.spec import grid_end, grid_start
from fretc.signals.bindings.frames import TfBuffer, frame_name
from fretc.signals.clock import (Clock, HeaderBuffer, Sampling, Tick, check_topics, present_tf,
                                 silence_end)
from fretc.signals.columns import Irregular
from fretc.signals.streams import Streams
from fretc.signals.tick_windows import with_tick_windows

__all__ = ["EntityKind", "EntityClock", "entity_kind", "read_entities"]

#: the key of a tick's values holding its per-entity values (never a FRET variable's name)
ENTITIES = "\x00entities"
_ABSENT = object()  # the key of no entity: a filter on it keeps nothing
#: Held key messages whose rows are evaluated at once (vectorized path): few, so that the
#: decoded messages waiting for their batch are few (4,096: 3.3 s against 2.9 s for 100,000
#: entities, ``bench/bench_audit.py --entities``; 3.0 s against 2.7 s with the garbage
#: collector off: the collections that walk them and the memory they hold)
BATCH = 256
#: (entity, tick) values a clock reads its entities met so far at every tick for (held on
#: their own, or through tf()): past it, the requirement is an error saying so rather than
#: a read whose memory grows with entities times ticks (about 100 bytes a value)
MAX_EVERY_ROWS = 5_000_000
#: Whether the per-entity variables that can be are evaluated over rows by numpy
#: (:mod:`fretc.audit.entities.rows`); False: each at each tick (the reference, for tests)
VECTORIZED = True
#: Whether a clock of a tick period without plain variables records its ticks as runs
#: (:mod:`fretc.audit.entities.runs`); False: tick by tick (the reference, for tests)
LEAN = True


class EntityClock(Clock):
    """A per-entity requirement's clock (module docstring): the :class:`Clock` of its plain
    variables, the entities of ``kind`` met in its key's messages, and at each evaluated
    tick, under :data:`ENTITIES` in the tick's values, the per-entity values
    ``(absent values, [(entity, values)])``."""

    def __init__(self, s: Sampling, plain: list[Binding], required: set[str], tick: Any,
                 kind: EntityKind, own: list[Binding], param: EntityParam, bound: int,
                 vectorized: bool = True) -> None:
        super().__init__(s, plain, required, tick, keep_going=True)
        self.kind, self.own, self.param, self.bound = kind, own, param, bound
        if self.state.tf is None and any(b.uses_tf for b in own):  # tf($car): every
            self.state.tf = TfBuffer()  # transform, each frame its newest
        if self.silence_end is None:  # age($car): the clock ticks to the log's end
            self.silence_end = silence_end(s.source, s.bindings, own)
        self.table = EntityTable()
        #: every entity met so far is read at each tick (not only those of the held key
        #: message): held on their own, or read through tf() (each frame in the TF buffer)
        self.held = kind.held
        self.every = self.held or any(b.uses_tf for b in own)
        #: held on their own: entity -> its newest key message (data, time, log time)
        self.newest: dict[int, tuple[Any, int, int]] = {}
        self.every_rows = 0  # (entity, tick) values read so far (MAX_EVERY_ROWS)
        self.key_state = EvalState()
        self.present: dict[int, list[int]] = {}  # id(held key message) -> its entities
        self.stream_state = EvalState()
        #: the absent values once computed, when they cannot depend on the message (every
        #: field read through a filter on the entity's key: nothing is left of it)
        self.absent_once: tuple | None = None
        self.static_absent = all(
            f.topic == kind.topic and any(isinstance(p, Filter) and by_entity(p) for p in f.path)
            for b in own for f in b.fields) and not any(b.uses_tf for b in own)
        #: the vectorized path (:mod:`fretc.audit.entities.rows`): the item fields of the
        #: per-entity variables when they are functions of the key's message and the
        #: entity alone (None: each evaluated at each tick, the reference)
        self.rows_of = (row_fields(own, kind.topic) if self.static_absent and not kind.stream
                        and not self.every and vectorized else None)
        #: vectorized: id of a held key message -> its rows (set by its batch), and the
        #: held messages waiting for their batch ``(message, entities, rows)``
        self.msg_rows: dict[int, HeldRows] = {}
        self.batch: list[tuple[Any, list[int], HeldRows, list | None]] = []
        self.evaluated = [0, 0]  # rows evaluated vectorized, by the reference
        # (frame names: read by _keys, which strips their slash as tf2 does)
        self.read_keys = key_reader(kind.binding) if vectorized and not kind.frames else None
        #: the rows of a held message are its items (:func:`~fretc.audit.entities.rows.
        #: reads_items_of`), and the items of the held message when its entities were
        #: read from them in order (:func:`fretc.audit.entities.runs.lean_messages`)
        self.items_rows = self.rows_of is not None and reads_items_of(self.rows_of,
                                                                       self.read_keys)
        self.held_items: list | None = None
        self.key_topics = frozenset({base_topic(kind.topic), kind.topic})
        #: a tick period and nothing evaluated per tick but the rows of the held key
        #: message: the ticks are recorded as runs in :attr:`runs`, none yielded
        #: (:mod:`fretc.audit.entities.runs`)
        self.lean = (LEAN and self.period is not None and self.tick_topic is None
                     and not self.variables and not self.window
                     and not self.sliding and not self.stateful and self.state.tf is None
                     and self.rows_of is not None)
        self.runs = TickRuns(self.period or 0)
        #: lean: the key's messages not yet recorded ``(t, log time, data)``
        self.waiting: list[tuple[int, int, Any]] = []

    def push(self, topic: str, t: int, log_time: int, data: Any) -> Iterator[Tick]:
        """Hold message ``data`` of ``topic`` at ``t`` after yielding the clock's ticks due
        before it, and record the entities it carries when it is the key's (iterate to the
        end)."""
        if self.lean:
            self._lean_push(topic, t, log_time, data)
            return iter(())
        return self._push(topic, t, log_time, data)

    def _push(self, topic: str, t: int, log_time: int, data: Any) -> Iterator[Tick]:
        if topic in self.fed:
            yield from super().push(topic, t, log_time, data)
        if topic in self.key_topics:
            self._key_message(topic, t, log_time, data)

    def _lean_push(self, topic: str, t: int, log_time: int, data: Any) -> None:
        """:meth:`push` of a clock of a tick period without plain variables
        (:attr:`lean`): the key's messages wait to be recorded by batch
        (:func:`fretc.audit.entities.runs.lean_messages`: the ticks between them as runs in
        :attr:`runs`, none yielded)."""
        if topic == self.kind.topic and topic in self.fed and entity_runs.LEAN_BATCH:
            self.waiting.append((t, log_time, data))
            if len(self.waiting) >= entity_runs.LEAN_BATCH:
                lean_messages(self)
            return
        if self.waiting:
            lean_messages(self)
        self._lean_one(topic, t, log_time, data)

    def _lean_one(self, topic: str, t: int, log_time: int, data: Any) -> None:
        """One message of :meth:`_lean_push`: the ticks due before it as one run
        (:func:`fretc.audit.entities.runs.grid_run`), then held."""
        if topic in self.fed:
            if self.next_grid is None:
                self.next_grid = grid_start(t, self.period)  # type: ignore[arg-type]
            if self.next_grid < t:
                grid_run(self, t)
            st = self.state  # (held as Clock.push holds it: nothing of a variable to keep)
            st.msgs[topic], st.times[topic], self.log_times[topic] = data, t, log_time
            self.held_items = None
            self.missing.discard(topic)
            if topic in self.counted:
                self.since[topic] = self.since.get(topic, 0) + 1
            self.last = t
        if topic in self.key_topics:
            self._key_message(topic, t, log_time, data)

    fed: frozenset[str] = frozenset()  # (set by read_entities: the topics the clock holds)

    def _key_message(self, topic: str, t: int, log_time: int, data: Any) -> None:
        """Record the entities a message of the key's topic carries (at ``t`` on the time
        base, ``log_time`` its log time, ns)."""
        got = self._key_entities(topic, t, data, log_time)
        if self.held:
            rows = self.table.rows
            for i in got:
                self.newest[i] = (data, t, log_time)
                rows.append((i, t, (), log_time))
        if not self.kind.stream:
            self._held_entities(data, got)

    def _key_entities(self, topic: str, t: int, data: Any, log_time: int = -1) -> list[int]:
        """The entities (indexes) a message of the key's topic at ``t`` (log time
        ``log_time``) carries, recorded in the table (one-value keys: with the entity's
        values).

        Raises:
            SignalError: its keys cannot be read."""
        kind = self.kind
        values = self.read_keys(data) if self.read_keys is not None else None
        if values is None:
            values = self._keys(topic, t, data)
        table, matching = self.table, kind.matching
        index, last = table.index, table.last
        got: list[int]
        if matching is None and not kind.stream:  # (a float key equal to an int finds it)
            found = list(map(index.get, values))
            if None in found:
                return self._new_keys(values, found, t)
            got = cast("list[int]", found)
            for k in got:
                last[k] = t
            return got
        got = []
        for x in values:
            if isinstance(x, float) and x.is_integer():
                x = int(x)
            if matching is not None and not fnmatchcase(str(x), matching):
                continue
            i = index.get(x)
            if i is not None:  # (an entity met before: its last message, as see() has it)
                last[i] = t
            else:
                i = table.see(x, t, self.bound)
                if i is None:
                    continue
            got.append(i)
            if kind.stream:
                self._stream_values(i, x, t, data, log_time)
        return got

    def _new_keys(self, values: list, found: list, t: int) -> list[int]:
        """The entities of keys ``values`` of a message at ``t`` (``found``: their index
        or None, looked up before), the new ones added to the table in order."""
        table, last = self.table, self.table.last
        got: list[int] = []
        for x, i in zip(values, found):
            if i is not None:
                last[i] = t
            else:
                if isinstance(x, float) and x.is_integer():
                    x = int(x)
                i = table.see(x, t, self.bound)
                if i is None:
                    continue
            got.append(i)
        return got

    def _held_entities(self, data: Any, got: list[int]) -> None:
        """Array keys: key message ``data`` carries the entities ``got`` (only the
        messages held or waiting for their tick are kept)."""
        if not self.pending and self.state.msgs.get(self.kind.topic) is data:  # (the rows
            # of no other message are needed)
            self.present, self.msg_rows = {id(data): got}, {}
            return
        keep = {id(self.state.msgs.get(self.kind.topic))} | {id(p[1]) for p in self.pending}
        self.present = {k: v for k, v in self.present.items() if k in keep}
        self.present[id(data)] = got
        self.msg_rows = {k: v for k, v in self.msg_rows.items() if k in keep}

    def _keys(self, topic: str, t: int, data: Any) -> list:
        """The keys a message of the key's topic carries, by the key's binding, read exactly
        where the key is a field path (:attr:`EntityKind.exact`: integers of any width as
        ints, so ``uint64`` ids 2**53 and 2**53 + 1 are two entities).

        Raises:
            SignalError: they cannot be read (named with the message's log time)."""
        kind, st = self.kind, self.key_state
        try:
            if kind.exact is not None:  # (a field path: its keys exact, no float64 between)
                return _frames(kind, key_items(kind.exact(data)))
            st.msgs[kind.topic], st.times[kind.topic], st.now = data, t, t
            st.values.clear()
            values = _frames(kind, key_items(kind.binding._scalar(st)))  # type: ignore[misc]
        except Exception as exc:  # noqa: BLE001 - an extractor's error, named with the message
            raise SignalError(f"[entities] {kind.name}: {kind.key} cannot be read from the "
                              f"message of {kind.topic} at log time {t}: {exc}") from None
        return values

    def _stream_values(self, i: int, key: Any, t: int, data: Any, log_time: int) -> None:
        """One-value keys: entity ``i``'s variables on its message ``data`` at ``t`` (log
        time ``log_time``)."""
        st = self.stream_state
        for b in self.own:
            for f in b.fields:
                st.msgs[f.topic], st.times[f.topic] = data, t
        st.now = t
        self.table.rows.append((i, t, self._values(st, key, i), log_time))

    def _values(self, st: EvalState, key: Any, i: int | None) -> tuple:
        """The per-entity variables with the entity's key ``key`` (NaN where one fails; the
        first failure of entity ``i`` kept)."""
        self.param.value = key
        out = []
        for b in self.own:
            st.values.clear()  # (the extraction memo does not know the key)
            try:
                with np.errstate(all="ignore"):
                    out.append(b.evaluate(st))
            except SignalError as exc:
                if i is not None and i not in self.table.errors:
                    self.table.errors[i] = exc
                out.append(float("nan"))
        st.values.clear()
        return tuple(out)

    def _emit(self, t: int) -> Tick | None:
        tick = super()._emit(t)
        if tick is None:
            return None
        tick.values[ENTITIES] = self._entity_values()  # type: ignore[assignment]
        return tick

    def _entity_values(self) -> tuple[tuple, Any]:
        """The per-entity values at the tick being made: ``(absent values, rows)``."""
        st = self.state
        absent = self.absent_once
        if absent is None:
            absent = self._absent(st) if not self.kind.stream else ()
            if self.static_absent:
                self.absent_once = absent
        rows: list = []
        if not self.kind.stream:
            held = st.msgs.get(self.kind.topic)
            got = self.present.get(id(held), ()) if held is not None else ()
            if self.rows_of is not None:
                if got:  # the held message's rows, shared by the ticks that hold it
                    rows = self.msg_rows.get(id(held))  # type: ignore[assignment]
                    if rows is None:
                        rows = self.msg_rows[id(held)] = self.held_rows(held, got,
                                                                        self.held_items)
            elif self.every:
                rows = self._every_row(st)
            else:
                for i in got:
                    rows.append((i, self._values(st, self.table.keys[i], i)))
        return absent, rows

    def _every_row(self, st: EvalState) -> list:
        """The rows of every entity met so far (:attr:`every`): held on their own, each
        read in its newest key message (that message held on the key's topic, ``age($car)``
        its age); else in the messages held at the tick (``tf()``: its frame's newest
        transform)."""
        keys = self.table.keys
        self.every_rows += len(keys)
        if self.every_rows > MAX_EVERY_ROWS:
            raise SignalError(
                f"the entities {self.kind.name} ({self.kind.key}) are read at every tick "
                f"({'held on their own' if self.held else 'through tf()'}): more than "
                f"{MAX_EVERY_ROWS:,} (entity, tick) values ({len(keys):,} entities at tick "
                f"{self.index}); narrow them with matching = \"GLOB\" in [entities], or "
                "audit a shorter log")
        if not self.held:
            return [(i, self._values(st, keys[i], i)) for i in range(len(keys))]
        topic, param, newest = self.kind.topic, self.param, self.newest
        had = topic in st.msgs
        msg, tm = st.msgs.get(topic), st.times.get(topic)
        out = []
        try:
            for i in range(len(keys)):
                data, t, _lt = newest[i]
                st.msgs[topic], st.times[topic] = data, t
                param.time = t
                out.append((i, self._values(st, keys[i], i)))
        finally:
            param.time = None
            if had:
                st.msgs[topic], st.times[topic] = msg, tm  # type: ignore[assignment]
            else:
                st.msgs.pop(topic, None)
                st.times.pop(topic, None)
        return out

    def held_rows(self, held: Any, got: list[int], items: list | None = None) -> HeldRows:
        """The rows of held key message ``held`` (carrying the entities ``got``, read in
        order from its ``items`` when given), to be evaluated with its batch (:meth:`flush`
        at :data:`BATCH` messages)."""
        rows = HeldRows()
        self.batch.append((held, list(got), rows, items))
        if len(self.batch) >= BATCH:
            self.flush()
        return rows

    def flush(self) -> None:
        """Evaluate the rows of the held messages waiting for it (vectorized: one batch;
        what the rows cannot take, message by message with the reference evaluator, which
        records the entities' first errors in tick order)."""
        batch, self.batch = self.batch, []
        if not batch:
            return
        keys = self.table.keys
        ents = list(chain.from_iterable(b[1] for b in batch))
        offsets = np.cumsum([0] + [len(b[1]) for b in batch], dtype=np.int64)
        try:
            items = self._items_in_order(batch, ents, offsets)
            vals = (item_values(self.own, self.rows_of, items)  # type: ignore[arg-type]
                    if items is not None else
                    row_values(self.own, self.rows_of,  # type: ignore[arg-type]
                               [(b[0], [keys[i] for i in b[1]]) for b in batch]))
            self.evaluated[0] += len(ents)
        except (Irregular, SignalError):
            st, topic, got = EvalState(), self.kind.topic, []
            for m, e, *_r in batch:
                st.msgs[topic] = m
                got += [self._values(st, keys[i], i) for i in e]
            vals = [floats([v[j] for v in got]) for j in range(len(self.own))]
            self.evaluated[1] += len(ents)
        block = RowBlock(np.array(ents, np.int64), offsets,
                         {b.name: v for b, v in zip(self.own, vals)})
        for q, b in enumerate(batch):
            b[2].block, b[2].at = block, q

    def _items_in_order(self, batch: list, ents: list[int], offsets: np.ndarray
                        ) -> list | None:
        """The items the rows of ``batch`` read, laid end to end, when each message's
        entities were read in order from its items (:func:`fretc.audit.entities.runs.
        lean_messages`) and none repeats in it; else None."""
        if not self.items_rows or any(b[3] is None for b in batch):
            return None
        e = np.array(ents, np.int64)
        q = np.repeat(np.arange(len(batch), dtype=np.int64), np.diff(offsets))
        pairs = np.sort(q * (len(self.table.keys) + 1) + e)
        if len(pairs) > 1 and bool((pairs[1:] == pairs[:-1]).any()):
            return None  # (a key repeated in a message: rows of several items)
        return list(chain.from_iterable(b[3] for b in batch))

    def finish(self) -> Iterator[Tick]:
        """The ticks left at the end of the log, the last rows evaluated (iterate to the
        end)."""
        if self.lean:
            lean_messages(self)
            if self.last is not None:
                grid_run(self, grid_end(self.last, self.period) + 1)  # type: ignore[arg-type]
            self.s.missing_topics = sorted(self.missing)
        else:
            yield from super().finish()
        self.flush()

    def lean_ticks(self) -> list[Tick]:
        """A lean clock's ticks (:attr:`runs`) as :class:`Tick` objects, as the
        tick-by-tick clock makes them (for tests)."""
        return self.runs.ticks(ENTITIES, self.absent_once or ())

    def _absent(self, st: EvalState) -> tuple:
        """The per-entity variables of an entity the held messages do not carry."""
        self.param.value = _ABSENT
        out = []
        for b in self.own:
            st.values.clear()
            try:
                with np.errstate(all="ignore"):
                    out.append(b.evaluate(st))
            except (SignalError, TypeError):
                out.append(float("nan"))
        st.values.clear()
        return tuple(out)


def _frames(kind: EntityKind, keys: list) -> list:
    """``keys`` as entity keys of ``kind``: TF frame names without their leading ``/``
    (:attr:`EntityKind.frames`, :func:`fretc.signals.bindings.frames.frame_name`)."""
    if not kind.frames:
        return keys
    return [frame_name(x) if isinstance(x, str) else x for x in keys]


def read_entities(source: Any, bindings: Bindings,
                  clocks: dict[Any, tuple[str, list[str]]], bound: int
                  ) -> tuple[dict[Any, EntityClock], dict[Any, list[Tick]], dict[Any, Any]]:
    """Sample the per-entity requirements ``clocks`` (key -> (entity name, variable
    names)) in one read of ``source``.

    Returns:
        ``(clocks, ticks, errors)``: key -> its :class:`EntityClock` (entities met, their
        rows; its ``s`` the clock's :class:`~fretc.signals.clock.Sampling`), key -> its
        evaluated ticks (count_ticks warm-up applied; a lean clock's: none, its ticks are
        its ``runs``), key -> the error that stopped it.

    Raises:
        BindingError: a per-entity variable the read cannot take
            (:func:`~fretc.audit.entities.kinds.own_bindings`), or a bad key.
        SignalError: a topic missing from the log.
    """
    made: dict[Any, EntityClock] = {}
    fed: dict[str, list[Any]] = {}
    available = source.topics()
    buffers: dict[Any, HeaderBuffer] = {}
    every: list[Binding] = []
    for key, (name, names) in clocks.items():
        kind = entity_kind(bindings, name)
        plain, own, param = own_bindings(bindings, name, names)
        if kind.stream:
            check_stream(kind, own, str(bindings.source))
        topics = clock_topics(kind, plain, own)
        sub = Bindings({b.name: b for b in plain}, bindings.tick, bindings.time_base,
                       bindings.header_lag_ns, bindings.source)
        s = Sampling(source, sub)
        c = made[key] = EntityClock(s, plain, present_tf(topics, available), bindings.tick,
                                    kind, own, param, bound, VECTORIZED)
        c.fed = frozenset(topics | ({bindings.tick.topic} if bindings.tick.topic else set()))
        if bindings.time_base != "log":
            buffers[key] = HeaderBuffer(source, sub, s._problems)
        for t in c.fed:
            fed.setdefault(t, []).append(key)
        every += plain + own + [kind.binding]
    check_topics(source, Bindings({}, bindings.tick, bindings.time_base,
                                  bindings.header_lag_ns, bindings.source),
                 extra=set(fed), users=bindings)
    install_selective(source, Bindings({b.name + str(i): b for i, b in enumerate(every)},
                                       bindings.tick, bindings.time_base,
                                       bindings.header_lag_ns, bindings.source))
    errors: dict[Any, Any] = {}
    pairs = with_tick_windows(_run(source, made, buffers, fed, errors),
                              {k: c.s for k, c in made.items()},
                              {k: c.variables for k, c in made.items()})
    ticks: dict[Any, list[Tick]] = {k: [] for k in made}
    for key, tick in pairs:
        ticks[key].append(tick)
    return made, ticks, errors


def _run(source: Any, clocks: dict[Any, EntityClock], buffers: dict[Any, HeaderBuffer],
         fed: dict[str, list[Any]], errors: dict[Any, Any]) -> Iterator[tuple[Any, Tick]]:
    """One read feeding every clock (as :func:`fretc.signals.groups.sample_groups`)."""
    streams = Streams([b for c in clocks.values() for b in c.variables])

    def stream_failed(stream: str, exc: SignalError) -> None:
        for key in fed.get(stream, ()):
            errors.setdefault(key, exc)

    for m in streams.messages(source.messages(log_topics(fed)), fed, stream_failed):
        for key in fed.get(m.topic, ()):
            if key in errors:
                continue
            c = clocks[key]
            try:
                if c.lean and key not in buffers:  # (no tick yielded: c.push without the
                    c._lean_push(m.topic, m.log_time, m.log_time, m.data)  # generator)
                    continue
                items = (buffers[key].push(m) if key in buffers
                         else ((m.topic, m.log_time, m.log_time, m.data),))
                for item in items:
                    for t in c.push(*item):
                        yield key, t
            except SignalError as exc:
                errors[key] = exc
    for key, c in clocks.items():
        if key in errors:
            continue
        try:
            if key in buffers:
                for item in buffers[key].drain():
                    for t in c.push(*item):
                        yield key, t
            for t in c.finish():
                yield key, t
        except SignalError as exc:
            errors[key] = exc
