"""Trees of fretc's own dataclasses as JSON, for the disk cache's data entries
(:mod:`fretc.common.cache`): the parsed requirements of a ``.fret`` file, the parsed
expressions of a binding file.

Design notes: ARCHITECTURE.md, `common/cache_json.py`."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Iterable, Mapping
from types import ModuleType
from typing import Any

__all__ = ["classes_of", "dumps", "loads"]


def classes_of(*modules: ModuleType) -> dict[str, type]:
    """The dataclasses and named tuples defined in ``modules`` (not imported into them), by
    qualified name: what :func:`dumps` may write and :func:`loads` may make."""
    out: dict[str, type] = {}
    for module in modules:
        for value in vars(module).values():
            if (isinstance(value, type) and value.__module__ == module.__name__
                    and (dataclasses.is_dataclass(value)
                         or (issubclass(value, tuple) and hasattr(value, "_fields")))):
                out[value.__qualname__] = value
    return out


def dumps(value: object, classes: Mapping[str, type],
          persistent: Callable[[object], str | None] | None = None) -> bytes:
    """``value`` as the UTF-8 JSON of the module's layout. ``classes``: the classes that may
    appear, by name (:func:`classes_of`); ``persistent(obj)``: a name for an object written
    as ``{"p": name}``, or None for the others.

    Raises:
        TypeError: a value of a type the layout has no form for (a class not listed).
        ValueError, RecursionError: a tree nested too deeply."""
    names = {cls: name for name, cls in classes.items()}

    def enc(v: object) -> object:
        t = type(v)
        if v is None or t in (bool, int, float, str):
            return v
        if persistent is not None:
            pid = persistent(v)
            if pid is not None:
                return {"p": pid}
        if t is list:
            return [enc(x) for x in v]  # type: ignore[attr-defined]
        if t is tuple:
            return {"t": [enc(x) for x in v]}  # type: ignore[attr-defined]
        if t is frozenset:
            return {"f": [enc(x) for x in v]}  # type: ignore[attr-defined]
        if t is dict:
            return {"d": [[enc(k), enc(x)] for k, x in v.items()]}  # type: ignore[attr-defined]
        if t.__name__ == "Fraction" and t.__module__ == "fractions":
            return {"q": [v.numerator, v.denominator]}  # type: ignore[attr-defined]
        name = names.get(t)
        if name is None:
            raise TypeError(f"no cache form for {t.__module__}.{t.__qualname__}")
        if dataclasses.is_dataclass(t):
            items: Iterable = (getattr(v, f.name) for f in dataclasses.fields(t))
        else:
            items = v  # type: ignore[assignment]
        return {"c": name, "v": [enc(x) for x in items]}

    return json.dumps(enc(value), ensure_ascii=True, separators=(",", ":")).encode("ascii")


def loads(data: bytes, classes: Mapping[str, type],
          persistent: Callable[[str], object] | None = None) -> Any:
    """The value :func:`dumps` wrote as ``data``, its instances made only of ``classes``;
    ``persistent(name)`` gives back the object written as ``{"p": name}`` (raising
    KeyError when it has none).

    Raises:
        ValueError: not the layout (unknown tag, class or persistent name, wrong arity, not
            JSON), or nested too deeply."""
    def dec(v: Any) -> Any:
        t = type(v)
        if t is list:
            return [dec(x) for x in v]
        if t is not dict:
            return v
        if len(v) == 1:
            ((tag, x),) = v.items()
            if tag == "t":
                return tuple([dec(y) for y in x])
            if tag == "f":
                return frozenset([dec(y) for y in x])
            if tag == "d":
                return {dec(k): dec(y) for k, y in x}
            if tag == "q":
                from fractions import Fraction  # lazy: start-up

                numerator, denominator = x
                if type(numerator) is not int or type(denominator) is not int:
                    raise ValueError("a fraction of two integers")
                return Fraction(numerator, denominator)
            if tag == "p" and persistent is not None and type(x) is str:
                return persistent(x)
        elif len(v) == 2 and type(v.get("c")) is str and type(v.get("v")) is list:
            return _make(classes[v["c"]], [dec(y) for y in v["v"]])
        raise ValueError(f"not a cache tag: {sorted(v)}")

    try:
        return dec(json.loads(data))
    except (KeyError, TypeError, ValueError, RecursionError, ZeroDivisionError) as exc:
        raise ValueError(f"not a cache entry of this layout: {type(exc).__name__}") from None


def _make(cls: type, values: list) -> object:
    """An instance of ``cls`` holding ``values`` (its dataclass fields in order, or its named
    tuple's items), made as pickle makes one: without calling ``__init__``. Raises
    ValueError on a wrong number of values."""
    if not dataclasses.is_dataclass(cls):
        if len(values) != len(cls._fields):  # type: ignore[attr-defined]
            raise ValueError(f"{cls.__qualname__} has {len(cls._fields)} items")  # type: ignore[attr-defined]
        return tuple.__new__(cls, values)
    fields = dataclasses.fields(cls)
    if len(values) != len(fields):
        raise ValueError(f"{cls.__qualname__} has {len(fields)} fields")
    obj = object.__new__(cls)
    for f, value in zip(fields, values):
        object.__setattr__(obj, f.name, value)
    return obj
