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

Start-up CPU of the FRETish parser (``bench/bench_lark_tables.py``): tables built in memory
about 0.38 s, from this cache about 19 ms (Lark's pickle about 20 ms).
"""

from __future__ import annotations

import marshal
import sys
from collections.abc import Callable, Mapping
from typing import Any

from fretc.common import cache

__all__ = ["cached_parser", "KIND"]

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
                  runtime: Mapping[str, Any], build: Callable[[], Any]) -> Any:
    """A Lark parser of ``grammar`` with ``options`` (LALR) and ``runtime`` options (the
    transformer and the other options Lark takes when it loads tables): loaded from the entry
    ``lark/NAME-KEY.lark`` of fretc's cache when there is a sealed one for the same grammar,
    options, Lark and Python versions (KEY names them), else ``build()`` (which makes the same
    parser from the grammar) and its tables kept. The cache off, refused or unwritable, or
    an entry Lark cannot load: built in memory (the same parser, slower to start). Raises
    what ``build`` raises."""
    import lark
    from lark.grammar import Rule
    from lark.lexer import TerminalDef

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
    parser = build()
    try:
        data, memo = parser.memo_serialize([TerminalDef, Rule])
        data["options"] = {k: v for k, v in data["options"].items() if k not in allowed}
        tables = {"data": data, "memo": memo}
        if _plain(tables):
            cache.write_sealed(KIND, entry, _MAGIC, made_from, marshal.dumps(tables))
    except Exception:  # noqa: BLE001 - tables Lark cannot serialize are not kept
        pass
    return parser
