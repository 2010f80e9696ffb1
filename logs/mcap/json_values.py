"""JSON values (and CBOR's) as message objects, and their check against a JSON Schema's
``type`` (JSON Schema draft 2020-12, "type"): the rules :mod:`fretc.logs.mcap.encodings` reads
``json`` and ``cbor`` channels with (its module docstring gives the objects' shapes).

:func:`type_check` checks a whole decoded message; :func:`checked_picker` checks and
converts only the fields the bindings read (:mod:`fretc.logs.field_select`), in one walk.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import numpy as np

from fretc.logs.field_select import json_picker, pruned_schema

__all__ = ["as_message", "type_check", "checked_picker"]


_JSON_TYPES: dict[str, Callable[[Any], bool]] = {
    "number": lambda v: type(v) in (int, float),
    "integer": lambda v: type(v) is int or (type(v) is float and v.is_integer()),
    "boolean": lambda v: type(v) is bool,
    "string": lambda v: type(v) is str,
    "object": lambda v: type(v) is dict,
    "array": lambda v: type(v) is list,
    "null": lambda v: v is None,
}


def type_check(doc: dict) -> Callable[[Any], Any] | None:
    """A function that returns a decoded JSON message unchanged when the scalar values of
    the properties its JSON Schema declares have the declared ``type`` (JSON Schema
    draft 2020-12, "type": a JSON ``true`` is no number, a number no boolean), and raises
    ``ValueError`` naming the first field that does not (an undecodable message: the schema
    does not describe it). Properties the schema does not declare, and schemas that cannot
    be read, are not checked (None). ``doc``: the JSON Schema document."""
    check = _compile_check(doc, "", 0)
    if check is None:
        return None

    def checked(value: Any) -> Any:
        check(value)
        return value
    return checked


#: Python types of the JSON values of each JSON Schema ``type`` (bool is no number).
_JSON_PY: dict[str, tuple[type, ...]] = {
    "number": (int, float), "boolean": (bool,), "string": (str,), "object": (dict,),
    "array": (list,), "null": (type(None),), "integer": (int, float)}


def _compile_check(spec: Any, where: str, depth: int) -> Callable[[Any], None] | None:
    """The check of one schema node, made once (None: nothing to check there): its own
    ``type``, its declared properties' checks, and its items' (an array of scalars in one
    pass over the list)."""
    if not isinstance(spec, dict) or depth > 64:
        return None
    t = spec.get("type")
    allowed = [t] if isinstance(t, str) else [x for x in t if isinstance(x, str)] \
        if isinstance(t, list) else []
    tests = [_JSON_TYPES[x] for x in allowed if x in _JSON_TYPES]
    kinds = frozenset(k for x in allowed if x in _JSON_PY for k in _JSON_PY[x])
    exact = "integer" not in allowed  # (an integer: a float only when whole)
    props = [(name, c) for name, sub in (spec.get("properties") or {}).items()
             if (c := _compile_check(sub, f"{where}.{name}" if where else name,
                                     depth + 1)) is not None]
    items = spec.get("items")
    item = _compile_check(items, f"{where}[]", depth + 1) if isinstance(items, dict) else None
    scalar_items = (isinstance(items, dict) and not items.get("properties")
                    and not isinstance(items.get("items"), dict))
    it = items.get("type") if isinstance(items, dict) else None
    item_allowed = [it] if isinstance(it, str) else [x for x in it if isinstance(x, str)] \
        if isinstance(it, list) else []
    # an array of scalars of exact types: checked by the set of its items' types (map(type)
    # runs in C), the item named only when one is wrong
    fast = (scalar_items and item_allowed and "integer" not in item_allowed
            and all(x in _JSON_PY for x in item_allowed))
    item_kinds = frozenset(k for x in item_allowed if x in _JSON_PY for k in _JSON_PY[x])
    if not tests and not props and item is None:
        return None

    def wrong(value: Any, at: str) -> None:
        shown = json.dumps(value)[:40] if not isinstance(value, (dict, list)) else \
            type(value).__name__
        raise ValueError(f"{at or 'the message'} is {shown}, but the schema says "
                         f"{' or '.join(allowed)}")

    def check(value: Any) -> None:
        if tests and not (type(value) in kinds if exact else any(f(value) for f in tests)):
            wrong(value, where)
        if props and type(value) is dict:
            for name, c in props:
                if name in value:
                    c(value[name])
        elif item is not None and type(value) is list:
            if fast and set(map(type, value)) <= item_kinds:
                return
            if scalar_items:  # the first item of another type is named
                for i, x in enumerate(value):
                    try:
                        item(x)
                    except ValueError:
                        raise ValueError(str(_item_error(item, x, f"{where}[{i}]"))) from None
            else:
                for i, x in enumerate(value):
                    try:
                        item(x)
                    except ValueError as exc:
                        raise ValueError(str(exc).replace(f"{where}[]", f"{where}[{i}]", 1)) \
                            from None
    return check


def checked_picker(doc: dict, tree: dict) -> Callable[[Any], Any]:
    """A function ``decoded JSON message -> message object`` holding the fields of ``tree``
    (:func:`fretc.logs.field_select.field_tree`), each checked against its schema's ``type``
    as :func:`type_check` checks it (the same first error, ``ValueError``) in the same walk
    that converts it: an array of scalars by the set of its items' types, made once for the
    check and the conversion; a field nobody reads is neither. ``doc``: the JSON Schema."""
    return _checked_node(doc, tree, "", 0)


def _checked_node(spec: Any, tree: dict, where: str, depth: int) -> Callable[[Any], Any]:
    """The checked picker of a schema node whose fields ``tree`` reads."""
    whole = _compile_check(pruned_schema(spec, tree), where, depth)  # a value of no object
    own = (_compile_check({"type": spec["type"]}, where, depth)
           if isinstance(spec, dict) and "type" in spec else None)
    props = spec.get("properties") if isinstance(spec, dict) else None
    props = props if isinstance(props, dict) else {}
    children = []  # in the schema's order of properties (the check's order of errors)
    for name, sub in sorted(tree.items(), key=lambda kv: _order(props, kv[0])):
        at = f"{where}.{name}" if where else name
        if name not in props:
            children.append((name, as_message if sub is None else
                             json_picker(sub, as_message)))
        elif sub is None:
            children.append((name, _checked_leaf(props[name], at, depth + 1)))
        else:
            children.append((name, _checked_node(props[name], sub, at, depth + 1)))

    def pick(value: Any) -> Any:
        if type(value) is not dict:
            if whole is not None:
                whole(value)
            return as_message(value)
        if own is not None:
            own(value)
        out = SimpleNamespace()
        d = out.__dict__
        for name, f in children:
            if name in value:
                d[name] = f(value[name])
        return out
    return pick


def _order(props: dict, name: str) -> int:
    """The place of property ``name`` in ``props`` (after all of them when absent)."""
    for k, key in enumerate(props):
        if key == name:
            return k
    return len(props)


def _checked_leaf(spec: Any, where: str, depth: int) -> Callable[[Any], Any]:
    """A field read whole: checked (:func:`_compile_check`) and converted (:func:`as_message`);
    an array of scalars of exact types (``"type": "array"``) by one set of its items'
    types, a ``number`` that is a float as it is."""
    check = _compile_check(spec, where, depth)
    if check is None:
        return as_message
    items = spec.get("items")
    it = items.get("type") if isinstance(items, dict) else None
    if (spec.get("type") == "array" and isinstance(it, str) and it in _JSON_PY
            and it != "integer" and not items.get("properties")
            and not isinstance(items.get("items"), dict)):
        item_kinds = frozenset(_JSON_PY[it])

        def array(value: Any) -> Any:
            if type(value) is list:
                kinds = set(map(type, value))
                if kinds <= item_kinds:
                    return _list_message(value, kinds)
            check(value)
            return as_message(value)
        return array
    if spec.get("type") == "number":
        def number(value: Any) -> Any:
            if type(value) is float:
                return value
            check(value)
            return as_message(value)
        return number

    def leaf(value: Any) -> Any:
        check(value)
        return as_message(value)
    return leaf


def _item_error(item: Callable[[Any], None], x: Any, at: str) -> str:
    """The error of ``item`` on ``x``, named at ``at``."""
    try:
        item(x)
    except ValueError as exc:
        text = str(exc)
        return at + text[text.index(" is "):] if " is " in text else text
    return at


def as_message(value: Any) -> Any:
    """A decoded JSON/CBOR value as a message object (module docstring)."""
    if isinstance(value, dict):
        return SimpleNamespace(**{str(k): as_message(v) for k, v in value.items()})
    if isinstance(value, list):
        return _list_message(value, set(map(type, value)))  # (exact built-in types)
    if isinstance(value, (bytes, bytearray)):
        return np.frombuffer(bytes(value), dtype=np.uint8)
    if type(value) is int and not _INT64[0] <= value <= _UINT64_MAX:
        return _big(value)
    return value  # (an integer of int64's or uint64's range exact: an id past 2**53 too)


def _list_message(value: list, kinds: set) -> Any:
    """A decoded JSON/CBOR list as :func:`as_message` gives it, ``kinds`` the set of the
    types of its items."""
    if kinds == {bool}:
        return np.array(value, dtype=bool)
    if kinds == {int}:
        try:
            return np.array(value, dtype=np.int64)
        except OverflowError:
            pass
        if min(value) >= 0 and max(value) <= _UINT64_MAX:  # (uint64 ids: exact, as CDR's)
            return np.array(value, dtype=np.uint64)
        return np.array([_big(x) for x in value], dtype=np.float64)
    if kinds and kinds <= {int, float}:
        try:  # (numpy converts each int as float() does)
            return np.array(value, dtype=np.float64)
        except OverflowError:
            return np.array([_big(x) if type(x) is int else x for x in value],
                            dtype=np.float64)
    return [as_message(x) for x in value]


_INT64 = (-(2**63), 2**63 - 1)
#: The largest uint64: integers up to it are kept exact (a ``uint64`` id written as a JSON
#: or CBOR integer is the integer it is, as CDR and protobuf read it), past it a float64
_UINT64_MAX = 2**64 - 1


def _big(value: int) -> float:
    """An integer past int64 and uint64 as the nearest float64; past the largest float, +-inf (as
    IEEE 754 rounds an overflow; a JSON ``1e999`` is read as inf too)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf
