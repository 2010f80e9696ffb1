"""Satisfiability of future-time formulas on infinite words by z3, for bounds Spot cannot
reach (``fretc check`` with deadlines of hundreds of ticks).

Spot translates ``F[0,N] q`` into an automaton whose size grows with N (and refuses N > 254);
here no bound is unrolled into an automaton. A query (a conjunction of IR formulas, read on
infinite words as Spot reads them) gets two encodings, tried in turn within one budget:

Design notes: ARCHITECTURE.md, `check/smt.py`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any
from fretc.compiler import ir
from fretc.compiler.ir import Node

from fretc.check.budget import (BYTES_PER_NODE, NODES_PER_Z3_TERM, UNKNOWN, Z3_RLIMIT_PER_UNIT, Budget,
                     RunStopped)
from fretc.check.numeric_abstraction import simple_comparison
from fretc.check.safety_game import letter_name

__all__ = ["SmtSolver", "max_bound", "solve_capped"]

_TEMPORAL = ("X", "F", "G", "U", "V")


def max_bound(formulas: Sequence[Node]) -> int:
    """The largest tick bound ``hi`` of a bounded ``F``/``G`` in ``formulas`` (0 if none)."""
    out = 0
    for f in formulas:
        for n in ir.walk(f):
            if n.hi is not None and n.op in ("F", "G"):
                out = max(out, n.hi)
    return out


def _is_atom(n: Node) -> bool:
    return n.op in ("ap", "cmp", "call", "past", "future", "LAST")


def _z3():
    import z3  # lazy: z3 loads only when a query needs it

    return z3


class _Atoms:
    """z3 terms of the atoms at a position: functions of an Int (``prefix`` "") or, with
    ``prefix`` "@", one constant per position (an int)."""

    def __init__(self, z3, prefix: str):
        self.z3 = z3
        self.prefix = prefix
        self.funcs: dict[tuple, object] = {}

    def _fn(self, name: str, sort):
        z3 = self.z3
        key = (name, str(sort))
        if key not in self.funcs:
            if self.prefix == "@":  # one constant per position (no function to reason on)
                make = z3.Bool if sort == z3.BoolSort() else z3.Real
                self.funcs[key] = lambda t, make=make: make(f"{name}@{t}")
            else:
                self.funcs[key] = z3.Function(f"{self.prefix}{name}", z3.IntSort(), sort)
        return self.funcs[key]

    def at(self, atom: Node, t):
        """Truth of ``atom`` at position ``t`` (a z3 Int term)."""
        z3 = self.z3
        sc = simple_comparison(atom) if atom.op == "cmp" else None
        if sc is None:
            return self._fn("b:" + letter_name(atom), z3.BoolSort())(t)
        name, op, c = sc
        if isinstance(c, float):  # +-inf (1e999): a real is below inf, above -inf
            below = c > 0
            return z3.BoolVal({"<": below, "<=": below, ">": not below, ">=": not below,
                               "=": False, "!=": True}[op])
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
        self.atoms = _Atoms(z3, "@")
        self.memo: dict[Node, list] = {}
        self.counts: dict[Any, list] = {}  # a node, or (a node, a width)
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
            return [self.atoms.at(n, i) for i in range(K)]
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

    def _distance(self, p: Node, width: int) -> list:
        """``d[i]``: ticks from position ``i`` to the next position where ``p`` holds,
        saturated at ``width + 1`` (more than ``width``, or never). Each position relates
        to its successor only (difference constraints), so the size does not grow with
        ``width``; on the loop the saturation makes the solution unique."""
        key = (p, width)
        got = self.counts.get(key)
        if got is None:
            z3 = self.z3
            x = self.series(p)
            bits = (width + 1).bit_length()
            self.fresh += 1
            got = self.counts[key] = [z3.BitVec(f"_d{self.fresh}_{i}", bits)
                                      for i in range(self.K)]
            for i in range(self.K):
                nxt = got[self.step(i, 1)]
                self.constraints.append(got[i] == z3.If(
                    x[i], z3.BitVecVal(0, bits), z3.If(z3.UGE(nxt, width), z3.BitVecVal(
                        width + 1, bits), nxt + 1)))
        return got

    def _window(self, n: Node) -> list:
        """``F[lo,hi] p`` at ``i``: from ``lo`` steps after ``i``, the next ``p`` is at most
        ``hi - lo`` ticks away; ``G[lo,hi] p`` = ``!F[lo,hi] !p``."""
        z3 = self.z3
        assert n.hi is not None  # (bounded)
        lo, width = n.lo or 0, n.hi - (n.lo or 0)
        p = n.args[0] if n.op == "F" else ir.not_(n.args[0])
        d = self._distance(p, width)
        out = [z3.ULE(d[self.step(i, lo)], width) for i in range(self.K)]
        return out if n.op == "F" else [z3.Not(x) for x in out]


# --------------------------------------------------------------------------- the solver
class SmtSolver:
    """Answers ``fretc check``'s satisfiability queries with z3 (module docstring).

    ``budget``: each query's :class:`fretc.check.budget.Budget` (default the defaults): its work
    as z3's deterministic resource count (``rlimit``, :data:`fretc.check.budget.Z3_RLIMIT_PER_UNIT`
    per unit), shared by the attempts of the plan; its memory bounds the lasso encodings
    before they are built (:data:`fretc.check.budget.NODES_PER_Z3_TERM` per term) and, when the
    query runs in ``worker``, everything z3 allocates for it (:func:`solve_capped`).
    ``deadline``: the run's wall-clock limit (``time.monotonic()`` value): past it
    :meth:`sat` raises :class:`fretc.check.budget.RunStopped`. ``worker``: a
    :class:`fretc.check.solver.SpotWorker` whose process runs the queries (None, or one that does
    not fork: in this process, z3's memory not capped). :meth:`sat` returns
    ``(True, (prefix, cycle))`` (letters ``{atom name: bool}`` as
    :class:`fretc.check.solver.SpotWorker` gives them), ``(False, None)``, or :data:`UNKNOWN`;
    ``failures`` says for each unknown answer what was tried, ``spent`` counts them. Raises
    nothing for a formula it cannot encode (a past-time operator in a future formula): that
    answer is unknown too, with the reason.
    """

    def __init__(self, budget: Budget | None = None, deadline: float | None = None,
                 worker=None):
        self.budget = budget or Budget()
        self.deadline = deadline
        self.worker = worker
        self.failures: list[str] = []
        self.spent = 0
        #: a query of this solver ran past z3's memory cap (z3's state is unusable after)
        self.out_of_memory = False

    def sat(self, formulas: Sequence[Node]) -> Any:  # True, False or UNKNOWN
        """Is the conjunction of ``formulas`` satisfiable on infinite words?"""
        if self.worker is not None and self.worker.fork:
            status, value = self.worker.call(("smt", list(formulas)))
            if status == "ok":
                answer, failures, spent = value
                self.failures += failures
                self.spent += spent
                return answer
            self.spent += 1
            self.failures.append(f"z3's worker process ended without an answer (exit code "
                                 f"{value})" if status == "ended" else f"z3: {value}")
            return UNKNOWN
        z3 = _z3()
        bound = max_bound(formulas)
        size = sum(1 for f in formulas for _n in ir.walk(f))
        self._left = self.budget.work * Z3_RLIMIT_PER_UNIT
        self._count = _rlimit_count(z3, z3.Solver())
        tried, skipped = 0, 0
        try:
            shapes = [(1, 0), (2, 1), (2, 0), (4, 3), (4, 0)]
            big = [(K, loop) for K in sorted({bound + 2, 2 * bound + 3})
                   for loop in (0, K - 1, (K - 1) // 2)]
            # small lassos, short proofs by model-based instantiation then by E-matching
            # alone (each proves what the other misses on FRET's formulas), a lasso past the
            # largest bound, a longer proof, the other lassos, and the proof again; each
            # attempt a share of the resource count left (``cap``: at most that share of
            # the whole budget)
            plan: list[tuple[str, Any]] = ([("lasso", (x, 1.0)) for x in shapes] + [("proof", (0.15, True, 0.1))]
                    + [("proof", (0.1, False, 0.1))] + [("lasso", (big[0], 0.5))]
                    + [("proof", (0.4, True, None))]
                    + [("lasso", (x, 0.5)) for x in big[1:]] + [("proof", (1.0, True, None))])
            for kind, arg in plan:
                if self._left <= 0:
                    break
                if kind == "lasso":
                    K = arg[0][0]
                    if K * size * NODES_PER_Z3_TERM > self.budget.memory:
                        skipped = max(skipped, K)
                        continue
                    got = self._lasso(z3, formulas, arg[0], arg[1])
                    tried = max(tried, K)
                else:
                    got = self._proof(z3, formulas, *arg)
                if got is not None:
                    return got
        except (ValueError, z3.Z3Exception) as exc:
            if _memory_out(str(exc)):  # building terms or checking (:meth:`_check`)
                self.out_of_memory = True
                self.spent += 1
                mb = self.budget.memory * BYTES_PER_NODE / 2 ** 20
                self.failures.append("z3: " + self.budget.memory_spent(
                    f"z3 allocated more than its {mb:.0f} MB"))
                return UNKNOWN
            self.failures.append(f"z3 could not take the query: {exc}")
            return UNKNOWN
        self.spent += 1
        self.failures.append(
            f"z3: no lasso model of up to {tried} positions and no proof of "
            f"unsatisfiability within the {self.budget.work_spent()}"
            + (f"; lassos of {skipped} positions skipped, past the memory budget of "
               f"{self.budget.memory} BDD nodes" if skipped else ""))
        return UNKNOWN

    def _check(self, z3, s, share: float, cap: float | None):
        """``s.check()`` with ``share`` of the resource count left (at most ``cap`` of the
        whole budget), the run's deadline as z3's timeout; the count spent is taken off."""
        import time

        whole = self.budget.work * Z3_RLIMIT_PER_UNIT
        limit = max(1, int(min(self._left * share, whole * cap if cap else self._left)))
        s.set("rlimit", limit)
        if self.deadline is not None:
            s.set("timeout", max(1, int((self.deadline - time.monotonic()) * 1000)))
        ans = s.check()
        if ans == z3.unknown and _memory_out(s.reason_unknown()):
            raise z3.Z3Exception("out of memory")  # as z3 raises it while building terms
        count = _rlimit_count(z3, s)  # the context's: cumulative over its solvers
        self._left -= max(1, count - self._count)
        self._count = count
        if ans == z3.unknown and self.deadline is not None \
                and time.monotonic() >= self.deadline:
            raise RunStopped("the run's wall-clock limit (--timeout) passed")
        return ans

    def _lasso(self, z3, formulas, shape, share: float):
        K, loop = shape
        enc = _Lasso(z3, K, loop)
        s = z3.Solver()
        for f in formulas:
            s.add(enc.series(f)[0])
        s.add(*enc.constraints)
        if self._check(z3, s, share, None) != z3.sat:
            return None
        return (True, _word(z3, s.model(), enc, formulas))

    def _proof(self, z3, formulas, share: float, mbqi: bool, cap: float | None):
        enc = _FirstOrder(z3)
        s = z3.Solver()
        s.set("mbqi", mbqi)
        for f in formulas:
            s.add(enc.at(f, z3.IntVal(0)))
        s.add(*enc.axioms)
        return (False, None) if self._check(z3, s, share, cap) == z3.unsat else None


def _memory_out(reason: str) -> bool:
    """Is z3's reason (of an unknown answer or an exception) its memory cap?"""
    return "out of memory" in reason or "max. memory" in reason


def solve_capped(formulas: Sequence[Node], budget: Budget) -> tuple:
    """Answer one query in this process with z3's memory capped at ``budget.memory`` BDD
    nodes of :data:`fretc.check.budget.BYTES_PER_NODE` bytes, counted from what z3 holds before
    the query (z3's ``memory_max_size`` is process-wide; z3 counts the bytes it asks for, so
    the cap falls at the same point on every machine). Returns ``(answer, failures, spent,
    out_of_memory)`` (:class:`SmtSolver`'s). Meant for a worker process
    (:mod:`fretc.check.solver`): past the cap z3's state is unusable, and the caller ends the
    process when ``out_of_memory``."""
    z3 = _z3()
    z3.main_ctx()  # made before the count: its tables are not the query's
    held = z3.z3core.Z3_get_estimated_alloc_size()
    cap = held + budget.memory * BYTES_PER_NODE
    z3.set_param("memory_max_size", max(1, -(-cap // 2 ** 20)))
    solver = SmtSolver(budget)
    try:
        answer = solver.sat(formulas)
    finally:
        z3.set_param("memory_max_size", 0)
    return answer, solver.failures, solver.spent, solver.out_of_memory


def _rlimit_count(z3, s) -> int:
    """z3's resource count so far (cumulative in the context), read off ``s``'s statistics
    after a check (an unchecked solver is checked first: an empty check costs nothing)."""
    stats = s.statistics()
    if "rlimit count" not in stats.keys():
        s.check()
        stats = s.statistics()
    return int(stats.get_key_value("rlimit count"))


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
            letter[letter_name(a)] = z3.is_true(v)
        letters.append(letter)
    return letters[:enc.l], letters[enc.l:]

