"""The numbers of outputs bounded by the inputs and of twists, standard library only: part of
the shield's step (:mod:`fretc.shield.runtime`), written into the Python form after
:mod:`fretc.shield.runtime_values` (:func:`fretc.shield.emit_python.render_python`).

Design notes: ARCHITECTURE.md, `shield/runtime_bounds.py`."""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from typing import Any

from fretc.shield.runtime_values import _NOT, term_value

__all__ = ["threshold", "bounded_value", "scaled", "DOUBLE_MAX"]

#: the largest finite double: a bounded output is a finite number
DOUBLE_MAX = 1.7976931348623157e308


def _key(x: float) -> int:
    """The position of the double ``x`` in the order of the doubles (0 for both zeros)."""
    bits = int(struct.unpack("<q", struct.pack("<d", x))[0])
    return bits if bits >= 0 else -(bits & 0x7FFFFFFFFFFFFFFF)


def _double(k: int) -> float:
    """The double at position ``k`` (:func:`_key`'s inverse, +0.0 for 0)."""
    if k >= 0:
        return float(struct.unpack("<d", struct.pack("<q", k))[0])
    return float(struct.unpack("<d", struct.pack("<Q", (-k) | (1 << 63)))[0])


#: the position of the largest finite double
_KEY_MAX = _key(DOUBLE_MAX)


