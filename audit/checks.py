"""Checks of one log's inputs before it is read: the bindings a CSV trace gets, the number
of ticks a fixed period would give, the binding types against the log's schemas, and the
tick topic's measured rate against its nominal rate."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from fretc.common.units import NS_PER_S, format_ns
from fretc.compiler import ir

from fretc.signals.bindings import Bindings, check_types, compile_expression
from fretc.signals.bindings.expression import FUNCS
from fretc.common.problems import BindingError
from fretc.logs.schema import TopicSchema, log_schemas
from fretc.logs import CSV_TOPIC
from fretc.audit.model import AuditPlan, RequirementPlan
from fretc.audit.passes import MAX_TICKS, expected_ticks

if TYPE_CHECKING:
    from fretc.audit.verdict import LogAudit
    from fretc.logs.base import LogSource

__all__ = ["RATE_TOLERANCE", "csv_bindings", "too_many_ticks", "binding_type_errors",
           "check_nominal_rate", "rate_hint", "call_hint"]

#: A tick topic's measured rate may differ this much from its nominal rate without warning.
RATE_TOLERANCE = 0.10


def csv_bindings(plan: AuditPlan, bindings: Bindings, source: LogSource) -> Bindings:
    """CSV with bindings: the bound variables as bound; every other variable of the
    requirements that names a column reads it (``/csv.<column>``). A sampled trace (its
    first line :data:`fretc.logs.csv.source.SAMPLED_MARK`, as ``fretc audit --write-csv``
    writes it) holds the variables with the bindings already applied: a variable that
    names one of its columns reads it, whatever the binding files bind it to, and its
    ±inf are the variable's values (``max`` over a filter that keeps nothing is -inf), not
    a field's undeclared ones (docs/bindings.md, "NaN, ±inf")."""
    variables = dict(bindings.variables)
    sampled = getattr(source, "sampled", False)
    for r in plan.requirements:
        for v in r.variables:
            if (v not in variables or sampled) and v in source.columns:  # type: ignore[attr-defined]  # a CsvSource
                variables[v] = compile_expression(v, f"{CSV_TOPIC}.{v}",
                                                  source=f"<CSV column {v}>",
                                                  inf="value" if sampled else "unread")
    return Bindings(variables, bindings.tick, bindings.time_base, bindings.header_lag_ns,
                    bindings.source)


def too_many_ticks(source: LogSource, bindings: Bindings | None, path: str) -> str | None:
    """The error when the fixed tick period would give more than :data:`MAX_TICKS` ticks
    over the log's span (first to last message), else None."""
    if bindings is None or not bindings.tick.period_ns or source.kind == "csv":
        return None
    n = expected_ticks(source, bindings)
    if n is None or n <= MAX_TICKS:
        return None
    assert source.end_time is not None and source.start_time is not None  # (n: a span)
    span = (source.end_time - source.start_time) / NS_PER_S
    return (f"{path}: the tick period {format_ns(bindings.tick.period_ns)} ({bindings.source}) "
            f"would give {n:,} ticks over the {span:.3f} s of the log, more than the limit of "
            f"{MAX_TICKS:,}; choose a longer period")


def binding_type_errors(source: LogSource, bindings: Bindings, plan: AuditPlan, skip: set[int],
                        schemas: Mapping[str, TopicSchema | None] | None = None
                        ) -> dict[int, str]:
    """The bindings the requirements use checked against the log's message types
    (:func:`fretc.signals.bindings.check_types`): requirement index -> why it is an ``error``
    (a binding that names a field the schema does not declare, mixes strings, booleans and
    numbers, or is used as the other kind), before anything is evaluated. Requirements whose
    index is in ``skip`` (already in error) are not checked, nor a sampled trace
    (:mod:`fretc.audit.sampled.csv`: its columns are variables checked on their log).
    ``schemas``: topic -> :class:`fretc.logs.schema.TopicSchema` when not the log's own (a
    watch's advertised ones, :func:`fretc.logs.schema.record_schemas`)."""
    if getattr(source, "sampled", False):  # the variables' types were checked on their log
        return {}
    try:
        schemas = log_schemas(source) if schemas is None else schemas
    except Exception:  # unreadable schemas: the reader reports the damage itself
        return {}
    errors: dict[int, str] = {}
    bad: dict[str, str] = {}
    types: dict[str, str] = {}
    undecodable = _undecodable_topics(source, schemas)
    for r in plan.requirements:
        if r.index in skip:
            continue
        uses = variable_uses(r)
        for v in r.variables:
            b = bindings.variables.get(v)
            if b is None:
                continue
            if v not in bad:
                lost = sorted(set(b.topics) & set(undecodable))
                try:
                    if lost:
                        bad[v] = undecodable[lost[0]]
                    else:
                        types[v] = check_types(b, schemas)
                        bad[v] = ""
                except BindingError as exc:
                    bad[v] = str(exc)
            if bad[v]:
                errors[r.index] = bad[v]
                break
            use, t = uses.get(v, set()), types.get(v)
            where = f"{b.source}:{b.line}" if b.line is not None else str(b.source)
            if t == "bool" and "var" in use:
                errors[r.index] = (
                    f"{where}: type error: {r.id} uses {v!r} as a number, but its binding "
                    f"{b.expr!r} is a boolean; bind it to a number")
                break
            if t == "number" and "ap" in use:
                errors[r.index] = (
                    f"{where}: type error: {r.id} uses {v!r} as a boolean, but its binding "
                    f"{b.expr!r} is a number; compare it (e.g. {b.expr.strip()} > 0) to make "
                    "a boolean")
                break
    return errors


