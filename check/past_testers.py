"""Past-time formulas inside future-time queries, exactly, by temporal testers.

A FRET ft formula holds past-time parts as *derived atoms* (IR ``past`` nodes: FRET's
``occurred``, ``persisted``, ``preBool``, and the since of a latched mode,
:mod:`fretc.fretish.fret_since`), which Spot, a future-time LTL tool, reads as free
propositions: a trace it finds may give such an atom a value its expansion does not have,
and the judge then rejects the trace (a test not generated, a witness not built).

Design notes: ARCHITECTURE.md, `check/past_testers.py`."""

from __future__ import annotations

from collections.abc import Sequence

from fretc.compiler import ir
from fretc.compiler.ir import Node, window

__all__ = ["with_testers", "MAX_WINDOW", "TESTER_PREFIX"]

#: the widest bounded ``O``/``H`` window written as a chain of testers (one per tick)
MAX_WINDOW = 16

#: the testers' propositions: this prefix and a number (renumbered past any atom of the
#: formulas that starts with it)
TESTER_PREFIX = "fretc_tester_"

_LOGIC = ("!", "&", "|", "->", "<->", "xor")


class _Unsupported(Exception):
    """A part of an expansion no tester writes (module docstring)."""


class _Testers:
    """The testers of one query: the memo of translated nodes and the axioms written."""

    def __init__(self, taken: set[str]):
        self.taken = taken
        self.memo: dict[Node, Node] = {}
        self.axioms: list[Node] = []
        self.count = 0

    def fresh(self) -> Node:
        """A proposition no formula of the query reads."""
        while True:
            self.count += 1
            name = f"{TESTER_PREFIX}{self.count}"
            if name not in self.taken:
                return ir.ap(name)

    def of(self, n: Node) -> Node:
        """``n`` (a pt formula) over testers: a formula of the present position."""
        if n not in self.memo:
            self.memo[n] = self._translate(n)
        return self.memo[n]

    def _translate(self, n: Node) -> Node:
        op = n.op
        if op in ("true", "false", "ap", "call") or (op == "cmp" and not ir.has_op(n, ("pre",))):
            return n
        if op in _LOGIC:
            return Node(op, tuple(self.of(a) for a in n.args), n.name, n.lo, n.hi)
        if op == "FTP":
            t = self.fresh()
            self.axioms.append(ir.and_(t, ir.X(ir.G(ir.not_(t)))))
            return t
        if op in ("Y", "Z"):
            return self._previous(self.of(n.args[0]), op == "Z")
        if op in ("S", "T"):
            a, b = (self.of(x) for x in n.args)
            if op == "T":
                return ir.not_(self._since(ir.not_(a), ir.not_(b)))
            return self._since(a, b)
        if op in ("O", "H"):
            return self._window(n)
        if op == "stream":  # (ir.stream: p when it held at the previous position, else q)
            p, q = (self.of(x) for x in n.args)
            t = self.fresh()
            now = ir.or_(ir.and_(t, p), ir.and_(ir.not_(t), q))
            step = ir.iff(ir.X(t), now)
            self.axioms.append(ir.and_(ir.not_(t), ir.G(step)))
            return now
        raise _Unsupported(op)

    def _previous(self, a: Node, weak: bool) -> Node:
        t = self.fresh()
        first = t if weak else ir.not_(t)
        self.axioms.append(ir.and_(first, ir.G(ir.iff(ir.X(t), a))))
        return t

    def _since(self, a: Node, b: Node) -> Node:
        t = self.fresh()
        step = ir.iff(ir.X(t), ir.or_(ir.X(b), ir.and_(ir.X(a), t)))
        self.axioms.append(ir.and_(ir.iff(t, b), ir.G(step)))
        return t

    def _window(self, n: Node) -> Node:
        a = self.of(n.args[0])
        once = n.op == "O"
        if n.hi is None:
            if once:
                return self._since(ir.TRUE, a)
            return ir.not_(self._since(ir.TRUE, ir.not_(a)))
        lo, hi = window(n)
        if hi - lo > MAX_WINDOW or hi > 4 * MAX_WINDOW:
            raise _Unsupported(f"a window of {hi - lo + 1} ticks")
        parts = []
        x = a
        for k in range(hi + 1):
            if k >= lo:
                parts.append(x)
            if k < hi:
                x = self._previous(x, not once)
        out = parts[0]
        for p in parts[1:]:
            out = ir.or_(out, p) if once else ir.and_(out, p)
        return out


def with_testers(formulas: Sequence[Node], last: Node | None = None
                 ) -> tuple[list[Node], list[Node]]:
    """``formulas`` (ft) with every derived past atom (``past`` node) its testers can write
    replaced by its expansion over them, and the testers' axioms (module docstring): the
    query ``formulas & axioms`` has a model exactly where ``formulas`` has one whose past
    atoms have their expansions' values, and the same models on the formulas' own
    atoms. ``formulas`` unchanged and no axiom when none holds a past atom.

    ``last``: the proposition true at a finite trace's last tick (FRET's ``LAST``, in the
    encoding of :mod:`fretc.check.witness`), after which FRET's evaluator reads every past
    atom false (the absorbing state, :func:`fretc.compiler.evaluate.ft_at`): each atom is
    then its expansion and "not after ``last``" (a tester of its own)."""
    pasts = [n for f in formulas for n in ir.walk(f) if n.op == "past"]
    if not pasts:
        return list(formulas), []
    taken = {ir.name_of(n) for f in formulas for n in ir.walk(f) if n.op == "ap"}
    testers = _Testers(taken)
    done: dict[Node, Node] = {}
    for p in dict.fromkeys(pasts):
        keep, memo = len(testers.axioms), dict(testers.memo)
        try:
            done[p] = testers.of(p.args[0])
        except _Unsupported:  # (the testers written for it alone are not kept)
            del testers.axioms[keep:]
            testers.memo = memo
    if not done:
        return list(formulas), []
    if last is not None:  # (after: true at every position after the last tick)
        after = testers.fresh()
        testers.axioms.append(ir.and_(ir.not_(after),
                                      ir.G(ir.iff(ir.X(after), ir.or_(after, last)))))
        done = {p: ir.and_(e, ir.not_(after)) for p, e in done.items()}
    return [_substitute(f, done, {}) for f in formulas], testers.axioms


def _substitute(n: Node, done: dict[Node, Node], memo: dict[Node, Node]) -> Node:
    """``n`` with each node of ``done`` replaced by its value (memoized by node)."""
    if n in done:
        return done[n]
    if not n.args or n.op in ("cmp", "call", "future", "past"):
        return n
    if n not in memo:
        memo[n] = ir.rebuild(n, tuple(_substitute(a, done, memo) for a in n.args))
    return memo[n]
