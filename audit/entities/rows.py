"""The per-entity variables of many (message, entity) rows at once, by numpy
(:func:`row_values`): the vectorized path of :mod:`fretc.audit.entities.read`.

Design notes: ARCHITECTURE.md, `audit/entities/rows.py`."""

from __future__ import annotations

import operator
from itertools import chain
from dataclasses import dataclass
from typing import Any

import numpy as np

from fretc.signals.between_ticks import is_boolean
from fretc.signals.bindings.binding import Binding
from fretc.signals.bindings.expression import (BinOp, Const, EntityParam, Field, Filter, FuncCall,
                                               Named, Slice, UnaryOp, walk)
from fretc.signals.bindings.extract import Valid, by_entity, entity_key, normalize_scalar
from fretc.signals.columns import Irregular

__all__ = ["ItemField", "row_fields", "row_values", "item_values", "reads_items_of", "RowColumns",
           "key_reader", "KeyReader"]

#: The functions a row-wise variable may call (reductions and arithmetic over the items).
_FUNCS = frozenset({"abs", "min", "max", "mean", "norm", "any", "all", "count", "len",
                    "invalid", "sqrt"})


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


#: Integers a float64 holds exactly. Keys are no longer read through a float64
#: (:func:`fretc.signals.bindings.extract.entity_key`: integers of every width exact); kept
#: for what still compares with it.
_EXACT = 2 ** 53


def key_reader(b: Binding) -> KeyReader | None:
    """For an entity key ``/topic.array[:].field`` (names only around one full slice), its
    :class:`KeyReader`; None when the key has another form."""
    ast = b.ast
    if not isinstance(ast, Field) or ast.filters:
        return None
    at = [k for k, p in enumerate(ast.path) if isinstance(p, Slice)]
    if len(at) != 1:
        return None
    cut = ast.path[at[0]]
    before, after = ast.path[:at[0]], ast.path[at[0] + 1:]
    if (cut.lo is not None or cut.hi is not None or not before or not after  # type: ignore[union-attr]
            or not all(type(p) is str for p in before + after)):
        return None
    return KeyReader(".".join(before), ".".join(after))  # type: ignore[arg-type]


class KeyReader:
    """A reader of the keys of an entity key ``/topic.array[:].field`` that gives what the
    key's binding gives (``entity_kinds.key_items`` of its value) when the keys are all strings
    or all finite numbers: one message's (call), or a batch's when they are all integers
    (:meth:`batch`); None otherwise (the caller then evaluates the binding: bools,
    infinities, NaN, missing fields and their errors are its)."""

    def __init__(self, array: str, key: str) -> None:
        self.path = (array, key)  # (the dotted paths: an ItemField's array and key)
        self.array = operator.attrgetter(array)
        self.key = operator.attrgetter(key)

    def __call__(self, data: Any) -> list | None:
        """The keys of one message, or None (class docstring)."""
        try:
            items = self.array(data)
            if not isinstance(items, (list, tuple)):
                return None
            vals = [self.key(x) for x in items]
        except Exception:  # noqa: BLE001 - the binding reads it again and names the error
            return None
        if all(type(v) is int for v in vals):
            return vals  # (the binding's exact keys: ints of any width, no float64 between)
        vals = [entity_key(v) for v in vals]
        if all(type(v) is str for v in vals):
            return vals
        if all(type(v) in (int, float) and v - v == 0 for v in vals):  # (finite numbers)
            return vals
        return None

    def batch(self, datas: list) -> tuple[list[int], list[list]] | None:
        """The keys of the messages ``datas`` laid end to end and each message's items
        (the array's elements, a list each), when each message's keys are what a call gives
        and all are integers (the common case, read without a Python loop per key); None
        otherwise (read them one message at a time)."""
        try:
            arrays = list(map(self.array, datas))
            if any(type(a) is not list for a in arrays):
                return None
            keys = list(map(self.key, chain.from_iterable(arrays)))
        except Exception:  # noqa: BLE001 - one at a time: the binding names the error
            return None
        if keys and set(map(type, keys)) != {int}:  # (ints of any width: exact keys)
            return None
        return keys, arrays


class RowColumns:
    """What :meth:`~fretc.signals.bindings.Binding.evaluate_columns` reads over ``n`` rows:
    each item field's values (a :class:`Valid` of rows x items)."""

    def __init__(self, n: int, fields: dict[str, Valid]) -> None:
        self.n = n
        self.fields = fields

    def field(self, topic: str, path: tuple, node: Field) -> Any:
        """The item field ``node``'s values over the rows.

        Raises:
            Irregular: not an item field of the rows."""
        try:
            return self.fields[node.text()]
        except KeyError:
            raise Irregular(f"{node.text()}: not an item field") from None

    def age(self, topic: str) -> np.ndarray:
        """Raises :class:`Irregular`: a row has no tick time (such variables are refused)."""
        raise Irregular("age() over rows")

    @property
    def tf(self) -> Any:
        """Raises :class:`Irregular`: tf() reads every transform, not a row."""
        raise Irregular("tf() over rows")

    def per_message(self, node: Any, topic: str, vector: Any, scalar: Any) -> np.ndarray:
        """A reduction of one topic's fields: by ``vector`` over the rows (a row is one
        message and one entity)."""
        return vector(self)


