"""FRET's semantics: a FRETish :class:`~fretish.ast.Requirement` to its three formulas.

For each of FRET's 288 template keys (8 scopes x 3 condition kinds x 12 timings) this module
builds, in the formula IR (:mod:`compiler.ir`):

* **ft** - future-time LTL over finite traces, evaluated at position 0, with ``LAST`` true
  exactly at the last position;
* **ft_inf** - ft with ``LAST`` false everywhere (infinite traces), simplified;
* **pt** - past-time LTL evaluated at the last position.

The meaning is FRET's interval semantics (Giannakopoulou et al., "Automated formalization of
structured natural language requirements", IST 2021; FRET's ``fretishSemantics`` manual;
``../shared/fretish/README.md`` sections 2-4): the scope selects intervals of the run, the
condition selects trigger points inside each interval, and the timing says what the response
must do from each trigger until the interval ends. ``only*`` scopes negate the timing and
apply it to the complement intervals. The construction here is compositional - scope
wrapper (condition wrapper (timing)) - in the style of FRET's own templates, and is checked
on traces against FRET's formulas and FRET's interval verdicts in the tests.

FRET defects fixed here (../shared/fretish/README.md section 7): units are converted with the declared tick
period instead of being dropped; decimal or inexact durations are rejected; ``preBool`` with
a non-boolean initial value is an error; ``if A then B`` is ``A -> B`` everywhere.
"""

from __future__ import annotations

import gc
from dataclasses import dataclass, field
from fractions import Fraction
from typing import List, Optional

from fretish import ast as A
from fretish.limits import MAX_DURATION_TICKS, duration_too_long
from fretish.units import format_period_ms
try:
    from fretish.errors import FretishError
except ImportError:  # pragma: no cover - during bootstrap
    FretishError = Exception

from . import ir
from .ir import (FALSE, FTP, LAST, TRUE, F, G, H, Node, O, S, U, V, X, Y, and_, and_all,
                 implies, not_, or_)


class SemanticsError(FretishError):
    """A requirement that parses but cannot be formalized (bad duration, bad function
    argument). ``span`` points at the offending part of the sentence."""

    def __init__(self, message: str, span: Optional[A.Span] = None):
        super().__init__(message)
        self.message = message
        self.span = span


@dataclass
class Formalization:
    """The formulas of one requirement.

    ``ft``/``ft_inf``/``pt`` are IR nodes; ``variables`` the FRET variable names in order of
    appearance; ``durations`` maps each duration phrase to its tick count; ``warnings``
    human-readable notes (e.g. units read as ticks for lack of a tick period);
    ``pt_causal`` is False when the pt formula refers to a future-time function (FRET leaves
    those unexpanded in pt), so pt cannot be computed online tick by tick.
    """

    key: str
    ft: Node
    ft_inf: Node
    pt: Node
    variables: List[str]
    warnings: List[str] = field(default_factory=list)
    ticks: Optional[int] = None
    pt_causal: bool = True


# --------------------------------------------------------------------------- durations
def duration_ticks(d: A.Duration, tick_period: Optional[Fraction],
                   warnings: List[str]) -> int:
    """Number of ticks of a duration.

    With ``tick_period`` (seconds, exact) a time unit converts exactly; an amount that is not
    a whole number of ticks raises :class:`SemanticsError`. Without one, FRET's behaviour is
    kept (``N unit`` means N ticks) and a warning is recorded; a fractional amount is then
    an error (FRET would print ``F[<=2.5]``, a defect, ../shared/fretish/README.md section 7.5).
    """
    amount = d.value
    if d.unit == "ticks":
        ticks = amount
    elif tick_period is None:
        ticks = amount
        warnings.append(
            f"'{d.amount} {d.unit}' read as {d.amount} ticks (FRET ignores units); declare a "
            "tick period (tick_period: 100 ms) to convert time units exactly")
    else:
        ticks = amount * A.UNIT_SECONDS[d.unit] / tick_period
    if ticks.denominator != 1:
        if d.unit != "ticks" and tick_period is not None:
            raise SemanticsError(
                f"'{d.amount} {d.unit}' is {float(ticks):g} ticks of {format_period_ms(tick_period)}: "
                "not a whole number of ticks; change the duration or the tick period", d.span)
        raise SemanticsError(
            f"duration '{d.amount} {d.unit}' is not a whole number of ticks"
            + ("" if tick_period else "; declare a tick period to use time units"), d.span)
    if ticks < 0:
        raise SemanticsError("a duration cannot be negative", d.span)
    if ticks > MAX_DURATION_TICKS:
        raise SemanticsError(duration_too_long(ticks), d.span)
    return int(ticks)


