"""How far back a machine's requirements look: the ticks after which a shield that lost its
state knows it again (:mod:`fretc.shield.runtime`, "a lost state recovers").

Design notes: ARCHITECTURE.md, `shield/lookback.py`."""

from __future__ import annotations

from collections.abc import Iterable

from fretc.compiler.ir import Node

__all__ = ["lookback"]

_UNBOUNDED = ("O", "H", "S", "T", "stream")


def lookback(formulas: Iterable[Node]) -> int | None:
    """The ticks the pt ``formulas`` look back together (module docstring): the largest of
    theirs, each read below its top ``H``; None when one looks back without bound."""
    most = 0
    for f in formulas:
        body = f.args[0] if f.op == "H" and f.hi is None and f.args else f
        got = _depth(body)
        if got is None:
            return None
        most = max(most, got)
    return most


def _depth(n: Node) -> int | None:
    """The ticks ``n`` looks back (``FTP`` one: the tick it is true at), None unbounded."""
    if n.op in ("true", "false", "ap", "cmp", "call", "var", "num", "LAST"):
        return max([0, *(d for d in map(_depth, n.args) if d is not None)]) \
            if all(_depth(a) is not None for a in n.args) else None
    if n.op == "FTP":
        return 1
    if n.op == "->" and len(n.args) == 2:
        guarded = _guarded(n.args[0], n.args[1])
        if guarded is not None:
            return guarded
    if n.op in ("Y", "Z"):
        d = _depth(n.args[0])
        return None if d is None else d + 1
    if n.op in ("O", "H") and n.hi is not None:
        d = _depth(n.args[0])
        return None if d is None else d + n.hi
    if n.op in _UNBOUNDED:
        return None
    parts = [_depth(a) for a in n.args]
    if any(d is None for d in parts):
        return None
    return max([0, *(d for d in parts if d is not None)])


def _guarded(left: Node, right: Node) -> int | None:
    """The depth of ``O[l,h] x -> (H !x | y)`` (module docstring) read as ``O[l,h] x ->
    y``; None when ``left -> right`` is not of that form (or looks back without bound)."""
    if left.op != "O" or left.hi is None or right.op != "|" or len(right.args) != 2:
        return None
    x = left.args[0]
    for h, y in (right.args, right.args[::-1]):
        if h.op == "H" and h.hi is None and h.args and h.args[0].op == "!" \
                and h.args[0].args and _implies(x, h.args[0].args[0]):
            a, b = _depth(left), _depth(y)
            return None if a is None or b is None else max(a, b)
    return None


def _implies(x: Node, z: Node) -> bool:
    """Whether ``x`` is ``z`` or a conjunction one of whose parts implies ``z``."""
    return x == z or (x.op == "&" and any(_implies(a, z) for a in x.args))
