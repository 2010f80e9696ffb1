"""The signal bindings of an audit: the binding files read and merged into one
:class:`~fretc.signals.bindings.Bindings`, with the command line's overrides (``--tick-period``,
``--tick-topic``, ``--time-base``, ``--bind``) applied last."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from fretc.common.units import format_ns

from fretc.signals.bindings import Binding, Bindings, TickSpec, load_bindings, parse_duration
from fretc.signals.bindings.paths import topic_name
from fretc.common.problems import BindingError
from fretc.audit.config import AuditConfig, AuditInputError
from fretc.audit.discovery import discover_bindings

__all__ = ["load_audit_bindings", "merge_bindings", "binding_files", "tick_text"]

def binding_files(config: AuditConfig) -> list[tuple[Path, Bindings]]:
    """The binding files of ``config`` (given, or :func:`discover_bindings` next to the
    requirements), each read.

    Raises:
        AuditInputError: a binding file that cannot be read or has an error (its message
            names the file and line).
    """
    files = ([Path(p) for p in config.bindings] if config.bindings is not None
             else discover_bindings(config.requirements))
    parts = []
    for f in files:
        try:
            parts.append((f, load_bindings(f)))
        except BindingError as exc:
            raise AuditInputError(str(exc)) from None
    return parts


def load_audit_bindings(config: AuditConfig, files: list[tuple[Path, Bindings]] | None = None
                        ) -> tuple[Bindings | None, list[str]]:
    """(the merged bindings with the command line's overrides, or None when there are none;
    the binding files read: ``files``, :func:`binding_files`' read of them, else read here).

    Raises:
        AuditInputError: unreadable or conflicting binding files, bad tick options.
    """
    if files is None:
        files = binding_files(config)
    parts = [b for _f, b in files]
    b = merge_bindings(parts) if parts else None
    if config.tick_period is not None and config.tick_topic is not None:
        raise AuditInputError("--tick-period and --tick-topic exclude each other")
    tick = None
    if config.tick_period is not None:
        try:
            tick = TickSpec(period_ns=parse_duration(config.tick_period))
        except ValueError as exc:
            raise AuditInputError(f"--tick-period: {exc}") from None
    elif config.tick_topic is not None:
        topic = topic_name(config.tick_topic)
        if topic is None:
            raise AuditInputError(f"--tick-topic {config.tick_topic!r} is not a topic name "
                                  "(one as fretc inspect lists it)")
        tick = TickSpec(topic=topic)
    if b is None and (config.inline or tick is not None):
        if tick is None:
            raise AuditInputError("--bind without a binding file needs --tick-period or "
                                  "--tick-topic (signals are declared, never guessed)")
        b = Bindings({}, tick, config.time_base or "log")
    if b is not None:
        if tick is not None or config.time_base is not None:
            if tick is not None:  # the binding file's NaN policy stays
                tick = dataclasses.replace(tick, nan=b.tick.nan, inf=b.tick.inf)
            b = Bindings(dict(b.variables), tick or b.tick, config.time_base or b.time_base,
                         b.header_lag_ns, b.source, types=dict(b.types), entities=b.entities,
                         per_entity=b.per_entity, path_vars=b.path_vars,
                         allowance=dict(b.allowance))
        if config.inline:
            try:
                b = b.with_inline(config.inline)
            except BindingError as exc:
                raise AuditInputError(str(exc)) from None
    return _with_allowance(b, config), [str(f) for f, _b in files]


def _with_allowance(b: Bindings | None, config: AuditConfig) -> Bindings | None:
    """``b`` with ``--allowance`` over its files' ``[audit] allowance``, topic by topic.

    Raises:
        AuditInputError: ``--allowance`` without bindings, or naming a topic no binding
            reads (the option named)."""
    if not config.allowance:
        return b
    if b is None:
        raise AuditInputError("--allowance needs signal bindings: a CSV trace read without "
                              "them has no topics to read earlier")
    read = b.log_topics_read()
    for topic, _ns in config.allowance:
        if topic not in read:
            raise AuditInputError(
                f"--allowance {topic}: no binding reads the topic {topic} (the bindings "
                f"read {', '.join(sorted(read)) or 'no topic'})")
    b = dataclasses.replace(b)  # (a copy: the bindings as read stay as they were)
    given = {**b.allowance, **dict(config.allowance)}
    # (an allowance of 0 is none: the audit reads and writes what it does without one)
    b.allowance = {t: ns for t, ns in sorted(given.items()) if ns}
    return b


def merge_bindings(parts: list[Bindings]) -> Bindings:
    """One Bindings from several files: variables united; the same variable bound twice
    differently, or different ticks / time bases, is an :class:`AuditInputError`."""
    first = parts[0]
    variables: dict[str, Binding] = {}
    types: dict[str, str] = {}
    entities: dict = {}
    per_entity: dict = {}
    path_vars: dict = {}
    allowance: dict[str, int] = {}
    for b in parts:
        entities.update(b.entities)
        per_entity.update(b.per_entity)
        path_vars.update(b.path_vars)
        for topic, name in b.types.items():
            if types.setdefault(topic, name) != name:
                raise AuditInputError(f"{b.source}: [types] gives {topic} the type {name}, "
                                      f"another binding file {types[topic]}")
        for topic, ns in b.allowance.items():
            if allowance.setdefault(topic, ns) != ns:
                raise AuditInputError(
                    f"{b.source}: [audit] allowance gives {topic} {format_ns(ns) if ns else 0}"
                    f", another binding file {format_ns(allowance[topic])}; one audit reads "
                    "a topic with one allowance")
        if (b.tick, b.time_base, b.header_lag_ns) != (first.tick, first.time_base,
                                                        first.header_lag_ns):
            raise AuditInputError(
                f"{b.source}: [tick] ({tick_text(b.tick)}, time {b.time_base}) differs from "
                f"{first.source} ({tick_text(first.tick)}, time {first.time_base}); one audit "
                "uses one clock: pass --bindings to choose")
        for name, v in b.variables.items():
            old = variables.get(name)
            if old is not None and old.expr.strip() != v.expr.strip():
                raise AuditInputError(
                    f"{v.source}:{v.line}: variable {name!r} is bound to {v.expr!r}, but "
                    f"{old.source}:{old.line} binds it to {old.expr!r}")
            variables.setdefault(name, v)
    source = ", ".join(str(b.source) for b in parts)
    return Bindings(variables, first.tick, first.time_base, first.header_lag_ns, source,
                    types=types, entities=entities, per_entity=per_entity, path_vars=path_vars,
                    allowance=allowance)


def tick_text(tick: TickSpec) -> str:
    """The tick in words: ``every 100 ms`` or ``one per /odom message``."""
    if tick.period_ns is not None:
        return f"every {format_ns(tick.period_ns)}"
    return f"one per {tick.topic} message"
