"""Binding files: TOML (read with :mod:`tomllib`) with the tables ``[tick]``,
``[variables]`` and optionally ``[logs]`` (format: ``docs/bindings.md``) -> :class:`Bindings`.

Errors name the file, line and column: :mod:`tomllib` does not keep positions, so
:class:`_Locations` finds tables and keys in the text again (one per line, as binding files
are written; anything else gets the line of its table, or none).
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from fretc.common.units import parse_duration

from fretc.common.problems import BindingError
from fretc.signals.bindings.binding import VARNAME, Binding, compile_expression
from fretc.signals.bindings.expression import refs
from fretc.signals.bindings.parse_cache import kept_parses
from fretc.signals.bindings.paths import topic_name
from fretc.signals.bindings.spec import (DEFAULT_HEADER_LAG_NS, INF_POLICIES, NAN_POLICIES, TIME_BASES, Bindings, EntitySpec, HOLDS, LogSelector,
                   TickSpec)

__all__ = ["parse_bindings", "load_bindings", "MAX_REFERENCE_CHAIN"]

#: How deep variables may refer to one another (``a = "b"``, ``b = "c"``, ...)
MAX_REFERENCE_CHAIN = 100

# ------------------------------------------------------------------------------------------------
# Where things are in the TOML text
# ------------------------------------------------------------------------------------------------

_TABLE = re.compile(r"\s*\[\s*([A-Za-z0-9_.\"' -]+?)\s*\]\s*(#.*)?\Z")
_KEY = re.compile(r"""\s*(?:"((?:[^"\\]|\\.)*)"|'([^']*)'|([A-Za-z0-9_-]+))\s*=\s*""")


class _Locations:
    """Lines and columns of the tables and keys of a binding file's text."""

    def __init__(self, text: str) -> None:
        #: (table, key) → (line, col of the value's first char, value text rest of line);
        #: ("[table]", table) → the table header; ("[key]", "table.key") → the key itself.
        self.where: dict[tuple[str, str], tuple[int, int, str]] = {}
        table = ""
        for i, raw in enumerate(text.splitlines(), start=1):
            m = _TABLE.match(raw)
            if m and not raw.lstrip().startswith("[["):
                table = m.group(1).strip().strip("\"'")
                self.where.setdefault(("[table]", table), (i, raw.index("[") + 1, ""))
                continue
            m = _KEY.match(raw)
            if m:
                key = next(g for g in m.groups() if g is not None)
                self.where.setdefault((table, key), (i, m.end() + 1, raw[m.end():]))
                self.where.setdefault(("[key]", table + "." + key),
                                      (i, len(raw) - len(raw.lstrip()) + 1, ""))

    def at(self, table: str, key: str | None = None) -> tuple[int | None, int | None]:
        """(line, col) of ``key``'s value in ``table`` (of the table header without a key)."""
        loc = self.where.get((table, key) if key is not None else ("[table]", table))
        return (loc[0], loc[1]) if loc else (None, None)


def _value_start(rest: str, value: str) -> tuple[int, bool]:
    """Offset from the value token to the string's first char, and whether columns map exactly."""
    for q in ('"""', "'''", '"', "'"):
        if rest.startswith(q):
            body = rest[len(q):]
            if q.startswith('"') and "\\" in body.split(q)[0]:
                return len(q), False
            if q in ('"""', "'''"):
                return len(q), False
            return len(q), body.startswith(value)
    return 0, False


# ------------------------------------------------------------------------------------------------
# The tables
# ------------------------------------------------------------------------------------------------


def _load_toml(text: str, source: str) -> dict[str, Any]:
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise BindingError(source, "TOML nested too deeply (arrays or tables inside one "
                           "another beyond Python's recursion limit)") from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise BindingError(source, f"TOML syntax error: {msg}",
                           line=int(m.group(1)) if m else None,
                           col=int(m.group(2)) if m else None) from None


