"""FRET's template building blocks in the formula IR: what a timing requires at a trigger
(ft, pt) and how a scope selects its intervals (ft markers and wrapper; pt endpoints and
wrapper).

Restated from FRET's ``formalizations_future`` / ``formalizations_past`` building blocks and
``../shared/fretish/README.md`` section 4; :mod:`fretc.compiler.semantics` composes them (scope
wrapper (condition wrapper (timing))).
"""

from __future__ import annotations

from fretc.compiler.ir import FTP, LAST, F, G, H, Node, O, S, U, V, X, Y, and_, and_all, implies, not_, or_

__all__ = ["ft_timing", "pt_timing", "ft_markers", "pt_markers", "ft_right", "fn_right",
           "pt_endpoints", "ft_scope", "pt_scope"]


# --------------------------------------------------------------------------- timings
def ft_timing(kind: str, negate: bool, R: Node, right: Node, n: int | None,
               stop: Node | None) -> Node:
    """What must hold at a trigger point (ft), with ``right`` marking the interval's last
    point (../shared/fretish/README.md section 4; FRET ``formalizations_future`` building
    blocks)."""
    nR = not_(R)

    def within(r: Node, k: int) -> Node:
        return or_(F(r, 0, k), F(right, 0, k - 1))

    def for_(r: Node, k: int) -> Node:
        return or_(G(r, 0, k), V(right, r))

    def until(r: Node) -> Node:
        assert stop is not None  # until and before have a stop condition
        return or_(V(stop, or_(r, stop)), V(right, r))

    def before(r: Node) -> Node:
        assert stop is not None
        return V(or_(r, right), not_(stop))

    def eventually(r: Node) -> Node:
        return U(not_(right), r)

    # same cases as _obligation in tests/differential.py (kept: formulas here, that test's
    # independent truth-value oracle there)
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
    if kind in ("within", "for", "after") and n is not None:  # (they have a duration)
        if kind == "within":
            return for_(nR, n) if negate else within(R, n)
        if kind == "for":
            return within(nR, n) if negate else for_(R, n)
        if negate:
            return or_(within(R, n), for_(nR, n + 1))
        return and_(for_(nR, n), within(R, n + 1))
    if kind == "until":
        return before(nR) if negate else until(R)
    if kind == "before":
        return until(nR) if negate else before(R)
    raise AssertionError(kind)


class _PastTiming:
    """The building blocks of FRET's past-time timings for one interval: ``left`` marks the
    interval's first point, ``trig`` the triggers (None: the interval start is the only
    one), ``no_cond`` says no condition has held since the interval started, ``stop`` is
    the stop condition of ``until``/``before``."""

    def __init__(self, left: Node, trig: Node | None, no_cond: Node | None,
                 stop: Node | None):
        self.left, self.trig, self.no_cond, self.stop = left, trig, no_cond, stop
        self.focus = left if trig is None else trig

    def since_left(self, f: Node) -> Node:  # f held at every point of the current interval
        return S(f, and_(f, self.left))

    @staticmethod
    def occurs_by(r: Node, start: Node) -> Node:  # r held since the latest start
        return not_(S(not_(r), and_(not_(r), start)))

    def vac(self, f: Node) -> Node:  # no trigger yet in this interval, or f
        if self.trig is None:
            return f
        assert self.no_cond is not None  # a trigger comes with its no-condition formula
        return or_(self.no_cond, f)

    def immediately(self, r: Node) -> Node:
        return self.since_left(implies(self.focus, r))

    def next_(self, r: Node) -> Node:
        return self.since_left(implies(Y(self.focus),
                                       or_(r, self.left) if self.trig is not None else r))

    def always(self, r: Node) -> Node:
        return self.since_left(self.vac(r))

    def eventually(self, r: Node) -> Node:
        return self.vac(self.occurs_by(r, self.focus))

    def finally_(self, r: Node) -> Node:
        return self.vac(r)

    def for_(self, r: Node, k: int) -> Node:
        return self.since_left(implies(O(self.focus, 0, k), self.vac(r)))

    def within(self, r: Node, k: int) -> Node:
        left, trig = self.left, self.trig
        if trig is None:
            return self.since_left(implies(S(not_(r), and_(not_(r), left)), O(left, 0, k - 1)))
        return self.since_left(implies(O(and_(trig, not_(r)), k, k),
                                       O(or_(left, r), 0, k - 1)))

    def until(self, r: Node) -> Node:
        stop = self.stop
        assert stop is not None  # until and before have a stop condition
        not_stopped = S(not_(stop), and_(not_(stop), self.focus))
        return self.since_left(self.vac(implies(not_stopped, r)))

    def before(self, r: Node) -> Node:
        left, trig = self.left, self.trig
        if trig is None:
            enforce = and_(not_(left), Y(self.occurs_by(r, left)))
        else:
            assert self.no_cond is not None  # a trigger comes with its no-condition formula
            enforce = or_(self.no_cond, and_(and_(not_(left), not_(trig)),
                                             Y(self.occurs_by(r, trig))))
        assert self.stop is not None  # until and before have a stop condition
        return self.since_left(implies(self.stop, enforce))

    def not_after(self, r: Node, k: int) -> Node:
        # FRET: checked at exactly k+1 after each trigger, pointwise (formalizations_past)
        left, trig = self.left, self.trig
        if trig is None:
            focus_pt = O(left, k + 1, k + 1)
            ok = or_(or_(O(left, 0, k), not_(r)), Y(self.occurs_by(r, left)))
        else:
            focus_pt = O(trig, k + 1, k + 1)
            ok = or_(or_(O(left, 0, k), not_(r)), Y(O(r, 0, k)))
        return self.since_left(implies(focus_pt, ok))


