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

A definition is accepted when its layout equals that of the same type in any ROS
distribution rosbags knows (ROS 1 Noetic for ``ros1msg``; Dashing to the newest ROS 2 for
``ros2msg``/``ros2idl``): the layout is the field names, kinds and primitive types in order,
nested messages expanded, fixed array lengths kept; bounds of strings and sequences and
constants are left out (they do not change the bytes). A type no distribution defines (a
project's own message) is not checked.
"""

from __future__ import annotations

from functools import lru_cache, cache
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["layout_mismatch", "layout"]

_ROS2 = ("ros2_humble", "ros2_jazzy", "ros2_iron", "ros2_kilted", "ros2_lyrical",
         "ros2_foxy", "ros2_galactic", "ros2_eloquent", "ros2_dashing")
_MAX_DEPTH = 32


@cache
def _store(name: str):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores(name))


@lru_cache(maxsize=4096)
def _ref_layout(store_name: str, typename: str) -> tuple | None:
    ref = _store(store_name)
    return layout(ref, typename) if typename in ref.fielddefs else None


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


def _first_difference(got: tuple, want: tuple, prefix: str = "") -> str:
    for k in range(max(len(got), len(want))):
        if k >= len(got):
            return f"it lacks {prefix}{want[k][0]}"
        if k >= len(want):
            return f"it adds {prefix}{got[k][0]}"
        (gn, gk), (wn, wk) = got[k], want[k]
        if gn != wn:
            return f"field {k + 1}{' of ' + prefix[:-1] if prefix else ''} is {gn!r} where " \
                   f"ROS has {wn!r}"
        if gk != wk:
            if gk[0] == wk[0] == "msg":
                return _first_difference(gk[1], wk[1], f"{prefix}{gn}.")
            return f"{prefix}{gn} is {_show(gk)} where ROS has {_show(wk)}"
    return "the layouts differ"


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
    newest matching distribution), or None when it matches one or no distribution defines
    ``typename``.

    Raises nothing: a definition that cannot be laid out (nested too deep) is a mismatch.
    """
    names = ("ros1_noetic",) if schema_encoding == "ros1msg" else _ROS2
    refs = [r for r in (_ref_layout(name, typename) for name in names) if r is not None]
    if not refs:
        return None
    try:
        got = layout(store, typename)
    except (KeyError, RecursionError) as exc:
        return f"its definition cannot be laid out ({exc})"
    if any(got == want for want in refs):
        return None
    return (f"the log's definition of {typename} is not ROS's ("
            f"{_first_difference(got, refs[0])}): values read with it would be other "
            "fields'")