# --------------------------------------------------------------------------- expressions
_NUMERIC_FUNCS = {"absReal", "absInt", "minReal", "minInt", "maxReal", "maxInt",
                  "preInt", "preReal"}
#: FRET's numeric functions and their arities (absReal(x), maxReal(x, y), ...).
_NUMERIC_ARITY = {"absReal": 1, "absInt": 1, "minReal": 2, "minInt": 2, "maxReal": 2,
                  "maxInt": 2}
_PAST_FUNCS = {"persisted", "occurred", "preBool", "prevOcc", "preInt", "preReal"}
_FUTURE_FUNCS = {"persists", "occurs", "nextOcc"}


class _Expander:
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
        self.has_future_atom = False

    # boolean context
    def bool(self, e: A.Expr) -> Node:
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
        if name in _PAST_FUNCS and name not in ("preInt", "preReal"):
            expansion = self._past_function(e)
            if self.kind == "pt":
                return expansion
            return Node("past", (expansion,), name=_call_text(e))
        if name in _FUTURE_FUNCS:
            expansion = self._future_function(e)
            if self.kind == "ft":
                return expansion
            self.has_future_atom = True
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

    def _bounds(self, e: A.Call, x: "_Expander"):
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
        """FRET's past-time functions (../shared/fretish/README.md section 6b, FRET's expansions restated):
        persisted(m,n,p) = H[m,n] p & H[0,n-1] !Left; occurred(n,p) = ((!Left) S p) &
        O[0,n] p; occurred(m,n,p) = (!Left) S[m,n] p; preBool(b,p) = (FTP & b) | (Y p);
        prevOcc(p,q) = Left | Y(((!Left & !p) S p) -> ((!Left & !p) S (p & q))). Endpoint-
        free forms inside scope conditions: H[m,n] p, O[m,n] p, Y((!p) S (p & q))."""
        name, args = e.name, e.args
        # Function expansions are built in a pt expander whatever the formula kind.
        px = _Expander("pt", self.left_pt, self.right_ft, self.free)
        left = self.left_pt
        free = self.free
        if name in ("persisted", "occurred"):
            m, n, p = self._bounds(e, px)
            if name == "persisted":
                if free:
                    return H(p, m, n)
                return and_(H(p, m, n), H(not_(left), 0, n - 1))
            if free:
                return O(p, m, n)
            return _since_bounded(not_(left), p, m, n)
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
        if name == "prevOcc":
            if len(args) != 2:
                raise SemanticsError("prevOcc takes (p, q)", e.span)
            p, q = px.bool(args[0]), px.bool(args[1])
            if free:
                return Y(S(not_(p), and_(p, q)))
            guard = and_(not_(left), not_(p))
            return or_(left, Y(implies(S(guard, p), S(guard, and_(p, q)))))
        raise SemanticsError(f"unknown past-time function {name}", e.span)

    def _future_function(self, e: A.Call) -> Node:
        """FRET's future-time functions: persists(m,n,p) = G[m,n] p & G[0,n-1] !Right;
        occurs(n,p) = ((!Right) U p) & F[0,n] p; occurs(m,n,p) = (!Right) U[m,n] p;
        nextOcc(p,q) = Right | X(((!p & !Right) U p) -> ((!p & !Right) U (p & q))).
        Endpoint-free forms inside scope conditions: G[m,n] p, F[m,n] p,
        X((!p) U (p & q))."""
        name, args = e.name, e.args
        fx = _Expander("ft", self.left_pt, self.right_ft, self.free)
        right = self.right_ft
        free = self.free
        if name in ("persists", "occurs"):
            m, n, p = self._bounds(e, fx)
            if name == "persists":
                if free:
                    return G(p, m, n)
                return and_(G(p, m, n), G(not_(right), 0, n - 1))
            if free:
                return F(p, m, n)
            return _until_bounded(not_(right), p, m, n)
        if name == "nextOcc":
            if len(args) != 2:
                raise SemanticsError("nextOcc takes (p, q)", e.span)
            p, q = fx.bool(args[0]), fx.bool(args[1])
            if free:
                return X(U(not_(p), and_(p, q)))
            guard = and_(not_(p), not_(right))
            return or_(right, X(implies(U(guard, p), U(guard, and_(p, q)))))
        raise SemanticsError(f"unknown future-time function {name}", e.span)

    # numeric context
    def term(self, e: A.Expr) -> Node:
        if isinstance(e, A.Var):
            return ir.var(e.name)
        if isinstance(e, A.NumLit):
            return ir.num(e.text)
        if isinstance(e, A.Unary) and e.op == "-":
            inner = self.term(e.operand)
            if inner.op == "num" and not inner.name.startswith("-"):
                return ir.num("-" + inner.name)
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