def _check_tables(doc: dict[str, Any], source: str, loc: _Locations) -> None:
    for key in doc:
        if key not in ("tick", "variables", "logs", "types", "constants", "path_variables",
                       "entities", "shield", "audit"):
            table = isinstance(doc[key], dict)
            line, col = loc.at(key) if table else loc.at("", key)
            what = f"table [{key}]" if table else f"key {key!r}"
            raise BindingError(source, f"unknown {what} (expected [tick], [variables] and "
                               "optionally [logs], [types], [constants], [path_variables], "
                               "[entities], [shield], [audit])",
                               line=line, col=col)


def _duration(tick_t: dict[str, Any], key: str, source: str, loc: _Locations) -> int:
    try:
        return parse_duration(tick_t[key])
    except ValueError as exc:
        line, col = loc.at("tick", key)
        raise BindingError(source, f"[tick] {key}: {exc}", line=line, col=col) from None


def _tick_clock(tick_t: dict[str, Any], source: str, loc: _Locations) -> TickSpec:
    has_p, has_t = "period" in tick_t, "topic" in tick_t
    if has_p == has_t:
        line, col = loc.at("tick")
        raise BindingError(source, "[tick] needs exactly one of period = \"...\" and "
                           "topic = \"/...\"", line=line, col=col)
    if has_p:
        return TickSpec(period_ns=_duration(tick_t, "period", source, loc))
    topic = topic_name(tick_t["topic"])
    if topic is None:
        line, col = loc.at("tick", "topic")
        raise BindingError(source, f"[tick] topic {tick_t['topic']!r} is not a topic name "
                           "(one as fretc inspect lists it: \"/scan\", "
                           "\"vehicle_local_position\")", line=line, col=col)
    nominal = None
    if "nominal_rate" in tick_t:
        nominal = _duration(tick_t, "nominal_rate", source, loc)
    return TickSpec(topic=topic, nominal_period_ns=nominal)


def _tick_table(doc: dict[str, Any], source: str, loc: _Locations
                ) -> tuple[TickSpec, str, int]:
    """``[tick]`` -> (the clock, the time base, the header lag in ns)."""
    tick_t = doc.get("tick")
    if not isinstance(tick_t, dict):
        raise BindingError(source, "missing [tick] table: say period = \"100 ms\" or topic = "
                           "\"/scan\" (signals are declared, never guessed)", line=1)
    for key in tick_t:
        if key not in ("period", "topic", "time", "header_lag", "nominal_rate", "nan", "inf"):
            line, col = loc.at("tick", key)
            raise BindingError(source, f"unknown key {key!r} in [tick] (period, topic, "
                               "nominal_rate, time, header_lag, nan, inf)", line=line, col=col)
    tick = _tick_clock(tick_t, source, loc)
    if "nan" in tick_t:
        tick = dataclasses.replace(tick, nan=_one_of(tick_t, "nan", NAN_POLICIES, source, loc))
    if "inf" in tick_t:
        tick = dataclasses.replace(tick, inf=_one_of(tick_t, "inf", INF_POLICIES, source, loc))
    if "period" in tick_t and "nominal_rate" in tick_t:
        line, col = loc.at("tick", "nominal_rate")
        raise BindingError(source, "[tick] nominal_rate goes with topic = \"/...\" (a fixed "
                           "period is its own rate)", line=line, col=col)
    time_base = _one_of({"time": "log", **tick_t}, "time", TIME_BASES, source, loc)
    lag = DEFAULT_HEADER_LAG_NS
    if "header_lag" in tick_t:
        lag = _duration(tick_t, "header_lag", source, loc)
    return tick, time_base, lag


