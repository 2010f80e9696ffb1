"""The definitions of a FRET glossary's Internal variables and modes, expanded for the
analyses.

Design notes: ARCHITECTURE.md, `fretish/fret_definitions.py`."""

from __future__ import annotations

import dataclasses
import functools
import re
from dataclasses import dataclass
from typing import Any

from fretc.fretish import ast as A
from fretc.fretish.fret_since import (reads_itself_as_bit, reads_itself_monotonically,
                                      since_expansion, stream_expansion)
from fretc.fretish.limits import MAX_EXPR_DEPTH, depth
from fretc.fretish.lustre import LustreError, LustreTooDeep, parse_definition, pre_groups

__all__ = ["Definitions", "definitions", "substitute", "constant_of", "MAX_EXPANSION_NODES",
           "GROUPED"]

#: A Lustre literal (Lustre's ``INT``/``REAL`` constants, ``true``/``false``)
_LITERAL = re.compile(r"[-+]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][-+]?[0-9]+)?\Z")

#: An expansion past this many expression nodes is not made (the variable stays free, the
#: notes say so): a definition that reads a definition that reads ... can grow each time.
MAX_EXPANSION_NODES = 2000


def constant_of(v: Any) -> A.Expr | None:
    """The literal an Internal variable's assignment is (a number or ``true``/``false`` as
    Lustre writes them), else None; ``v`` a :class:`fretc.fretish.fret_variables.FretVariable`."""
    text = v.assignment.strip()
    if v.kind != "Internal" or not text:
        return None
    if text in ("true", "false"):
        return A.BoolLit(text == "true")
    if _LITERAL.match(text):
        return A.NumLit(text.lstrip("+"))
    return None


@dataclass(frozen=True)
class Definitions:
    """``values``: Internal variable -> its expanded expression (constants included);
    ``free``: Internal variable with an assignment fretc does not expand -> why (one
    clause); ``texts``: variable -> its assignment as FRET wrote it; ``streams``: the
    free ones that are streams with state fretc computes tick by tick (a definition that
    reads itself or another of them through ``pre``, or reads one of them; each also in
    ``free``, which the analyses keep free) -> its definition as read (the variables it
    reads not expanded), in an order where each reads the earlier ones only outside ``pre``
    (:mod:`fretc.fretish.fret_streams`); ``pasts``: the boolean streams monotone in their
    previous value that ``values`` has as past-time formulas (:mod:`fretc.fretish.
    fret_since`; with :func:`definitions`' ``since``); ``bits``: the other boolean streams
    of booleans ``values`` has as one-bit machines (with :func:`definitions`' ``bits``)."""

    values: dict[str, A.Expr]
    free: dict[str, str]
    texts: dict[str, str]
    streams: dict[str, A.Expr] = dataclasses.field(default_factory=dict)
    pasts: frozenset[str] = frozenset()
    bits: frozenset[str] = frozenset()


