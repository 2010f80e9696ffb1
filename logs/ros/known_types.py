"""Schemas that lie: an embedded definition of a standard ROS type (``geometry_msgs/msg/Twist``)
whose layout is not ROS's.

A log carries the definition its messages were written with, and fretc decodes by it. When
the definition names a type of ROS's own packages but declares another layout (fields
swapped, renamed or retyped: ``Vector3 angular`` before ``Vector3 linear``), the payload
still deserializes when the sizes agree and every value read from it is silently another
field's. ROS identifies a message type by its name (ROS 1 by the MD5 sum of its definition,
ROS 2 by its type hash, REP 2011), so such a definition is damage, not a variant: the topic
is reported and skipped as an unknown schema (:func:`layout_mismatch` is called by
:func:`fretc.logs.decoding.schema_decoder`).

Design notes: ARCHITECTURE.md, `logs/ros/known_types.py`."""

from __future__ import annotations

from functools import lru_cache, cache
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["layout_mismatch", "layout", "same_spelling", "ROS2_SAME", "ROS1_SAME"]

_ROS2 = ("ros2_humble", "ros2_jazzy", "ros2_iron", "ros2_kilted", "ros2_lyrical",
         "ros2_foxy", "ros2_galactic", "ros2_eloquent", "ros2_dashing")
_MAX_DEPTH = 32

#: ROS 2: primitive spellings of one type (module docstring: rosidl_adapter maps ``.msg``'s
#: ``byte`` to IDL ``octet`` and ``char`` to ``uint8``; octet and uint8 are one unsigned
#: byte each in XCDR), each mapped to the one the comparison uses
ROS2_SAME = {"byte": "uint8", "char": "uint8", "octet": "uint8"}
#: ROS 1: the deprecated aliases (the ROS wiki's msg page: ``byte`` is ``int8``, ``char``
#: is ``uint8``)
ROS1_SAME = {"byte": "int8", "char": "uint8"}


@cache
def _store(name: str):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores(name))


@lru_cache(maxsize=4096)
def _ref_layout(store_name: str, typename: str) -> tuple | None:
    ref = _store(store_name)
    return layout(ref, typename) if typename in ref.fielddefs else None


def same_spelling(kind_layout: tuple, same: dict[str, str]) -> tuple:
    """A layout (:func:`layout`) with every primitive spelled as ``same`` maps it
    (:data:`ROS2_SAME` or :data:`ROS1_SAME`), so that two spellings of one type compare
    equal; the field names, order, nesting and array lengths are kept."""
    return tuple((name, _same_kind(kind, same)) for name, kind in kind_layout)


def _same_kind(kind: tuple, same: dict[str, str]) -> tuple:
    if kind[0] == "base":
        return ("base", same.get(kind[1], kind[1]))
    if kind[0] == "msg":
        return ("msg", same_spelling(kind[1], same))
    if kind[0] == "array":
        return ("array", _same_kind(kind[1], same), kind[2])
    return ("seq", _same_kind(kind[1], same))


def layout(store: Typestore, typename: str, depth: int = 0) -> tuple:
    """The layout of ``typename`` in the rosbags Typestore ``store`` (module docstring): a
    tuple of ``(field name, kind)``, kind ``("base", type)``, ``("msg", layout)``,
    ``("array", kind, length)`` or ``("seq", kind)``.

    Raises:
        KeyError: a type the store does not hold; RecursionError: nesting deeper than 32.
    """
    if depth > _MAX_DEPTH:
        raise RecursionError(f"{typename} nests messages more than {_MAX_DEPTH} deep")
    _consts, fields = store.fielddefs[typename]
    return tuple((name, _kind(store, node, depth)) for name, node in fields)


def _kind(store, node, depth: int) -> tuple:
    kind, args = int(node[0]), node[1]
    if kind == 1:
        return ("base", args[0])
    if kind == 2:
        return ("msg", layout(store, args, depth + 1))
    inner, n = args
    if kind == 3:
        return ("array", _kind(store, inner, depth), n)
    return ("seq", _kind(store, inner, depth))


def _first_difference(got: tuple, want: tuple, prefix: str = "",
                      same: dict[str, str] | None = None) -> str:
    """The first difference of the layouts ``got`` (the log's) and ``want`` (ROS's), in
    words naming the field by its path (``prefix``): two spellings ``same`` maps to one
    primitive are not a difference; the types are shown as each layout spells them."""
    same = same or {}
    for k in range(max(len(got), len(want))):
        if k >= len(got):
            return f"it lacks {prefix}{want[k][0]}"
        if k >= len(want):
            return f"it adds {prefix}{got[k][0]}"
        (gn, gk), (wn, wk) = got[k], want[k]
        if gn != wn:
            return f"field {k + 1}{' of ' + prefix[:-1] if prefix else ''} is {gn!r} where " \
                   f"ROS has {wn!r}"
        if _same_kind(gk, same) != _same_kind(wk, same):
            inner = _inner_difference(gk, wk, f"{prefix}{gn}", same)
            if inner is not None:
                return inner
            return f"{prefix}{gn} is {_show(gk)} where ROS has {_show(wk)}"
    return "the layouts differ"


def _inner_difference(got: tuple, want: tuple, path: str, same: dict[str, str]
                      ) -> str | None:
    """The first difference inside two kinds of the field at ``path`` that are both
    messages, or both arrays of one length or sequences whose items differ (``[]`` added to
    the path, as far down as messages go), or None when the kinds themselves differ."""
    if got[0] != want[0]:
        return None
    if got[0] == "msg":
        return _first_difference(got[1], want[1], f"{path}.", same)
    if got[0] == "seq" or (got[0] == "array" and got[2] == want[2]):
        return _inner_difference(got[1], want[1], f"{path}[]", same)
    return None


def _show(kind: tuple) -> str:
    if kind[0] == "base":
        return kind[1]
    if kind[0] == "msg":
        return "a message"
    if kind[0] == "array":
        return f"{_show(kind[1])}[{kind[2]}]"
    return f"{_show(kind[1])}[]"


def layout_mismatch(schema_encoding: str, store: Any, typename: str) -> str | None:
    """Why the definition of ``typename`` in ``store`` (built from a log's schema of
    ``schema_encoding``) is not ROS's own (a sentence naming the first difference from the
    newest matching distribution, by its field's path), or None when it matches one or no
    distribution defines ``typename``. Spellings of one primitive type are equal (module
    docstring: :data:`ROS2_SAME`, :data:`ROS1_SAME`).

    Raises nothing: a definition that cannot be laid out (nested too deep) is a mismatch.
    """
    ros1 = schema_encoding == "ros1msg"
    names = ("ros1_noetic",) if ros1 else _ROS2
    same = ROS1_SAME if ros1 else ROS2_SAME
    refs = [r for r in (_ref_layout(name, typename) for name in names) if r is not None]
    if not refs:
        return None
    try:
        got = layout(store, typename)
    except (KeyError, RecursionError) as exc:
        return f"its definition cannot be laid out ({exc})"
    if any(same_spelling(got, same) == same_spelling(want, same) for want in refs):
        return None
    return (f"the log's definition of {typename} is not ROS's ("
            f"{_first_difference(got, refs[0], '', same)}): values read with it would be other "
            "fields'")
