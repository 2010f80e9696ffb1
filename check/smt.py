"""Satisfiability of future-time formulas on infinite words by z3, for bounds Spot cannot
reach (``fretc check`` with deadlines of hundreds of ticks).

Spot translates ``F[0,N] q`` into an automaton whose size grows with N (and refuses N > 254);
here no bound is unrolled into an automaton. A query (a conjunction of IR formulas, read on
infinite words as Spot reads them) gets two encodings, tried in turn within one budget:

1. **Lasso models** (bounded model checking with a loop, Biere, Cimatti, Clarke, Zhu, TACAS
   1999): positions ``0 .. K-1`` whose successor of ``K-1`` is ``l``. Each atom is a z3
   variable per position; ``U`` (and ``F``, ``G``, ``V`` through it) is computed on the lasso
   by two backward passes over the loop; a bounded ``F[lo,hi]``/``G[lo,hi]`` counts its
   operand in the window by prefix sums (z3 ``Int``), so its size does not depend on the
   bound. A model found is an ultimately periodic word meeting every formula: **sat** with
   that word. A shape without model says nothing (a longer lasso may have one).
2. **A first-order proof** (the translation of LTL into first-order logic over the naturals,
   Kamp 1968; the SMT encodings of MLTL by Li, Rozier et al. do the same for finite
   traces): each temporal sub-formula is a z3 function ``Int -> Bool`` defined by its
   meaning at every position ``t >= 0`` (``F[lo,hi] p``: some ``j`` in ``[t+lo, t+hi]`` has
   ``p``, and the first such ``j``; ``a U b``: the first ``b`` at or after ``t`` with ``a``
   before it; ``G``, ``V`` their duals). Naming the *first* occurrence states the
   well-ordering of the naturals that first-order logic does not prove by itself. z3
   answering **unsat** means no infinite word (none at all, lasso or not) meets the formulas.

When neither settles the query within the budget the answer is :data:`UNKNOWN` and
:attr:`SmtSolver.failures` says what was tried.

Atoms mean what they mean to Spot through :mod:`check.numeric_abstraction`: a boolean
variable is a z3 ``Bool`` per position; a comparison of one variable with a constant
(``s <= 0.5``) is that comparison on a z3 ``Real`` per position and variable (exact, where the
abstraction's region invariant says the same); every other atom (``x + y > 2``, a boolean
function, a past-time function, ``LAST``) is an independent proposition per position.
``FTP`` is position 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from compiler import ir
from compiler.ir import Node
from compiler.printers import mangle, to_smv

from .numeric_abstraction import simple_comparison
from .solver import UNKNOWN

__all__ = ["SmtSolver", "max_bound", "atom_name"]

_TEMPORAL = ("X", "F", "G", "U", "V")


def max_bound(formulas: Sequence[Node]) -> int:
    """The largest tick bound ``hi`` of a bounded ``F``/``G`` in ``formulas`` (0 if none)."""
    out = 0
    for f in formulas:
        for n in ir.walk(f):
            if n.hi is not None and n.op in ("F", "G"):
                out = max(out, n.hi)
    return out


def atom_name(atom: Node) -> str:
    """The atom's name in a word's letters, as Spot's words name it (:mod:`check.solver`):
    the mangled name of a boolean variable, the FRET/SMV text of any other atom."""
    return mangle(atom.name) if atom.op == "ap" else to_smv(atom)


def _is_atom(n: Node) -> bool:
    return n.op in ("ap", "cmp", "call", "past", "future", "LAST")


def _z3():
    import z3  # lazy: z3 loads only when a query needs it

    return z3


class _Atoms:
    """z3 terms of the atoms at a position (shared by both encodings of one query)."""

    def __init__(self, z3, prefix: str):
        self.z3 = z3
        self.prefix = prefix
        self.funcs: dict[tuple, object] = {}

    def _fn(self, name: str, sort):
        z3 = self.z3
        key = (name, str(sort))
        if key not in self.funcs:
            self.funcs[key] = z3.Function(f"{self.prefix}{name}", z3.IntSort(), sort)
        return self.funcs[key]

    def at(self, atom: Node, t):
        """Truth of ``atom`` at position ``t`` (a z3 Int term)."""
        z3 = self.z3
        sc = simple_comparison(atom) if atom.op == "cmp" else None
        if sc is None:
            return self._fn("b:" + atom_name(atom), z3.BoolSort())(t)
        name, op, c = sc
        v = self._fn("r:" + name, z3.RealSort())(t)
        k = z3.RealVal(f"{c.numerator}/{c.denominator}")
        return {"<": v < k, "<=": v <= k, ">": v > k, ">=": v >= k, "=": v == k,
                "!=": v != k}[op]


# --------------------------------------------------------------------------- proofs
class _FirstOrder:
    """The first-order encoding (module docstring, item 2): :meth:`at` gives the truth of a
    formula at an Int term; the definitions of temporal sub-formulas collect in ``axioms``."""

    def __init__(self, z3):
        self.z3 = z3
        self.atoms = _Atoms(z3, "")
        self.defs: dict[Node, object] = {}
        self.axioms: list = []

    def at(self, n: Node, t):
        """Truth of ``n`` at position ``t`` (z3 Int term)."""
        z3 = self.z3
        op = n.op
        if op == "true":
            return z3.BoolVal(True)
        if op == "false":
            return z3.BoolVal(False)
        if op == "FTP":
            return t == 0
        if _is_atom(n):
            return self.atoms.at(n, t)
        if op == "!":
            return z3.Not(self.at(n.args[0], t))
        if op in ("&", "|", "->", "<->", "xor"):
            a, b = self.at(n.args[0], t), self.at(n.args[1], t)
            return {"&": lambda: z3.And(a, b), "|": lambda: z3.Or(a, b),
                    "->": lambda: z3.Implies(a, b), "<->": lambda: a == b,
                    "xor": lambda: z3.Xor(a, b)}[op]()
        if op == "X":  # a chain of X as one shift (witness lengths nest X a thousand deep)
            depth = 0
            while n.op == "X":
                n, depth = n.args[0], depth + 1
            return self.at(n, t + depth)
        if op in ("F", "U", "G", "V"):
            return self._defined(n)(t)
        raise ValueError(f"no z3 encoding of IR node {op!r} in a future formula")

    def _defined(self, n: Node):
        z3 = self.z3
        f = self.defs.get(n)
        if f is not None:
            return f
        k = len(self.defs)
        f = self.defs[n] = z3.Function(f"_d{k}", z3.IntSort(), z3.BoolSort())
        s, j, i = z3.Int(f"_s{k}"), z3.Int(f"_j{k}"), z3.Int(f"_i{k}")
        if n.op == "F":
            lo = n.lo or 0

            def window(x):
                return (x >= s + lo) if n.hi is None else z3.And(x >= s + lo, x <= s + n.hi)

            p = n.args[0]
            body = z3.Exists([j], z3.And(window(j), self.at(p, j), z3.ForAll(
                [i], z3.Implies(z3.And(window(i), i < j), z3.Not(self.at(p, i))))))
        elif n.op == "G":
            lo = n.lo or 0
            window = (j >= s + lo) if n.hi is None else z3.And(j >= s + lo, j <= s + n.hi)
            body = z3.ForAll([j], z3.Implies(window, self.at(n.args[0], j)))
        elif n.op == "V":
            a, b = n.args
            body = z3.ForAll([j], z3.Implies(j >= s, z3.Or(self.at(b, j), z3.Exists(
                [i], z3.And(i >= s, i < j, self.at(a, i))))))
        else:
            a, b = n.args
            body = z3.Exists([j], z3.And(j >= s, self.at(b, j), z3.ForAll(
                [i], z3.Implies(z3.And(i >= s, i < j),
                                z3.And(self.at(a, i), z3.Not(self.at(b, i)))))))
        self.axioms.append(z3.ForAll([s], z3.Implies(s >= 0, f(s) == body),
                                     patterns=[f(s)]))
        return f


# --------------------------------------------------------------------------- lassos
class _Lasso:
    """The lasso encoding (module docstring, item 1) on ``K`` positions looping to ``l``:
    :meth:`series` gives a formula's truth per position; ``constraints`` the definitions."""

    def __init__(self, z3, K: int, loop: int):
        self.z3, self.K, self.l = z3, K, loop
        self.atoms = _Atoms(z3, "")
        self.memo: dict[Node, list] = {}
        self.counts: dict[Node, list] = {}
        self.constraints: list = []
        self.fresh = 0

    def step(self, i: int, d: int) -> int:
        """The position ``d`` steps after ``i``."""
        v = i + d
        return v if v < self.K else self.l + (v - self.l) % (self.K - self.l)

    def _vars(self, sort: str) -> list:
        z3 = self.z3
        self.fresh += 1
        make = z3.Bool if sort == "bool" else z3.Int
        return [make(f"_{sort}{self.fresh}_{i}") for i in range(self.K)]

    def series(self, n: Node) -> list:
        """Truth of ``n`` at positions ``0 .. K-1`` (z3 Bool terms)."""
        got = self.memo.get(n)
        if got is None:
            got = self.memo[n] = self._compute(n)
        return got

    def _compute(self, n: Node) -> list:
        z3, K = self.z3, self.K
        op = n.op
        if op in ("true", "false"):
            return [z3.BoolVal(op == "true")] * K
        if op == "FTP":
            return [z3.BoolVal(i == 0) for i in range(K)]
        if _is_atom(n):
            return [self.atoms.at(n, z3.IntVal(i)) for i in range(K)]
        if op == "!":
            return [z3.Not(x) for x in self.series(n.args[0])]
        if op in ("&", "|", "->", "<->", "xor"):
            fn = {"&": z3.And, "|": z3.Or, "->": z3.Implies, "<->": lambda a, b: a == b,
                  "xor": z3.Xor}[op]
            return [fn(a, b) for a, b in zip(self.series(n.args[0]), self.series(n.args[1]))]
        if op == "X":  # a chain of X as one shift (no recursion per X)
            depth = 0
            while n.op == "X":
                n, depth = n.args[0], depth + 1
            x = self.series(n)
            return [x[self.step(i, depth)] for i in range(K)]
        if op in ("F", "G") and n.hi is not None:
            return self._window(n)
        if op == "F":
            return self._until([z3.BoolVal(True)] * K, self.series(n.args[0]))
        if op == "G":
            return [z3.Not(x) for x in self._until(
                [z3.BoolVal(True)] * K, [z3.Not(y) for y in self.series(n.args[0])])]
        if op == "U":
            return self._until(self.series(n.args[0]), self.series(n.args[1]))
        if op == "V":
            a = [z3.Not(x) for x in self.series(n.args[0])]
            b = [z3.Not(x) for x in self.series(n.args[1])]
            return [z3.Not(x) for x in self._until(a, b)]
        raise ValueError(f"no z3 encoding of IR node {op!r} in a future formula")

    def _until(self, a: list, b: list) -> list:
        """``a U b`` per position: the least fixpoint, by a first pass over the loop that
        ends false and a second that ends in the first."""
        z3, K, loop = self.z3, self.K, self.l
        first, out = self._vars("bool"), self._vars("bool")
        c = self.constraints
        for i in range(loop, K):
            nxt = first[i + 1] if i + 1 < K else z3.BoolVal(False)
            c.append(first[i] == z3.Or(b[i], z3.And(a[i], nxt)))
        for i in range(K):
            nxt = out[i + 1] if i + 1 < K else first[loop]
            c.append(out[i] == z3.Or(b[i], z3.And(a[i], nxt)))
        return out

    def _count(self, p: Node) -> list:
        """Prefix sums: ``c[i]`` the number of positions ``0 .. i`` where ``p`` holds."""
        got = self.counts.get(p)
        if got is None:
            z3 = self.z3
            x = self.series(p)
            got = self.counts[p] = self._vars("int")
            for i in range(self.K):
                prev = got[i - 1] if i else z3.IntVal(0)
                self.constraints.append(got[i] == prev + z3.If(x[i], 1, 0))
        return got

    def ranges(self, i: int, lo: int, hi: int) -> list[tuple[int, int]]:
        """The positions ``lo .. hi`` steps after ``i`` as at most three ranges ``(a, b)``."""
        K, loop = self.K, self.l
        period = K - loop
        A, B = i + lo, i + hi
        out = []
        if A <= K - 1:
            out.append((A, min(B, K - 1)))
        start = max(A, K)
        if B >= start:
            length = B - start + 1
            if length >= period:
                return out + [(loop, K - 1)]
            s0 = loop + (start - loop) % period
            end = s0 + length - 1
            if end <= K - 1:
                out.append((s0, end))
            else:
                out += [(s0, K - 1), (loop, loop + end - K)]
        return out

    def _window(self, n: Node) -> list:
        z3 = self.z3
        c = self._count(n.args[0])

        def count(a: int, b: int):
            return c[b] - (c[a - 1] if a else 0)

        out = []
        for i in range(self.K):
            parts = self.ranges(i, n.lo or 0, n.hi)
            if n.op == "F":
                out.append(z3.Or(*[count(a, b) > 0 for a, b in parts]))
            else:
                out.append(z3.And(*[count(a, b) == b - a + 1 for a, b in parts]))
        return out


