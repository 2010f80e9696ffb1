"""Field access: a message's field as a binding value (:func:`make_extractor`).

Values are Python ``bool``/``float`` (integer fields are read as floats), :class:`Valid`
arrays (numeric arrays as float64), or the raw object for anything else (strings, nested
messages).  A field path ending in ``ranges`` of a ``sensor_msgs/LaserScan`` (without an
index) yields only the valid returns (REP 117): values inside ``[range_min, range_max]``,
with -inf ("detected, too close to measure") read as ``range_min``.

An entity's key is read exactly (:func:`entity_key`, ``make_extractor(..., exact=True)``):
an integer key stays the Python int it is, whatever its width (``uint64`` ids of ROS 2 CDR,
protobuf, JSON past 2**53 are distinct integers a float64 would merge: 2**53 and 2**53 + 1
are one double), and a filter on an entity's key (``{id==$track}``) compares the items'
keys with the entity's as integers (Python compares an int with a float exactly).
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from typing import Any

import numpy as np

from fretc.signals.bindings.expression import Const, EntityParam, Field, Filter, Slice, const_value
from fretc.signals.bindings.frames import FRAME_FIELDS, frame_name

__all__ = ["LASER_SCAN", "rep117", "Valid", "FieldAccessError", "make_extractor", "message_filter", "by_entity",
           "normalize_scalar", "entity_key"]

LASER_SCAN = "sensor_msgs/msg/LaserScan"


class Valid:
    """An array value with an optional validity mask (REP 117-filtered LaserScan ranges).

    ``data`` is 1-D (one tick) or 2-D (ticks × items, vectorized path); ``mask`` is None
    (all items valid) or a bool array of the same shape.
    """

    __slots__ = ("data", "mask")

    def __init__(self, data: np.ndarray, mask: np.ndarray | None) -> None:
        self.data = data
        self.mask = mask


class FieldAccessError(Exception):
    """A field an extractor cannot read from a message: no such field, an index out of
    range, or indexing (slicing) what is not a sequence.  The message starts with the
    field's text (``/scan.ranges[3]: index out of range``)."""


def normalize_scalar(v: Any) -> Any:
    """A scalar field value as a binding value: ints and numpy numbers as float, numpy
    bools as bool; anything else (strings, messages) as it is."""
    t = type(v)
    if t is float or t is bool:
        return v
    if t is int:
        return float(v)
    if isinstance(v, np.generic):
        v = v.item()
        return v if type(v) is bool else float(v) if isinstance(v, (int, float)) else v
    return v


def entity_key(v: Any) -> Any:
    """A field value as an entity's key, exact (module docstring): Python and numpy
    integers as the Python int they are (never through a float64: ``uint64`` ids past
    2**53 stay distinct), numpy floats as Python floats (an integral float key equals and
    hashes as the int it is: Python's exact comparison), numpy bools as bool; anything else
    (strings) as it is."""
    if isinstance(v, np.generic):
        return v.item()
    return v


def _frame_key(v: Any) -> Any:
    """An item's key compared with an entity that is a TF frame (the filter's field one of
    :data:`~fretc.signals.bindings.frames.FRAME_FIELDS`): a string without its leading
    ``/`` (:func:`~fretc.signals.bindings.frames.frame_name`, tf2's rule)."""
    v = entity_key(v)
    return frame_name(v) if isinstance(v, str) else v


def _as_array(v: np.ndarray) -> np.ndarray:
    if v.dtype == np.bool_:
        return v
    if v.dtype.kind in "iuf":
        return v.astype(np.float64, copy=False)
    return v


def _identity(data: Any) -> Any:
    return data


def _walker(path: tuple) -> Callable[[Any], Any]:
    """message -> the object at ``path`` (names and indexes): runs of names become one
    ``attrgetter``, indexes ``itemgetter``s."""
    steps: list[Callable[[Any], Any]] = []
    attrs: list[str] = []
    for p in path:
        if isinstance(p, str):
            attrs.append(p)
            continue
        if attrs:
            steps.append(operator.attrgetter(".".join(attrs)))
            attrs = []
        steps.append(operator.itemgetter(p))
    if attrs:
        steps.append(operator.attrgetter(".".join(attrs)))
    if len(steps) == 1:
        return steps[0]  # fast path: one attrgetter
    if not steps:
        return _identity

    def walk_steps(data: Any) -> Any:
        for s in steps:
            data = s(data)
        return data
    return walk_steps


