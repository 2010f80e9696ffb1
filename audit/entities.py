"""One verdict per entity (docs/bindings.md, "One verdict per entity"): a requirement whose
variables read an entity of the binding file's ``[entities]`` table (``$track`` in a filter,
``{id==$track}``) is judged once for every value of the entity's key that appears in the log
(first-order monitoring's universal quantifier over the trace's objects, as DejaVu and
MonPoly have it; FRET's parameterised requirements over N identical components). Each
instance is an ordinary verdict named ``R[track=7]`` with its evidence, its variables bound
with ``$track`` = 7; a summary over the entities is added to each instance's notes.

The entities are found by one read of the key's topic (every message, the key path's values,
those matching the ``matching`` glob); each entity is then audited in a read of its own (the
log is read once per entity: :data:`MAX_ENTITIES` bounds them; past it, the requirement has
one more verdict, ``R[track=...]``, an error saying that entities were left unjudged; the
requirement's own verdict is then an error too, unless a judged entity violates it). The audit of each
instance is the plain audit (:func:`fretc.audit.log.audit_log`): warm-up, gaps and damage
per instance, as per requirement.
"""

from __future__ import annotations

import dataclasses
import re
from fnmatch import fnmatchcase
from typing import Any

import numpy as np

from fretc.audit.verdict import LogAudit, Verdict
from fretc.common.problems import BindingError, FretcInputError, SignalError
from fretc.common.streams import base_topic, log_topics
from fretc.logs import open_log
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.extract import Valid
from fretc.signals.streams import Streams

__all__ = ["MAX_ENTITIES", "entity_of_requirements", "find_entities", "audit_entities"]

#: Entities of one key judged in one log (each costs one read of the log).
MAX_ENTITIES = 1000

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


def _items(v: Any) -> list:
    """The values a key path read from one message (an array, or one value)."""
    if isinstance(v, Valid):
        data = v.data if v.mask is None else v.data[v.mask]
        return np.asarray(data).tolist()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (list, tuple)):
        return list(v)
    return [v]


def find_entities(path: str, bindings: Any, name: str) -> tuple[list, dict, bool]:
    """The entities of ``name`` in the log at ``path``: (values in order of first
    appearance, value -> (first, last) log time ns of a message carrying it, whether
    :data:`MAX_ENTITIES` cut the list).

    Raises:
        BindingError: the key is not a field path of one topic.
        SignalError: the key cannot be read from a message (named with its log time).
    """
    key, matching = bindings.entities[name]
    b = compile_expression(f"entity_{name}", key, source=f"{bindings.source} [entities]")
    if len(b.topics) != 1 or not b.fields:
        raise BindingError(str(bindings.source), f"[entities] {name}: the key {key!r} is a "
                           "field path of one topic, e.g. \"/tracks.tracks[:].id\"")
    topic = next(iter(b.topics))
    st, seen, cut = EvalState(), dict[Any, Any](), False
    src = open_log(path)
    for m in Streams([b]).messages(src.messages({base_topic(topic)}), {topic}):
        st.msgs[topic], st.times[topic], st.now = m.data, m.log_time, m.log_time
        try:
            values = _items(b._scalar(st))  # type: ignore[misc]
        except Exception as exc:  # noqa: BLE001 - an extractor's error: named with the message
            raise SignalError(f"[entities] {name}: {key} cannot be read from the message of "
                              f"{topic} at log time {m.log_time}: {exc}") from None
        for x in values:
            if isinstance(x, float) and x.is_integer():
                x = int(x)
            if matching is not None and not fnmatchcase(str(x), matching):
                continue
            if x not in seen:
                if len(seen) >= MAX_ENTITIES:
                    cut = True
                    continue
                seen[x] = [m.log_time, m.log_time]
            seen[x][1] = m.log_time
    return list(seen), {k: tuple(v) for k, v in seen.items()}, cut


def _key_topic_absent(path: str, bindings: Any, name: str) -> tuple[str, str] | None:
    """When the topic of entity ``name``'s key is not in the log at ``path``: the verdict of
    its requirement, as a plain requirement's whose bound topic is absent (``error``, or
    ``unknown`` when the damage found reading the log's topics may have taken it), with the
    reason. None when the topic is there (no entity in its messages is then ``vacuous``)
    or the key does not compile (:func:`find_entities` says why)."""
    key = bindings.entities[name][0]
    try:
        topics = compile_expression(f"entity_{name}", key, source=str(bindings.source)).topics
        src = open_log(path)
        available = src.topics()
    except (BindingError, OSError, FretcInputError):
        return None
    absent = sorted(t for t in log_topics(topics) if t not in available)
    if not absent:
        return None
    why = (f"topic {', '.join(absent)} (the key {key} of entity {name}) is not in the log "
           f"(it has {', '.join(available) or 'no topics'}): no entity was looked for")
    if src.partial:
        return "unknown", f"{why}; the log is damaged: the damage may have taken it"
    return "error", why


