"""Live events of per-entity requirements in ``fretc watch`` (docs/bindings.md, "One verdict
per entity"): while watching, each entity of a per-entity requirement gets its own clock and
generated monitor, and its ``pt`` and ``ltl3`` events are made as a plain requirement's,
named by the instance (``T[track=7]``). Their verdicts are still those of the audit at the
end (:mod:`fretc.live.entities`); the live events follow the same rules, so an entity's
``ltl3`` violation is at its verdict's first violation.

Design notes: ARCHITECTURE.md, `live/entity_events.py`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from fnmatch import fnmatchcase
from types import SimpleNamespace
from typing import Any

from fretc.audit.entities.log import MAX_ENTITIES, entity_of_requirements
from fretc.audit.passes import clock_key
from fretc.common.problems import BindingError, SignalError
from fretc.common.streams import log_topics
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.expression import Field
from fretc.signals.bindings.extract import Valid, make_extractor
from fretc.signals.bindings.frames import FRAME_FIELDS, frame_name
from fretc.audit.passes import restrict as restrict_bindings
from fretc.signals.clock import Clock, Sampling, Tick, present_tf
from fretc.signals.streams import Streams
from fretc.signals.tick_windows import TickWindows

__all__ = ["MAX_LIVE_MESSAGES", "EntityEvents"]

#: Messages kept in memory to start the clock of an entity found later in the run.
MAX_LIVE_MESSAGES = 200_000


@dataclasses.dataclass
class _Instance:
    req: Any  # id (``T[track=7]``) and variables, as Watch._step reads them
    clock: Clock
    streams: Streams
    windows: TickWindows
    monitor: Any
    state: Any
    topics: set
    first: int = 0  # the log time of the entity's first message: its first tick at or after
    n: int = 0  # ticks stepped


class _Kind:
    """One per-entity requirement: its entity's key and the instances found so far."""

    def __init__(self, r: Any, name: str, bindings: Any) -> None:
        self.r, self.name = r, name
        key, self.matching, _hold = bindings.entities[name]
        self.key = compile_expression(f"entity_{name}", key, source=str(bindings.source))
        self.key_topic = next(iter(self.key.topics)) if len(self.key.topics) == 1 else None
        # (a field path: its keys read exactly, integers of any width as ints, as the audit
        # reads them: fretc.audit.entities.kinds.EntityKind.exact)
        ast = self.key.ast
        self.exact = (make_extractor(ast, self.key.constants, exact=True)
                      if isinstance(ast, Field) and not ast.filters else None)
        # (TF frames: without their leading slash, as tf2 and the audit name them)
        last = self.key.fields[0].path[-1] if self.key.fields and self.key.fields[0].path \
            else None
        self.frames = isinstance(last, str) and last in FRAME_FIELDS
        self.seen: set = set()
        self.instances: list[_Instance] = []

    def values(self, data: Any, log_time: int) -> list:
        """The key's values on one message of its topic (as fretc.audit.entities.log reads them)."""
        st, topic = EvalState(), self.key_topic
        assert topic is not None  # (values of a key of one topic)
        st.msgs[topic], st.times[topic], st.now = data, log_time, log_time
        try:
            v = self.exact(data) if self.exact is not None else self.key._scalar(st)  # type: ignore[misc]
        except Exception:  # noqa: BLE001 - the audit at the end names the error
            return []
        if isinstance(v, Valid):
            v = (v.data if v.mask is None else v.data[v.mask]).tolist()
        items = list(v) if isinstance(v, (list, tuple)) else [v]
        out = []
        for x in items:
            if isinstance(x, float) and x.is_integer():
                x = int(x)
            if self.frames and isinstance(x, str):
                x = frame_name(x)
            if self.matching is None or fnmatchcase(str(x), self.matching):
                out.append(x)
        return out


