"""FRET's Internal variables that are streams with state, as the equations fretc computes
tick by tick.

An Internal variable whose Lustre definition reads itself through ``pre`` (FRET's LMCPS
case study: ``psiAtZero`` is ``Psi -> if (hdg and not pre hdg) then Psi else pre
psiAtZero``, the heading when the heading mode was last engaged) is no expression of the
other variables' present and past values: the expansions keep it free
(:mod:`fretc.fretish.fret_definitions`); ``fretc check`` reads a comparison reading it as one
reading the variables its definition reads through ``pre`` (:mod:`fretc.check.streams`),
``fretc shield`` refuses it by name. The audit and the runtime monitors
compute it, as a Lustre node does (the Lustre of Kind 2 / CoCoSpec that FRET generates):

Design notes: ARCHITECTURE.md, `fretish/fret_streams.py`."""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from fretc.fretish import ast as A
from fretc.fretish.fret_definitions import GROUPED, definitions, substitute

__all__ = ["StreamSystem", "stream_system", "STREAM_NOTE", "stream_why", "FIRST_TICK",
           "is_boolean"]

#: FRET's first time point (``a -> b``'s first tick), a variable of no glossary
FIRST_TICK = "FTP"

#: what the notes say of a stream variable computed (after "FRET defines it (Internal) as
#: ...; that definition is"), ``{why}`` :func:`stream_why`'s clause
STREAM_NOTE = ("a stream with state ({why}): computed tick by tick from the variables it "
               "reads, as Lustre defines it")


def stream_why(free_reason: str) -> str:
    """Why a stream variable is one, from the reason the analyses keep it free
    (:class:`fretc.fretish.fret_definitions.Definitions`' ``free``): it reads itself
    through ``pre`` (alone or round a cycle of definitions), or it reads such a variable."""
    if free_reason.startswith("its definition reads itself"):
        return "it reads itself through pre"
    if free_reason == GROUPED:
        return "its pre groups nest past the depth of an expression: a table of values over time"
    return "it reads a variable that reads itself through pre"


@dataclass(frozen=True)
class StreamSystem:
    """The stream variables one requirement reads, as equations computed tick by tick.

    Attributes:
        names: the variables computed, in evaluation order (each reads those before it,
            and any of them through ``pre``).
        exprs: each one's definition (:mod:`fretc.fretish.ast`, FRET's reading of Lustre:
            ``ite``, ``FTP``, ``preBool``/``preInt``/``preReal``) over ``inputs``, ``FTP``
            and ``names``.
        booleans: whether each one is a truth value (else a real number).
        inputs: the variables read from outside, sorted (never ``FTP``).
        input_booleans: whether each input is a truth value (the glossary's ``boolean``).
        texts: each one's definition as FRET wrote it.
    """

    names: tuple[str, ...]
    exprs: tuple[A.Expr, ...]
    booleans: tuple[bool, ...]
    inputs: tuple[str, ...]
    input_booleans: tuple[bool, ...]
    texts: tuple[str, ...]


def stream_system(variables: tuple[Any, ...], reads: Iterable[str],
                  keep: Collection[str] = ()) -> StreamSystem | None:
    """The :class:`StreamSystem` of the stream variables among ``reads`` (and those their
    definitions read), of one component's FRET ``variables``
    (:class:`fretc.fretish.fret_variables.FretVariable`), None when ``reads`` has none.
    ``keep``: variables read from outside whatever FRET defines (the audit's bound ones);
    the other definitions a stream reads are expanded (:func:`fretc.fretish.
    fret_definitions.definitions` without ``since``: a stream the analyses read as a
    past-time formula, :mod:`fretc.fretish.fret_since`, is computed here as every other)."""
    defs = definitions(tuple(variables), since=False)  # (every stream computed tick by tick)
    streams = {n: e for n, e in defs.streams.items() if n not in keep}
    values = {n: e for n, e in defs.values.items() if n not in keep}
    need = _closure({n for n in reads if n in streams}, streams)
    if not need:
        return None
    names = tuple(n for n in streams if n in need)

    def var(v: A.Var) -> A.Expr:
        return values.get(v.name, v) if v.name not in streams else v

    exprs = tuple(substitute(streams[n], var) for n in names)
    kinds = {v.name: v.data_type for v in variables}
    inputs = tuple(sorted({x.name for e in exprs for x in A.walk(e) if isinstance(x, A.Var)
                           and x.name not in need and x.name != FIRST_TICK}))
    booleans: dict[str, bool] = {n: kinds.get(n) == "boolean" for n in inputs}
    for n, e in zip(names, exprs):
        booleans[n] = (kinds[n] == "boolean" if kinds.get(n) else
                       is_boolean(e, booleans))
    return StreamSystem(names, exprs, tuple(booleans[n] for n in names), inputs,
                        tuple(booleans[n] for n in inputs),
                        tuple(defs.texts.get(n, "") for n in names))


def _closure(names: set[str], streams: dict[str, A.Expr]) -> set[str]:
    """``names`` with every stream variable their definitions read, transitively."""
    out, todo = set(names), list(names)
    while todo:
        for x in A.walk(streams[todo.pop()]):
            if isinstance(x, A.Var) and x.name in streams and x.name not in out:
                out.add(x.name)
                todo.append(x.name)
    return out


_LOGICAL = frozenset({"&", "|", "xor", "->", "<->", "=", "!=", "<", "<=", ">", ">="})


def is_boolean(e: A.Expr, known: Mapping[str, bool]) -> bool:
    """Whether the expression ``e`` (a stream's definition or a part of it) is a truth
    value, by Lustre's typing (:mod:`fretc.fretish.lustre`): a variable as ``known`` says
    (else a number); ``ite`` and ``pre`` their operands'."""
    if isinstance(e, A.BoolLit):
        return True
    if isinstance(e, A.Unary):
        return e.op == "!"
    if isinstance(e, A.Binary):
        return e.op in _LOGICAL
    if isinstance(e, A.Var):
        return known.get(e.name, False)
    if isinstance(e, A.Call) and e.name == "ite":
        return is_boolean(e.args[1], known) and is_boolean(e.args[2], known)
    return isinstance(e, A.Call) and e.name == "preBool"