def audit_entities(plan: Any, path: str, progress: Any, run: Any) -> LogAudit:
    """Audit ``plan`` on the log at ``path`` with its per-entity requirements instantiated per
    entity (module docstring); ``run(plan, path, progress)`` audits a plan (the plain audit).

    Returns:
        the log's audit: the other requirements' verdicts, then per requirement its verdict
        over all entities (named as the requirement: violated when one entity violates it,
        satisfied when all satisfy it) and one verdict per entity in order of first
        appearance (none appeared: one ``vacuous`` verdict saying so; an error reading the
        key: one ``error`` verdict naming it).
    """
    groups = entity_of_requirements(plan)
    plain = [r for r in plan.requirements if r.index not in groups]
    la = run(dataclasses.replace(plan, requirements=plain), path, progress) if plain else None
    extra: list[Verdict] = []
    for r in [r for r in plan.requirements if r.index in groups]:
        extra += _instances(plan, r, groups[r.index], path, run)
    if la is None:
        la = LogAudit(log=path)
        la.verdicts = []
    la.verdicts = la.verdicts + extra
    return la


def _instances(plan: Any, r: Any, names: list[str], path: str, run: Any) -> list[Verdict]:
    """The verdicts of requirement ``r`` on its entities ``names`` (one entity only)."""
    def alone(verdict: str, **kw: Any) -> list[Verdict]:
        return [Verdict(log=path, requirement=r.id, text=r.text, source=r.source,
                        verdict=verdict, **kw)]

    if len(names) != 1:
        return alone("error", error=f"{r.id} reads the entities {', '.join(names)}: a "
                     "requirement is judged per entity of one key")
    name = names[0]
    absent = _key_topic_absent(path, plan.bindings, name)
    if absent is not None:
        verdict, why = absent
        return alone(verdict, **({"unknown_reason": why} if verdict == "unknown" else
                                 {"error": why}))
    try:
        values, span, cut = find_entities(path, plan.bindings, name)
    except (BindingError, SignalError, OSError) as exc:
        return alone("error", error=str(exc))
    key = plan.bindings.entities[name][0]
    if not values:
        return alone("vacuous", notes=[f"no entity {name} ({key}) appeared in the log: the "
                                       "requirement holds of none"])
    out: list[Verdict] = []
    for _i, value in enumerate(values):
        sub = dataclasses.replace(plan, bindings=plan.bindings.for_entity({name: value}),
                                  requirements=[dataclasses.replace(
                                      r, id=f"{r.id}[{name}={value}]", index=0)])
        v = run(sub, path, None).verdicts[0]
        v.notes = list(v.notes) + [f"entity {name} = {value!r} ({key}): first seen at log time "
                                   f"{span[value][0]}, last at {span[value][1]}"]
        out.append(v)
    counts: dict[str, int] = {}
    for v in out:
        counts[v.verdict] = counts.get(v.verdict, 0) + 1
    summary = (f"{r.id} over {len(out)} entities {name}: "
               + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))
    for v in out:
        v.notes.append(summary)
    if cut:  # the entities left unjudged: a verdict of their own, never named r.id
        rest = alone("error", error=f"more than {MAX_ENTITIES:,} entities {name} ({key}) in "
                     f"the log: only the first {MAX_ENTITIES:,} are judged")
        rest[0].requirement = f"{r.id}[{name}=...]"
        out += rest
    return [_summary(r, path, out, summary)] + out


#: The verdict over all entities: the first of these that some entity has. A violated
#: entity decides it (the universal quantifier is false whatever the others are); else an
#: error or an unjudged entity (past :data:`MAX_ENTITIES`) leaves the whole undecided.
_PRECEDENCE = ("violated", "error", "unknown", "satisfied", "vacuous")


def _summary(r: Any, path: str, out: list[Verdict], summary: str) -> Verdict:
    """The requirement's verdict over its entities (every entity satisfies it: satisfied;
    one violates it: violated, with the earliest violation's evidence, whatever is left
    unjudged, which its notes name), named ``r.id``."""
    verdict = next(k for k in _PRECEDENCE if any(v.verdict == k for v in out))
    v = Verdict(log=path, requirement=r.id, text=r.text, source=r.source, verdict=verdict)
    bad = [x for x in out if x.verdict == "violated" and x.first_violation is not None]
    if verdict == "violated" and bad:
        first = min(bad, key=lambda x: x.first_violation.at.time_ns)  # type: ignore[union-attr]  # (bad: with one)
        v.first_violation = first.first_violation
        v.notes.append(f"first violated by {first.requirement}")
    margins = [x.robustness for x in out if x.robustness is not None]
    v.robustness = min(margins) if margins else None
    errors = "; ".join(f"{x.requirement}: {x.error}" for x in out if x.error)
    if verdict == "error":
        v.error = errors
    elif errors:  # violated all the same: what was not judged is said
        v.notes.append(f"not judged: {errors}")
    if verdict == "unknown":
        v.unknown_reason = "; ".join(f"{x.requirement}: {x.unknown_reason}" for x in out
                                     if x.verdict == "unknown")
    v.notes.append(summary)
    v.notes.append("violated by: " + (", ".join(x.requirement for x in out
                                                if x.verdict == "violated") or "none"))
    return v