def _no_field(data: Any, path: tuple, text: str, exc: AttributeError) -> FieldAccessError:
    owner = data
    for p in path:  # find the object that lacks the field, for the message
        if isinstance(p, str) and not hasattr(owner, p):
            break
        try:
            owner = getattr(owner, p) if isinstance(p, str) else owner[p]
        except (IndexError, TypeError, KeyError):
            break
    typename = getattr(owner, "__msgtype__", type(owner).__name__)
    return FieldAccessError(f"{text}: a {typename} message has no field {exc.name!r}")


def rep117(ranges: np.ndarray, range_min: Any, range_max: Any) -> Valid:
    """LaserScan ranges as :class:`Valid` under REP 117: -inf is a detection closer than
    ``range_min`` and reads as ``range_min`` (a too-close object is never hidden); valid are
    the values inside ``[range_min, range_max]``. ``ranges`` is 1-D (one message, scalar
    limits) or 2-D (messages x beams, limits as columns of shape (messages, 1))."""
    arr = np.asarray(ranges, dtype=np.float64)
    too_close = arr == -np.inf
    if too_close.any():
        arr = np.where(too_close, range_min, arr)
    return Valid(arr, (arr >= range_min) & (arr <= range_max))


def _laser_ranges(parent: Any) -> Any:
    """``parent.ranges``: as :class:`Valid` with the REP 117 mask when ``parent`` is a
    LaserScan, else as it is."""
    v = parent.ranges
    if getattr(parent, "__msgtype__", None) != LASER_SCAN:
        return v
    return rep117(v, parent.range_min, parent.range_max)


def _sliced(f: Field) -> Callable[[Any], Any]:
    inner = make_extractor(Field(f.col, f.topic, f.path[:-1]))
    last = f.path[-1]
    assert isinstance(last, Slice)
    sl = slice(last.lo, last.hi)
    text = f.text()

    def sliced(data: Any) -> Any:
        v = inner(data)  # REP 117 validity of LaserScan ranges is kept for the slice
        if isinstance(v, Valid):
            return Valid(v.data[..., sl], None if v.mask is None else v.mask[..., sl])
        if isinstance(v, (list, tuple)):
            return list(v[sl])
        raise FieldAccessError(f"{text}: only arrays can be sliced")
    return sliced


_FILTER_OPS = {"=": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
               ">": operator.gt, ">=": operator.ge}


def _filter_test(flt: Filter, constants: dict[str, Any], text: str) -> Callable[[Any], bool]:
    """item -> whether ``flt`` keeps it (its field compared with the filter's value)."""
    get = operator.attrgetter(".".join(flt.path))
    op = _FILTER_OPS[flt.op]
    value_node = flt.value
    # (compared with an entity's key: the item's key read exactly, :func:`entity_key`; a
    # frame name without its leading slash, :func:`_frame_key`)
    read = ((_frame_key if flt.path and flt.path[-1] in FRAME_FIELDS else entity_key)
            if isinstance(value_node, Const) and isinstance(value_node.value, EntityParam)
            else normalize_scalar)

    def keep(item: Any) -> bool:
        want: Any
        if isinstance(value_node, Const):
            want = const_value(value_node.value)
        else:  # a Named constant, resolved against the log's schemas
            if value_node.name not in constants:  # type: ignore[attr-defined]
                raise FieldAccessError(f"{text}: {value_node.name} is not a constant of the "  # type: ignore[attr-defined]
                                       "message definition")
            want = constants[value_node.name]  # type: ignore[attr-defined]
        v = read(get(item))
        if isinstance(want, str) != isinstance(v, str):
            return False
        return bool(op(v, want))
    return keep