class EntityEvents:
    """The live events of the per-entity requirements of ``plan`` (module docstring).

    Args:
        plan: the watch's plan.
        source: the watch's source (decoders, gaps).
        step: ``step(rows, values, time, tick, depends_on)``: steps monitors and makes their
            events (the watch's own, :meth:`fretc.live.watch.Watch._step`).
        new_state: a fresh live state of one requirement (the watch's ``_Live``).
    """

    def __init__(self, plan: Any, source: Any, step: Callable, new_state: Callable) -> None:
        self.plan, self.source, self.step, self.new_state = plan, source, step, new_state
        b = plan.bindings
        self.kinds: list[_Kind] = []
        if b is not None and b.time_base == "log":
            for i, names in entity_of_requirements(plan).items():
                r = plan.requirements[i] if plan.requirements[i].index == i else next(
                    x for x in plan.requirements if x.index == i)
                if (len(names) == 1 and r.error is None and not r.offline and r.monitor_cls
                        and b.entities[names[0]].hold != "entity"):
                    try:
                        kind = _Kind(r, names[0], b)
                    except BindingError:
                        continue
                    if kind.key_topic is not None:
                        self.kinds.append(kind)
        self.history: list[tuple[str, int, Any]] = []
        self.full = False

    def message(self, topic: str, log_time: int, payload: bytes) -> None:
        """One message the watch used (log time ns, payload as received)."""
        if not self.kinds:
            return
        dec = self.source.decoders.get(topic)
        if dec is None:
            return
        data = dec(payload)
        if len(self.history) < MAX_LIVE_MESSAGES:
            self.history.append((topic, log_time, data))
        else:
            self.full = True
        for kind in self.kinds:
            for inst in kind.instances:
                self._push(inst, topic, log_time, data)
            if topic == kind.key_topic and not self.full:
                for value in kind.values(data, log_time):
                    if value not in kind.seen and len(kind.seen) < MAX_ENTITIES:
                        kind.seen.add(value)
                        self._start(kind, value, log_time)

    def finish(self) -> None:
        """The run ended: the ticks left on every instance's clock."""
        for kind in self.kinds:
            for inst in kind.instances:
                self._ticks(inst, inst.clock.finish())

    def _start(self, kind: _Kind, value: Any, first: int) -> None:
        b, r = self.plan.bindings, kind.r
        try:
            sub = b.for_entity({kind.name: value})
        except BindingError:
            return
        names = [v for v in r.variables if v in sub.variables]
        own = restrict_bindings(sub, names)
        variables = list(own.variables.values())
        topics = set(clock_key(r, own).topics)
        s = Sampling(self.source, own)
        clock = Clock(s, variables, present_tf(topics, self.source.topics()), own.tick,
                      keep_going=True)
        windows = TickWindows({None: s}, {None: variables})
        req = SimpleNamespace(id=f"{r.id}[{kind.name}={value}]", variables=r.variables)
        inst = _Instance(req, clock, Streams(variables), windows, r.monitor_cls(),
                         self.new_state(), topics | ({own.tick.topic} if own.tick.topic
                                                     else set()), first)
        kind.instances.append(inst)
        for topic, log_time, data in self.history:
            self._push(inst, topic, log_time, data)

    def _push(self, inst: _Instance, topic: str, log_time: int, data: Any) -> None:
        ticks: list[Tick] = []
        try:
            if topic in inst.topics:
                ticks += inst.clock.push(topic, log_time, log_time, data)
            for stream in inst.streams.fan_out(topic, log_time, data, inst.topics):
                ticks += inst.clock.push(stream, log_time, log_time, data)
        except SignalError:
            inst.topics = set()  # no more live events; the audit at the end names the error
            return
        self._ticks(inst, ticks)

    def _ticks(self, inst: _Instance, ticks: Iterable[Tick]) -> None:
        src = self.source
        for tick in ticks:
            tick = inst.windows.apply(None, tick)
            if tick is None or tick.time < inst.first:  # before the entity's life
                continue
            t, i = tick.time, inst.n
            inst.n += 1
            gaps = src.gaps
            if (gaps and any(a < t < e for a, e in gaps[-4:])) or (
                    src.absent and src.absent.at(log_topics(inst.topics), t)):
                continue  # inside a gap: the monitor not stepped over it, as the watch's
            dep = max(tick.log_times.values()) if tick.log_times else None
            self.step([(inst.req, inst.monitor, inst.state)], tick.values, t, i, dep)