def _last_true(g: Callable[[float], bool], k: int) -> int | None:
    """The last position in ``[-_KEY_MAX, _KEY_MAX]`` at which ``g`` (true, then false, in
    the doubles' order) is true, searched from position ``k``: galloping (steps 1, 2, 4, ...)
    to a true and a false position, then bisection between them; None when ``g`` is false
    at every finite double."""
    if g(_double(k)):
        good, step = k, 1
        while True:
            probe = _KEY_MAX if _KEY_MAX - good < step else good + step
            if probe == good:
                return good
            if not g(_double(probe)):
                bad = probe
                break
            good, step = probe, (_KEY_MAX if step > _KEY_MAX // 2 else step * 2)
    else:
        bad, step = k, 1
        while True:
            probe = -_KEY_MAX if bad + _KEY_MAX < step else bad - step
            if probe == bad:
                return None
            if g(_double(probe)):
                good = probe
                break
            bad, step = probe, (_KEY_MAX if step > _KEY_MAX // 2 else step * 2)
    while bad - good > 1:
        mid = good + (bad - good) // 2
        if g(_double(mid)):
            good = mid
        else:
            bad = mid
    return good


def threshold(f: Callable[[float], bool], down: bool, estimate: float) -> float:
    """The end of the finite doubles at which the comparison ``f`` (of one output's value,
    monotone in it) holds, searched from ``estimate`` (its bound's value; NaN reads 0):
    ``down``, its true values a half-line downwards, the last such double (``-inf`` when none
    is, the largest finite double when all are); else the first (``+inf`` when none is, the
    smallest finite double when all are). An infinite bound is read as the reals read it,
    whatever the rounding: ``v <= +inf`` holds at every finite double, ``v <= -inf`` at none
    (``1.5 * v`` overflows to ``-inf`` for ``v`` below -1.2e308, where ``1.5 * v <= -inf``
    holds in doubles: no speed a robot is given)."""
    if estimate == math.inf:
        return DOUBLE_MAX if down else math.inf
    if estimate == -math.inf:
        return -math.inf if down else -DOUBLE_MAX
    e = estimate if estimate == estimate else 0.0
    e = min(max(e, -DOUBLE_MAX), DOUBLE_MAX)
    if down:
        k = _last_true(f, _key(e))
        return -math.inf if k is None else _double(k)
    k = _last_true(lambda x: not f(x), _key(e))
    if k is None:
        return -DOUBLE_MAX
    return math.inf if k == _KEY_MAX else _double(k + 1)


def _test(t: tuple[Any, ...], var: str, values: dict[str, Any]) -> Callable[[float], bool]:
    """The comparison ``t`` (a term, :func:`fretc.shield.runtime_values.term_value`) as a
    function of the value of ``var``, the other variables at ``values``."""
    given = dict(values)

    def holds(x: float) -> bool:
        given[var] = x
        return bool(term_value(t, given))
    return holds


def bounded_value(specs: list[tuple[str, str | None, Any]], truths: list[int],
                  metas: list[tuple[int, tuple[Any, ...]] | None], x: float,
                  inputs: dict[str, Any], fallback: float) -> tuple[float, str]:
    """The number of a bounded output (module docstring): ``specs`` its output atoms (a
    comparison with a constant, or ``(variable, "pred", term)``), ``truths`` their decided
    values, ``metas`` per atom None (a constant's) or a bound's ``(down, estimate term)``,
    ``x`` the proposal (NaN: none), ``inputs`` the tick's readable inputs, ``fallback`` the
    number to be near when no number gives the comparisons: then the number nearest it that
    gives the decided comparisons that can be met (those whose bounds are read, else those
    with constants alone). Returns ``(value, "")``, or the value and why it is the
    fallback's nearest (the decision's fault, ``VARIABLE: why``)."""
    lo, hi = -DOUBLE_MAX, DOUBLE_MAX
    unread = False
    for (_v, op, c), t, meta in zip(specs, truths, metas):
        if meta is None:
            lo, hi = _narrow(str(op), float(c), t, lo, hi)
    lo_c, hi_c = lo, hi  # (the comparisons with constants: one region, by the game's)
    for (var, _op, c), t, meta in zip(specs, truths, metas):
        if meta is None:
            continue
        down, estimate = meta
        try:
            b = float(term_value(estimate, inputs))
            f = _test(c, var, inputs)
        except (KeyError, ValueError):  # (an input it reads cannot be read)
            unread = True
            continue
        lo, hi = _narrow("<=" if down else ">=", threshold(f, bool(down), b), t, lo, hi)
    var = specs[0][0]
    if not unread and lo <= hi:
        target = x if x == x else fallback
        return min(max(target, lo), hi), ""
    if lo > hi:
        lo, hi = lo_c, hi_c
    value = min(max(fallback, lo), hi) if lo <= hi else fallback
    why = ("a bound of it reads an input that cannot be read" if unread else
           "no finite number gives its decided comparisons at this tick")
    return value, f"{var}: {why}; {value!r}, nearest the fallback's {fallback!r}"


def _narrow(op: str, c: float, t: int, lo: float, hi: float) -> tuple[float, float]:
    """``[lo, hi]`` narrowed by the truth ``t`` of ``x op c`` (``op`` in ``< <= > >=``)."""
    o = op if t else _NOT[op]
    if o == "<=":
        hi = min(hi, c)
    elif o == "<":
        hi = min(hi, math.nextafter(c, -math.inf))
    elif o == ">=":
        lo = max(lo, c)
    elif o == ">":
        lo = max(lo, math.nextafter(c, math.inf))
    return lo, hi


def scaled(names: tuple[str, ...] | list[str], decided: dict[str, Any],
           proposed: dict[str, Any]) -> tuple[dict[str, float], float] | None:
    """The speeds of the twist ``names`` scaled together (module docstring): each its
    proposal times the factor of the most restrictive correction in ``decided`` (that one
    exactly its decided value), and the factor; None when no speed was corrected, a proposal
    is no finite number, or a correction is no slowdown towards 0 of its proposal."""
    factor, limiting = 1.0, ""
    for v in names:
        p, c = _number(proposed.get(v)), _number(decided.get(v))
        if p is None or c is None:
            return None
        if c == p:
            continue
        if p == 0.0:
            return None
        r = c / p
        if not 0.0 <= r < 1.0:
            return None
        if r < factor:
            factor, limiting = r, v
    if not limiting:
        return None
    return {v: (float(decided[v]) if v == limiting else factor * float(proposed[v]))
            for v in names}, factor


def _number(x: Any) -> float | None:
    """``x`` as a finite float, None when it is no finite number (or a boolean)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    y = float(x)
    return y if math.isfinite(y) else None