def message_filter(filters: tuple[Filter, ...], constants: dict[str, Any], text: str
                   ) -> Callable[[Any], bool]:
    """message -> whether it passes every filter of ``filters`` (written right after the
    topic: ``/track{id==3}{ok==true}``), each as a filter on the items of an array compares
    (a string only with a string; FoxQL's filter semantics).

    Raises (from the returned function):
        FieldAccessError: the message has no field a filter names (``text``: the field as
            written, first in the message).
    """
    tests = [_filter_test(f, constants, text) for f in filters]

    def passes(data: Any) -> bool:
        try:
            return all(t(data) for t in tests)
        except AttributeError as exc:
            typename = getattr(data, "__msgtype__", type(data).__name__)
            raise FieldAccessError(f"{text}: a {typename} message has no field "
                                   f"{exc.name!r}") from None
    return passes


def _select(items: list, many: bool, kind: str, fn: Any, text: str) -> tuple[list, bool]:
    """One slice or filter of a path: on an array (or on each array of ``items``, their
    items joined) a slice takes items and a filter keeps those it accepts; a filter right
    after a slice filters the items the slice took."""
    arrays = all(isinstance(x, (list, tuple, np.ndarray)) for x in items)
    if kind == "slice" or not many or arrays:
        if not arrays:
            raise FieldAccessError(f"{text}: only arrays can be sliced or filtered")
        if kind == "slice":
            return [x for it in items for x in list(it)[fn]], True
        items = [x for it in items for x in it]
    return [x for x in items if fn(x)], True


def by_entity(flt: Filter) -> bool:
    """``{id==$track}``: a filter on an entity's key (its items grouped by the key field
    once per message, :func:`_grouper`)."""
    return (flt.op == "=" and isinstance(flt.value, Const)
            and isinstance(flt.value.value, EntityParam))


def _grouper(flt: Filter, text: str) -> Callable[[Any, int, list, bool], list]:
    """The step of a filter on an entity's key (``{id==$track}``, FoxQL's filter semantics:
    a string matches only a string): the items of the message's arrays grouped by their
    key field once per message (the last message's groups kept), the entity's items
    looked up; as :func:`_filter_test` keeps them, in their order. The items' keys are read
    exactly (:func:`entity_key`: two ``uint64`` ids a float64 merges stay two groups)."""
    get = operator.attrgetter(".".join(flt.path))
    param = flt.value.value  # type: ignore[attr-defined]
    memo: list[Any] = [None, -1, None]  # message, step, groups
    read = _frame_key if flt.path and flt.path[-1] in FRAME_FIELDS else entity_key

    def step(data: Any, k: int, items: list, many: bool) -> list:
        if memo[0] is not data or memo[1] != k:
            flat, _m = _select(items, many, "filter", lambda x: True, text)
            groups: dict[tuple[bool, Any], list] = {}
            for x in flat:
                v = read(get(x))
                groups.setdefault((isinstance(v, str), v), []).append(x)
            memo[0], memo[1], memo[2] = data, k, groups
        want = param.value
        try:
            return list(memo[2].get((isinstance(want, str), want), ()))
        except TypeError:  # a key that cannot be looked up (unhashable): none matches
            return []
    return step


def _multi(f: Field, constants: dict[str, Any], exact: bool = False) -> Callable[[Any], Any]:
    """Extractor of a path with a slice or a filter before its end (Foxglove's message path
    semantics): from the first of them on, each step applies to every item, a slice or a
    filter selects items, and the value is the array of what is left (``exact``: the list
    of the items' values as :func:`entity_key` reads them, an entity key's)."""
    text = f.text()
    steps: list[tuple[str, Any]] = []
    for p in f.path:
        if isinstance(p, Filter) and by_entity(p):
            steps.append(("group", _grouper(p, text)))
        elif isinstance(p, Filter):
            steps.append(("filter", _filter_test(p, constants, text)))
        elif isinstance(p, Slice):
            steps.append(("slice", slice(p.lo, p.hi)))
        else:
            steps.append(("step", operator.itemgetter(p) if isinstance(p, int)
                          else operator.attrgetter(p)))

    def extract(data: Any) -> Any:
        items, many = [data], False
        try:
            for k, (kind, fn) in enumerate(steps):
                if kind == "step":
                    items = [fn(x) for x in items]
                    continue
                if kind == "group":
                    items, many = fn(data, k, items, many), True
                    continue
                items, many = _select(items, many, kind, fn, text)
        except AttributeError as exc:
            raise FieldAccessError(f"{text}: an item has no field {exc.name!r}") from None
        except IndexError:
            raise FieldAccessError(f"{text}: index out of range") from None
        if exact:
            return [entity_key(x) for x in items]
        vals = [normalize_scalar(x) for x in items]
        if all(type(v) is bool for v in vals) and vals:
            return Valid(np.array(vals, dtype=np.bool_), None)
        if all(type(v) in (bool, float) for v in vals):
            return Valid(np.array(vals, dtype=np.float64), None)
        return vals
    return extract