def _one_of(table: dict[str, Any], key: str, allowed: tuple[str, ...], source: str,
            loc: _Locations) -> str:
    """``[tick] key``'s value, one of ``allowed``. Raises :class:`BindingError` at the key
    naming the values allowed."""
    value = table[key]
    if value not in allowed:
        line, col = loc.at("tick", key)
        words = ", ".join(f'"{a}"' for a in allowed[:-1]) + f' or "{allowed[-1]}"'
        raise BindingError(source, f"[tick] {key} must be {words}, not {value!r}",
                           line=line, col=col)
    return value


def _variables_table(doc: dict[str, Any], source: str, loc: _Locations
                     ) -> dict[str, tuple[str, int | None, int | None, bool]]:
    """``[variables]`` -> name -> (expression, line, col, whether columns map exactly)."""
    var_t = doc.get("variables", {})
    if not isinstance(var_t, dict):
        line, col = loc.at("", "variables")
        raise BindingError(source, "variables must be a table [variables]", line=line, col=col)
    pending: dict[str, tuple[str, int | None, int | None, bool]] = {}
    for name, expr in var_t.items():
        found = loc.where.get(("variables", name))
        line, col, rest = found if found else (None, None, "")
        if not isinstance(expr, str):
            raise BindingError(source, "the binding must be a string expression",
                               line=line, col=col, variable=name)
        if not VARNAME.match(name):
            kline, kcol, _ = loc.where.get(("[key]", "variables." + name), (line, None, ""))
            raise BindingError(source, f"variable name {name!r} is not an identifier nor the "
                               "text of a quoted FRETish variable",
                               line=kline, col=kcol, variable=name)
        exact = False
        if col is not None:
            off, exact = _value_start(rest, expr)
            col = col + off
        pending[name] = (expr, line, col, exact)
    return pending


def _compile_in_order(pending: dict[str, tuple[str, int | None, int | None, bool]],
                      source: str, nan: str = "unread", inf: str = "unread",
                      path_vars: dict | None = None) -> dict[str, Binding]:
    """Compile the variables, each after the ones it refers to; a cycle is an error."""
    parsed = kept_parses(source, pending, path_vars)
    deps = {name: [r for r in refs(parsed[name][0]) if r in pending] for name in pending}
    state: dict[str, int] = {}
    compiled: dict[str, Binding] = {}

    def visit(name: str, chain: list[str]) -> None:
        if state.get(name) == 2:
            return
        _expr, line, col, _e = pending[name]
        if state.get(name) == 1:
            cyc = chain[chain.index(name):] + [name]
            raise BindingError(source, "variables refer to each other in a cycle: "
                               + " -> ".join(cyc), line=line, col=col, variable=name)
        if len(chain) >= MAX_REFERENCE_CHAIN:
            raise BindingError(source, f"variables refer to each other more than "
                               f"{MAX_REFERENCE_CHAIN} deep: {chain[0]} -> {chain[1]} -> ... "
                               f"-> {name}", line=line, col=col, variable=name)
        state[name] = 1
        for d in deps[name]:
            visit(d, chain + [name])
        expr, line, col, exact = pending[name]
        compiled[name] = compile_expression(name, expr, source=source, line=line, col=col,
                                            exact=exact, refs=compiled, nan=nan, inf=inf,
                                            path_vars=path_vars, parsed=parsed[name])
        state[name] = 2

    for name in pending:
        visit(name, [])
    return {name: compiled[name] for name in pending}


def _msg_path(table: Any, source: str, loc: _Locations) -> tuple[str, ...]:
    """``[types] msg_path = ["DIR", ...]``: folders of ``.msg``/``.idl`` files (as
    ``--msg-path``), relative to the binding file's folder."""
    if not isinstance(table, dict) or "msg_path" not in table:
        return ()
    value = table["msg_path"]
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        line, col = loc.at("types", "msg_path")
        raise BindingError(source, "[types] msg_path is a folder or a list of folders "
                           "(\"msgs\" or [\"msgs\", \"../ws/src\"])", line=line, col=col)
    base = Path(source).parent if not source.startswith("<") else Path(".")
    return tuple(str(base / v) for v in value)


