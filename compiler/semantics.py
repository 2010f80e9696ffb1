"""FRET's semantics: a FRETish :class:`~fretc.fretish.ast.Requirement` to its three formulas.

For each of FRET's 288 template keys (8 scopes x 3 condition kinds x 12 timings) this module
builds, in the formula IR (:mod:`fretc.compiler.ir`):

Design notes: ARCHITECTURE.md, `compiler/semantics.py`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # fractions is imported lazily (start-up time)
    from fractions import Fraction

from fretc.fretish import ast as A
from fretc.fretish.limits import MAX_DURATION_TICKS, duration_too_long
from fretc.common.units import format_period_ms

from fretc.compiler import ir
from fretc.compiler.expressions import Expander, SemanticsError, mentions_time
from fretc.compiler.ir import FALSE, FTP, LAST, Node, S, V, X, Y, and_, and_all, implies, not_, or_
from fretc.compiler.scope_timing import (fn_right, ft_right, ft_scope, ft_timing, pt_endpoints, pt_scope,
                           pt_timing)


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
    variables: list[str]
    warnings: list[str] = field(default_factory=list)
    ticks: int | None = None
    pt_causal: bool = True
    #: FRETish's ``with probability OP p`` (:class:`fretc.compiler.ir.ProbabilityBound`), or None:
    #: the bound applies to each trigger (FRET 3.1, :mod:`fretc.compiler.pctl`), the formulas
    #: to each run
    probability: ir.ProbabilityBound | None = None


# --------------------------------------------------------------------------- durations
def duration_ticks(d: A.Duration, tick_period: Fraction | None,
                   warnings: list[str]) -> int:
    """Number of ticks of a duration.

    With ``tick_period`` (seconds, exact) a time unit converts exactly; an amount that is not
    a whole number of ticks raises :class:`SemanticsError`. Without one, FRET's behaviour is
    kept (``N unit`` means N ticks) and a warning is recorded; a fractional amount is then
    an error (FRET would print ``F[<=2.5]``, a defect, ../shared/fretish/README.md section
    7.5).
    """
    if not d.resolved:
        raise SemanticsError(
            f"duration {d.name} is not declared: declare it in the requirement file "
            f"('@constant {d.name} 1.5 s') or, for audits, in the bindings file "
            f"('[constants] {d.name} = \"1.5 s\"')", d.span)
    text = d.amount
    # a whole number as written: its int (what Fraction(text) equals), without parsing it
    # as a decimal
    amount = int(text) if text.isdigit() and text.isascii() else d.value
    if d.unit == "ticks":
        ticks = amount
    elif tick_period is None:
        ticks = amount
        warnings.append(
            f"'{d.amount} {d.unit}' read as {d.amount} ticks (FRET ignores units); give a "
            "tick period (--tick-period 100ms, or '@tick_period 100 ms' in a .fret file) to "
            "convert time units exactly")
    else:
        ticks = amount * A.UNIT_SECONDS[d.unit] / tick_period
    named = f"{d.name} = " if d.name else ""
    if ticks.denominator != 1:
        if d.unit != "ticks" and tick_period is not None:
            raise SemanticsError(
                f"'{named}{d.amount} {d.unit}' is {float(ticks):g} ticks of "
                f"{format_period_ms(tick_period)}: "
                "not a whole number of ticks; change the duration or the tick period", d.span)
        raise SemanticsError(
            f"duration '{d.amount} {d.unit}' is not a whole number of ticks"
            + ("" if tick_period else "; declare a tick period to use time units"), d.span)
    if ticks < 0:
        raise SemanticsError("a duration cannot be negative", d.span)
    if d.name:  # a named duration: every output shows the value used
        warnings.append(f"{d.name} = {d.amount} {d.unit} ({int(ticks)} ticks)")
    if ticks > MAX_DURATION_TICKS:
        raise SemanticsError(duration_too_long(ticks), d.span)
    return int(ticks)


# --------------------------------------------------------------------------- entry point
def formalize(req: A.Requirement, tick_period: Fraction | None = None) -> Formalization:
    """ft, ft_inf and pt of a parsed requirement.

    ``tick_period`` is the duration of one tick in seconds (``None``: units are read as
    ticks, as FRET does, with a warning). Raises :class:`SemanticsError` for a free-form
    requirement, a bad duration or a bad temporal-function argument.
    """
    return _formalize(req, tick_period)


def marked_ft_inf(req: A.Requirement, tick_period: Fraction | None,
                  mark: Callable[[Node], Node]) -> Node:
    """The ft_inf formula of ``req`` (as :func:`formalize` builds it) with each occurrence of
    the timing's obligation wrapped by ``mark(T) -> Node`` (:func:`construct`): where FRET's
    probabilistic templates put a trigger's bound (:mod:`fretc.compiler.pctl`). Raises as
    :func:`formalize`."""
    return _formalize(req, tick_period, mark)


def _formalize(req: A.Requirement, tick_period: Fraction | None, mark=None):
    scope, cond, timing, n, warnings = template_parts(req, tick_period)
    exprs = [req.response, req.condition.expr if cond != "null" else None,
             req.timing.stop if timing in A.STOP_TIMINGS else None]
    # Without temporal functions or FTP an expression means the same in every formula:
    # convert it once.
    plain = not any(e is not None and mentions_time(e) for e in exprs)
    shared: list = []

    def fields(x: Expander):
        if plain and shared:
            return shared[0]
        # converted in sentence order (condition, stop, response), so the first bad
        # expression of the sentence is the one reported, as compiler.instantiate does
        c, s, r = (None if e is None else x.bool(e) for e in exprs[1:] + exprs[:1])
        out = (r, c, s)
        if plain:
            shared.append(out)
        return out

    def mode(kind: str, last: Node) -> Node | None:
        # Scope conditions: temporal functions take FRET's endpoint-free forms.
        if scope == "null":
            return None
        assert req.scope.mode is not None  # (a scope other than null has its mode)
        return Expander(kind, FTP, last, free=True).bool(req.scope.mode)

    ft, ft_inf, pt, used, px = construct(scope, cond, timing, n, mode, fields, mark)
    if mark is not None:
        return ft_inf
    # variables in sentence order: mode, condition, stop, response
    variables = ir.variables(Node("vars", tuple(x for x in used if x is not None)))
    # pt_causal from the pt tree itself: the scope mode is expanded by its own Expander,
    # whose future-time functions px does not see
    assert req.key is not None  # (template_parts refused a free-form requirement)
    return Formalization(req.key, ft, ft_inf, pt, variables, warnings, n,
                         pt_causal=not ir.has_op(pt, ("future",)),
                         probability=ir.probability_bound(req.probability))


def template_parts(req: A.Requirement, tick_period: Fraction | None
                   ) -> tuple[str, str, str, int | None, list[str]]:
    """(scope, condition kind, timing, ticks or None, warnings) of a requirement; raises
    :class:`SemanticsError` for a free-form requirement or a bad duration."""
    if req.freeform:
        raise SemanticsError("a free-form requirement has no formalization")
    scope, cond, timing = req.scope.kind, req.condition.kind, req.timing.kind
    warnings: list[str] = []
    if "then" in req.text.lower():
        from fretc.compiler.ifthen import regrouping_warnings  # lazy: only for 'then' (start-up time)

        warnings.extend(regrouping_warnings(req))
    n = None
    if timing in A.DURATION_TIMINGS:
        n = duration_ticks(timing_duration(req), tick_period, warnings)
    return scope, cond, timing, n, warnings


def construct(scope: str, cond: str, timing: str, n: int | None,
              mode: Callable[[str, Node], Node | None],
              fields: Callable[[Expander], tuple[Node, Node | None, Node | None]],
              mark: Callable[[Node], Node] | None = None) -> tuple:
    """The three formulas of one template key, from its atoms.

    ``mode(kind, last)`` gives the scope condition (None for the null scope) for formula
    ``kind`` (``"ft"``/``"pt"``) with ``last`` (``LAST``, or FALSE for ft_inf);
    ``fields(expander)`` gives ``(response, condition, stop)`` (None where absent)
    converted by that :class:`Expander`. Returns ``(ft, ft_inf, pt, used, px)``: the IR
    nodes, the atoms of ft ``(mode, condition, stop, response)`` and pt's expander. Both
    the full build (:func:`formalize`) and the per-template-key instantiation
    (:mod:`fretc.compiler.instantiate`, with placeholder atoms) run this one construction.
    ``mark(T) -> Node``, when given, wraps each occurrence of the timing's obligation ``T``
    in ft_inf (the place of a trigger's probability bound, :mod:`fretc.compiler.pctl`).
    """
    negate = scope.startswith("only")
    m_pt = mode("pt", LAST)
    left, right_pt = pt_endpoints(scope, m_pt)

    # ---- ft (last = LAST) and ft_inf (last = FALSE): the same construction
    def future(last: Node):
        m = mode("ft", last)
        right = ft_right(scope, m, last)
        R, c, s = fields(Expander("ft", left, fn_right(scope, m, last)))
        T = ft_timing(timing, negate, R, right, n, s)
        if mark is not None and last is FALSE:
            T = mark(T)
        if cond == "null":
            body = T
        else:
            assert c is not None  # (a condition other than null has its expression)
            if cond == "holding":
                body = V(right, implies(c, T))
            else:
                rise = and_all(not_(c), not_(right), X(c))
                body = and_(V(right, implies(rise, X(T))), implies(c, T))
        return ft_scope(scope, body, m, last), (m, c, s, R)

    ft, used = future(LAST)
    ft_inf, _ = future(FALSE)

    # ---- pt
    px = Expander("pt", left, fn_right(scope, mode("ft", LAST), LAST))
    R, c, s = fields(px)
    if cond == "null":
        trig = no_cond = None
    else:
        assert c is not None  # (a condition other than null has its expression)
        trig = c if cond == "holding" else and_(c, or_(Y(not_(c)), left))
        no_cond = S(not_(c), and_(not_(c), left))
    base = pt_timing(timing, negate, R, left, trig, no_cond, n, s)
    pt = pt_scope(base, left, right_pt)
    return ft, ft_inf, pt, used, px


def timing_duration(req: A.Requirement) -> A.Duration:
    """The duration of a ``within/for/after`` timing; :class:`SemanticsError` if absent."""
    if req.timing.duration is None:
        raise SemanticsError(f"timing '{req.timing.kind}' needs a duration", req.timing.span)
    return req.timing.duration
