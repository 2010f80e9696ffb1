"""The per-entity variables of many (message, entity) rows at once, by numpy
(:func:`row_values`): the vectorized path of :mod:`fretc.audit.entity_read`.

A per-entity variable whose fields all read the items of one array of the key's message
through a filter on the entity's key (``min(/tracks.tracks[:]{id==$track}.distance)``) is a
function of that message and the entity alone. For a batch of such messages, each message's
items are grouped by their key field (as :func:`fretc.signals.bindings.extract._grouper`
groups them: FoxQL's filter semantics, a string matches only a string), each (message,
entity present in it) is one row, each field's values over a row's items one row of a
:class:`~fretc.signals.bindings.extract.Valid` array, and each binding is evaluated once over
all rows (:meth:`fretc.signals.bindings.Binding.evaluate_columns`, the operations of the
tick-by-tick evaluator over ticks x items).

What this path does not take raises :class:`~fretc.signals.columns.Irregular` and the caller
evaluates those rows message by message with :meth:`~fretc.signals.bindings.Binding.evaluate`
(the reference, which gives the values and the errors): a row whose items differ in number
from the others' (a key repeated in some message), values that are not all numbers or all
booleans, a field missing from an item, a message without the array. :func:`row_fields`
says which variables the path can take at all (else the caller always uses the reference).
"""

from __future__ import annotations

import operator
from dataclasses import dataclass
from typing import Any

import numpy as np

from fretc.signals.between_ticks import is_boolean
from fretc.signals.bindings.binding import Binding
from fretc.signals.bindings.expression import (BinOp, Const, EntityParam, Field, Filter, FuncCall,
                                               Named, Slice, UnaryOp, walk)
from fretc.signals.bindings.extract import Valid, by_entity, normalize_scalar
from fretc.signals.columns import Irregular

__all__ = ["ItemField", "row_fields", "row_values", "RowColumns"]

#: The functions a row-wise variable may call (reductions and arithmetic over the items).
_FUNCS = frozenset({"abs", "min", "max", "mean", "norm", "any", "all", "count", "len", "sqrt"})


@dataclass(frozen=True)
class ItemField:
    """A field ``/topic.array[:]{key==$e}.rest``: ``array`` the dotted path to the array
    of items, ``key`` the dotted path of an item's key field, ``rest`` the dotted path of the
    value read from each item kept."""

    array: str
    key: str
    rest: str


def _item_field(f: Field, topic: str) -> ItemField | None:
    """The :class:`ItemField` of ``f`` when it has that form on ``topic``, else None."""
    if f.filters or f.topic != topic:
        return None
    at = [k for k, p in enumerate(f.path) if isinstance(p, Filter)]
    if len(at) != 1:
        return None
    k = at[0]
    flt = f.path[k]
    assert isinstance(flt, Filter)
    before, after = list(f.path[:k]), f.path[k + 1:]
    if before and isinstance(before[-1], Slice):
        if before[-1].lo is not None or before[-1].hi is not None:
            return None
        before.pop()
    if (not by_entity(flt) or not before or not after
            or not all(type(p) is str for p in before) or not all(type(p) is str for p in after)):
        return None
    return ItemField(".".join(before), ".".join(flt.path), ".".join(after))  # type: ignore[arg-type]


def row_fields(own: list[Binding], topic: str) -> dict[Field, ItemField] | None:
    """The item fields of the per-entity variables ``own`` when each can be evaluated over
    rows (module docstring): only fields of that form on the key's ``topic``, constants,
    named constants, operators and the functions of :data:`_FUNCS`; the entity's key read
    nowhere but in those filters. None otherwise."""
    out: dict[Field, ItemField] = {}
    for b in own:
        if b.aggregate is not None or b.window is not None or b.tick_window is not None \
                or b.parts or b.uses_tf:
            return None
        for n in walk(b.ast):
            if isinstance(n, Field):
                spec = _item_field(n, topic)
                if spec is None:
                    return None
                out[n] = spec
            elif isinstance(n, Const):
                if isinstance(n.value, EntityParam):
                    return None
            elif isinstance(n, FuncCall):
                if n.func not in _FUNCS or (n.func in ("min", "max") and len(n.args) > 1 and any(
                        is_boolean(a) or isinstance(a, FuncCall) for a in n.args)):
                    return None  # (min/max of several values is one of them: a boolean
                    # there stays one tick by tick, a number by numpy)
            elif not isinstance(n, (Named, UnaryOp, BinOp)):
                return None
    return out