def _types_table(table: Any, source: str, loc: _Locations) -> dict[str, str]:
    """``[types]``: topic -> ROS message type (``"/scan" = "sensor_msgs/msg/LaserScan"``);
    the key ``msg_path`` is :func:`_msg_path`'s."""
    if table is None:
        return {}
    if not isinstance(table, dict):
        line, col = loc.at("types")
        raise BindingError(source, "types must be a table [types]", line=line, col=col)
    table = {k: v for k, v in table.items() if k != "msg_path"}
    for topic, name in table.items():
        if not re.fullmatch(r"(/[A-Za-z0-9_]+)+", topic) or not isinstance(name, str) \
                or not re.fullmatch(r"[A-Za-z0-9_]+(/msg)?/[A-Za-z0-9_]+", name):
            kl, kc = loc.at("types", topic)
            raise BindingError(source, f"[types] needs \"/topic\" = \"pkg/msg/Type\", not "
                               f"{topic!r} = {name!r}", line=kl, col=kc)
    return dict(table)


def _logs_table(table: Any, source: str, loc: _Locations) -> LogSelector | None:
    if table is None:
        return None
    line, col = loc.at("logs")
    if not isinstance(table, dict):
        raise BindingError(source, "logs must be a table [logs]", line=line, col=col)
    for key in table:
        if key not in ("glob", "topics"):
            kl, kc = loc.at("logs", key)
            raise BindingError(source, f"unknown key {key!r} in [logs] (glob, topics)",
                               line=kl, col=kc)

    def strings(key: str) -> tuple[str, ...]:
        v = table.get(key, [])
        v = [v] if isinstance(v, str) else v
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            kl, kc = loc.at("logs", key)
            raise BindingError(source, f"[logs] {key} must be a string or a list of strings",
                               line=kl, col=kc)
        return tuple(v)

    sel = LogSelector(strings("glob"), strings("topics"))
    if not sel.glob and not sel.topics:
        raise BindingError(source, "[logs] needs glob = \"...\" and/or topics = [...]",
                           line=line, col=col)
    return sel


# ------------------------------------------------------------------------------------------------
# Reading a binding file
# ------------------------------------------------------------------------------------------------


def parse_bindings(text: str, source: str = "<bindings>") -> Bindings:
    """Bindings from binding-file text (format: ``docs/bindings.md``).

    Raises:
        BindingError: TOML syntax error; unknown table or key; [tick] without exactly one of
            period/topic, a bad duration, time not "log"/"header"; a variable that is not a
            string, a bad name, or a bad expression; a bad [logs] table.  Names
            source:line:col.
    """
    doc = _load_toml(text, source)
    loc = _Locations(text)
    _check_tables(doc, source, loc)
    tick, time_base, lag = _tick_table(doc, source, loc)
    path_vars = _path_variables(doc.get("path_variables"), source, loc)
    entities = _entities(doc.get("entities"), source, loc)
    pending = _variables_table(doc, source, loc)
    later = _per_entity(pending, entities)
    variables = _compile_in_order({k: v for k, v in pending.items() if k not in later}, source,
                                  tick.nan, tick.inf, path_vars)
    out = Bindings(variables, tick, time_base, lag, source, entities=entities,
                   per_entity={k: pending[k] + (tick.nan, tick.inf) for k in later},
                   path_vars=path_vars)
    out.logs = _logs_table(doc.get("logs"), source, loc)
    out.types = _types_table(doc.get("types"), source, loc)
    out.msg_path = _msg_path(doc.get("types"), source, loc)
    out.constants = _constants(doc.get("constants"), source, loc)
    out.allowance = _audit_table(doc.get("audit"), source, loc, out)
    return out