@functools.lru_cache(maxsize=256)
def definitions(variables: tuple[Any, ...], since: bool = True,
                bits: bool = False) -> Definitions:
    """The :class:`Definitions` of one component's FRET variables (a tuple of
    :class:`fretc.fretish.fret_variables.FretVariable`; those that are not Internal or have
    no assignment are not definitions). Deterministic; memoized by the tuple.

    ``since`` (the analyses' reading): a boolean stream monotone in its own previous value
    (:mod:`fretc.fretish.fret_since`) is its past-time formula ``P S psi``, in ``values``
    with the definitions that read it, out of ``free`` and ``streams`` (named in
    ``pasts``); without (the audit's and the runtime monitors' reading, which compute every
    stream tick by tick) it is a stream like the others. The streams are those of the
    reading without ``since`` in both (less the expanded ones).

    ``bits`` (with ``since``; the readings of ``fretc check`` and ``fretc shield``, whose
    pt monitors keep state bits): a boolean stream that is not monotone but reads only
    booleans and itself only through ``preBool`` (:func:`fretc.fretish.fret_since.
    reads_itself_as_bit`) is its one-bit machine (:func:`fretc.fretish.fret_since.
    stream_expansion`), in ``values`` likewise (named in ``bits``); without, it stays a
    stream (the other readers of these expansions, testgen's and ``fretc compile``'s
    emitters, have no form for it)."""
    kinds = {v.name: v for v in variables}
    grouped: dict[str, bool] = {}  # (a pre group's variable: whether it is boolean)

    def is_boolean(name: str) -> bool:
        if name in grouped:
            return grouped[name]
        v = kinds.get(name)
        return v is not None and v.data_type == "boolean"

    raw: dict[str, A.Expr] = {}
    free: dict[str, str] = {}
    texts = {v.name: v.assignment.strip() for v in variables
             if v.kind == "Internal" and v.assignment.strip()}
    for v in variables:
        if v.kind == "Mode" and v.mode_requirement.strip():
            texts[v.name] = v.mode_requirement.strip()
            try:
                raw[v.name] = _mode(texts[v.name], is_boolean)
            except LustreError as exc:
                free[v.name] = f"its mode requirement is not a FRETish condition ({exc})"
            continue
        if v.name not in texts:
            continue
        literal = constant_of(v)
        if literal is not None:
            raw[v.name] = literal
            continue
        try:
            raw[v.name] = parse_definition(texts[v.name], is_boolean)
        except LustreTooDeep as exc:
            if not _grouped(v.name, texts, raw, free, grouped, kinds, is_boolean):
                free[v.name] = f"its definition is {exc}"
        except LustreError as exc:
            free[v.name] = (f"its definition is outside FRET's Lustre subset that fretc reads "
                            f"({exc})")
    values: dict[str, A.Expr] = {}
    monotone = frozenset(n for n in raw if since and n in kinds
                         and (is_boolean(n) or kinds[n].kind == "Mode")
                         and reads_itself_monotonically(raw[n], n))
    machines = frozenset(n for n in raw if since and bits and n not in monotone
                         and is_boolean(n) and reads_itself_as_bit(raw[n], n, is_boolean))
    for name in sorted(raw):
        _expand(name, raw, values, free, (), monotone, machines)
    if not since:
        return Definitions(values, free, texts, _streams(raw, values, free))
    ticked = definitions(variables, False).streams
    return Definitions(values, free, texts, {n: e for n, e in ticked.items() if n not in values},
                       frozenset(monotone & set(values)), frozenset(machines & set(values)))


#: the clause of a definition read as its ``pre`` groups' equations (:func:`_grouped`)
GROUPED = ("its definition nests pre past the depth of an expression (a table of values "
           "over time): each pre group an equation of its own")


def _grouped(name: str, texts: dict[str, str], raw: dict[str, A.Expr], free: dict[str, str],
             grouped: dict[str, bool], kinds: dict[str, Any], is_boolean: Any) -> bool:
    """Read ``name``'s definition, too deep for one expression, as the equations of its
    ``pre`` groups (:func:`fretc.fretish.lustre.pre_groups`): each into ``raw``, ``texts``
    and ``grouped`` (its type), free with :data:`GROUPED` (a stream computed tick by tick,
    never expanded). False when it cannot be (an equation still too deep)."""
    try:
        eqs = pre_groups(texts[name], name, lambda n: n in kinds or n in raw, is_boolean)
    except LustreError:
        return False
    if eqs is None:
        return False
    for var, e, boolean, source in eqs:
        raw[var] = e
        free[var] = GROUPED
        if var != name:
            grouped[var] = boolean
            texts[var] = source
    return True


def _mode(text: str, is_boolean: Any) -> A.Expr:
    """A Mode's requirement (FRET's glossary: a condition on the component's variables, in
    FRETish's expression syntax, ``altitude > 1000 & engaged``; else read as Lustre, the
    syntax of FRET's Internal assignments). Raises :class:`LustreError` when it is neither."""
    from fretc.common.errors import FretishError
    from fretc.fretish.parser import parse_expression

    try:
        return _plain(parse_expression(text))
    except FretishError as exc:
        try:
            return parse_definition(text, is_boolean)
        except LustreError:
            raise LustreError(str(exc).splitlines()[0]) from None


