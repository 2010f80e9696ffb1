"""What a per-entity requirement's read is made of (:mod:`fretc.audit.entities.read`): the
kind of an ``[entities]`` name (its key, the topic it is read from, an array of keys per
message or one key per message: :func:`entity_kind`), the table of the entities met
(:class:`EntityTable`), the plain and per-entity variables of a requirement
(:func:`own_bindings`) and the topics its clock holds (:func:`clock_topics`);
docs/bindings.md, "One verdict per entity"."""

from __future__ import annotations

from array import array
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fretc.common.problems import BindingError, SignalError
from fretc.common.streams import base_topic, is_stream, log_topics
from fretc.signals.bindings import Bindings
from fretc.signals.bindings.binding import Binding, compile_kept
from fretc.signals.bindings.expression import EntityParam, Field
from fretc.signals.bindings.extract import Valid, make_extractor
from fretc.signals.bindings.frames import FRAME_FIELDS

__all__ = ["EntityKind", "EntityTable", "entity_kind", "key_items", "own_bindings",
           "check_stream", "clock_topics"]


@dataclass
class EntityKind:
    """One ``[entities]`` name: ``key`` its key path, compiled (``binding``) and read from
    ``topic`` (a topic, or a stream); ``stream``: one key per message (each entity a stream
    of its own messages), else an array of keys per message (the entities present);
    ``hold``: what a tick reads of an entity of an array key
    (:data:`~fretc.signals.bindings.spec.HOLDS`: ``"entity"``, its own newest message that
    carried it, held to the end of the log). ``exact``: message -> its keys read exactly
    (:func:`fretc.signals.bindings.extract.entity_key`: an integer key of any width an int,
    never a float64 that merges ``uint64`` ids past 2**53) when the key is a field path, as
    it is; None: read by ``binding``."""

    name: str
    key: str
    matching: str | None
    binding: Binding
    topic: str
    stream: bool
    hold: str = "message"
    exact: Callable[[Any], Any] | None = None
    #: the keys are TF frame names (the key's field is one of
    #: :data:`~fretc.signals.bindings.frames.FRAME_FIELDS`): read as
    #: :func:`~fretc.signals.bindings.frames.frame_name` gives them (tf2's rule: ``/car``
    #: and ``car`` one frame, one entity named ``car``)
    frames: bool = False

    @property
    def held(self) -> bool:
        """Each entity of an array key held on its own (``hold = "entity"``)."""
        return self.hold == "entity" and not self.stream


def entity_kind(bindings: Bindings, name: str) -> EntityKind:
    """The :class:`EntityKind` of ``[entities]`` name ``name``.

    Raises:
        BindingError: the key is not a field path of one topic."""
    key, matching, hold = bindings.entities[name]
    b = compile_kept(f"entity_{name}", key, f"{bindings.source} [entities]")
    if len(b.topics) != 1 or not b.fields:
        raise BindingError(str(bindings.source), f"[entities] {name}: the key {key!r} is a "
                           "field path of one topic, e.g. \"/tracks.tracks[:].id\"")
    topic = next(iter(b.topics))
    exact = (make_extractor(b.ast, b.constants, exact=True) if isinstance(b.ast, Field)
             and not b.ast.filters else None)
    last = b.fields[0].path[-1] if b.fields[0].path else None
    return EntityKind(name, key, matching, b, topic, not any(f.multi for f in b.fields), hold,
                      exact, isinstance(last, str) and last in FRAME_FIELDS)


def key_items(v: Any) -> list:
    """The values a key path read from one message (an array, or one value)."""
    if isinstance(v, Valid):
        data = v.data if v.mask is None else v.data[v.mask]
        return np.asarray(data).tolist()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (list, tuple)):
        return list(v)
    return [v]


@dataclass
class EntityTable:
    """The entities of one clock as the read meets them: key -> index (first appearance
    order), their first and last message times (ns, the clock's time base), the first error
    evaluating one, and the messages of the entities read in their own messages (one-value
    keys: with their values; array keys held on their own)."""

    index: dict[Any, int] = field(default_factory=dict)
    keys: list[Any] = field(default_factory=list)
    #: (int64 arrays of the standard library: 8 bytes an entity, not a Python int each)
    first: array = field(default_factory=lambda: array("q"))
    last: array = field(default_factory=lambda: array("q"))
    errors: dict[int, SignalError] = field(default_factory=dict)
    #: the messages of the entities read in their own messages, in the order met: (entity,
    #: message time (the clock's time base), its values (one-value keys; () for an array
    #: key's entities held on their own), log time)
    rows: list[tuple[int, int, tuple, int]] = field(default_factory=list)
    cut: bool = False  # more entities than the bound met

    def see(self, key: Any, t: int, bound: int) -> int | None:
        """Entity ``key`` carried by a message at ``t``: its index (None past ``bound``)."""
        i = self.index.get(key)
        if i is None:
            if len(self.keys) >= bound:
                self.cut = True
                return None
            i = self.index[key] = len(self.keys)
            self.keys.append(key)
            self.first.append(t)
            self.last.append(t)
        else:
            self.last[i] = t
        return i


def own_bindings(bindings: Bindings, name: str, names: list[str]
                  ) -> tuple[list[Binding], list[Binding], EntityParam]:
    """The plain and the per-entity variables of ``names`` (the latter compiled once, the
    entity's key an :class:`EntityParam`).

    Raises:
        BindingError: a per-entity variable that aggregates messages or reads a window."""
    param = EntityParam(name)
    every = bindings.for_entity({name: param}).variables
    plain = [bindings.variables[n] for n in names if n in bindings.variables]
    own = [every[n] for n in names if n in bindings.per_entity]
    for b in own:
        if b.aggregate is not None or b.window is not None or b.tick_window is not None:
            raise BindingError(str(bindings.source), f"{b.name}: a per-entity variable reads "
                               f"the held messages (its entity ${name}), not an aggregation "
                               f"or a window over messages ({b.expr})")
    return plain, own, param


def check_stream(kind: EntityKind, own: list[Binding], source: str) -> None:
    """A key of one value per message: the per-entity variables read the entity's own
    messages only (its stream, ``"PARM"{Name==$param}.Value``).

    Raises:
        BindingError: one reads another topic."""
    for b in own:
        if log_topics(b.topics) != {base_topic(kind.topic)}:
            raise BindingError(source, f"{b.name}: the entities {kind.name} are the messages "
                               f"of {base_topic(kind.topic)} ({kind.key}: one per message); a "
                               f"per-entity variable reads that topic only ({b.expr})")


def clock_topics(kind: EntityKind, plain: list[Binding], own: list[Binding]) -> set[str]:
    """The topics (and streams) the clock holds: its plain variables' and the per-entity
    variables' (an entity's stream stands for its topic), and the key's."""
    out = {t for b in plain for t in b.topics}
    for b in own:
        out |= {base_topic(t) if is_stream(t) else t for t in b.topics}
    return out | {kind.topic if not is_stream(kind.topic) else base_topic(kind.topic)}