def _per_entity(pending: dict, entities: dict) -> list[str]:
    """The variables that read an entity (``$track``, a name of ``[entities]``) or refer to
    one that does, in declaration order (compiled per entity, not now)."""
    out: set[str] = set()
    grew = True
    while grew:
        grew = False
        for name, (expr, *_rest) in pending.items():
            if name in out:
                continue
            uses = set(re.findall(r"\$([A-Za-z_][A-Za-z0-9_]*)", expr)) & set(entities)
            if uses or any(re.search(rf"(?<![\w/.$]){re.escape(o)}(?!\w)", expr) for o in out):
                out.add(name)
                grew = True
    return [n for n in pending if n in out]


def _entities(table: Any, source: str, loc: _Locations) -> dict[str, EntitySpec]:
    """``[entities] track = "/tracks.tracks[:].id"`` or ``motor = { key =
    "/diagnostics.status[:].name", matching = "motor*", hold = "entity" }``: name -> its
    :class:`~fretc.signals.bindings.spec.EntitySpec` (key path, glob or None, what a tick
    reads of an entity: :data:`~fretc.signals.bindings.spec.HOLDS`).

    Raises:
        BindingError: not a table, a bad name, a key that is not a string path, a bad glob,
            a ``hold`` not in :data:`~fretc.signals.bindings.spec.HOLDS`; at the entry.
    """
    if table is None:
        return {}
    if not isinstance(table, dict):
        line, col = loc.at("", "entities")
        raise BindingError(source, "entities must be a table: [entities] then track = "
                           "\"/tracks.tracks[:].id\"", line=line, col=col)
    out: dict[str, EntitySpec] = {}
    for name, value in table.items():
        line, col = loc.at("entities", name)
        if not re.match(r"[A-Za-z_][A-Za-z0-9_]*\Z", name):
            raise BindingError(source, f"[entities] {name!r} is not a name (letters, digits, "
                               "_)", line=line, col=col)
        key, matching, hold = value, None, "message"
        if isinstance(value, dict):
            key, matching = value.get("key"), value.get("matching")
            hold = value.get("hold", "message")
            extra = set(value) - {"key", "matching", "hold"}
            if extra or not isinstance(matching, (str, type(None))):
                raise BindingError(source, f"[entities] {name}: key = \"PATH\" and optionally "
                                   "matching = \"GLOB\" and hold = \"entity\"", line=line,
                                   col=col)
            if hold not in HOLDS:
                raise BindingError(source, f"[entities] {name}: hold is one of "
                                   f"{', '.join(map(repr, HOLDS))}, not {hold!r} (\"entity\": "
                                   "each entity's newest message that carried it)", line=line,
                                   col=col)
        if not isinstance(key, str) or not key.strip():
            raise BindingError(source, f"[entities] {name}: the key is a field path in quotes, "
                               "e.g. \"/tracks.tracks[:].id\"", line=line, col=col)
        out[name] = EntitySpec(key, matching, hold)
    return out


def _path_variables(table: Any, source: str, loc: _Locations) -> dict[str, Any]:
    """``[path_variables] track = 7``: the values of FoxQL's message path variables
    (``{id==$track}``, ``[$lo:$hi]``), as Foxglove's panels take them: name -> bool, number
    or string.

    Raises:
        BindingError: not a table, a name that is not an identifier, or another value.
    """
    if table is None:
        return {}
    if not isinstance(table, dict):
        line, col = loc.at("", "path_variables")
        raise BindingError(source, "path_variables must be a table: [path_variables] then "
                           "track = 7", line=line, col=col)
    for name, value in table.items():
        line, col = loc.at("path_variables", name)
        if not re.match(r"[A-Za-z_][A-Za-z0-9_]*\Z", name):
            raise BindingError(source, f"[path_variables] {name!r} is not a name (letters, "
                               "digits, _)", line=line, col=col)
        if not isinstance(value, (bool, int, float, str)):
            raise BindingError(source, f"[path_variables] {name}: a number, a string or "
                               "true/false", line=line, col=col)
    return dict(table)


