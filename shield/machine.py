"""The synthesized shield as data, and its reference step.

A shield (Bloem, Könighofer, Könighofer, Wang, "Shield Synthesis", TACAS 2015) is made of one
:class:`Machine` per connected component of the enforced requirements. A machine reads, each
tick, the truth values of its **input atoms** (the environment's boolean variables and the
comparisons of its numeric variables with constants), the **proposed** truth values of its
**output atoms** (the controller's), and its **state**: the bits of the requirements' pt
monitors (:class:`fretc.check.pt_monitor.Monitor`: one bit per ``Y``/``O``/``H``/``S``
sub-formula, binary counters for bounded ones). Its functions are BDDs exported from BuDDy
into one node table (:mod:`fretc.shield.synthesis`):

Design notes: ARCHITECTURE.md, `shield/machine.py`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from collections.abc import Sequence
from typing import Any

__all__ = ["Atom", "Machine", "evaluate"]

_TESTS = {"<": lambda x, c: x < c, "<=": lambda x, c: x <= c, ">": lambda x, c: x > c,
          ">=": lambda x, c: x >= c, "=": lambda x, c: x == c, "!=": lambda x, c: x != c}


@dataclass(frozen=True)
class Atom:
    """An atom of the game: the boolean FRET variable ``variable`` (``op`` None), the
    comparison ``variable op constant`` (``op`` in ``< <= > >= = !=``, the variable on the
    left, the constant as a float of FRET's text), or a comparison of several variables
    (``op`` ``"pred"``, ``term`` its :func:`fretc.shield.predicates.term`, ``variable`` the
    first it reads, or for a bound, :mod:`fretc.check.bounds`, the output it bounds;
    :mod:`fretc.shield.predicates`). ``text``: its FRET/SMV text (the name ``fretc check``
    gives it)."""

    text: str
    variable: str
    op: str | None = None
    constant: float | None = None
    #: the atom's name in Spot's formulas (``fretc check``'s letters): the mangled variable,
    #: or the comparison's FRET/SMV text
    name: str = ""
    #: a comparison of several variables: its term (``op`` ``"pred"``)
    term: tuple[Any, ...] | None = None

    @property
    def spec(self) -> tuple[str, str | None, Any]:
        """The atom as the runtimes' tables give it (:mod:`fretc.shield.runtime`)."""
        return (self.variable, self.op, self.term if self.op == "pred" else self.constant)

    def value(self, x: Any) -> bool:
        """The atom's truth for the variable's value ``x`` (a bool for a boolean variable,
        a float for a numeric one, a dict of every variable's value for a comparison of
        several). Raises ValueError for a NaN (no truth value)."""
        if self.op == "pred":
            from fretc.shield.runtime import term_value

            assert self.term is not None  # a predicate has its term
            return bool(term_value(self.term, x))
        if self.op is None:
            return bool(x)
        v = float(x)
        if math.isnan(v):
            raise ValueError(f"{self.variable} is NaN: {self.text} has no truth value")
        assert self.constant is not None  # a comparison has its constant
        return bool(_TESTS[self.op](v, self.constant))


@dataclass(frozen=True)
class Machine:
    """One component's shield (module docstring): ``requirements`` the enforced ids,
    ``inputs``/``outputs`` the atoms, ``init`` the state bits' initial values, ``nodes`` the
    node table, ``safe``/``next``/``keep``/``env_ok``/``ctl_ok`` its roots (``keep`` one per
    requirement), ``messages`` its outputs corrected together
    (:class:`fretc.shield.plan.MessageGroup`), ``clusters`` the numbers of its comparisons
    of several variables, ``stats`` sizes (state bits, BDD nodes of the
    winning region, iterations)."""

    requirements: tuple[str, ...]
    inputs: tuple[Atom, ...]
    outputs: tuple[Atom, ...]
    init: tuple[bool, ...]
    nodes: tuple[tuple[int, int, int], ...]
    safe: int
    next: tuple[int, ...]
    keep: tuple[int, ...]
    env_ok: int
    #: the root of the output atoms' consistency (1: true, no constraint)
    ctl_ok: int = 1
    messages: tuple[Any, ...] = ()
    #: output clusters of comparisons of several variables (:mod:`fretc.shield.predicates`):
    #: ``{"atoms": [output atom indices], "variables": [...], "numbers": {valuation bits:
    #: {variable: value}}}`` (:mod:`fretc.shield.runtime`)
    clusters: tuple[dict[str, Any], ...] = ()
    stats: dict[str, Any] = field(default_factory=dict, compare=False)
    #: the root of the output valuations safe from every winning state whatever the inputs
    #: (0: none; the fallback's, :func:`fretc.shield.fallback.fallback_of`)
    robust: int = 0
    #: the assumptions of the environment the game took (ids), and per assumption the root
    #: of "it has held at every tick so far" (``H A``, :mod:`fretc.shield.plan`)
    assumptions: tuple[str, ...] = ()
    assumed: tuple[int, ...] = ()
    #: the output atoms that bound an output by the inputs (:mod:`fretc.check.bounds`):
    #: ``{"atom": output atom index, "variable": the output, "down": 1 when its true values
    #: are a half-line downwards, "estimate": the bound's term over the inputs}``
    #: (:mod:`fretc.shield.runtime_bounds`)
    bounds: tuple[dict[str, Any], ...] = ()
    #: the twists this machine corrects (``[shield] twists``: outputs scaled together)
    twists: tuple[tuple[str, ...], ...] = ()

    @property
    def output_variables(self) -> list[str]:
        """The FRET variables of the output atoms, in first-seen order."""
        return list(dict.fromkeys(a.variable for a in self.outputs))

    @property
    def input_variables(self) -> list[str]:
        """The FRET variables of the input atoms, in first-seen order."""
        return list(dict.fromkeys(a.variable for a in self.inputs))


def evaluate(nodes: Sequence[tuple[int, int, int]], root: int, values: Sequence[int]) -> bool:
    """The BDD ``root`` of ``nodes`` at the variable values ``values`` (one bool or 0/1 per
    variable of the node table)."""
    n = root
    while n > 1:
        var, lo, hi = nodes[n]
        n = hi if values[var] else lo
    return n == 1
