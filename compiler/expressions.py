"""FRETish expressions to the formula IR, for one formula kind (ft or pt).

Temporal functions of the formula's own direction are expanded with FRET's definitions
(``../shared/fretish/README.md`` section 6b: past functions in pt, future ones in ft and
ft_inf); functions of the other direction become derived atoms (IR ``past``/``future``
nodes named by FRET's printed call). :mod:`fretc.compiler.semantics` uses :class:`Expander` for
the response, condition, stop and scope expressions of a requirement.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

from fretc.fretish import ast as A
from fretc.fretish.fret_since import SINCE, stream_name
from fretc.common.errors import FretishError
from fretc.fretish.limits import MAX_DURATION_TICKS, duration_too_long

from fretc.compiler import ir
from fretc.compiler.ir import FALSE, FTP, TRUE, F, G, H, Node, O, S, U, X, Y, and_, implies, name_of, not_, or_
from fretc.compiler.printers import expr_text

__all__ = ["Expander", "SemanticsError", "mentions_time"]


class SemanticsError(FretishError):
    """A requirement that parses but cannot be formalized (bad duration, bad function
    argument). ``span`` points at the offending part of the sentence."""

    # the position in the file, set by fretc.compiler.build when the requirement's is known
    source: str
    line: int
    column: int

    def __init__(self, message: str, span: A.Span | None = None):
        super().__init__(message)
        self.message = message
        self.span = span



_NUMERIC_FUNCS = {"absReal", "absInt", "minReal", "minInt", "maxReal", "maxInt",
                  "preInt", "preReal"}
#: FRET's numeric functions and their arities (absReal(x), maxReal(x, y), ...).
_NUMERIC_ARITY = {"absReal": 1, "absInt": 1, "minReal": 2, "minInt": 2, "maxReal": 2,
                  "maxInt": 2}
#: (SINCE: a FRET stream monotone in its previous value, :mod:`fretc.fretish.fret_since`)
_PAST_FUNCS = {"persisted", "occurred", "preBool", "prevOcc", "preInt", "preReal", SINCE}
_FUTURE_FUNCS = {"persists", "occurs", "nextOcc"}


class Expander:
    """Turns AST expressions into IR for one formula kind.

    ``kind`` is ``"ft"`` or ``"pt"``. Temporal functions of the formula's own direction are
    expanded (FRET: past functions in pt, future ones in ft and ft_inf); functions of the
    other direction become *derived atoms*: IR nodes ``past``/``future`` whose name is
    FRET's printed call and whose single argument is the expansion, which evaluators and
    monitors compute pointwise.

    ``left_pt`` is FRET's ``Left`` (pt formula true at the first position of a scope
    interval) and ``right_ft`` its ``Right`` (ft formula true at the last position), per
    scope (../shared/fretish/README.md section 6b). ``free`` selects FRET's endpoint-free
    expansions, used inside scope conditions (``while C``, ``after C`` ...).
    """

    def __init__(self, kind: str, left_pt: Node, right_ft: Node, free: bool = False):
        self.kind = kind
        self.left_pt = left_pt
        self.right_ft = right_ft
        self.free = free

    # boolean context
    def bool(self, e: A.Expr) -> Node:
        """``e`` as a boolean IR formula of this expander's kind (ft or pt), temporal functions
        expanded (../shared/fretish/README.md section 6b). Raises :class:`SemanticsError`
        for an expression that is not boolean or a bad function argument."""
        if isinstance(e, A.Var):
            if e.name == "FTP":
                return FTP
            return ir.ap(e.name)
        if isinstance(e, A.BoolLit):
            return TRUE if e.value else FALSE
        if isinstance(e, A.Unary):
            if e.op == "!":
                return not_(self.bool(e.operand))
            raise SemanticsError("arithmetic minus where a condition is expected", e.span)
        if isinstance(e, A.Binary):
            op = e.op
            if op in A.COMPARISON_OPS:
                return self._atom(ir.cmp(op, self.term(e.left), self.term(e.right)))
            if op in A.ARITH_OPS:
                raise SemanticsError(f"arithmetic '{op}' where a condition is expected", e.span)
            a, b = self.bool(e.left), self.bool(e.right)
            if op == "&":
                return Node("&", (a, b))
            if op == "|":
                return Node("|", (a, b))
            if op == "->":
                return Node("->", (a, b))
            if op == "xor":
                return ir.xor(a, b)
            if op == "<->":
                return ir.iff(a, b)
        if isinstance(e, A.Call):
            return self._bool_call(e)
        raise SemanticsError(f"cannot formalize {type(e).__name__}", getattr(e, "span", None))

    def _atom(self, node: Node) -> Node:
        """A comparison whose terms contain past values (``preReal``) is a derived atom in
        ft."""
        if self.kind == "ft" and ir.has_op(node, ("pre",)):
            return Node("past", (node,), name=None)
        return node

    def _bool_call(self, e: A.Call) -> Node:
        name, args = e.name, e.args
        if name == "ite" and len(args) == 3:
            c, a, b = (self.bool(x) for x in args)
            return Node("|", (Node("&", (c, a)), Node("&", (not_(c), b))))
        if stream_name(e) is not None:  # (a stream by its state bit: fret_since)
            px = Expander("pt", self.left_pt, self.right_ft, self.free)
            got = ir.stream(str(stream_name(e)), px.bool(args[0]), px.bool(args[1]))
            return got if self.kind == "pt" else Node("past", (got,), name=_call_text(e))
        if name in _PAST_FUNCS and name not in ("preInt", "preReal"):
            expansion = self._past_function(e)
            if self.kind == "pt":
                return expansion
            return Node("past", (expansion,), name=_call_text(e))
        if name in _FUTURE_FUNCS:
            expansion = self._future_function(e)
            if self.kind == "ft":
                return expansion
            return Node("future", (expansion,), name=_call_text(e))
        if name in _NUMERIC_FUNCS:
            raise SemanticsError(f"'{name}' gives a number where a condition is expected",
                                 e.span)
        return Node("call", tuple(self._arg(a) for a in args), name=name)

    def _arg(self, a: A.Expr) -> Node:
        return self.term(a) if _looks_numeric(a) else self.bool(a)

    def _int_arg(self, e: A.Call, a: A.Expr) -> int:
        if isinstance(a, A.NumLit) and isinstance(a.value, int) and a.value >= 0:
            if a.value > MAX_DURATION_TICKS:
                raise SemanticsError(f"{e.name}: {duration_too_long(a.value)}", a.span)
            return a.value
        raise SemanticsError(f"{e.name}: the bound must be a non-negative integer literal",
                             getattr(a, "span", e.span))

    def _bounds(self, e: A.Call, x: Expander):
        """(m, n, p) of ``f(n, p)`` (m = 0) or ``f(m, n, p)``."""
        args = e.args
        if len(args) == 2:
            return 0, self._int_arg(e, args[0]), x.bool(args[1])
        if len(args) == 3:
            m, n = self._int_arg(e, args[0]), self._int_arg(e, args[1])
            if m > n:
                raise SemanticsError(f"{e.name}: lower bound {m} above upper bound {n}",
                                     e.span)
            return m, n, x.bool(args[2])
        raise SemanticsError(f"{e.name} takes (n, p) or (m, n, p)", e.span)

    def _past_function(self, e: A.Call) -> Node:
        """FRET's past-time functions (../shared/fretish/README.md section 6b, FRET's
        expansions restated): persisted(m,n,p) = H[m,n] p & H[0,n-1] !Left; occurred(n,p) =
        ((!Left) S p) & O[0,n] p; occurred(m,n,p) = (!Left) S[m,n] p; preBool(b,p) = (FTP &
        b) | (Y p); prevOcc(p,q) = Left | Y(((!Left & !p) S p) -> ((!Left & !p) S (p & q)));
        a FRET stream monotone in its previous value, SINCE(a, c) = a S c over the whole
        trace, as Lustre computes it (:mod:`fretc.fretish.fret_since`).
        Endpoint-free forms inside scope conditions: H[m,n] p, O[m,n] p, Y((!p) S (p & q))."""
        name, args = e.name, e.args
        # Function expansions are built in a pt expander whatever the formula kind.
        px = Expander("pt", self.left_pt, self.right_ft, self.free)
        if name == "preBool":
            if len(args) != 2:
                raise SemanticsError("preBool takes (initial value, p)", e.span)
            init = args[0]
            if not isinstance(init, A.BoolLit):
                raise SemanticsError(
                    "preBool: the initial value must be true or false (FRET would print "
                    "'undefined' here)", getattr(init, "span", e.span))
            p = px.bool(args[1])
            return or_(and_(FTP, ir.const(init.value)), and_(not_(FTP), Y(p)))
        if name == SINCE and len(args) == 2:  # (the trace's own since: no Left, no scope)
            return S(px.bool(args[0]), px.bool(args[1]))
        return self._mirrored(e, _PAST)

    def _future_function(self, e: A.Call) -> Node:
        """FRET's future-time functions: persists(m,n,p) = G[m,n] p & G[0,n-1] !Right;
        occurs(n,p) = ((!Right) U p) & F[0,n] p; occurs(m,n,p) = (!Right) U[m,n] p;
        nextOcc(p,q) = Right | X(((!p & !Right) U p) -> ((!p & !Right) U (p & q))).
        Endpoint-free forms inside scope conditions: G[m,n] p, F[m,n] p,
        X((!p) U (p & q))."""
        return self._mirrored(e, _FUTURE)

    def _mirrored(self, e: A.Call, mirror: _Mirror) -> Node:
        """The functions FRET defines in both directions (persisted/persists,
        occurred/occurs, prevOcc/nextOcc) with ``mirror``'s operators and end (Left, Right).
        Raises :class:`SemanticsError` for another name or a wrong arity."""
        name, args = e.name, e.args
        x = Expander(mirror.kind, self.left_pt, self.right_ft, self.free)
        end = self.left_pt if mirror.kind == "pt" else self.right_ft
        hold_name, happen_name, occurrence_name = mirror.names
        if name in (hold_name, happen_name):
            lo, hi, p = self._bounds(e, x)
            if name == hold_name:
                if self.free:
                    return mirror.hold(p, lo, hi)
                return and_(mirror.hold(p, lo, hi), mirror.hold(not_(end), 0, hi - 1))
            if self.free:
                return mirror.happen(p, lo, hi)
            return mirror.bounded(not_(end), p, lo, hi)
        if name == occurrence_name:
            if len(args) != 2:
                raise SemanticsError(f"{name} takes (p, q)", e.span)
            p, q = x.bool(args[0]), x.bool(args[1])
            if self.free:
                return mirror.step(mirror.tie(not_(p), and_(p, q)))
            guard = mirror.guard(end, p)
            return or_(end, mirror.step(implies(mirror.tie(guard, p),
                                                mirror.tie(guard, and_(p, q)))))
        raise SemanticsError(f"unknown {mirror.direction}-time function {name}", e.span)

    # numeric context
    def term(self, e: A.Expr) -> Node:
        """``e`` as a numeric IR term (variables, numbers, arithmetic, calls). Raises
        :class:`SemanticsError` for a boolean where a number is expected."""
        if isinstance(e, A.Var):
            return ir.var(e.name)
        if isinstance(e, A.NumLit):
            return ir.num(e.text)
        if isinstance(e, A.Unary) and e.op == "-":
            inner = self.term(e.operand)
            if inner.op == "num" and not name_of(inner).startswith("-"):
                return ir.num("-" + name_of(inner))
            return Node("neg", (inner,))
        if isinstance(e, A.Binary) and e.op in A.ARITH_OPS:
            return ir.arith(e.op, self.term(e.left), self.term(e.right))
        if isinstance(e, A.Call):
            if e.name == "ite" and len(e.args) == 3:
                return Node("ite", (self.bool(e.args[0]), self.term(e.args[1]),
                                    self.term(e.args[2])))
            if e.name in ("preInt", "preReal"):
                if len(e.args) != 2 or not _looks_numeric(e.args[0]):
                    raise SemanticsError(f"{e.name} takes (numeric initial value, x)", e.span)
                return Node("pre", (self.term(e.args[0]), self.term(e.args[1])), name=e.name)
            if e.name in _NUMERIC_ARITY and len(e.args) != _NUMERIC_ARITY[e.name]:
                want = _NUMERIC_ARITY[e.name]
                raise SemanticsError(f"{e.name} takes {want} argument{'s' if want > 1 else ''}"
                                     f", not {len(e.args)}", e.span)
            return Node("fn", tuple(self.term(a) for a in e.args), name=e.name)
        if isinstance(e, A.BoolLit):
            raise SemanticsError("a truth value where a number is expected", e.span)
        raise SemanticsError("a condition where a number is expected",
                             getattr(e, "span", None))


def _since_bounded(a: Node, b: Node, m: int, n: int) -> Node:
    """``a S[m,n] b``: b at some j in [t-n, t-m] and a at every position in (j, t] (FRET's
    bounded since). Built from unbounded since and bounded once/historically, anchored at
    the same position: ``H[0,m-1] a & O[m,m] ((a S b) & O[0,n-m] b)``; for m = 0 the most
    recent b is the witness, so ``(a S b) & O[0,n] b`` (FRET's occurred(n,p))."""
    inner = and_(S(a, b), O(b, 0, n - m))
    if m == 0:
        return inner
    return and_(H(a, 0, m - 1), O(inner, m, m))


def _until_bounded(a: Node, b: Node, m: int, n: int) -> Node:
    """``a U[m,n] b``: b at some j in [t+m, t+n] and a at every position in [t, j) (FRET's
    bounded until), as ``G[0,m-1] a & F[m,m] ((a U b) & F[0,n-m] b)``; for m = 0
    ``(a U b) & F[0,n] b`` (FRET's occurs(n,p))."""
    inner = and_(U(a, b), F(b, 0, n - m))
    if m == 0:
        return inner
    return and_(G(a, 0, m - 1), F(inner, m, m))


class _Mirror(NamedTuple):
    """One direction of FRET's mirrored functions: its formula kind, direction word,
    function names (hold, happen, occurrence), operators and the guard of the occurrence."""
    kind: str
    direction: str
    names: tuple[str, str, str]
    hold: Callable[..., Node]
    happen: Callable[..., Node]
    bounded: Callable[[Node, Node, int, int], Node]
    step: Callable[[Node], Node]
    tie: Callable[[Node, Node], Node]
    guard: Callable[[Node, Node], Node]


_PAST = _Mirror("pt", "past", ("persisted", "occurred", "prevOcc"), H, O, _since_bounded, Y, S,
                lambda left, p: and_(not_(left), not_(p)))
_FUTURE = _Mirror("ft", "future", ("persists", "occurs", "nextOcc"), G, F, _until_bounded, X,
                  U, lambda right, p: and_(not_(p), not_(right)))


_TIME_NAMES = _PAST_FUNCS | _FUTURE_FUNCS


def mentions_time(e: A.Expr) -> bool:
    """Does the expression use a temporal function or FTP (whose meaning depends on the
    formula kind and the scope)?"""
    return any((isinstance(n, A.Call) and (n.name in _TIME_NAMES
                                           or stream_name(n) is not None))
               or (isinstance(n, A.Var) and n.name == "FTP") for n in A.walk(e))


def _looks_numeric(e: A.Expr) -> bool:
    if isinstance(e, A.NumLit):
        return True
    if isinstance(e, A.Unary):
        return e.op == "-"
    if isinstance(e, A.Binary):
        return e.op in A.ARITH_OPS
    if isinstance(e, A.Call):
        return e.name in _NUMERIC_FUNCS
    return False


def _call_text(e: A.Call) -> str:
    return expr_text(e)