def _plain(e: Any) -> Any:
    """``e`` without its spans (so one definition substituted at many places is one value)."""
    if isinstance(e, A.Var):
        return A.Var(e.name)
    if isinstance(e, A.BoolLit):
        return A.BoolLit(e.value)
    if isinstance(e, A.NumLit):
        return A.NumLit(e.text)
    if isinstance(e, A.Unary):
        return A.Unary(e.op, _plain(e.operand))
    if isinstance(e, A.Binary):
        return A.Binary(e.op, _plain(e.left), _plain(e.right))
    if isinstance(e, A.Call):
        return A.Call(e.name, tuple(_plain(a) for a in e.args))
    return e


def _expand(name: str, raw: dict[str, A.Expr], values: dict[str, A.Expr],
            free: dict[str, str], stack: tuple[str, ...],
            monotone: frozenset[str] = frozenset(),
            machines: frozenset[str] = frozenset()) -> A.Expr | None:
    """The expansion of ``name`` (memoized in ``values``), None when it stays free (the
    reason recorded in ``free``); a name of ``monotone`` (a boolean stream monotone in its
    previous value) reads itself as is, its expansion its past-time formula
    (:func:`fretc.fretish.fret_since.since_expansion`); one of ``machines`` likewise, its
    expansion its one-bit machine (:func:`fretc.fretish.fret_since.stream_expansion`)."""
    if name in values:
        return values[name]
    if name in free:
        return None
    if name in stack:
        cycle = stack[stack.index(name):]
        why = ("its definition reads itself (a stream with state, through pre): no "
               "expression of the other variables is it" if _through_pre(cycle, raw) else
               "its definition reads itself without pre (a cycle: Lustre defines no value "
               "for it)")
        for n in cycle:
            free.setdefault(n, why)
        return None
    blocked: list[str] = []

    def var(v: A.Var) -> A.Expr:
        if v.name not in raw or (v.name == name and name in monotone | machines):
            return v
        got = _expand(v.name, raw, values, free, (*stack, name), monotone, machines)
        if got is None:
            blocked.append(v.name)
            return v
        return got

    out = substitute(raw[name], var)
    if name in free:  # (found on a cycle through it)
        return None
    if blocked:
        free[name] = ("it reads " + ", ".join(sorted(set(blocked)))
                      + ", which fretc keeps free")
        return None
    if name in monotone:
        out = since_expansion(out, name)
    elif name in machines:
        out = stream_expansion(out, name)
    if _size(out) > MAX_EXPANSION_NODES:
        free[name] = f"its expansion has more than {MAX_EXPANSION_NODES} nodes"
        return None
    if depth(out) > MAX_EXPR_DEPTH:
        free[name] = (f"its expansion is nested more than {MAX_EXPR_DEPTH} levels deep (the "
                      "limit of a FRETish expression)")
        return None
    values[name] = out
    return out


def substitute(e: Any, var: Any) -> Any:
    """``e`` (an expression of :mod:`fretc.fretish.ast`, or None) with each variable ``v``
    replaced by ``var(v)`` (iteratively over nested operands would need a stack per node
    kind; definitions nest to Lustre's depth only, which the reader has bounded)."""
    if e is None:
        return None
    if isinstance(e, A.Var):
        return var(e)
    if isinstance(e, A.Unary):
        return dataclasses.replace(e, operand=substitute(e.operand, var))
    if isinstance(e, A.Binary):
        return dataclasses.replace(e, left=substitute(e.left, var),
                                   right=substitute(e.right, var))
    if isinstance(e, A.Call):
        return dataclasses.replace(e, args=tuple(substitute(a, var) for a in e.args))
    return e


def _through_pre(cycle: tuple[str, ...], raw: dict[str, Any]) -> bool:
    """Whether a definition of ``cycle`` (Internal variables that read each other round) reads
    one of them inside ``pre`` (FRET's ``preBool``/``preInt``/``preReal``): a stream with
    state, where a cycle without ``pre`` defines no value (Lustre's causality rule)."""
    names = set(cycle)
    for n in cycle:
        stack: list = [(raw[n], False)]
        while stack:
            x, under = stack.pop()
            if isinstance(x, A.Var) and under and x.name in names:
                return True
            if isinstance(x, A.Unary):
                stack.append((x.operand, under))
            elif isinstance(x, A.Binary):
                stack += [(x.left, under), (x.right, under)]
            elif isinstance(x, A.Call):
                inside = under or x.name in ("preBool", "preInt", "preReal")
                stack += [(a, inside) for a in x.args]
    return False