def _undecodable_topics(source, schemas: Mapping[str, TopicSchema | None]) -> dict[str, str]:
    """Topic -> why its messages cannot be decoded, for the topics that name a message type
    whose definition the log does not carry or that cannot be parsed (a custom type of a
    bag that stores no definitions: the reason names ``--msg-path``)."""
    out: dict[str, str] = {}
    if source.kind not in ("bag", "rosbag2"):  # logs that carry their schemas report them
        return out
    from fretc.logs.ros.msg_path import MSG_PATH_HINT  # lazy: bags only (start-up)

    for topic, typ in source.topics().items():
        if typ and topic in schemas and schemas[topic] is None:
            out[topic] = (f"topic {topic}: its messages cannot be decoded: the log carries no "
                          f"usable definition of {typ} (give it with {MSG_PATH_HINT})")
    return out


def variable_uses(r: RequirementPlan) -> dict[str, set]:
    """FRET variable -> {"ap"} (used as a boolean) and/or {"var"} (used as a number, inside
    a comparison or arithmetic), from the requirement's formulas (compiler.ir)."""
    out: dict[str, set] = {}
    f = r.formalization
    if f is None:
        return out
    stack = [f.pt, f.ft]
    while stack:
        n = stack.pop()
        if n is None:
            continue
        if n.op in ("ap", "var"):
            out.setdefault(ir.name_of(n), set()).add(n.op)
        stack.extend(n.args)
    return out


def check_nominal_rate(la: LogAudit, bindings: Bindings | None) -> None:
    """Warn when one tick per message of a topic whose nominal rate converts the durations
    runs at a measured rate (messages over the log's span) more than
    :data:`RATE_TOLERANCE` away from it: ``within 1 second`` then means a different time."""
    if bindings is None or bindings.tick.topic is None or not bindings.tick.nominal_period_ns:
        return
    n = la.messages.get(bindings.tick.topic, 0)
    st, en = la.start_time_ns, la.end_time_ns
    if n < 2 or st is None or en is None or en <= st:
        return
    measured = (n - 1) * NS_PER_S / (en - st)
    nominal = NS_PER_S / bindings.tick.nominal_period_ns
    if abs(measured - nominal) > RATE_TOLERANCE * nominal:
        la.warnings.append(
            f"{bindings.tick.topic} runs at {measured:.3g} Hz, not its nominal "
            f"{nominal:.3g} Hz ({bindings.source}): durations in time units, converted with "
            f"the nominal rate, are off by {abs(measured / nominal - 1):.0%}")



def rate_hint(source: LogSource, topic: str, counts: dict[str, int]) -> str:
    """The ``nominal_rate`` to write for ``topic``, measured on this log (messages over
    the log's span; ``counts``: messages per topic already read, else the topic is counted
    now): ``'; /scan runs at 50 Hz in this log: nominal_rate = "50 Hz"'``, or "" when the
    log does not tell (fewer than two messages, no span)."""
    n = counts.get(topic)
    if n is None:
        try:
            n = sum(1 for _ in source.messages({topic}))
        except Exception:  # a damaged log: the reader reports it; no hint
            return ""
    st, en = source.start_time, source.end_time
    if n < 2 or st is None or en is None or en <= st:
        return ""
    rate = f"{(n - 1) * NS_PER_S / (en - st):.3g} Hz"
    return f"; {topic} runs at {rate} in this log: nominal_rate = \"{rate}\""


#: The binding language's functions that FRETish does not have (FRETish has abs, min and max
#: as absReal/absInt, minReal/minInt, maxReal/maxInt): a requirement that calls one reads it
#: as an unknown variable.
BINDING_FUNCTIONS = frozenset(FUNCS) - {"abs", "min", "max"}


def call_hint(name: str) -> str:
    """What to write instead of a call FRET does not know (``abs(x)``, ``fabs(x)``, which a
    requirement reads as one variable): FRET's own functions (FRET's manual, "Arithmetic
    expressions": absReal/absInt, minReal/minInt, maxReal/maxInt), or the binding's."""
    func, _, rest = name.partition("(")
    f = func.strip().lower()
    if func.strip() in BINDING_FUNCTIONS:
        return (f"{name!r} calls {func.strip()!r}, a function of the binding language, not "
                "of FRETish: bind a variable to it in a binding file (e.g. "
                f"x = \"{func.strip()}(/topic.field)\") and use x in the requirement")
    fret = {"abs": "absReal(...) or absInt(...)", "fabs": "absReal(...) or absInt(...)",
            "min": "minReal(...) or minInt(...)", "max": "maxReal(...) or maxInt(...)"}.get(f)
    spelled = f"FRET spells it {fret}" if fret else (
        "FRET's functions are absReal/absInt, minReal/minInt, maxReal/maxInt")
    return (f"{name!r} is a call of {func.strip()!r}, a function FRET does not know: "
            f"{spelled}; or bind a variable to the value (e.g. {f}({rest.rstrip(')')}) in "
            "a binding file)" if f in ("abs", "min", "max") else
            f"{name!r} is a call of {func.strip()!r}, a function FRET does not know: "
            f"{spelled}")