_TIME_NAMES = _PAST_FUNCS | _FUTURE_FUNCS


def _mentions_time(e: A.Expr) -> bool:
    """Does the expression use a temporal function or FTP (whose meaning depends on the
    formula kind and the scope)?"""
    return any((isinstance(n, A.Call) and n.name in _TIME_NAMES)
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
    from .printers import expr_text
    return expr_text(e)


# --------------------------------------------------------------------------- timings
def _ft_timing(kind: str, negate: bool, R: Node, right: Node, n: Optional[int],
               stop: Optional[Node]) -> Node:
    """What must hold at a trigger point (ft), with ``right`` marking the interval's last
    point (../shared/fretish/README.md section 4; FRET ``formalizations_future`` building blocks)."""
    nR = not_(R)

    def within(r: Node, k: int) -> Node:
        return or_(F(r, 0, k), F(right, 0, k - 1))

    def for_(r: Node, k: int) -> Node:
        return or_(G(r, 0, k), V(right, r))

    def until(r: Node) -> Node:
        return or_(V(stop, or_(r, stop)), V(right, r))

    def before(r: Node) -> Node:
        return V(or_(r, right), not_(stop))

    def eventually(r: Node) -> Node:
        return U(not_(right), r)

    if kind == "immediately":
        return nR if negate else R
    if kind == "next":
        return or_(right, X(nR if negate else R))
    if kind == "finally":
        return V(right, implies(right, nR if negate else R))
    if kind in ("eventually", "null"):
        return V(right, nR) if negate else eventually(R)
    if kind == "always":
        return eventually(nR) if negate else V(right, R)
    if kind == "never":
        return eventually(R) if negate else V(right, nR)
    if kind == "within":
        return for_(nR, n) if negate else within(R, n)
    if kind == "for":
        return within(nR, n) if negate else for_(R, n)
    if kind == "after":
        if negate:
            return or_(within(R, n), for_(nR, n + 1))
        return and_(for_(nR, n), within(R, n + 1))
    if kind == "until":
        return before(nR) if negate else until(R)
    if kind == "before":
        return until(nR) if negate else before(R)
    raise AssertionError(kind)


def _pt_timing(kind: str, negate: bool, R: Node, left: Node, trig: Optional[Node],
               no_cond: Optional[Node], n: Optional[int], stop: Optional[Node]) -> Node:
    """``baseform@`` of FRET's past-time construction: true at position j iff every trigger
    in the interval [left .. j] met its obligation, reading j as the interval's end.
    ``trig`` is the trigger formula (None: the interval start is the only trigger) and
    ``no_cond`` says no condition has held since the interval started."""

    def since_left(f: Node) -> Node:  # f held at every point of the current interval
        return S(f, and_(f, left))

    def occurs_by(r: Node, start: Node) -> Node:  # r held since the latest start
        return not_(S(not_(r), and_(not_(r), start)))

    def vac(f: Node) -> Node:  # no trigger yet in this interval, or f
        return f if trig is None else or_(no_cond, f)

    focus = left if trig is None else trig

    def immediately(r: Node) -> Node:
        return since_left(implies(focus, r))

    def next_(r: Node) -> Node:
        return since_left(implies(Y(focus), or_(r, left) if trig is not None else r))

    def always(r: Node) -> Node:
        return since_left(vac(r))

    def eventually(r: Node) -> Node:
        return vac(occurs_by(r, focus))

    def finally_(r: Node) -> Node:
        return vac(r)

    def for_(r: Node, k: int) -> Node:
        return since_left(implies(O(focus, 0, k), vac(r)))

    def within(r: Node, k: int) -> Node:
        if trig is None:
            return since_left(implies(S(not_(r), and_(not_(r), left)), O(left, 0, k - 1)))
        return since_left(implies(O(and_(trig, not_(r)), k, k), O(or_(left, r), 0, k - 1)))

    def until(r: Node) -> Node:
        not_stopped = S(not_(stop), and_(not_(stop), focus))
        return since_left(vac(implies(not_stopped, r)))

    def before(r: Node) -> Node:
        if trig is None:
            enforce = and_(not_(left), Y(occurs_by(r, left)))
        else:
            enforce = or_(no_cond, and_(and_(not_(left), not_(trig)), Y(occurs_by(r, trig))))
        return since_left(implies(stop, enforce))

    def not_after(r: Node, k: int) -> Node:
        # FRET: checked at exactly k+1 after each trigger, pointwise (formalizations_past)
        if trig is None:
            focus_pt = O(left, k + 1, k + 1)
            ok = or_(or_(O(left, 0, k), not_(r)), Y(occurs_by(r, left)))
        else:
            focus_pt = O(trig, k + 1, k + 1)
            ok = or_(or_(O(left, 0, k), not_(r)), Y(O(r, 0, k)))
        return since_left(implies(focus_pt, ok))

    nR = not_(R)
    if kind == "immediately":
        return immediately(nR if negate else R)
    if kind == "next":
        return next_(nR if negate else R)
    if kind == "finally":
        return finally_(nR if negate else R)
    if kind in ("eventually", "null"):
        return always(nR) if negate else eventually(R)
    if kind == "always":
        return eventually(nR) if negate else always(R)
    if kind == "never":
        return eventually(R) if negate else always(nR)
    if kind == "within":
        return for_(nR, n) if negate else within(R, n)
    if kind == "for":
        return within(nR, n) if negate else for_(R, n)
    if kind == "after":
        if negate:
            return not_after(R, n)
        return and_(for_(nR, n), within(R, n + 1))
    if kind == "until":
        return before(nR) if negate else until(R)
    if kind == "before":
        return until(nR) if negate else before(R)
    raise AssertionError(kind)


# --------------------------------------------------------------------------- scopes
def _ft_markers(m: Node, last: Node = LAST):
    """ft: the point just before M starts (FiM) and M's last point before it stops (LiM).
    ``last`` is ``LAST`` (finite traces) or FALSE (infinite traces, ft_inf)."""
    nl = not_(last)
    return (and_all(not_(m), nl, X(m)), and_all(m, nl, X(not_(m))))


def _pt_markers(m: Node):
    """pt: first point of an M interval (FiM), first point after it (LiM)."""
    start = and_(m, or_(FTP, Y(not_(m))))
    end = and_(not_(m), Y(m))
    return start, end


def _ft_right(kind: str, m: Optional[Node], last: Node) -> Node:
    """ft: true at the last point of a scope interval (``last`` = LAST, or FALSE for
    ft_inf)."""
    if kind in ("null", "after", "onlyBefore"):
        return last
    if kind in ("notin", "onlyIn"):
        m = not_(m)
    fim, lim = _ft_markers(m, last)
    return or_(fim if kind == "before" else lim, last)


def _fn_right(kind: str, m: Optional[Node], last: Node) -> Node:
    """FRET's ``Right`` for the temporal functions (../shared/fretish/README.md section 6b): true at the last
    position of a scope interval. For ``in``/``onlyAfter`` it is ``m & (LAST | X !m)``, for
    ``notin``/``onlyIn``/``before`` ``(!m & !LAST) & X m`` (no LAST disjunct), else LAST.
    ``last`` is ``LAST``, or FALSE for ft_inf."""
    if kind in ("null", "after", "onlyBefore"):
        return last
    if kind in ("in", "onlyAfter"):
        return and_(m, or_(last, X(not_(m))))
    return and_all(not_(m), not_(last), X(m))


def _ft_mode(req: A.Requirement, scope: str) -> Optional[Node]:
    """The scope condition in ft (endpoint-free functions), or None for the null scope."""
    if scope == "null":
        return None
    return _Expander("ft", FTP, LAST, free=True).bool(req.scope.mode)


def _pt_endpoints(kind: str, m: Optional[Node]):
    """pt: (left, right) with ``left`` true at an interval's first point and ``right`` at
    the first point after it (``LAST`` when intervals run to the end of the trace); FRET's
    past-time endpoint rules (FiM, LiM, FNiM, LNiM, FFiM, FLiM)."""
    if kind == "null":
        return FTP, LAST
    if kind in ("in", "notin", "onlyIn"):
        return _pt_markers(m if kind == "in" else not_(m))
    if kind in ("before", "onlyBefore"):
        fim, _ = _pt_markers(m)
        ffim = and_(fim, or_(FTP, Y(H(not_(m)))))  # first M point ever
        return (FTP, ffim) if kind == "before" else (ffim, LAST)
    _, lim = _pt_markers(m)
    flim = and_(lim, Y(H(not_(lim))))  # first point after the first M interval
    return (flim, LAST) if kind == "after" else (FTP, flim)


def _ft_scope(kind: str, body: Node, m: Optional[Node], last: Node = LAST) -> Node:
    """Wrap the interval formula ``body`` (true at an interval's first point) by the scope."""
    if kind == "null":
        return body
    fim, lim = _ft_markers(m, last)
    if kind == "in":
        return and_(V(last, implies(fim, X(body))), implies(m, body))
    if kind in ("notin", "onlyIn"):
        nfim, _ = _ft_markers(not_(m), last)
        return and_(V(last, implies(nfim, X(body))), implies(not_(m), body))
    if kind == "before":
        return or_(body, m)
    if kind == "onlyAfter":
        return body
    if kind == "after":
        return or_(U(not_(lim), and_(lim, X(body))), V(last, not_(lim)))
    if kind == "onlyBefore":
        first = or_(U(not_(fim), and_(fim, X(body))), V(last, not_(fim)))
        return and_(implies(not_(m), first), implies(m, body))
    raise AssertionError(kind)


def _pt_scope(base: Node, left: Node, right: Node) -> Node:
    """FRET's past-time scope construction: intervals closed by ``right`` are checked one
    step after they end; an interval still open at the end of the trace is checked now."""
    if right is LAST:
        return implies(O(left), base) if left is not FTP else base
    closed = H(implies(and_(right, not_(FTP)), Y(base)))
    still_open = implies(S(not_(right), and_(not_(right), left)), base)
    return and_(closed, still_open)


# --------------------------------------------------------------------------- entry point
def formalize(req: A.Requirement, tick_period: Optional[Fraction] = None) -> Formalization:
    """ft, ft_inf and pt of a parsed requirement.

    ``tick_period`` is the duration of one tick in seconds (``None``: units are read as
    ticks, as FRET does, with a warning). Raises :class:`SemanticsError` for a free-form
    requirement, a bad duration or a bad temporal-function argument.

    The formula trees are acyclic, so Python's cyclic garbage collector is paused while they
    are built (it would otherwise spend half the time rescanning the new nodes).
    """
    paused = gc.isenabled()
    if paused:
        gc.disable()
    try:
        return _formalize(req, tick_period)
    finally:
        if paused:
            gc.enable()


def _formalize(req: A.Requirement, tick_period: Optional[Fraction]) -> Formalization:
    if req.freeform:
        raise SemanticsError("a free-form requirement has no formalization")
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    negate = scope.startswith("only")
    warnings: List[str] = []
    if "then" in req.text.lower():
        from .ifthen import regrouping_warnings
        warnings.extend(regrouping_warnings(req))
    n = None
    if timing in A.DURATION_TIMINGS:
        n = duration_ticks(timing_duration(req), tick_period, warnings)

    exprs = [req.response, req.condition.expr if cond != "null" else None,
             req.timing.stop if timing in A.STOP_TIMINGS else None]
    # Without temporal functions or FTP an expression means the same in every formula:
    # convert it once.
    plain = not any(e is not None and _mentions_time(e) for e in exprs)
    shared: list = []

    def fields(x: _Expander):
        if plain and shared:
            return shared[0]
        out = tuple(None if e is None else x.bool(e) for e in exprs)
        if plain:
            shared.append(out)
        return out

    # Scope conditions: temporal functions take FRET's endpoint-free forms.
    m_pt = None if scope == "null" else _Expander("pt", FTP, LAST, free=True).bool(
        req.scope.mode)
    left, right_pt = _pt_endpoints(scope, m_pt)

    # ---- ft (last = LAST) and ft_inf (last = FALSE): the same construction
    def future(last: Node):
        m = None if scope == "null" else _Expander("ft", FTP, last, free=True).bool(
            req.scope.mode)
        right = _ft_right(scope, m, last)
        R, c, s = fields(_Expander("ft", left, _fn_right(scope, m, last)))
        T = _ft_timing(timing, negate, R, right, n, s)
        if cond == "null":
            body = T
        elif cond == "holding":
            body = V(right, implies(c, T))
        else:
            rise = and_all(not_(c), not_(right), X(c))
            body = and_(V(right, implies(rise, X(T))), implies(c, T))
        return _ft_scope(scope, body, m, last), (m, c, s, R)

    ft, used = future(LAST)
    ft_inf, _ = future(FALSE)

    # ---- pt
    px = _Expander("pt", left, _fn_right(scope, _ft_mode(req, scope), LAST))
    R, c, s = fields(px)
    if cond == "null":
        trig = no_cond = None
    else:
        trig = c if cond == "holding" else and_(c, or_(Y(not_(c)), left))
        no_cond = S(not_(c), and_(not_(c), left))
    base = _pt_timing(timing, negate, R, left, trig, no_cond, n, s)
    pt = _pt_scope(base, left, right_pt)

    # variables in sentence order: mode, condition, stop, response
    variables = ir.variables(Node("vars", tuple(x for x in used if x is not None)))
    return Formalization(req.key, ft, ft_inf, pt, variables, warnings, n,
                         pt_causal=not px.has_future_atom)


def timing_duration(req: A.Requirement) -> A.Duration:
    """The duration of a ``within/for/after`` timing; :class:`SemanticsError` if absent."""
    if req.timing.duration is None:
        raise SemanticsError(f"timing '{req.timing.kind}' needs a duration", req.timing.span)
    return req.timing.duration