def make_extractor(f: Field, constants: dict[str, Any] | None = None, exact: bool = False
                   ) -> Callable[[Any], Any]:
    """A function message-data → value of field ``f`` (normalized; module docstring).
    ``constants``: values of the named constants a filter compares with (filled in when
    the binding is checked against the log's schemas). ``exact``: an entity key's read
    (module docstring): an array as the list of its values and a scalar as
    :func:`entity_key` gives them (integers as Python ints, never float64), no LaserScan
    validity mask.

    Returns Python bool/float, :class:`Valid` for arrays (masked for LaserScan ranges), a
    list for arrays of strings or messages, or the raw object for anything else (strings,
    nested messages).

    Raises (from the returned function):
        FieldAccessError: no such field, index out of range, or indexing a non-sequence.
    """
    if f.multi:
        return _multi(f, constants if constants is not None else {}, exact)
    if exact:
        return _exact(f)
    if f.path and isinstance(f.path[-1], Slice):
        return _sliced(f)
    path = f.path
    laser = isinstance(path[-1], str) and path[-1] == "ranges"
    walk = _walker(path[:-1] if laser else path)
    text = f.text()

    def extract(data: Any) -> Any:
        try:
            v = walk(data)
            if laser:
                v = _laser_ranges(v)
                if isinstance(v, Valid):
                    return v
        except AttributeError as exc:
            raise _no_field(data, path, text, exc) from None
        except IndexError:
            raise FieldAccessError(f"{text}: index out of range") from None
        except (TypeError, KeyError) as exc:
            raise FieldAccessError(f"{text}: cannot index ({exc})") from None
        if isinstance(v, np.ndarray):
            return Valid(_as_array(v), None)
        if isinstance(v, (list, tuple)) and v and all(isinstance(x, (bool, int, float)) for x in v):
            return Valid(_as_array(np.asarray(v)), None)
        return normalize_scalar(v)

    return extract


def _walked(walk: Callable[[Any], Any], data: Any, path: tuple[Any, ...], text: str) -> Any:
    """``walk(data)``, its lookup errors as :class:`FieldAccessError` naming the field
    ``text`` (as :func:`make_extractor`'s).

    Raises:
        FieldAccessError: no such field, an index out of range, or a value not indexable."""
    try:
        return walk(data)
    except AttributeError as exc:
        raise _no_field(data, path, text, exc) from None
    except IndexError:
        raise FieldAccessError(f"{text}: index out of range") from None
    except (TypeError, KeyError) as exc:
        raise FieldAccessError(f"{text}: cannot index ({exc})") from None


def _exact(f: Field) -> Callable[[Any], Any]:
    """:func:`make_extractor`'s exact read of a path without a filter before its end: an
    array (numpy, list, a slice of one) as the list of its values, a scalar as
    :func:`entity_key` gives them.

    Raises (from the returned function): FieldAccessError, as :func:`make_extractor`."""
    sl = None
    path = f.path
    if path and isinstance(path[-1], Slice):
        sl, path = slice(path[-1].lo, path[-1].hi), path[:-1]
    walk = _walker(path)
    text = f.text()

    def extract(data: Any) -> Any:
        v = _walked(walk, data, path, text)
        if isinstance(v, np.ndarray):
            v = v.tolist()  # (Python ints of any width: int64, uint64 exact)
        elif isinstance(v, tuple):
            v = list(v)
        elif sl is not None and not isinstance(v, list):
            raise FieldAccessError(f"{text}: only arrays can be sliced")
        if isinstance(v, list):
            return [entity_key(x) for x in (v[sl] if sl is not None else v)]
        return entity_key(v)
    return extract
