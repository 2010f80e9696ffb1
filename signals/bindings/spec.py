"""A binding set as the audit uses it: the variables, the tick clock (:class:`TickSpec`), the
time base and which logs it applies to (:class:`LogSelector`).  Read from a binding file by
:mod:`fretc.signals.bindings.files`; made from a mapping by :func:`make_bindings`."""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import PurePath
from typing import NamedTuple

from fretc.common.units import NS_PER_S

from fretc.common.problems import BindingError
from fretc.signals.bindings.binding import Binding, compile_expression, parse_inline
from fretc.signals.bindings.expression import EntityParam
from fretc.signals.bindings.parse_cache import kept_parses

__all__ = ["DEFAULT_HEADER_LAG_NS", "NAN_POLICIES", "TIME_BASES", "TickSpec", "LogSelector",
           "Bindings", "EntitySpec", "HOLDS", "entities_read", "make_bindings", "grid_start", "grid_end", "MAX_TICKS",
           "MAX_COLUMN_BYTES", "tick_bound_error"]

#: The time bases of ``[tick] time``: ``log`` (the log's own time of each message),
#: ``header`` (every bound message's ``header.stamp``; a message without one is an error),
#: ``header-where-stamped`` (``header.stamp`` where the message has a header, its log time
#: where it has none: a ``geometry_msgs/Twist`` ``cmd_vel`` beside stamped sensor topics).
TIME_BASES = ("log", "header", "header-where-stamped")

#: ``[tick] header_lag`` when not given: 1 s (ns).
DEFAULT_HEADER_LAG_NS = NS_PER_S


#: The meanings a binding file may give a comparison with NaN (``[tick] nan``).
NAN_POLICIES = ("unread", "false")
#: The meanings a binding file may give ±inf read from a log field (``[tick] inf``).
INF_POLICIES = ("unread", "value")


@dataclass(frozen=True)
class TickSpec:
    """When the signals are sampled.

    Exactly one of:
        period_ns: fixed period (ns): ticks at start + k·period, sample-and-hold.
        topic: one tick per message of this topic, other topics held.

    Raises:
        ValueError: neither or both given, or a period that is not positive.
    """

    period_ns: int | None = None
    topic: str | None = None
    #: topic ticks only: the tick topic's nominal period (``[tick] nominal_rate``), with
    #: which durations in time units convert to ticks; the audit warns when the measured
    #: rate differs by more than 10 %.
    nominal_period_ns: int | None = None
    #: what a comparison with NaN in a requirement means (``[tick] nan``,
    #: :data:`NAN_POLICIES`): ``"unread"`` (the default: the tick's value is neither true
    #: nor false, the requirement is judged only before it, :mod:`fretc.monitors.nan`) or
    #: ``"false"`` (IEEE 754: every ordered comparison with NaN is false, ``!=`` true).
    nan: str = "unread"
    #: what ±inf read from a log field means (``[tick] inf``, :data:`INF_POLICIES`):
    #: ``"unread"`` (the default: no number was measured, read as NaN; REP 117 fields keep
    #: their meaning) or ``"value"`` (a number like any other).
    inf: str = "unread"

    def __post_init__(self) -> None:
        if self.inf not in INF_POLICIES:
            raise ValueError(f"TickSpec.inf must be one of {INF_POLICIES}, not {self.inf!r}")
        if self.nan not in NAN_POLICIES:
            raise ValueError(f"TickSpec.nan must be one of {NAN_POLICIES}, not {self.nan!r}")
        if (self.period_ns is None) == (self.topic is None):
            raise ValueError("TickSpec needs exactly one of period_ns and topic")
        if self.period_ns is not None and self.period_ns <= 0:
            raise ValueError("TickSpec.period_ns must be positive")


