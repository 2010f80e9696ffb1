"""Reference evaluator of IR formulas on finite traces - the oracle the monitors and the
semantics are tested against. Written for clarity, not speed.

Trace model (FRET's own NuSMV tests; ``../shared/fretish/README.md`` section 6): a finite trace
``s0 .. s(L-1)`` (a sequence of mappings from variable name to bool or number) is followed by
one absorbing state, repeated forever, in which every variable is false (numbers are 0) and
``LAST`` is false. ``LAST`` holds exactly at ``s(L-1)``. Future operators read that infinite
word; past operators read the finite prefix (``Y`` is false and ``Z`` true at position 0;
bounded ``O[l,h]``/``H[l,h]`` look at positions ``i-h .. i-l`` that are >= 0).

Derived atoms: a ``past`` node inside a future formula is its past-time expansion evaluated
at each position (false in the absorbing state); a ``future`` node inside a past formula is
its future-time expansion evaluated at each position.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from fretc.compiler.ir import Node, name_of, window
from fretc.compiler.printers import to_smv

Trace = Sequence[Mapping[str, Any]]

ADD_SUB_MUL = {"+": operator.add, "-": operator.sub, "*": operator.mul}
_CMP = {"=": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
        ">": operator.gt, ">=": operator.ge}


# same cases as monitors.arrays.arith (kept: scalars here, numpy columns with NaN masks
# there)
def _arith(op: str, a: float, b: float) -> float:
    try:
        if op in ADD_SUB_MUL:
            return ADD_SUB_MUL[op](a, b)
        if op == "/":
            return a / b
        if op == "mod":
            return math.fmod(a, b)
        if op == "^":
            if (isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1
                    and (abs(a).bit_length() - 1) * b >= 1024):
                return math.nan  # beyond a float (the generated _pow's rule, no bigint)
            return a ** b
    except (ZeroDivisionError, OverflowError, ValueError):
        return math.nan
    raise ValueError(f"unknown arithmetic operator {op}")


_FUNCS: dict[str, Callable[..., Any]] = {
    "absReal": abs, "absInt": abs, "minReal": min, "minInt": min, "maxReal": max,
    "maxInt": max,
}

#: the functions computed from their arguments; any other function application is
#: uninterpreted and read from the trace under its printed name (its own column)
INTERPRETED_FUNCTIONS = frozenset(_FUNCS)


class _Evaluator:
    """Series of truth values of every sub-formula over positions ``0..L`` (``L`` = the
    absorbing state)."""

    def __init__(self, trace: Trace):
        self.trace = trace
        self.L = len(trace)
        self.memo: dict[Node, list[Any]] = {}

    def value(self, name: str, i: int, numeric: bool):
        if i >= self.L:
            return 0 if numeric else False
        v = self.trace[i].get(name, 0 if numeric else False)
        return v if numeric else bool(v)

    def series(self, n: Node) -> list[Any]:
        got = self.memo.get(n)
        if got is None:
            got = self._compute(n)
            self.memo[n] = got
        return got

    def _compute(self, n: Node) -> list[Any]:
        op = n.op
        if op in _FUTURE_OPS:
            return self._future(n)
        if op in _PAST_OPS:
            return self._past(n)
        got = self._leaf(n)
        if got is None:
            got = self._pointwise(n)
        if got is None:
            raise ValueError(f"cannot evaluate IR node {op!r}")
        return got

    def _leaf(self, n: Node) -> list[Any] | None:
        """Constants, markers and reads of the trace (None for other nodes)."""
        L, op = self.L, n.op
        rng = range(L + 1)
        if op == "true":
            return [True] * (L + 1)
        if op == "false":
            return [False] * (L + 1)
        if op == "LAST":
            return [i == L - 1 for i in rng]
        if op == "FTP":
            return [i == 0 for i in rng]
        if op == "ap":
            return [self.value(name_of(n), i, False) for i in rng]
        if op == "var":
            return [self.value(name_of(n), i, True) for i in rng]
        if op == "num":
            v = float(name_of(n)) if any(c in name_of(n) for c in ".eE") else int(name_of(n))
            return [v] * (L + 1)
        if op == "call":
            key = to_smv(n)
            return [self.value(key, i, False) for i in rng]
        return None

    def _pointwise(self, n: Node) -> list[Any] | None:
        """Operators whose value at a position depends on that position only (and
        ``pre``, on the previous one); None for other nodes."""
        L, op, a = self.L, n.op, n.args
        rng = range(L + 1)
        if op == "cmp":
            x, y, f = self.series(a[0]), self.series(a[1]), _CMP[name_of(n)]
            return [bool(f(x[i], y[i])) for i in rng]
        if op == "arith":
            x, y = self.series(a[0]), self.series(a[1])
            return [_arith(name_of(n), x[i], y[i]) for i in rng]
        if op == "neg":
            return [-v for v in self.series(a[0])]
        if op == "fn":
            args = [self.series(x) for x in a]
            fn = _FUNCS.get(name_of(n))
            if fn is None:  # uninterpreted: read the trace under its printed name
                key = to_smv(n)
                return [self.value(key, i, True) for i in rng]
            return [fn(*(s[i] for s in args)) for i in rng]
        if op == "ite":
            c, x, y = (self.series(s) for s in a)
            return [x[i] if c[i] else y[i] for i in rng]
        if op == "pre":
            init, x = self.series(a[0]), self.series(a[1])
            return [init[i] if i == 0 else x[i - 1] for i in rng]
        if op in ("past", "future"):
            s = self.series(a[0])
            return s[:L] + [False]
        if op == "!":
            return [not v for v in self.series(a[0])]
        if op in _BOOL_BINARY:
            x, y = self.series(a[0]), self.series(a[1])
            f = _BOOL_BINARY[op]
            return [f(p, q) for p, q in zip(x, y)]
        return None

    def _future(self, n: Node) -> list[Any]:
        """X, F, G, U, V: backward over positions, absorbing state first."""
        L, op, a = self.L, n.op, n.args
        rng = range(L + 1)
        if op == "X":
            x = self.series(a[0])
            return [x[min(i + 1, L)] for i in rng]
        if op in ("F", "G"):
            x = self.series(a[0])
            agg = any if op == "F" else all
            if n.hi is None:
                out = [False] * (L + 1)
                out[L] = x[L]
                for i in range(L - 1, -1, -1):
                    out[i] = (x[i] or out[i + 1]) if op == "F" else (x[i] and out[i + 1])
                return out
            lo, hi = window(n)
            return [agg(x[min(j, L)] for j in range(i + lo, i + hi + 1)) for i in rng]
        x, y = self.series(a[0]), self.series(a[1])
        out = [False] * (L + 1)
        out[L] = y[L]
        for i in range(L - 1, -1, -1):
            if op == "U":
                out[i] = y[i] or (x[i] and out[i + 1])
            else:
                out[i] = y[i] and (x[i] or out[i + 1])
        return out

    def _past(self, n: Node) -> list[Any]:
        """Y, Z, O, H, S, T, stream: forward over positions 0..L-1 (the absorbing state reads as
        false)."""
        L, op, a = self.L, n.op, n.args
        if op in ("Y", "Z"):
            x = self.series(a[0])
            first = op == "Z"
            return [first if i == 0 else x[i - 1] for i in range(L)] + [False]
        if op in ("O", "H"):
            x = self.series(a[0])
            if n.hi is None:
                out = []
                acc = op == "H"
                for i in range(L):
                    acc = (acc or x[i]) if op == "O" else (acc and x[i])
                    out.append(acc)
                return out + [False]
            agg = any if op == "O" else all
            lo, hi = window(n)
            return [agg(x[j] for j in range(max(0, i - hi), i - lo + 1))
                    for i in range(L)] + [False]
        x, y = self.series(a[0]), self.series(a[1])
        out = []
        prev = op == "T"
        for i in range(L):
            if op == "stream":  # (ir.stream: x when it held at i-1, else y)
                prev = x[i] if prev else y[i]
            elif op == "S":
                prev = y[i] or (x[i] and prev)
            else:
                prev = y[i] and (x[i] or prev)
            out.append(prev)
        return out + [False]


_FUTURE_OPS = frozenset(("X", "F", "G", "U", "V"))
_PAST_OPS = frozenset(("Y", "Z", "O", "H", "S", "T", "stream"))
_BOOL_BINARY = {"&": lambda p, q: p and q, "|": lambda p, q: p or q,
                "xor": lambda p, q: p != q, "->": lambda p, q: (not p) or q,
                "<->": lambda p, q: p == q}


def ft_at(node: Node, trace: Trace, pos: int = 0) -> bool:
    """Truth of a future-time formula at ``pos`` (default 0) of ``trace`` + absorbing state."""
    return bool(_Evaluator(trace).series(node)[pos])


def pt_at(node: Node, trace: Trace, pos: int = -1) -> bool:
    """Truth of a past-time formula at ``pos`` (default the last position). An empty trace
    has no last position: raises ``ValueError``."""
    if not trace:
        raise ValueError("a past-time formula needs a non-empty trace")
    ev = _Evaluator(trace)
    return bool(ev.series(node)[pos if pos >= 0 else len(trace) + pos])


def series(node: Node, trace: Trace) -> list[Any]:
    """Values of ``node`` at positions ``0..L-1``."""
    return _Evaluator(trace).series(node)[: len(trace)]
