"""``fretc inspect LOG... [--json]``: what a log holds, to write its signal bindings.

Design notes: ARCHITECTURE.md, `fretc/cli/inspect.py`."""

from __future__ import annotations

import json
import math
import sys
from typing import Any

import click

from fretc.cli.options import MSG_PATH_OPTION

__all__ = ["inspect_cmd", "inspect_log", "MAX_VALUES", "plain"]

#: Distinct values of a text field listed at most (more: "and more").
MAX_VALUES = 40


#: Scalar values a field keeps before they are reduced to its minimum and maximum at once.
_PENDING = 65536


class _Stat:
    __slots__ = ("type", "min", "max", "nonfinite", "lengths", "true", "false", "n", "texts",
                 "constants", "pending", "arrays", "kept")

    def __init__(self, type_text: str, constants: dict | None = None) -> None:
        self.type = type_text
        self.texts: set = set()
        self.constants = constants or {}
        self.min = math.inf
        self.max = -math.inf
        self.nonfinite = 0
        self.lengths: set = set()
        self.true = self.false = self.n = 0
        self.pending: list = []
        self.arrays: list = []
        self.kept = 0

    def scalar(self, value) -> None:
        """One number (kept, then reduced with the others: one numpy call per many)."""
        self.pending.append(value)
        if len(self.pending) >= _PENDING:
            self.flush()

    def array(self, values) -> None:
        """An array of numbers (kept, then reduced with the others)."""
        self.arrays.append(values)
        self.kept += len(values)
        if self.kept >= _PENDING:
            self.flush()

    def flush(self) -> None:
        """Reduce the numbers kept by :meth:`scalar` and :meth:`array`."""
        import numpy as np  # lazy: numpy only when a log is read

        if self.pending:
            values, self.pending = self.pending, []
            self.numbers(values)
        if self.arrays:
            parts, self.arrays, self.kept = self.arrays, [], 0
            self.numbers(np.concatenate([np.asarray(a, dtype=np.float64).ravel()
                                         for a in parts]))

    def numbers(self, values) -> None:
        import numpy as np  # lazy: numpy only when a log is read
        a = np.asarray(values, dtype=np.float64).ravel()
        if a.size == 0:
            return
        fin = np.isfinite(a)
        self.nonfinite += int((~fin).sum())
        if fin.any():  # (+ 0.0: a zero is printed 0, whichever sign it was stored with)
            self.min = min(self.min, float(a[fin].min()) + 0.0)
            self.max = max(self.max, float(a[fin].max()) + 0.0)

    def text(self, values) -> None:
        for v in values:
            if len(self.texts) > MAX_VALUES:
                return
            self.texts.add(str(v))

    def to_json(self) -> dict:
        self.flush()
        out: dict[str, Any] = {"type": self.type}
        if self.texts:
            out["values"] = sorted(self.texts)[:MAX_VALUES]
            if len(self.texts) > MAX_VALUES:
                out["more_values"] = True
        if self.constants:
            out["constants"] = dict(self.constants)
        if self.min <= self.max:
            out["min"], out["max"] = self.min, self.max
        if self.nonfinite:
            out["nonfinite"] = self.nonfinite
        if self.lengths:
            out["lengths"] = [min(self.lengths), max(self.lengths)]
        if self.true or self.false:
            out["true"], out["false"] = self.true, self.false
        return out


def _field_constants(schema, typename: str, name: str, t) -> dict:
    """The named constants of ``typename`` that belong to its field ``name``: those named
    after the field (``POWER_SUPPLY_STATUS_*`` for ``power_supply_status``, ROS's habit), or,
    when no constant is named after any field, those of the field's own ROS type
    (DiagnosticStatus: ``byte OK = 0`` .. ``STALE`` for ``byte level``)."""
    consts = _constants(schema, typename)
    if not consts or t.kind not in ("number", "bool", "string"):
        return {}
    fields = [f for f, _ in schema.fields(typename)]
    prefix = name.upper() + "_"
    mine = {c: v for c, (ty, v) in consts.items() if c.startswith(prefix)}
    if mine:
        return mine
    if any(c.startswith(f.upper() + "_") for c in consts for f in fields):
        return {}
    return {c: v for c, (ty, v) in consts.items() if ty == t.name}


