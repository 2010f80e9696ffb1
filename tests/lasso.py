"""Exact evaluation of future-time IR formulas on lasso words ``u v^omega`` (for ft_inf
comparisons without Spot's equivalence check, which is slow for large bounded operators).

Positions ``0 .. n-1`` hold ``u`` then ``v`` (n = len(u) + len(v)); the successor of the
last position is ``len(u)``. ``X`` follows the successor; ``F[l,h]``/``G[l,h]`` look at the
successors l..h steps ahead; ``U`` is a least and ``V`` a greatest fixpoint over the loop.
``LAST`` is false (infinite word). Derived atoms (``past``/``future`` nodes) and atoms are
read from the states: a derived atom under the key of its printed name."""

from __future__ import annotations

from fretc.compiler.evaluate import _Evaluator


class _Lasso(_Evaluator):
    def __init__(self, u, v):
        super().__init__(list(u) + list(v))
        self.loop = len(u)

    def succ(self, i: int) -> int:
        return i + 1 if i + 1 < self.L else self.loop

    def _compute(self, n):
        op = n.op
        L = self.L
        if op == "LAST":
            return [False] * (L + 1)
        if op in ("past", "future") and n.name is None:  # a comparison over preReal
            return self.series(n.args[0])
        if op in ("past", "future"):
            return [bool(self.trace[i].get(n.name, False)) for i in range(L)] + [False]
        if op == "X":
            x = self.series(n.args[0])
            return [x[self.succ(i)] for i in range(L)] + [False]
        if op in ("F", "G") and n.hi is not None:
            x = self.series(n.args[0])
            out = []
            for i in range(L):
                j = i
                for _ in range(n.lo):
                    j = self.succ(j)
                vals = []
                for _ in range(n.hi - n.lo + 1):
                    vals.append(x[j])
                    j = self.succ(j)
                out.append(any(vals) if op == "F" else all(vals))
            return out + [False]
        if op in ("F", "G", "U", "V"):
            if op in ("F", "G"):
                a = self.series(n.args[0])
                x = [True] * L if op == "F" else [False] * L
                y = a
                op = "U" if op == "F" else "V"
            else:
                x, y = self.series(n.args[0]), self.series(n.args[1])
            out = [op == "V"] * L
            for _ in range(2):  # two backward sweeps reach the fixpoint on a lasso
                for i in range(L - 1, -1, -1):
                    nxt = out[self.succ(i)]
                    out[i] = (y[i] or (x[i] and nxt)) if op == "U" else \
                        (y[i] and (x[i] or nxt))
            return out + [False]
        if op in ("Y", "Z", "O", "H", "S", "T"):
            raise ValueError("past operator in a future formula")
        return super()._compute(n)


def lasso_at(node, u, v) -> bool:
    """Truth of the future-time formula ``node`` at position 0 of ``u v^omega``."""
    return bool(_Lasso(u, v).series(node)[0])