#: the clause :func:`_expand` gives a definition on a cycle through ``pre``
_STATE = "its definition reads itself (a stream with state"
#: FRET's functions a stream's definition may call (Lustre's ``if`` and ``pre``)
_STREAM_CALLS = frozenset({"ite", "preBool", "preInt", "preReal"})


def _streams(raw: dict[str, A.Expr], values: dict[str, A.Expr],
             free: dict[str, str]) -> dict[str, A.Expr]:
    """The free definitions of ``raw`` that are streams with state (:class:`Definitions`'
    ``streams``): those on a cycle through ``pre``, then those reading only them and
    expanded definitions, without a call other than ``if``/``pre`` (a glossary function
    has no value fretc knows), and with no cycle outside ``pre`` among them (Lustre's
    causality rule); in evaluation order (dependencies first, then by name)."""
    state = {n for n, why in free.items() if n in raw and (why.startswith(_STATE)
                                                           or why == GROUPED)}
    grown = True
    while grown:
        grown = False
        for n in sorted(set(free) - state):
            reads = _reads(raw.get(n), raw)
            if n in raw and free[n].startswith("it reads ") and reads & state \
                    and all(r in values or r in state for r in reads):
                state.add(n)
                grown = True
    state = {n for n in state if all(_computable(x) for x in A.walk(raw[n]))}
    while True:  # (drop those reading a dropped one, until none is)
        order = _causal_order(state, raw)
        keep = {n for n in order if all(
            r in order or (r in values and all(_computable(x) for x in A.walk(values[r])))
            for r in _reads(raw[n], raw))}
        if keep == state:
            return {n: raw[n] for n in order}
        state = keep


def _computable(x: A.Expr) -> bool:
    """Whether the node ``x`` is one a stream is computed with: not a call other than
    ``if`` and ``pre``, a ``pre`` whose first value is a literal (Lustre's reading)."""
    if not isinstance(x, A.Call):
        return True
    if x.name == "ite":
        return True
    return x.name in _STREAM_CALLS and isinstance(x.args[0], (A.BoolLit, A.NumLit))


def _reads(e: A.Expr | None, raw: dict[str, A.Expr]) -> set[str]:
    """The definitions of ``raw`` that ``e`` reads (None: none)."""
    if e is None:
        return set()
    return {x.name for x in A.walk(e) if isinstance(x, A.Var) and x.name in raw}


def _now_reads(e: A.Expr, names: set[str]) -> set[str]:
    """The ``names`` that ``e`` reads outside ``pre`` (at the same tick)."""
    out, stack = set(), [e]
    while stack:
        x = stack.pop()
        if isinstance(x, A.Var) and x.name in names:
            out.add(x.name)
        elif isinstance(x, A.Unary):
            stack.append(x.operand)
        elif isinstance(x, A.Binary):
            stack += [x.left, x.right]
        elif isinstance(x, A.Call) and x.name not in ("preBool", "preInt", "preReal"):
            stack += list(x.args)
    return out


def _causal_order(state: set[str], raw: dict[str, A.Expr]) -> list[str]:
    """``state`` in an order where each reads the earlier ones only at the same tick
    (Kahn's algorithm, the least name first); those on a cycle outside ``pre`` (or after
    one) are left out."""
    deps = {n: _now_reads(raw[n], state) - {n} for n in state}
    selfish = {n for n in state if n in _now_reads(raw[n], state)}
    order: list[str] = []
    ready = sorted(n for n in state if not deps[n] and n not in selfish)
    done: set[str] = set()
    while ready:
        n = ready.pop(0)
        order.append(n)
        done.add(n)
        ready = sorted(set(ready) | {m for m in state - done - selfish - set(ready)
                                     if deps[m] <= done})
    return order


def _size(e: Any) -> int:
    """The number of nodes of the expression ``e``."""
    n, stack = 0, [e]
    while stack:
        x = stack.pop()
        n += 1
        if isinstance(x, A.Unary):
            stack.append(x.operand)
        elif isinstance(x, A.Binary):
            stack += [x.left, x.right]
        elif isinstance(x, A.Call):
            stack += list(x.args)
    return n
