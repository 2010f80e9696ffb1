"""Lark's LALR parsers with their tables kept in fretc's disk cache
(:mod:`fretc.common.cache`), without Lark's own cache.

Lark's ``cache=PATH`` option (and ``Lark.save``/``Lark.load``) keeps the tables as a pickle
and unpickles the file before checking anything: a file planted there runs its code in every
fretc command. Here the tables are Lark's own serialized form (``Lark.memo_serialize``:
dicts, lists, tuples, strings, numbers), written with :mod:`marshal` (plain values only:
loading them runs no code) in a sealed cache entry (the cache's HMAC: a planted or altered
entry is a miss, never decoded), and given back to Lark by ``Lark._load_from_dict``, the entry
point of Lark's standalone parser generator (``lark/tools/standalone.py``), which makes only
Lark's rule and terminal classes from them.

Design notes: ARCHITECTURE.md, `common/lark_tables.py`."""

from __future__ import annotations

import json
import marshal
import sys
from collections.abc import Callable, Mapping
from typing import Any

from fretc.common import cache

__all__ = ["cached_parser", "KIND", "tables_text", "shipped_key"]

KIND = "lark"
_MAGIC = b"fretc lark-tables 1 marshal\n"
#: the options Lark takes again when it loads tables (``lark.lark._LOAD_ALLOWED_OPTIONS``
#: in Lark 1.1-1.3): the others are part of the tables
_RUNTIME = frozenset(("postlex", "transformer", "lexer_callbacks", "use_bytes", "debug",
                      "g_regex_flags", "regex", "propagate_positions", "tree_class",
                      "_plugins"))
_PLAIN = (str, int, float, bool, type(None))


def _plain(value: object, depth: int = 0) -> bool:
    """Whether ``value`` is made only of dicts, lists, tuples and plain scalars (what
    ``marshal`` writes as data, no code objects), at most 200 deep."""
    if isinstance(value, _PLAIN):
        return True
    if depth > 200:
        return False
    if type(value) in (list, tuple):
        return all(_plain(v, depth + 1) for v in value)  # type: ignore[attr-defined]
    if type(value) is dict:
        return all(_plain(k, depth + 1) and _plain(v, depth + 1)
                   for k, v in value.items())
    return False


def cached_parser(name: str, grammar: str, options: Mapping[str, Any],
                  runtime: Mapping[str, Any], build: Callable[[], Any],
                  shipped: str | None = None) -> Any:
    """A Lark parser of ``grammar`` with ``options`` (LALR) and ``runtime`` options (the
    transformer and the other options Lark takes when it loads tables): loaded from the entry
    ``lark/NAME-KEY.lark`` of fretc's cache when there is a sealed one for the same grammar,
    options, Lark and Python versions (KEY names them), else from the tables ``shipped``
    with fretc when they were made from the same grammar, options and Lark version (module
    docstring), else ``build()`` (which makes the same parser from the grammar); tables
    loaded or built are kept in the cache. The cache off, refused or unwritable, or an entry
    Lark cannot load: built in memory (the same parser, slower to start). Raises what
    ``build`` raises."""
    import lark

    key = cache.key_of(f"{name}-grammar", grammar, lark.__version__,
                       "%d.%d" % sys.version_info[:2], repr(sorted(options.items())))
    entry, made_from = f"{name}-{key[:40]}.lark", cache.digest(key.encode("ascii"))
    allowed = getattr(getattr(lark, "lark", None), "_LOAD_ALLOWED_OPTIONS", _RUNTIME)
    load = {k: v for k, v in {**options, **runtime}.items() if k in allowed}
    payload = cache.read_sealed(KIND, entry, _MAGIC, made_from)
    if payload is not None:
        try:
            tables = marshal.loads(payload)
            return lark.Lark._load_from_dict(tables["data"], tables["memo"], **load)
        except Exception:  # noqa: BLE001 - an entry Lark cannot load is a miss (rebuilt)
            pass
    parser = None
    if shipped is not None:
        parser = _from_shipped(shipped, shipped_key(name, grammar, options), load)
    if parser is None:
        parser = build()
    tables = _tables(parser, allowed)
    if tables is not None:
        cache.write_sealed(KIND, entry, _MAGIC, made_from, marshal.dumps(tables))
    return parser


def _tables(parser: Any, allowed: Any) -> dict | None:
    """``parser``'s tables as plain data (:func:`_plain`; the runtime options ``allowed``
    left out: they are given when loading), or None when Lark cannot serialize them."""
    from lark.grammar import Rule
    from lark.lexer import TerminalDef

    try:
        data, memo = parser.memo_serialize([TerminalDef, Rule])
        data["options"] = {k: v for k, v in data["options"].items() if k not in allowed}
        tables = {"data": data, "memo": memo}
    except Exception:  # noqa: BLE001 - tables Lark cannot serialize are not kept
        return None
    return tables if _plain(tables) else None


def shipped_key(name: str, grammar: str, options: Mapping[str, Any]) -> str:
    """The key of the tables shipped for parser ``name``: its grammar, options and Lark's
    version (not Python's: JSON, not marshal)."""
    import lark

    return cache.key_of(f"{name}-shipped", grammar, lark.__version__,
                        repr(sorted(options.items())))


_SHIPPED_FORMAT = "fretc lark tables 1"


def tables_text(name: str, grammar: str, options: Mapping[str, Any], parser: Any) -> str:
    """The tables of ``parser`` (built from ``grammar`` with ``options``) as the text of a
    shipped tables file (module docstring: the key, Lark's version, the tables tagged).

    Raises:
        ValueError: Lark cannot serialize the parser's tables as plain data."""
    import lark

    allowed = getattr(getattr(lark, "lark", None), "_LOAD_ALLOWED_OPTIONS", _RUNTIME)
    tables = _tables(parser, allowed)
    if tables is None:
        raise ValueError(f"the tables of {name} are not plain data")
    doc = {"format": _SHIPPED_FORMAT, "key": shipped_key(name, grammar, options),
           "lark": lark.__version__, "tables": _tagged(tables)}
    return json.dumps(doc, separators=(",", ":")) + "\n"


def _tagged(value: Any) -> Any:
    """Plain data as JSON values (module docstring's tags)."""
    if type(value) is tuple:
        return {"__t": [_tagged(v) for v in value]}
    if type(value) is list:
        return [_tagged(v) for v in value]
    if type(value) is dict:
        return {"__d": [[_tagged(k), _tagged(v)] for k, v in value.items()]}
    return value


def _untag(obj: dict) -> Any:
    """:func:`_tagged`'s tags read back (a ``json`` object hook)."""
    if len(obj) == 1:
        if "__t" in obj:
            return tuple(obj["__t"])
        if "__d" in obj:
            return dict(map(tuple, obj["__d"]))
    return obj


def _from_shipped(path: str, key: str, load: Mapping[str, Any]) -> Any | None:
    """The parser of the tables shipped at ``path`` when they are of ``key``, else None (a
    missing or unreadable file, other tables: the caller builds them)."""
    import lark

    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f, object_hook=_untag)
        if doc.get("format") != _SHIPPED_FORMAT or doc.get("key") != key:
            return None
        tables = doc["tables"]
        return lark.Lark._load_from_dict(tables["data"], tables["memo"], **load)
    except Exception:  # noqa: BLE001 - shipped tables Lark cannot load: built instead
        return None