class RowColumns:
    """What :meth:`~fretc.signals.bindings.Binding.evaluate_columns` reads over ``n`` rows:
    each item field's values (a :class:`Valid` of rows x items)."""

    def __init__(self, n: int, fields: dict[str, Valid]) -> None:
        self.n = n
        self.fields = fields

    def field(self, topic: str, path: tuple, node: Field) -> Any:
        try:
            return self.fields[node.text()]
        except KeyError:
            raise Irregular(f"{node.text()}: not an item field") from None

    def age(self, topic: str) -> np.ndarray:
        raise Irregular("age() over rows")

    @property
    def tf(self) -> Any:
        raise Irregular("tf() over rows")

    def per_message(self, node: Any, topic: str, vector: Any, scalar: Any) -> np.ndarray:
        return vector(self)  # (a row is one message and one entity)


def _column(flat: list, n: int, width: int, what: str) -> Valid:
    """``n`` rows of ``width`` values each as a :class:`Valid` (no mask), typed as the
    tick-by-tick extractor types one row: all booleans bool, all numbers float64.

    Raises:
        Irregular: other values, or booleans mixed with numbers (one row might differ)."""
    if not flat:
        return Valid(np.empty((n, 0), np.float64), None)
    kinds = {type(v) for v in flat}
    if kinds == {bool}:
        return Valid(np.array(flat, dtype=np.bool_).reshape(n, width), None)
    if kinds == {float}:
        return Valid(np.array(flat, dtype=np.float64).reshape(n, width), None)
    raise Irregular(f"{what}: values that are not all numbers or all booleans")


def _python(b: Binding, v: np.ndarray) -> list:
    """The values of ``b`` over the rows as the tick-by-tick evaluator gives them: a
    boolean by its form (a comparison, a logical operator) a Python bool, or NaN when
    unknown (numpy holds such a column as float)."""
    out = v.tolist()
    if v.dtype.kind == "f" and is_boolean(b.ast):
        return [x == 1.0 if x == x else x for x in out]
    return out


def row_values(own: list[Binding], specs: dict[Field, ItemField],
               batch: list[tuple[Any, list[Any]]]) -> list[list[tuple]]:
    """The per-entity variables ``own`` (:func:`row_fields` gave ``specs``) over ``batch``:
    (message data, the keys of the entities present in it) -> per message, per entity in
    that order, the tuple of the variables' values (Python bool or float).

    Raises:
        Irregular: rows the path does not take (module docstring).
        SignalError: a binding's evaluation error (the caller evaluates one at a time).
    """
    by_text = {f.text(): s for f, s in specs.items()}
    arrays = {s.array for s in by_text.values()}
    flats: dict[str, list] = {t: [] for t in by_text}
    widths: dict[str, int | None] = dict.fromkeys(by_text)
    getters = {a: operator.attrgetter(a) for a in arrays}
    keyget = {s.key: operator.attrgetter(s.key) for s in by_text.values()}
    restget = {t: operator.attrgetter(s.rest) for t, s in by_text.items()}
    n = 0
    try:
        for data, keys in batch:
            groups: dict[tuple[str, str], dict] = {}
            for t, s in by_text.items():
                g = groups.get((s.array, s.key))
                if g is None:
                    items = getters[s.array](data)
                    if not isinstance(items, (list, tuple, np.ndarray)):
                        raise Irregular(f"{s.array}: not an array")
                    g = groups[(s.array, s.key)] = {}
                    get = keyget[s.key]
                    for x in items:
                        v = normalize_scalar(get(x))
                        g.setdefault((isinstance(v, str), v), []).append(x)
                rest, flat = restget[t], flats[t]
                for want in keys:
                    kept = g.get((isinstance(want, str), want), ())
                    w = widths[t]
                    if w is None:
                        w = widths[t] = len(kept)
                    elif len(kept) != w:
                        raise Irregular("rows of different numbers of items")
                    flat.extend(normalize_scalar(rest(x)) for x in kept)
            n += len(keys)
    except (AttributeError, TypeError, IndexError) as exc:
        raise Irregular(f"an item the rows cannot read: {exc}") from None
    cols = RowColumns(n, {t: _column(flats[t], n, widths[t] or 0, t) for t in by_text})
    with np.errstate(all="ignore"):
        values = [_python(b, b.evaluate_columns(cols)) for b in own]
    rows = list(zip(*values)) if values else [() for _ in range(n)]
    out, at = [], 0
    for _data, keys in batch:
        out.append(rows[at:at + len(keys)])
        at += len(keys)
    return out
