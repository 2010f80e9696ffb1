"""The Internal variables' definitions of a CoCoSpec contract (``var NAME: TYPE = DEF;``), as
fretc re-prints them.

Design notes: ARCHITECTURE.md, `compiler/cocospec_definitions.py`."""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from fretc.fretish.fret_definitions import constant_of
from fretc.fretish.lustre import (LustreError, LustreTooDeep, PrintedDefinition, pre_groups,
                                  print_definition)

__all__ = ["DEFINITION_CALLS", "Ghost", "Ghosts", "ghost_definitions"]

#: the library nodes a definition may call (:data:`fretc.compiler.cocospec.LIBRARY`) and
#: their number of arguments
DEFINITION_CALLS = {"absReal": 1, "absInt": 1, "maxReal": 2, "maxInt": 2, "minReal": 2,
                    "minInt": 2, "preBool": 2, "preInt": 2, "preReal": 2}


@dataclass(frozen=True)
class Ghost:
    """One ghost variable of the contract: ``name`` (the FRET variable, or a ``pre`` group's
    ``NAME__preK``), ``lustre`` (its Lustre name), ``type`` (``bool``/``int``/``real``),
    ``text`` (its Lustre definition, as :func:`fretc.fretish.lustre.print_definition`
    writes it)."""

    name: str
    lustre: str
    type: str
    text: str


@dataclass
class Ghosts:
    """The ghosts of one contract: ``written`` (each after the ghosts its definition reads
    outside a cycle, else in the glossary's order), ``left_out`` (``[(variable, why)]``),
    ``used`` (the library nodes the definitions call)."""

    written: list[Ghost] = field(default_factory=list)
    left_out: list[tuple[str, str]] = field(default_factory=list)
    used: set[str] = field(default_factory=set)


@dataclass(frozen=True)
class _Equation:
    """One equation of a definition read: ``var`` (the variable, or a ``pre`` group's),
    ``source`` (the text it is printed from), ``printed`` (printed with the source names:
    what it reads and calls, its type)."""

    var: str
    source: str
    printed: PrintedDefinition


def ghost_definitions(variables: Sequence[Any], types: dict[str, str],
                      lustre_name: Callable[[str], str]) -> Ghosts:
    """The :class:`Ghosts` of ``variables`` (the component's Internal
    :class:`fretc.fretish.fret_variables.FretVariable` s with an ``assignment``, in the
    glossary's order). ``types`` gives each known variable's Lustre type (from the glossary
    and from the requirements' use; a variable it lacks reads as a number); ``lustre_name``
    gives a variable's Lustre name, naming it on first use (the contract's renaming:
    keywords, library nodes, clashes): it is asked only for what is written. A ghost's type
    is the glossary's, else its definition's (``bool``, else ``real``)."""
    def is_boolean(name: str) -> bool:
        return types.get(name) == "bool"

    words = {w for v in variables for w in _WORD.findall(v.assignment)}
    known = {v.name for v in variables} | set(types) | words
    read: dict[str, list[_Equation]] = {}
    out = Ghosts()
    for v in variables:
        try:
            read[v.name] = _read(v, known.__contains__, is_boolean)
        except LustreError as exc:
            out.left_out.append((v.name, str(exc)))
    for name in _order(read):
        eqs = read[name]
        typed = _typing({e.var: e.printed.boolean for e in eqs if e.var != name}, is_boolean)
        own = types.get(name)
        for e in eqs:
            text = print_definition(e.source, typed, lustre_name).text
            if e.var == name and own is not None:
                kind = own
            elif e.printed.boolean:
                kind = "bool"
            else:
                kind = own if own in ("int", "real") else "real"
            out.written.append(Ghost(e.var, lustre_name(e.var), kind, text))
            out.used |= {f for f, _n in e.printed.calls}
    return out


#: a name in a definition's text (:mod:`fretc.fretish.lustre`'s names)
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _read(v: Any, taken: Callable[[str], bool],
          is_boolean: Callable[[str], bool]) -> list[_Equation]:
    """The equations of ``v``'s definition. Raises :class:`LustreError` with the reason it
    is left out."""
    text = v.assignment.strip()
    if constant_of(v) is not None:  # (a literal; a leading + is Lustre's, not the subset's)
        text = text.lstrip("+")
    try:
        eqs = [_Equation(v.name, text, print_definition(text, is_boolean))]
    except LustreTooDeep as exc:
        eqs = _grouped(v.name, text, taken, is_boolean, exc)
    except LustreError as exc:
        raise LustreError(f"its definition is outside FRET's Lustre subset that fretc "
                          f"reads ({exc})") from None
    for e in eqs:
        for name, arity in e.printed.calls:
            if DEFINITION_CALLS.get(name) != arity:
                raise LustreError(f"its definition calls {name} with {arity} argument(s), "
                                  "which is no node of the contract's library")
    return eqs


def _grouped(name: str, text: str, taken: Callable[[str], bool],
             is_boolean: Callable[[str], bool], deep: LustreTooDeep) -> list[_Equation]:
    """A definition too deep for one expression as its ``pre`` groups' equations (the
    groups first, ``name`` last). Raises :class:`LustreError` when it cannot be (an
    equation still too deep, no group)."""
    try:
        groups = pre_groups(text, name, taken, is_boolean)
    except LustreError as exc:
        raise LustreError(f"its definition is outside FRET's Lustre subset that fretc "
                          f"reads ({exc})") from None
    if groups is None:
        raise LustreError(f"its definition is {deep}")
    typed = _typing({var: boolean for var, _e, boolean, _s in groups if var != name},
                    is_boolean)
    return [_Equation(var, source, print_definition(source, typed))
            for var, _e, _b, source in groups]


def _typing(groups: dict[str, bool],
            is_boolean: Callable[[str], bool]) -> Callable[[str], bool]:
    """Whether a name is boolean: a ``pre`` group's variable by ``groups``, another by
    ``is_boolean``."""
    return lambda n: groups[n] if n in groups else is_boolean(n)


def _order(read: dict[str, list[_Equation]]) -> list[str]:
    """The names of ``read`` with each after the definitions it reads (its groups' reads
    included), otherwise in the glossary's order; a cycle (through ``pre``) is cut where it
    closes. Without recursion (a chain of definitions may be long)."""
    order: list[str] = []
    state: dict[str, int] = {}
    reads = {name: [n for e in eqs for n in e.printed.names] for name, eqs in read.items()}
    for start in read:
        if state.get(start):
            continue
        state[start] = 1
        stack = [(start, iter(reads[start]))]
        while stack:
            top, rest = stack[-1]
            for word in rest:
                if word in read and not state.get(word):
                    state[word] = 1
                    stack.append((word, iter(reads[word])))
                    break
            else:
                stack.pop()
                order.append(top)
                state[top] = 2
    return order