def _constants(schema, typename: str) -> dict:
    try:
        consts = schema.store.fielddefs[typename][0]
    except (AttributeError, KeyError, TypeError):
        return {}
    return {c[0]: (c[1], c[2]) for c in consts}


def _plan(schema, typename: str, prefix: str, stats: dict[str, _Stat], plans: dict) -> list:
    """The fields of ``typename`` as visited under path ``prefix``: ``(attribute, kind,
    item kind, stat, sub-plan)`` per field, made once per (type, path) and kept in ``plans``
    (the schema's field list is not walked again for every message)."""
    key = (typename, prefix)
    got = plans.get(key)
    if got is not None:
        return got
    out: list = []
    plans[key] = out
    for name, t in schema.fields(typename):
        path = f"{prefix}.{name}"
        st = stats.get(path)
        if st is None:
            st = stats[path] = _Stat(t.text(), _field_constants(schema, typename, name, t))
        sub = None
        item = t.item.kind if t.kind == "array" else None
        if t.kind == "message":
            sub = _plan(schema, t.name, path, stats, plans)
        elif item == "message":
            sub = _plan(schema, t.item.name, f"{path}[:]", stats, plans)
        out.append((name, t.kind, item, st, sub))
    return out


def _visit(plan: list, obj) -> None:
    """Add the values of message ``obj`` to the stats of its fields (``plan``: :func:`_plan`)."""
    for name, kind, item, st, sub in plan:
        v = getattr(obj, name, None)
        if kind == "message":
            _visit(sub, v)
        elif kind == "array":
            v = v if v is not None else ()  # a field the message lacks: empty
            n = len(v)
            st.lengths.add(n)
            if item == "message":
                for x in v:
                    _visit(sub, x)
            elif item == "number":
                st.array(v)
            elif item == "bool":
                k = sum(1 for x in v if x)
                st.true += k
                st.false += n - k
            elif item == "string":
                st.text(v)
        elif kind == "number":
            st.scalar(v)
        elif kind == "string":
            if len(st.texts) <= MAX_VALUES:
                st.text([v])
        elif kind == "bool":
            if v:
                st.true += 1
            else:
                st.false += 1


def _visit_untyped(prefix: str, obj: Any, stats: dict[str, _Stat]) -> None:
    """Add the values of a message decoded without a field list (a ``SimpleNamespace``
    tree, as the JSON reader gives: :mod:`fretc.logs.mcap.encodings`) to ``stats``, each field
    typed by its JSON value; a field whose values change type is ``mixed``, an array whose
    items do ``mixed[]``."""
    import numpy as np  # lazy: as in _Stat

    for name, v in vars(obj).items():
        if name.startswith("__"):  # the reader's own marks (the type's name), not fields
            continue
        path = f"{prefix}.{name}"
        if hasattr(v, "__dict__") and not isinstance(v, np.ndarray):
            _visit_untyped(path, v, stats)
            continue
        if isinstance(v, np.ndarray) or isinstance(v, (list, tuple)):
            items = list(v)
            if not items:
                kind = "array"  # no item: the items' type comes with a later message
            elif all(hasattr(x, "__dict__") for x in items):
                kind = "object[]"
            elif all(isinstance(x, bool | np.bool_) for x in items):
                kind = "boolean[]"
            elif all(isinstance(x, int | float | np.number) and not isinstance(x, bool)
                     for x in items):
                kind = "number[]"
            elif all(isinstance(x, str) for x in items):
                kind = "string[]"
            else:
                kind = "mixed[]"  # items of several JSON types
        elif isinstance(v, bool):
            kind = "boolean"
        elif isinstance(v, int | float):
            kind = "number"
        elif isinstance(v, str):
            kind = "string"
        else:
            kind = "null" if v is None else type(v).__name__
        st = stats.get(path)
        if st is None:
            st = stats[path] = _Stat(kind)
        elif st.type != kind:
            if st.type == "array" and kind.endswith("[]"):
                st.type = kind  # an empty array first: its items' type when one comes
            elif not (kind == "array" and st.type.endswith("[]")):
                st.type = "mixed[]" if kind.endswith("[]") and st.type.endswith("[]") \
                    else "mixed"
        if kind == "object[]":
            st.lengths.add(len(items))
            for x in items:
                _visit_untyped(f"{path}[:]", x, stats)
        elif kind.endswith("[]") or kind == "array":
            st.lengths.add(len(items))
            if kind == "number[]":
                st.array(np.asarray(items, dtype=float))
            elif kind == "boolean[]":
                k = sum(1 for x in items if x)
                st.true += k
                st.false += len(items) - k
            elif kind == "string[]":
                st.text(items)
        elif kind == "number" and st.type == "number":
            st.scalar(v)
        elif kind == "boolean" and st.type == "boolean":
            st.true += v
            st.false += not v
        elif kind == "string" and st.type == "string" and len(st.texts) <= MAX_VALUES:
            st.text([v])


