"""The requirements as ``fretc check`` sees them (:class:`CheckItem`): the ft_inf and ft
formulas of each, the formulas saying its trigger fires (vacuity with respect to the response,
Kupferman & Vardi, STTT 2003), and its pt formula when that monitors it
(:mod:`fretc.check.monitor_sat`); and the map from the checks' formulas to those monitors."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from fretc.fretish import ast as A

from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.semantics import SemanticsError, formalize

from fretc.check.safety_game import pt_monitors_ft_inf

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["CheckItem", "make_item", "atom_variables", "monitored_forms"]


@dataclass
class CheckItem:
    """One formalized requirement as the checks see it.

    ``phi``/``phi_ft``: ft_inf / ft formula; ``trigger``/``trigger_ft``: the formula saying a
    trigger fires in scope (module docstring, item 2), None when the requirement has no
    response to vary; ``variables``: FRET variable names; ``pt``: the pt formula when it
    monitors ``phi`` (:func:`fretc.check.safety_game.pt_monitors_ft_inf`), else None;
    ``trigger_pt``: the pt formula true at the ticks where ``trigger`` is decided true
    (``!pt(R[false]) | !pt(R[true])``, :mod:`fretc.check.monitor_sat`), None when ``pt`` is;
    ``trigger_pt_last``: the same formula for every requirement, read at the last tick of
    a finite trace only (where it is ``trigger_ft``'s verdict: FRET's pt formula at the
    last tick is its ft formula, tests/compiler/test_semantics.py), None when the
    requirement has no response to vary.
    """

    index: int
    compiled: Compiled
    phi: Node
    phi_ft: Node
    trigger: Node | None
    trigger_ft: Node | None
    variables: list[str]
    pt: Node | None = None
    trigger_pt: Node | None = None
    trigger_pt_last: Node | None = None

    @property
    def id(self) -> str:
        """The requirement's id."""
        return self.compiled.id

    @property
    def location(self) -> str:
        """``file:line`` of the requirement."""
        return f"{self.compiled.entry.source}:{self.compiled.entry.line}"


def _with_response(req: A.Requirement, value: bool) -> A.Requirement:
    return dataclasses.replace(req, response=A.BoolLit(value))


def make_item(index: int, compiled: Compiled) -> CheckItem:
    """A :class:`CheckItem` of a formalized :class:`fretc.compiler.build.Compiled`."""
    f = compiled.formalization
    req = compiled.requirement
    assert f is not None and req is not None  # (a formalized requirement)
    period = compiled.entry.tick_period
    trig = trig_ft = trig_pt = last = None
    pt = f.pt if pt_monitors_ft_inf(f) else None
    try:
        lo = formalize(_with_response(req, False), period)
        hi = formalize(_with_response(req, True), period)
        trig = ir.or_(ir.not_(lo.ft_inf), ir.not_(hi.ft_inf))
        trig_ft = ir.or_(ir.not_(lo.ft), ir.not_(hi.ft))
        if lo.pt is not None and hi.pt is not None:
            last = ir.or_(ir.not_(lo.pt), ir.not_(hi.pt))
            if pt is not None and pt_monitors_ft_inf(lo) and pt_monitors_ft_inf(hi):
                trig_pt = last
    except SemanticsError:  # pragma: no cover - the requirement itself formalized
        pass
    def fold(x: Node | None) -> Node | None:  # (a comparison of constants: its truth value)
        return None if x is None else ir.fold_constants(x)

    return CheckItem(index, compiled, ir.fold_constants(f.ft_inf), ir.fold_constants(f.ft),
                     fold(trig), fold(trig_ft), list(f.variables), fold(pt), fold(trig_pt),
                     fold(last))


def atom_variables(node: Node) -> set[str]:
    """FRET variable names read by ``node`` (boolean and numeric)."""
    return set(ir.variables(node))


def monitored_forms(items: Sequence[CheckItem]) -> dict[bool, dict[Node, tuple]]:
    """The formulas of the checks that the pt monitors decide (:mod:`fretc.check.monitor_sat`),
    on infinite runs (``False``: ft_inf) and on finite traces (``True``: ft): each
    requirement's formula (``("safe", pt, index)``: pt true at every tick), its negation and
    its trigger (``("goal", pt, index)``: true at some tick). On finite traces, those of a
    requirement whose pt formula does not monitor its ft_inf (``eventually``, ``at the last
    timepoint``), and a trigger with no ``trigger_pt``, are ``("last", pt, index)``: pt true
    at the last tick (FRET's pt at the last tick is its ft)."""
    out: dict[bool, dict[Node, tuple]] = {False: {}, True: {}}
    for x in items:
        last = out[True]
        if x.trigger_ft is not None and x.trigger_pt_last is not None:
            last.setdefault(x.trigger_ft, ("last", x.trigger_pt_last, x.index))
        f = x.compiled.formalization
        assert f is not None  # (an item is made of a formalized requirement)
        full = f.pt
        if x.pt is None and full is not None:
            last[x.phi_ft] = ("last", full, x.index)
            last[ir.not_(x.phi_ft)] = ("last", ir.not_(full), x.index)
        if x.pt is None:
            continue
        for finite, phi, trig in ((False, x.phi, x.trigger), (True, x.phi_ft, x.trigger_ft)):
            forms = out[finite]
            forms[phi] = ("safe", x.pt, x.index)
            forms[ir.not_(phi)] = ("goal", ir.not_(x.pt), x.index)
            if x.trigger_pt is not None and trig is not None:
                forms[trig] = ("goal", x.trigger_pt, x.index)
    return out