def pt_timing(kind: str, negate: bool, R: Node, left: Node, trig: Node | None,
              no_cond: Node | None, n: int | None, stop: Node | None) -> Node:
    """``baseform@`` of FRET's past-time construction: true at position j iff every trigger
    in the interval [left .. j] met its obligation, reading j as the interval's end.
    ``trig`` is the trigger formula (None: the interval start is the only trigger) and
    ``no_cond`` says no condition has held since the interval started."""
    t = _PastTiming(left, trig, no_cond, stop)
    nR = not_(R)
    if kind == "immediately":
        return t.immediately(nR if negate else R)
    if kind == "next":
        return t.next_(nR if negate else R)
    if kind == "finally":
        return t.finally_(nR if negate else R)
    if kind in ("eventually", "null"):
        return t.always(nR) if negate else t.eventually(R)
    if kind == "always":
        return t.eventually(nR) if negate else t.always(R)
    if kind == "never":
        return t.eventually(R) if negate else t.always(nR)
    if kind in ("within", "for", "after") and n is not None:  # (they have a duration)
        if kind == "within":
            return t.for_(nR, n) if negate else t.within(R, n)
        if kind == "for":
            return t.within(nR, n) if negate else t.for_(R, n)
        if negate:
            return t.not_after(R, n)
        return and_(t.for_(nR, n), t.within(R, n + 1))
    if kind == "until":
        return t.before(nR) if negate else t.until(R)
    if kind == "before":
        return t.until(nR) if negate else t.before(R)
    raise AssertionError(kind)


# --------------------------------------------------------------------------- scopes
def ft_markers(m: Node, last: Node = LAST) -> tuple[Node, Node]:
    """ft: the point just before M starts (FiM) and M's last point before it stops (LiM).
    ``last`` is ``LAST`` (finite traces) or FALSE (infinite traces, ft_inf)."""
    nl = not_(last)
    return (and_all(not_(m), nl, X(m)), and_all(m, nl, X(not_(m))))


def pt_markers(m: Node) -> tuple[Node, Node]:
    """pt: first point of an M interval (FiM), first point after it (LiM)."""
    start = and_(m, or_(FTP, Y(not_(m))))
    end = and_(not_(m), Y(m))
    return start, end


def ft_right(kind: str, m: Node | None, last: Node) -> Node:
    """ft: true at the last point of a scope interval (``last`` = LAST, or FALSE for
    ft_inf)."""
    if kind in ("null", "after", "onlyBefore"):
        return last
    assert m is not None  # the scopes with a mode
    if kind in ("notin", "onlyIn"):
        m = not_(m)
    fim, lim = ft_markers(m, last)
    return or_(fim if kind == "before" else lim, last)


def fn_right(kind: str, m: Node | None, last: Node) -> Node:
    """FRET's ``Right`` for the temporal functions (../shared/fretish/README.md section 6b):
    true at the last position of a scope interval. For ``in``/``onlyAfter`` it is
    ``m & (LAST | X !m)``, for ``notin``/``onlyIn``/``before`` ``(!m & !LAST) & X m`` (no
    LAST disjunct), else LAST. ``last`` is ``LAST``, or FALSE for ft_inf."""
    if kind in ("null", "after", "onlyBefore"):
        return last
    assert m is not None  # the scopes with a mode
    if kind in ("in", "onlyAfter"):
        return and_(m, or_(last, X(not_(m))))
    return and_all(not_(m), not_(last), X(m))


def pt_endpoints(kind: str, m: Node | None) -> tuple[Node, Node]:
    """pt: (left, right) with ``left`` true at an interval's first point and ``right`` at
    the first point after it (``LAST`` when intervals run to the end of the trace); FRET's
    past-time endpoint rules (FiM, LiM, FNiM, LNiM, FFiM, FLiM)."""
    if kind == "null":
        return FTP, LAST
    assert m is not None  # the scopes with a mode
    if kind in ("in", "notin", "onlyIn"):
        return pt_markers(m if kind == "in" else not_(m))
    if kind in ("before", "onlyBefore"):
        fim, _ = pt_markers(m)
        ffim = and_(fim, or_(FTP, Y(H(not_(m)))))  # first M point ever
        return (FTP, ffim) if kind == "before" else (ffim, LAST)
    _, lim = pt_markers(m)
    flim = and_(lim, Y(H(not_(lim))))  # first point after the first M interval
    return (flim, LAST) if kind == "after" else (FTP, flim)


def ft_scope(kind: str, body: Node, m: Node | None, last: Node = LAST) -> Node:
    """Wrap the interval formula ``body`` (true at an interval's first point) by the scope."""
    if kind == "null":
        return body
    assert m is not None  # the scopes with a mode
    fim, lim = ft_markers(m, last)
    if kind == "in":
        return and_(V(last, implies(fim, X(body))), implies(m, body))
    if kind in ("notin", "onlyIn"):
        nfim, _ = ft_markers(not_(m), last)
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


def pt_scope(base: Node, left: Node, right: Node) -> Node:
    """FRET's past-time scope construction: intervals closed by ``right`` are checked one
    step after they end; an interval still open at the end of the trace is checked now."""
    if right is LAST:
        return implies(O(left), base) if left is not FTP else base
    closed = H(implies(and_(right, not_(FTP)), Y(base)))
    still_open = implies(S(not_(right), and_(not_(right), left)), base)
    return and_(closed, still_open)