def _constants(table: Any, source: str, loc: _Locations) -> dict[str, tuple[str, str]]:
    """``[constants] T_stop = "1.5 s"``: named durations of the requirements
    (:mod:`fretc.fretish.constants`): name -> (amount, unit)."""
    from fretc.fretish.constants import CONSTANT_NAME, parse_constant

    if table is None:
        return {}
    if not isinstance(table, dict):
        line, col = loc.at("", "constants")
        raise BindingError(source, "constants must be a table: [constants] then "
                           "T_stop = \"1.5 s\"", line=line, col=col)
    out = {}
    for name, value in table.items():
        line, col = loc.at("constants", name)
        if not CONSTANT_NAME.match(name):
            raise BindingError(source, f"[constants] {name!r} is not a name (letters, digits, "
                               "_)", line=line, col=col)
        if not isinstance(value, str):
            raise BindingError(source, f"[constants] {name}: a duration in quotes, e.g. "
                               "\"1.5 s\"", line=line, col=col)
        try:
            out[name] = parse_constant(value)
        except ValueError as exc:
            raise BindingError(source, f"[constants] {name}: {exc}", line=line,
                               col=col) from None
    return out


def _audit_table(table: Any, source: str, loc: _Locations, bindings: Bindings
                 ) -> dict[str, int]:
    """``[audit] allowance = {"/cmd_vel_filtered" = "120 ms"}``: topic -> ns its messages
    are read earlier by the audit (:mod:`fretc.logs.allowance`); ``{}`` without it.

    Raises:
        BindingError: not a table, an unknown key, an allowance that is not a table of
            topics to durations, a negative or malformed duration, or a topic no binding
            of this file reads (:meth:`Bindings.log_topics_read`); at the
            entry."""
    from fretc.logs.allowance import parse_allowance

    if table is None:
        return {}
    if not isinstance(table, dict):
        line, col = loc.at("", "audit")
        raise BindingError(source, "audit must be a table: [audit] then allowance = "
                           "{\"/cmd_vel_filtered\" = \"120 ms\"}", line=line, col=col)
    for key in table:
        if key != "allowance":
            line, col = loc.at("audit", key)
            raise BindingError(source, f"unknown key {key!r} in [audit] (allowance)",
                               line=line, col=col)
    line, col = loc.at("audit", "allowance")
    given = table.get("allowance", {})
    if not isinstance(given, dict):
        raise BindingError(source, "[audit] allowance is a table of topics to durations, "
                           "e.g. {\"/cmd_vel_filtered\" = \"120 ms\"}", line=line, col=col)
    read = bindings.log_topics_read()
    out: dict[str, int] = {}
    for topic, value in given.items():
        name = topic_name(topic)
        try:
            if name is None or not isinstance(value, str):
                raise ValueError(f"{topic!r} = {value!r}: a topic name and a duration in "
                                 "quotes, e.g. \"/cmd_vel_filtered\" = \"120 ms\"")
            if name not in read:
                raise ValueError(f"no binding of this file reads {name} (it reads "
                                 f"{', '.join(sorted(read)) or 'no topic'})")
            ns = parse_allowance(value)
            if ns:  # (0: none, as without the entry)
                out[name] = ns
        except ValueError as exc:
            raise BindingError(source, f"[audit] allowance: {exc}", line=line,
                               col=col) from None
    return out


def load_bindings(path: str | Path, inline: Iterable[str] = ()) -> Bindings:
    """Read a binding file (TOML), then apply ``inline`` ``NAME=EXPR`` overrides.

    Raises:
        BindingError: unreadable file, or see :func:`parse_bindings` /
            :func:`fretc.signals.bindings.binding.parse_inline`.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise BindingError(str(path), f"cannot read binding file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise BindingError(str(path), f"binding file is not UTF-8: {exc}") from None
    b = parse_bindings(text, str(path))
    return b.with_inline(inline) if inline else b