@dataclass(frozen=True)
class LogSelector:
    """``[logs]`` of a binding file: which logs it applies to. ``glob``: patterns matched
    against the log's path from the right (:meth:`pathlib.PurePath.match`: ``"*.bag"``,
    ``"stage_*"``, ``"real/*.mcap"``); ``topics``: topics the log must have. A log is
    selected when it matches some pattern (if any are given) and has every topic (if any
    are given)."""

    glob: tuple[str, ...] = ()
    topics: tuple[str, ...] = ()

    def matches(self, path: str, log_topics: Iterable[str] | None) -> bool:
        """Whether the log at ``path`` with topics ``log_topics`` (None: unknown) is
        selected."""
        p = PurePath(path)
        if self.glob and not any(p.match(g) or p.name == g for g in self.glob):
            return False
        if self.topics and (log_topics is None or not set(self.topics) <= set(log_topics)):
            return False
        return True

    def text(self) -> str:
        """``"glob *.bag; topics /scan, /odom"``: the selector in words."""
        parts = []
        if self.glob:
            parts.append("glob " + ", ".join(self.glob))
        if self.topics:
            parts.append("topics " + ", ".join(self.topics))
        return "; ".join(parts)


#: What a tick reads of an entity of an array key (``[entities] car = { key = ..., hold =
#: ... }``): ``"message"`` (the default) the message of the key's topic held at the tick,
#: through the filter on the entity (absent when that message does not carry it);
#: ``"entity"`` the newest message of the key's topic that carried the entity, held from
#: its first message to the end of the log (each frame of a TF buffer its newest
#: transform, tf2's rule), its age readable as ``age($car)``.
HOLDS = ("message", "entity")


class EntitySpec(NamedTuple):
    """One name of ``[entities]``: ``key`` its key path, ``matching`` the glob the key must
    match (None: every value), ``hold`` what a tick reads of an entity (:data:`HOLDS`)."""

    key: str
    matching: str | None = None
    hold: str = "message"


_DOLLAR = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


def entities_read(per_entity: dict[str, tuple], entities: Iterable[str], name: str,
                  seen: set[str] | None = None) -> set[str]:
    """The entities (names of ``entities``) the per-entity variable ``name`` reads, directly
    (``$track`` in its expression) or through the per-entity variables it refers to
    (``per_entity``: name -> (expression, ...))."""
    seen = set() if seen is None else seen
    if name in seen:
        return set()
    seen.add(name)
    expr = per_entity[name][0]
    out = set(_DOLLAR.findall(expr)) & set(entities)
    for other in per_entity:
        if other != name and re.search(rf"(?<![\w/.$]){re.escape(other)}(?!\w)", expr):
            out |= entities_read(per_entity, entities, other, seen)
    return out