def inspect_log(path: str, msg_path: tuple[str, ...] = ()) -> dict:
    """The inventory of one log (module docstring) as a JSON-ready dict; ``msg_path``:
    folders of the types the log does not carry (``--msg-path``).

    Raises:
        common.problems.FretcInputError: the file is not a readable log.
    """
    # lazy: the log readers (mcap, rosbags) only when the command runs
    from fretc.signals.bindings.paths import topic_text
    from fretc.logs.schema import log_schemas
    from fretc.logs import open_log

    source = open_log(path, msg_path=msg_path)
    types = source.topics()
    schemas = log_schemas(source)
    stats: dict[str, dict[str, _Stat]] = {t: {} for t in types}
    first: dict[str, int] = {}
    last: dict[str, int] = {}
    counts: dict[str, int] = {}
    plans: dict = {}
    untyped: set[str] = set()
    # a topic whose schema is missing or not parsed is listed without fields ("schema
    # unknown"), its messages counted
    visit = {t: _plan(s, s.typename, topic_text(t), stats[t], plans)
             for t, s in schemas.items()
             if s is not None and t in stats and source.kind != "csv"}
    for m in source.messages(None):
        counts[m.topic] = counts.get(m.topic, 0) + 1
        first.setdefault(m.topic, m.log_time)
        last[m.topic] = m.log_time
        plan = visit.get(m.topic)
        if plan is not None:
            _visit(plan, m.data)
        elif source.kind != "csv" and hasattr(m.data, "__dict__"):  # decoded, no field list
            _visit_untyped(topic_text(m.topic), m.data, stats[m.topic])
            untyped.add(m.topic)
        elif source.kind == "csv":
            for c in source.columns:  # type: ignore[attr-defined]  # a CsvSource
                st = stats[m.topic].setdefault(f"{m.topic}.{c}",
                                               _Stat(source.types.get(c, "")))  # type: ignore[attr-defined]
                v = getattr(m.data, c)
                if isinstance(v, bool):
                    st.true += v
                    st.false += not v
                else:
                    st.numbers([v])
    topics = []
    for t, typ in types.items():
        lost = [v for (_k, topic, _c), v in source.lost.items() if topic == t]
        undecoded = sum(v[2] for v in lost)
        n = max(source.records.get(t, 0), counts.get(t, 0) + undecoded)  # decoded or not
        times = [x for x in (first.get(t), last.get(t)) if x is not None]
        times += [x for v in lost for x in v[:2]]
        span = (max(times) - min(times)) / 1e9 if n > 1 and times else None
        topics.append({"topic": t, "type": typ or None, "messages": n,
                       "not_decoded": undecoded,
                       "not_decoded_why": lost[0][3] if lost else None,
                       "rate_hz": (n - 1) / span if span else None,
                       "schema": schemas.get(t) is not None,
                       "fields_from_messages": t in untyped,
                       "fields": {p: s.to_json() for p, s in stats[t].items()}})
    t0, t1 = source.start_time, source.end_time
    # a ULog's header start (PX4's logger stamps each topic's last sample before it, kept
    # as data: the span starts at the first sample, the recording at the header)
    header = getattr(source, "log_start", None)
    return {"log": str(path), "kind": source.kind, "start_time_ns": t0, "end_time_ns": t1,
            "duration_s": (t1 - t0) / 1e9 if t0 is not None and t1 is not None else None,
            "header_start_ns": header,
            "partial": bool(source.partial),
            "problems": [str(p) for p in source.problems], "topics": topics}


