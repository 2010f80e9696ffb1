"""A generated test's trace as an MCAP log of the bound topics (``fretc testgen --bindings``):
the messages that make each FRET variable's binding evaluate to the trace's value at every
tick, on the binding file's tick clock, which ``fretc audit`` reads back with the same
binding file.

Design notes: ARCHITECTURE.md, `testing/mcap_log.py`."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Sequence
from collections.abc import Set as AbstractSet
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np
from mcap.writer import CompressionType, Writer

from fretc.common.outputs import open_output, output_folder
from fretc.testing.invert import AGE, Assignment, NotWritable, field_defaults, margin, solve
from fretc.signals.bindings.spec import Bindings

if TYPE_CHECKING:
    from fretc.testing.generate import Generated
    from fretc.compiler.build import Compiled

#: other values to try for a numeric variable: (variable, trace value) -> values
Candidates = Callable[[str, float], list[Any]]

__all__ = ["EPOCH_NS", "Candidates", "plan_messages", "write_mcap", "read_back", "bind_tests",
           "thresholds", "same_side"]

#: log time of tick 0 (ns since the Unix epoch): 2023-11-14T22:13:20Z, as the simulator's
EPOCH_NS = 1_700_000_000 * 1_000_000_000


def _check_clock(bindings: Bindings) -> int:
    if bindings.tick.period_ns is None:
        raise NotWritable(f"{bindings.source}: the tick clock follows the topic "
                          f"{bindings.tick.topic}; only a fixed [tick] period is written")
    if bindings.time_base != "log":
        raise NotWritable(f"{bindings.source}: time base {bindings.time_base!r}; only log "
                          "time is written")
    return bindings.tick.period_ns


def _assignments(rows: list[dict[str, Any]], bindings: Bindings, candidates: Candidates | None
                 ) -> tuple[list[Assignment], list[str]]:
    """One assignment per tick (:func:`fretc.testing.invert.solve`), and the
    variables given other values at some tick (module docstring, "adjusted")."""
    names = list(rows[0]) if rows else []
    missing = [n for n in names if n not in bindings.variables]
    if missing:
        raise NotWritable(f"{', '.join(missing)}: no binding in {bindings.source}")
    for n in names:
        b = bindings.variables[n]
        if b.aggregate or b.window or b.uses_tf:
            raise NotWritable(f"{n} = {b.expr!r}: windows, aggregations over messages and "
                              "tf() are not inverted")
    out: list[Assignment] = []
    relaxed: set[str] = set()
    for k, row in enumerate(rows):
        wanted = [(n, bindings.variables[n].ast, _value(row[n])) for n in names]
        try:
            got, _, why = solve(wanted)
            kept = wanted
            if got is None:  # other numbers, then leave some to the messages
                wanted = _substitute(wanted, candidates)
                got = solve(wanted)[0]
                if got is None:
                    got, kept = _relax(wanted)
        except NotWritable as exc:
            raise NotWritable(f"tick {k}: {exc}") from None
        if got is None:
            raise NotWritable(f"tick {k}: {why} (no message of the bound topics gives "
                              "these values together)")
        relaxed.update(n for n, _, v in wanted if (n, v) not in {(x, y) for x, _, y in kept}
                       or v != _value(row[n]))
        out.append(got)
    return out, [n for n in names if n in relaxed]


def _value(v: Any) -> bool | float:
    """A trace value as the bindings give it: a bool (numpy's too) or a float."""
    return bool(v) if isinstance(v, (bool, np.bool_)) else float(v)


def _substitute(wanted: list[Any], candidates: Candidates | None) -> list[Any]:
    """``wanted`` with each number no message can give (``abs(x)`` = -0.5) replaced by the
    first of its ``candidates(name, value)`` one can; then, if the values still conflict,
    with the first one number replaced by a candidate that makes them agree (in order)."""
    if candidates is None:
        return wanted
    out = list(wanted)
    for i, (name, expr, value) in enumerate(out):
        if isinstance(value, bool) or solve([(name, expr, value)])[0] is not None:
            continue
        for c in candidates(name, value):
            if solve([(name, expr, c)])[0] is not None:
                out[i] = (name, expr, float(c))
                break
    if solve(out)[0] is not None:
        return out
    for i, (name, expr, value) in enumerate(out):
        if isinstance(value, bool):
            continue
        for c in candidates(name, value):
            trial = out[:i] + [(name, expr, float(c))] + out[i + 1:]
            if solve(trial)[0] is not None:
                return trial
    return out


def _relax(wanted: list[Any]) -> tuple[Assignment | None, list[Any]]:
    """An assignment for as many of ``wanted`` as a greedy pass keeps (numbers dropped
    first, in order, until the rest is solvable; then each dropped one put back when it
    fits), and the ones kept."""
    order = ([w for w in wanted if not isinstance(w[2], bool)]
             + [w for w in wanted if isinstance(w[2], bool)])
    dropped = []
    for w in order:
        dropped.append(w)
        if solve([x for x in wanted if x not in dropped])[0] is not None:
            break
    for w in list(dropped):
        trial = [x for x in wanted if x not in dropped or x is w]
        if solve(trial)[0] is not None:
            dropped.remove(w)
    kept = [x for x in wanted if x not in dropped]
    return solve(kept)[0], kept


def _held_fields(ticks: list[Assignment], defaults: Assignment
                 ) -> dict[str, list[dict[Any, Any]]]:
    """Topic -> one ``{path: value}`` per tick, every field the trace sets or the bindings
    read (``defaults``: :func:`fretc.testing.invert.field_defaults`) on the topic at
    every tick (held from the tick before; module docstring)."""
    keys: dict[tuple[Any, ...], Any] = {}
    for a in ticks:
        for k, v in a.items():
            if k[1] != AGE:
                keys.setdefault(k, v)
    for k, v in defaults.items():
        keys.setdefault(k, v)
    topics: dict[str, list[dict[Any, Any]]] = {t: [{} for _ in ticks] for t in
                                     sorted({k[0] for k in keys})}
    for key, first in sorted(keys.items(), key=lambda kv: (kv[0][0], kv[0][1])):
        held = first
        for i, a in enumerate(ticks):
            held = a.get(key, held)
            topics[key[0]][i][key[1]] = held
    return topics


def plan_messages(rows: list[dict[str, Any]], bindings: Bindings,
                  candidates: Candidates | None = None
                  ) -> tuple[list[tuple[int, str, dict[str, Any]]], list[str]]:
    """The messages of a trace: ``(log time ns, topic, JSON object)`` in log-time order
    (topics by name within a tick), and the numeric variables left to the messages
    (module docstring, "adjusted"). ``candidates(variable, value)``: other values of a
    numeric variable to try, in order, where the trace's cannot be given
    (:func:`write_mcap`).

    Raises:
        NotWritable: the trace cannot be written (module docstring)."""
    period = _check_clock(bindings)
    if not rows:
        raise NotWritable("the trace has no ticks")
    ticks, relaxed = _assignments(rows, bindings, candidates)
    defaults: dict[tuple[Any, ...], Any] = {}
    for n in rows[0]:
        defaults.update(field_defaults(bindings.variables[n].ast))
    fields = _held_fields(ticks, defaults)
    age_topics = sorted({k[0] for a in ticks for k in a if k[1] == AGE})
    for t in age_topics:
        fields.setdefault(t, [{} for _ in ticks])
    plan = _age_plan(ticks, age_topics, period)
    out: list[tuple[int, str, dict[str, Any]]] = []
    for topic, at in sorted(plan.items()):
        if at and at[0] < 0:
            out.append((EPOCH_NS + at[0] * period, topic, _nested(fields[topic][0])))
    sets = {t: set(at) for t, at in plan.items()}
    for i in range(len(ticks)):
        for topic in sorted(fields):
            if topic in sets and i not in sets[topic]:
                continue
            out.append((EPOCH_NS + i * period, topic, _nested(fields[topic][i])))
    out.sort(key=lambda m: m[0])
    return out, relaxed


def _age_plan(ticks: list[Assignment], topics: list[str], period: int) -> dict[str, list[int]]:
    """Topic with an ``age()`` constraint -> the tick indexes it has a message at (one
    index < 0 first when a message is needed before tick 0)."""
    plan = {}
    n = len(ticks)
    for topic in topics:
        keep = set(range(n))
        need_before = 0
        for k, a in enumerate(ticks):
            c = a.get((topic, AGE))
            if c is None or not c[0]:
                continue
            _, c_ns, strict = c
            # age > c (strict) needs no message at j with (k - j) * period <= c, age >= c
            # none with (k - j) * period < c: the last m ticks up to k are quiet
            m = c_ns // period if strict else -(-c_ns // period) - 1
            keep.difference_update(range(k - m, k + 1))
            need_before = min(need_before, k - m - 1)
        for k, a in enumerate(ticks):
            c = a.get((topic, AGE))
            if c is None or c[0]:
                continue
            _, c_ns, strict = c  # fresh: a message at j <= k with (k - j) * period <= c
            if not any((k - j) * period <= c_ns if strict else (k - j) * period < c_ns
                       for j in keep if j <= k):
                raise NotWritable(f"tick {k}: age({topic}) must be small there but a later "
                                  "tick needs the topic silent before it")
        plan[topic] = ([need_before] if need_before < 0 else []) + sorted(keep)
    return plan


def _nested(flat: dict[tuple[Any, ...], Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for path, v in sorted(flat.items()):
        d = out
        for p in path[:-1]:
            d = d.setdefault(p, {})
        d[path[-1]] = v
    return out


def _schema(obj: Any) -> dict[str, Any]:
    if isinstance(obj, dict):
        return {"type": "object", "properties": {k: _schema(v) for k, v in obj.items()}}
    if isinstance(obj, bool):
        return {"type": "boolean"}
    if isinstance(obj, list):
        return {"type": "array", "items": {"type": "number"}}
    return {"type": "string"} if isinstance(obj, str) else {"type": "number"}


def write_mcap(rows: list[dict[str, Any]], bindings: Bindings, path: str | Path,
               candidates: Candidates | None = None
               ) -> tuple[list[dict[str, Any]] | None, list[str], str | None]:
    """Write the MCAP log of ``rows`` (one mapping FRET variable -> value per tick) under
    ``bindings`` to ``path`` and check it by reading it back (module docstring). Returns the
    rows the audit reads from it (equal to ``rows`` but for the adjusted variables), the
    adjusted variables and None; or None, [] and why it is not written (nothing is left at
    ``path`` then). ``candidates(variable, value)``: values to try instead of a numeric
    trace value no message gives (:func:`bind_tests`: values on the same side of every
    threshold the requirements compare the variable with, :func:`same_side`)."""
    path = Path(path)
    try:
        msgs, relaxed = plan_messages(rows, bindings, candidates)
    except NotWritable as exc:
        return None, [], str(exc)
    schemas: dict[str, dict[str, Any]] = {}
    for _, topic, obj in msgs:
        schemas.setdefault(topic, _schema(obj))
    with open_output(path, "wb") as f:  # (never through a link planted there)
        w = Writer(f, compression=CompressionType.ZSTD)
        w.start(profile="", library="fretc-testgen")
        channels = {}
        for topic in sorted(schemas):
            name = bindings.types.get(topic) or "fretc_testgen" + topic
            sid = w.register_schema(name=name, encoding="jsonschema",
                                    data=json.dumps(schemas[topic], sort_keys=True).encode())
            channels[topic] = w.register_channel(topic=topic, message_encoding="json",
                                                 schema_id=sid)
        seq: dict[str, int] = {}
        for t, topic, obj in msgs:
            seq[topic] = seq.get(topic, -1) + 1
            w.add_message(channel_id=channels[topic], log_time=t, publish_time=t,
                          data=json.dumps(obj, sort_keys=True).encode(), sequence=seq[topic])
        w.finish()  # type: ignore[no-untyped-call]  # (mcap's Writer.finish has no annotations)
    got, why = read_back(rows, bindings, path, set(relaxed))
    if why is not None:
        path.unlink()
        return None, [], why
    return got, relaxed, None


def read_back(rows: list[dict[str, Any]], bindings: Bindings, path: str | Path,
              free: AbstractSet[str] = frozenset()) -> tuple[list[dict[str, Any]] | None, str | None]:
    """The rows the audit's sampler reads from ``path`` under ``bindings`` and None when
    they are ``rows`` (same ticks, every variable but those of ``free`` equal); else None
    and the first difference."""
    from dataclasses import replace

    from fretc.logs import open_log
    from fretc.signals.clock import sample
    from fretc.common.problems import SignalError

    names = list(rows[0]) if rows else []
    bindings = replace(bindings, variables={n: bindings.variables[n] for n in names})
    src = open_log(path)
    try:
        got = [t.values for t in sample(src, bindings)]
    except SignalError as exc:
        return None, f"the log written does not read back: {exc}"
    finally:
        src.close()
    if len(got) != len(rows):
        return None, (f"the log written reads back as {len(got)} ticks, the trace has "
                      f"{len(rows)}")
    out = []
    for k, (g, r) in enumerate(zip(got, rows)):
        for n, v in r.items():
            if n not in free and g.get(n) != _value(v):
                return None, (f"tick {k}: the log written reads back {n}={g.get(n)!r}, the "
                              f"trace has {v!r} (variables sharing a topic's messages)")
        out.append({n: g[n] for n in r})
    return out, None


def thresholds(compiled: Sequence[Compiled]) -> dict[str, list[float]]:
    """FRET variable -> the constants it is compared with in the ft formulas of ``compiled``
    (sorted, without repeats)."""
    from fretc.compiler import ir

    out: dict[str, set[float]] = {}
    for c in compiled:
        if c.formalization is None:
            continue
        for n in ir.walk(c.formalization.ft):
            if n.op != "cmp":
                continue
            a, b = n.args
            for var, k in ((a, b), (b, a)):
                if var.op == "var" and k.op == "num":
                    out.setdefault(ir.name_of(var), set()).add(float(ir.name_of(k)))
    return {v: sorted(cs) for v, cs in out.items()}


def same_side(value: float, limits: Iterable[float]) -> list[float]:
    """Values on the same side of every threshold of ``limits`` as ``value`` (so every
    comparison of the variable with a constant keeps its truth), the non-negative ones
    first: none when ``value`` is a threshold itself."""
    limits = sorted(limits)
    if value in limits:
        return []
    lo = max((t for t in limits if t < value), default=-float("inf"))
    hi = min((t for t in limits if t > value), default=float("inf"))
    picks = [0.0, abs(value), (lo + hi) / 2, hi - margin(hi), lo + margin(lo)]
    ok = [p for p in picks if lo < p < hi and p == p]
    return sorted(dict.fromkeys(ok), key=lambda p: (p < 0, ok.index(p)))


def bind_tests(gen: Generated, compiled: Sequence[Compiled], bindings: Bindings,
               out_dir: str | Path) -> None:
    """Write ``DIR/T01.mcap``... for the tests of ``gen`` (a
    :class:`fretc.testing.generate.Generated` of ``compiled``) under ``bindings``, setting each
    test's ``log`` (the file name) or ``log_why`` (why none was written) and ``adjusted``.

    A test whose trace the bindings can give only with some variables left to the messages
    (``adjusted``, module docstring) becomes the trace read back from its log: its
    ``covers`` and ``expected`` are the audit's again on it, and it is kept only if it still
    exercises every obligation it covered (else no log, and the reason)."""
    from fretc.check.stream_rows import trace_streams, with_stream_columns
    from fretc.testing.generate import column_kinds, covered_by, expected_of

    out = Path(output_folder(out_dir))
    kinds = column_kinds([c for c in compiled if c.formalization is not None])
    streams = trace_streams(compiled, kinds)
    limits = thresholds(compiled)
    for k, t in enumerate(gen.tests, 1):
        name = f"T{k:02d}.mcap"
        rows, adjusted, why = write_mcap(t.rows, bindings, out / name,
                                         lambda n, v: same_side(v, limits.get(n, ())))
        if rows is None:
            t.log, t.log_why, t.adjusted = None, why, []
            continue
        if adjusted:  # (a stream variable computed again from the values the log gives)
            rows = with_stream_columns(rows, streams)
            covers = covered_by(compiled, gen.obligations, rows, kinds)
            lost = sorted({(r, o) for r, o, _ in t.covers} - {(r, o) for r, o, _ in covers})
            if lost:
                (out / name).unlink()
                t.log, t.adjusted = None, []
                t.log_why = (f"the bindings give {', '.join(adjusted)} other values than the "
                             "trace's, and the trace they give no longer exercises "
                             + ", ".join(f"{r} {o}" for r, o in lost))
                continue
            t.rows, t.covers = rows, covers
            t.expected = expected_of(compiled, rows, kinds)
        t.log, t.log_why, t.adjusted = name, None, adjusted