@dataclass
class Bindings:
    """A set of variable bindings with a tick and a time base.

    Attributes:
        variables: FRET variable → Binding, in declaration order.
        tick: the tick clock.
        time_base: ``"log"`` (MCAP log time / bag timestamp), ``"header"`` or
            ``"header-where-stamped"`` (:data:`TIME_BASES`)
            (``header.stamp`` of each message).
        header_lag_ns: time_base "header" only: how far (ns, header clock) a message may
            arrive behind the newest stamp seen and still be placed in stamp order.
        source: the binding file, or None.
        logs: ``[logs]``: the logs this binding file applies to (None: every log).
        types: ``[types]``: topic -> ROS message type, for live servers that do not say
            (rosbridge without rosapi); logs carry their own schemas.
        msg_path: ``[types] msg_path``: folders of the ``.msg``/``.idl`` files of types a
            log does not carry (as ``--msg-path``; :mod:`fretc.logs.ros.msg_path`).
        constants: ``[constants]``: named durations of the requirements (name -> (amount,
            unit), :mod:`fretc.fretish.constants`), read by the audit before it compiles.
        entities: ``[entities]``: entity name -> its :class:`EntitySpec` (key path,
            ``matching`` glob or None, ``hold``): the values of the key in a log are the
            entities a per-entity requirement is judged for (docs/bindings.md, "One verdict
            per entity").
        per_entity: the variables whose expression reads an entity (``$track``) or such a
            variable, not compiled yet: name -> (expression, line, col, exact), compiled
            per entity by :meth:`for_entity`.
        path_vars: ``[path_variables]`` (FoxQL's ``$name`` values).
        allowance: ``[audit] allowance``: topic -> ns its messages are read earlier by the
            audit (a reaction allowance, :mod:`fretc.logs.allowance`; ``fretc audit
            --allowance`` adds to it); empty: none.

    Raises:
        ValueError: a time base not in :data:`TIME_BASES`.
    """

    variables: dict[str, Binding]
    tick: TickSpec
    time_base: str = "log"
    header_lag_ns: int = DEFAULT_HEADER_LAG_NS
    source: str | None = None
    logs: LogSelector | None = field(default=None, compare=False)
    types: dict[str, str] = field(default_factory=dict, compare=False)
    msg_path: tuple[str, ...] = field(default=(), compare=False)
    constants: dict[str, tuple[str, str]] = field(default_factory=dict, compare=False)
    entities: dict[str, EntitySpec] = field(default_factory=dict, compare=False)
    per_entity: dict[str, tuple] = field(default_factory=dict, compare=False)
    path_vars: dict[str, object] = field(default_factory=dict, compare=False)
    allowance: dict[str, int] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if self.time_base not in TIME_BASES:
            raise ValueError(f"time_base must be one of {', '.join(TIME_BASES)}, not "
                             f"{self.time_base!r}")

    @property
    def topics(self) -> frozenset[str]:
        """All topics the variables reference (fields and age())."""
        out: set[str] = set()
        for b in self.variables.values():
            out |= b.topics
        return frozenset(out)

    def log_topics_read(self) -> frozenset[str]:
        """The log topics these bindings read: their variables' (a stream's topic for the
        stream), the tick topic, and those named in the per-entity expressions and
        ``[entities]`` keys (not compiled yet) — the topics an allowance may name."""
        from fretc.common.streams import log_topics

        out = set(log_topics(self.topics))
        if self.tick.topic is not None:
            out.add(self.tick.topic)
        texts = [p[0] for p in self.per_entity.values()] + [e.key for e in self.entities.values()]
        for text in texts:
            out |= {m.split(".", 1)[0] for m in re.findall(r"/[A-Za-z0-9_/.]+", str(text))}
        return frozenset(out)

    def for_entity(self, values: dict[str, object]) -> Bindings:
        """A copy whose per-entity variables of the entities ``values`` are compiled with
        their values (``{"track": 7}``: ``$track`` reads 7), in declaration order, each after
        the ones it refers to; those that read another entity (a kind of the same
        ``[entities]`` table not given) are left out: a requirement is judged over its own
        kind.

        Raises:
            BindingError: a per-entity expression that does not compile with these values.
        """
        variables = dict(self.variables)
        pending = {n: p for n, p in self.per_entity.items()
                   if entities_read(self.per_entity, self.entities, n) <= set(values)}
        pvars = {**self.path_vars, **values}
        # (keys read at evaluation, as the audit compiles them once, are kept between runs;
        # the trees of one entity's value, as ``fretc watch`` makes them, are not)
        keys = all(type(v) is EntityParam for v in values.values())
        parsed = _per_entity_parses(str(self.source), pending, pvars) if keys else {}
        while pending:
            # the first that refers to no other pending one; only mutual references left:
            # the first (its error names them)
            name = next((n for n, p in pending.items()
                         if not any(other in p[0] for other in pending if other != n)),
                        next(iter(pending)))
            expr, line, col, exact, nan, inf = pending.pop(name)
            variables[name] = compile_expression(
                name, expr, source=str(self.source), line=line, col=col, exact=exact,
                refs=variables, nan=nan, inf=inf, path_vars=pvars, parsed=parsed.get(name))
        return Bindings(variables, self.tick, self.time_base, self.header_lag_ns, self.source,
                        types=dict(self.types), msg_path=self.msg_path,
                        constants=self.constants, allowance=dict(self.allowance))

    def with_inline(self, specs: Iterable[str]) -> Bindings:
        """A copy with ``NAME=EXPR`` bindings (CLI ``--bind``) added or replacing same-named ones.

        Raises:
            BindingError: as :func:`fretc.signals.bindings.binding.parse_inline`.
        """
        variables = dict(self.variables)
        for spec in specs:
            b = parse_inline(spec, refs=variables)
            variables[b.name] = b
        return Bindings(variables, self.tick, self.time_base, self.header_lag_ns, self.source,
                        types=dict(self.types), entities=self.entities,
                        per_entity={k: v for k, v in self.per_entity.items()
                                    if k not in variables}, path_vars=self.path_vars,
                        allowance=dict(self.allowance))


