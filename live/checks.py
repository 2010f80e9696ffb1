"""What a watch checks before it steps a requirement (the audit's own checks, on what the
server advertised instead of a log's records): every variable bound, every advertised topic
it reads with a schema that decodes, and the bindings' types against the advertised schemas
(:func:`fretc.audit.checks.binding_type_errors`: a binding that reads a string as a number,
or a variable that is not a boolean or a number, is the requirement's ``error`` in the watch
as in the audit). A topic not advertised yet (a node that starts after the watch, in any
order) is no error: the requirement waits for its first message as a clock waits for a
log's, and its types are checked when it is advertised (:func:`late_type_errors`); one
never advertised in the whole run is its requirement's error at the end."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from fretc.audit.checks import binding_type_errors
from fretc.audit.verdict import Verdict
from fretc.common.streams import log_topics
from fretc.logs.schema import record_schemas

__all__ = ["watchable", "listing", "late_type_errors"]


def listing(topics: Iterable[str], most: int = 20) -> str:
    """``topics`` for an error: sorted, at most ``most`` named, the rest counted."""
    names = sorted(topics)
    if not names:
        return "no topics"
    more = f" and {len(names) - most} more" if len(names) > most else ""
    return ", ".join(names[:most]) + more


def watchable(plan: Any, src: Any, verdicts: dict[int, Verdict], skip: set[int]) -> list:
    """The requirements of ``plan`` that can be watched on ``src`` (a
    :class:`fretc.live.source.WatchSource` after its advertisements so far); the others'
    verdicts get the error (module docstring). ``skip``: indexes judged elsewhere (per
    entity)."""
    b = plan.bindings
    active = []
    for r in plan.requirements:
        v = verdicts[r.index]
        if v.error is not None or r.index in skip:
            continue
        missing = [n for n in r.variables if n not in b.variables]
        if missing:
            v.error = f"no binding for {', '.join(map(repr, missing))} in bindings " \
                      f"({b.source})"
            continue
        topics = sorted({t for n in r.variables for t in log_topics(b.variables[n].topics)})
        bad = []
        for t in topics:  # (one not advertised yet is waited for: module docstring)
            if t in src.advertised and src.decoders.get(t) is None:
                bad.append(f"topic {t} cannot be read "
                           f"({src.schema_errors.get(t, 'no decoder')})")
        if bad:
            v.error = "; ".join(bad)
            continue
        active.append(r)
    typed = binding_type_errors(src, b, plan, {i for i, v in verdicts.items()
                                               if v.error is not None} | skip,
                                schemas=record_schemas(_records(src)))
    for i, why in typed.items():
        verdicts[i].error = why
    return [r for r in active if r.index not in typed]


def late_type_errors(plan: Any, src: Any, topic: str, active: Iterable[Any],
                     verdicts: dict[int, Verdict]) -> dict[int, str]:
    """The requirements of ``active`` that read ``topic``, advertised after the watch began,
    checked as :func:`watchable` checks them (a schema that cannot be read, the bindings'
    types): requirement index -> why it is an ``error``; their verdicts get it."""
    b = plan.bindings
    readers = {r.index for r in active if verdicts[r.index].error is None and any(
        topic in log_topics(b.variables[n].topics) for n in r.variables if n in b.variables)}
    if not readers:
        return {}
    out: dict[int, str] = {}
    if src.decoders.get(topic) is None:
        why = f"topic {topic} cannot be read ({src.schema_errors.get(topic, 'no decoder')})"
        out = dict.fromkeys(readers, why)
    else:
        skip = {r.index for r in plan.requirements} - readers
        out = binding_type_errors(src, b, plan, skip, schemas=record_schemas(_records(src)))
    for i, why in out.items():
        verdicts[i].error = why
    return out


def _records(src: Any) -> dict[str, tuple[str, str, str, bytes]]:
    """Topic -> (message encoding, schema encoding, schema name, schema bytes) of the
    readable advertised channels of ``src``."""
    return {t: (ch.encoding, ch.schema_encoding, ch.schema_name,
                ch.schema.encode("utf-8", "surrogatepass"))
            for t, ch in sorted(src.advertised.items()) if src.decoders.get(t) is not None}
