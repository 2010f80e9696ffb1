"""The parsed expressions of a binding file kept on disk between runs, as
:mod:`fretc.fretish.entry_cache` keeps a ``.fret`` file's parsed requirements.

Design notes: ARCHITECTURE.md, `signals/bindings/parse_cache.py`."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Mapping

from fretc.common import cache, cache_json
from fretc.common.libraries import package_init
from fretc.signals.bindings import expression
from fretc.signals.bindings.expression import EntityParam, Expr, ExprLocation

__all__ = ["cached_parses", "kept_parses"]

KIND = "binding-parses"
_MAGIC = b"fretc binding-parses 2 json\n"
#: the classes an entry may hold
_CLASSES = cache_json.classes_of(expression)
_HERE = os.path.dirname(os.path.abspath(__file__))
_SRC = os.path.dirname(os.path.dirname(_HERE))
#: what else an expression's tree depends on (limits, units, the error classes)
_OTHER = (("fretish", "limits.py"), ("common", "units.py"), ("common", "problems.py"),
          ("common", "errors.py"))
_CODE_KEY: str | None = None

Parsed = tuple[Expr, frozenset[str]]


def _code_key() -> str:
    """A key of the code that parses an expression (computed once a process)."""
    global _CODE_KEY
    if _CODE_KEY is None:
        paths = [os.path.join(_HERE, n) for n in sorted(os.listdir(_HERE))
                 if n.endswith((".py", ".lark"))]
        paths += [os.path.join(_SRC, *p) for p in _OTHER] + [package_init("lark")]
        _CODE_KEY = cache.files_key(KIND, paths, sys.version)
    return _CODE_KEY


def _keys(path_vars: Mapping | None) -> dict[str, EntityParam] | None:
    """The entity keys among ``path_vars`` by path variable, or None when a value is
    neither a key nor a plain value (such a file is not kept)."""
    keys = {}
    for name, v in (path_vars or {}).items():
        if type(v) is EntityParam:
            keys[name] = v
        elif type(v) not in (bool, int, float, str):
            return None
    return keys


def _key_name(keys: dict[str, EntityParam]) -> Callable[[object], str | None]:
    """The name of an entity key among ``keys`` (written ``{"p": name}``), None for other
    values; an entity key that is not among them raises TypeError (the file is not kept)."""
    names = {id(v): k for k, v in keys.items()}

    def name_of(obj: object) -> str | None:
        if type(obj) is not EntityParam:
            return None
        if id(obj) not in names:
            raise TypeError(f"an entity key not among the path variables: {obj!r}")
        return names[id(obj)]

    return name_of


def cached_parses(source: str, expressions: Mapping[str, str], path_vars: Mapping | None,
                  parse: Callable[[str], Parsed]) -> dict[str, Parsed]:
    """``{variable: parse(variable)}`` for the binding file ``source`` whose variables'
    expressions are ``expressions`` (variable -> text, in the file's order): those kept from
    an earlier parse of the same file, texts, path variables and code, else ``parse``'s
    (kept when every expression parsed, as :func:`fretc.signals.bindings.parse.parse_expression`
    returns them). Raises what ``parse`` raises, for the first variable that fails."""
    keys = _keys(path_vars)
    if keys is None:  # (a value that is neither plain nor a key: never kept)
        return {variable: parse(variable) for variable in expressions}
    name = cache.key_of(KIND, source)
    made_from = cache.digest("\x00".join(
        (_code_key(), source, repr(list(expressions.items())),
         repr(sorted((path_vars or {}).items())))).encode("utf-8", "surrogatepass"))
    payload = cache.read_sealed(KIND, name, _MAGIC, made_from)
    if payload is not None:
        try:
            got = cache_json.loads(payload, _CLASSES, keys.__getitem__)
        except ValueError:  # not this layout: a miss (the seal makes it unlikely)
            got = None
        if (isinstance(got, dict) and list(got) == list(expressions)
                and all(isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], Expr)
                        and isinstance(v[1], frozenset) for v in got.values())):
            return got
    out = {variable: parse(variable) for variable in expressions}
    try:
        payload = cache_json.dumps(out, _CLASSES, _key_name(keys))
    except (TypeError, ValueError, RecursionError):  # no JSON form: not kept
        return out
    cache.write_sealed(KIND, name, _MAGIC, made_from, payload)
    return out


def kept_parses(source: str, pending: Mapping[str, tuple], path_vars: dict | None
                ) -> dict[str, Parsed]:
    """:func:`cached_parses` of the expressions ``pending`` (variable -> ``(text, line, col,
    exact, ...)``: where the text starts in ``source``, 1-based or None) parsed by
    :func:`fretc.signals.bindings.parse.parse_expression` with ``path_vars``.

    Raises:
        BindingError: the first expression that does not parse, at its file:line:col."""
    def parse(name: str) -> Parsed:
        from fretc.signals.bindings.parse import parse_expression  # lazy: Lark (start-up)

        expr, line, col, exact = pending[name][:4]
        return parse_expression(expr, ExprLocation(source, name, line, col, exact), path_vars)

    return cached_parses(source, {n: p[0] for n, p in pending.items()}, path_vars, parse)