# --------------------------------------------------------------------------- the solver
class SmtSolver:
    """Answers ``fretc check``'s satisfiability queries with z3 (module docstring).

    ``timeout``: seconds of budget per query (None: 600). :meth:`sat` returns ``(True,
    (prefix, cycle))`` (letters ``{atom name: bool}`` as :class:`check.solver.SpotWorker`
    gives them), ``(False, None)``, or :data:`UNKNOWN`; ``failures`` says for each unknown
    answer what was tried. Raises nothing for a formula it cannot encode (a past-time
    operator in a future formula): that answer is unknown too, with the reason.
    """

    def __init__(self, timeout: float | None = None):
        self.timeout = 600.0 if timeout is None else float(timeout)
        self.failures: list[str] = []
        self.timeouts = 0

    def sat(self, formulas: Sequence[Node]):
        """Is the conjunction of ``formulas`` satisfiable on infinite words?"""
        import time

        z3 = _z3()
        deadline = time.monotonic() + self.timeout
        bound = max_bound(formulas)
        try:
            shapes = [(1, 0), (2, 1), (2, 0), (4, 3), (4, 0)]
            for shape in shapes:
                got = self._lasso(z3, formulas, shape, deadline)
                if got is not None:
                    return got
            # E-matching alone, then model-based instantiation: each proves what the other
            # misses on FRET's formulas (measured in bench/bench_check.py)
            for share, mbqi in ((0.2, False), (0.6, True)):
                proof = self._proof(z3, formulas, deadline, share, mbqi)
                if proof is not None:
                    return proof
            tried = max(shapes)[0]
            for K in sorted({bound + 2, 2 * bound + 3, 3 * bound + 4}):
                for loop in (K - 1, 0, (K - 1) // 2):
                    if time.monotonic() > deadline:
                        break
                    got = self._lasso(z3, formulas, (K, loop), deadline)
                    tried = max(tried, K)
                    if got is not None:
                        return got
            proof = self._proof(z3, formulas, deadline, 1.0, True)
            if proof is not None:
                return proof
        except (ValueError, z3.Z3Exception) as exc:
            self.failures.append(f"z3 could not take the query: {exc}")
            return UNKNOWN
        self.timeouts += 1
        self.failures.append(
            f"z3: no lasso model of up to {tried} positions and no proof of "
            f"unsatisfiability within {self.timeout:g} s")
        return UNKNOWN

    def _left(self, deadline: float, share: float = 1.0) -> int:
        import time

        return max(1, int((deadline - time.monotonic()) * share * 1000))

    def _lasso(self, z3, formulas, shape, deadline):
        K, loop = shape
        enc = _Lasso(z3, K, loop)
        s = z3.SolverFor("QF_LIRA")
        s.set("timeout", self._left(deadline))
        for f in formulas:
            s.add(enc.series(f)[0])
        s.add(*enc.constraints)
        if s.check() != z3.sat:
            return None
        return (True, _word(z3, s.model(), enc, formulas))

    def _proof(self, z3, formulas, deadline, share: float, mbqi: bool):
        enc = _FirstOrder(z3)
        s = z3.Solver()
        s.set("timeout", self._left(deadline, share))
        s.set("mbqi", mbqi)
        for f in formulas:
            s.add(enc.at(f, z3.IntVal(0)))
        s.add(*enc.axioms)
        return (False, None) if s.check() == z3.unsat else None


def _word(z3, model, enc: _Lasso, formulas) -> tuple[list, list]:
    """The lasso of a model as letters ``{atom name: bool}``: prefix, then cycle."""
    atoms = []
    for f in formulas:
        for n in ir.walk(f):
            if _is_atom(n) and n not in atoms:
                atoms.append(n)
    letters = []
    for i in range(enc.K):
        letter = {}
        for a in atoms:
            v = model.eval(enc.series(a)[i], model_completion=True)
            letter[atom_name(a)] = z3.is_true(v)
        letters.append(letter)
    return letters[:enc.l], letters[enc.l:]