def _column(flat: list, n: int, width: int, what: str) -> Valid:
    """``n`` rows of ``width`` values each as a :class:`Valid` (no mask), typed as the
    tick-by-tick extractor types one row: all booleans bool, all numbers float64.

    Raises:
        Irregular: other values, or booleans mixed with numbers (one row might differ)."""
    if not flat:
        return Valid(np.empty((n, 0), np.float64), None)
    kinds = set(map(type, flat))
    if kinds - {bool, float}:  # (ints and numpy numbers as the extractor reads them)
        flat = [normalize_scalar(v) for v in flat]
        kinds = set(map(type, flat))
    if kinds == {bool}:
        return Valid(np.array(flat, dtype=np.bool_).reshape(n, width), None)
    if kinds == {float}:
        return Valid(np.array(flat, dtype=np.float64).reshape(n, width), None)
    raise Irregular(f"{what}: values that are not all numbers or all booleans")


def _typed(b: Binding, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The values of ``b`` over the rows as float64 and whether each is a bool, as the
    tick-by-tick evaluator gives them (:func:`fretc.audit.entities.columns.floats` of its
    values): a boolean by its form (a comparison, a logical operator) is a bool, or NaN when
    unknown (numpy holds such a column as float)."""
    if v.dtype == np.bool_:
        return v.astype(np.float64), np.ones(len(v), np.bool_)
    if is_boolean(b.ast):
        return v, ~np.isnan(v)
    return v, np.zeros(len(v), np.bool_)


def reads_items_of(specs: dict[Field, ItemField], reader: KeyReader | None) -> bool:
    """Whether every item field of ``specs`` reads the items of the entity key's array
    through its key field (a held message's rows are then its items, in order, when no key
    repeats in it)."""
    return reader is not None and all((s.array, s.key) == reader.path for s in specs.values())


def item_values(own: list[Binding], specs: dict[Field, ItemField], items: list
                ) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`row_values` of rows that are ``items`` (the item each row reads, laid end to
    end; the caller knows each row's item: :func:`reads_items_of`).

    Raises:
        Irregular, SignalError: as :func:`row_values`."""
    n = len(items)
    try:
        cols = RowColumns(n, {f.text(): _column(list(map(operator.attrgetter(s.rest), items)),
                                                n, 1, f.text()) for f, s in specs.items()})
    except (AttributeError, TypeError, IndexError) as exc:
        raise Irregular(f"an item the rows cannot read: {exc}") from None
    with np.errstate(all="ignore"):
        return [_typed(b, b.evaluate_columns(cols)) for b in own]


def row_values(own: list[Binding], specs: dict[Field, ItemField],
               batch: list[tuple[Any, list[Any]]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The per-entity variables ``own`` (:func:`row_fields` gave ``specs``) over ``batch``:
    (message data, the keys of the entities present in it) -> per variable, its values
    over the rows (each message's entities in that order, message after message) as
    float64 and whether each is a bool (:func:`_typed`).

    Raises:
        Irregular: rows the path does not take (module docstring).
        SignalError: a binding's evaluation error (the caller evaluates one at a time).
    """
    by_text = {f.text(): s for f, s in specs.items()}
    arrays = {s.array for s in by_text.values()}
    flats: dict[str, list] = {t: [] for t in by_text}
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
                    get = keyget[s.key]
                    # (a string equals only a string: FoxQL's filter semantics as it is)
                    # (a key as read equals and hashes as normalize_scalar's: no call each)
                    g = groups[(s.array, s.key)] = {get(x): x for x in items}
                    if len(g) != len(items):
                        raise Irregular("a key repeated in a message: rows of several items")
                rest = restget[t]
                flats[t].extend([rest(g[want]) for want in keys])
            n += len(keys)
    except KeyError:
        raise Irregular("an entity without an item in an array: a row of no item") from None
    except (AttributeError, TypeError, IndexError) as exc:
        raise Irregular(f"an item the rows cannot read: {exc}") from None
    cols = RowColumns(n, {t: _column(flats[t], n, 1, t) for t in by_text})
    with np.errstate(all="ignore"):
        return [_typed(b, b.evaluate_columns(cols)) for b in own]