def plain(x: float) -> str:
    """A number in plain notation with the digits that tell it apart (``1432240000.25``,
    ``0.000158``; never ``1.43224e+09``): the shortest text that reads back as ``x``."""
    import numpy as np  # lazy: as in _Stat
    return np.format_float_positional(float(x), trim="-")


def _print(doc: dict) -> None:
    dur = f"{doc['duration_s']:.3f} s" if doc["duration_s"] is not None else "unknown span"
    t0, header = doc["start_time_ns"], doc.get("header_start_ns")
    if header is not None and t0 is not None and header > t0:
        dur += (f" (from the first sample; the ULog header starts the recording "
                f"{(header - t0) / 1e9:.3f} s after it)")
    click.echo(f"{doc['log']} ({doc['kind']}): {dur}, {len(doc['topics'])} topics"
               + (" [partial: damaged]" if doc["partial"] else ""))
    for t in doc["topics"]:
        rate = f"{t['rate_hz']:.3g} Hz" if t["rate_hz"] else "-"
        plural = "message" if t["messages"] == 1 else "messages"
        lost = (f"  ({t['not_decoded']} not decoded: {t['not_decoded_why']})"
                if t.get("not_decoded") else "")
        click.echo(f"  {t['topic']}  {t['type'] or '?'}  {t['messages']} {plural}  {rate}"
                   + ("  (no field list in the schema: fields from the messages)"
                      if t.get("fields_from_messages")
                      else "" if t["schema"] else "  (schema unknown)") + lost)
        for p, f in t["fields"].items():
            extra = []
            if "lengths" in f:
                lo, hi = f["lengths"]
                extra.append(f"length {lo}" if lo == hi else f"length {lo}..{hi}")
            if "min" in f:
                extra.append(f"min {plain(f['min'])} max {plain(f['max'])}")
            if f.get("nonfinite"):
                extra.append(f"{f['nonfinite']} NaN/inf")
            if "true" in f:
                extra.append(f"true {f['true']} false {f['false']}")
            if "values" in f:
                extra.append("values " + ", ".join(json.dumps(v) for v in f["values"])
                             + (" and more" if f.get("more_values") else ""))
            if "constants" in f:
                extra.append("constants " + ", ".join(f"{k} = {json.dumps(v)}"
                                                      for k, v in f["constants"].items()))
            click.echo(f"    {p}  {f['type']}" + (f"  {', '.join(extra)}" if extra else ""))
    for p in doc["problems"]:
        click.echo(f"  problem: {p}")


@click.command("inspect")
@click.argument("logs", nargs=-1, required=True)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list, one object per log.")
@MSG_PATH_OPTION
def inspect_cmd(logs: tuple[str, ...], as_json: bool, msg_path: tuple[str, ...]) -> None:
    """List what LOGS (.mcap, .bag, rosbag2 folders, .csv) hold: topics, message types,
    counts, rates, time span, and every field path in binding syntax, as it binds when pasted
    (quoted topics, [:] for items), with its type, array lengths, numeric min/max, the values
    of text fields and the constants of enum fields - what a binding file can name
    (docs/bindings.md)."""
    from fretc.common.problems import FretcInputError  # lazy: as the readers

    docs: list[dict] = []
    failed = False
    for p in logs:
        try:
            docs.append(inspect_log(p, tuple(msg_path)))
        except (FretcInputError, OSError) as exc:
            click.echo(f"error: {exc}", err=True)
            failed = True
    if as_json:
        click.echo(json.dumps(docs, indent=2, sort_keys=True))
    else:
        for d in docs:
            _print(d)
    sys.exit(2 if failed else 0)