def make_bindings(variables: dict[str, str], tick: TickSpec, *, time_base: str = "log",
                  header_lag_ns: int = DEFAULT_HEADER_LAG_NS) -> Bindings:
    """Bindings from a mapping of variable → expression text (source ``"<--bind NAME>"``).

    Raises:
        BindingError: a bad name or expression.
    """
    out = {name: compile_expression(name, expr, source=f"<--bind {name}>", line=1,
                                    col=len(name) + 2)
           for name, expr in variables.items()}
    return Bindings(out, tick, time_base, header_lag_ns, None)


def grid_start(first: int, period: int) -> int:
    """The first tick of a fixed-period clock whose first message is at ``first`` (ns): the
    first multiple of ``period`` at or after it. Ticks lie on the multiples of the period
    (of log time since the epoch, or of the header time base), never on where the first
    message read happens to lie: a lost first message (a gap) cannot shift the grid, and
    clocks of one period share it (docs/guide/ticks.md, "The tick grid")."""
    return -(-first // period) * period


def grid_end(last: int, period: int) -> int:
    """The last tick of a fixed-period clock whose last message is at ``last`` (ns): the
    first multiple of ``period`` at or after it, as :func:`grid_start` is for the first
    message. Every message of the clock's topics is then held by a tick or counted as
    unsampled: the last message of a run is judged (docs/guide/ticks.md, "The tick
    grid")."""
    return -(-last // period) * period


#: At most this many ticks per clock: a tick period that would give more (``tick period =
#: "1 ns"`` on an 88 s log: 8.8e10; a header.stamp that jumps by centuries) is an input error
#: that says how many, raised before any of them is made.
MAX_TICKS = 10**8
#: At most this many bytes of columns over the clocks of one read (8 bytes a tick for its
#: time, and per variable and per held topic): counted before the ticks are made, so a log
#: whose first message is far from its last (a 200-byte DataFlash log, a time stamp
#: bit-flipped) is refused before it takes gigabytes.
MAX_COLUMN_BYTES = 1 << 30


def tick_bound_error(path: str, period: int, first: int, last: int, ticks: int,
                     need: int) -> str | None:
    """Why a clock of ``period`` (ns) that would have ``ticks`` ticks in all, from ``first``
    to ``last`` (ns), cannot be sampled: more than :data:`MAX_TICKS`, or the columns of
    every clock of the read with them (``need`` bytes) more than :data:`MAX_COLUMN_BYTES`;
    None when it can (docs/guide/ticks.md, "A bound on ticks")."""
    if ticks <= MAX_TICKS and need <= MAX_COLUMN_BYTES:
        return None
    what = (f"more than {MAX_TICKS:,} ticks (the limit)" if ticks > MAX_TICKS else
            f"{ticks:,} ticks whose columns would take {need / 2**30:.2f} GiB, more than the "
            f"{MAX_COLUMN_BYTES / 2**30:g} GiB an audit keeps")
    return (f"{path}: {what}: the tick period {period} ns from {first} ns to the newest "
            f"message at {last} ns (time base: a header.stamp jump? a time stamp far from "
            "the others?); choose a longer tick period")


def _per_entity_parses(source: str, pending: dict[str, tuple], path_vars: dict) -> dict:
    """The per-entity expressions ``pending`` parsed with ``path_vars`` (the entities' keys
    among them), kept between runs (:func:`fretc.signals.bindings.parse_cache.kept_parses`);
    none when one does not parse (each is then parsed as it is compiled, whose error comes
    in the order of compiling)."""
    try:
        return kept_parses(f"{source}#per-entity", pending, path_vars)
    except BindingError:
        return {}
