"""FRET's stream variables as ``fretc check`` reads them.

Design notes: ARCHITECTURE.md, `check/streams.py`."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv

__all__ = ["CheckStream", "check_streams", "streams_of_entry", "stream_atoms",
           "stream_roles", "stream_why", "STREAM_USE"]

#: what ``fretc check``'s notes say of a stream variable (after "that definition is a
#: stream with state (...): "; :func:`fretc.fretish.fret_variables.unused`)
STREAM_USE = ("fretc check reads a comparison reading it as one reading the variables its "
              "definition reads, now and through pre: an independent proposition at each "
              "tick, the environment's or the controller's as those variables are (the "
              "abstraction notes)")


@dataclass(frozen=True)
class CheckStream:
    """One stream variable a requirement reads: ``name``; ``reads`` the variables its
    definition reads from outside the streams (sorted; the inputs of
    :class:`fretc.fretish.fret_streams.StreamSystem`, through the streams it reads);
    ``text`` its definition as FRET wrote it; ``boolean`` whether it is a truth value (a
    boolean stream here is one reading a number or a numeric stream: one reading booleans
    only, ``fretc check`` and ``fretc shield`` read as a past-time formula or by its state
    bit, :mod:`fretc.fretish.fret_since`; testgen reads it here), else a real number."""

    name: str
    reads: tuple[str, ...]
    text: str
    boolean: bool = False


def streams_of_entry(entry: Any, names: Iterable[str]) -> dict[str, CheckStream]:
    """The stream variables among ``names`` (variables a requirement reads) of the FRET
    export of ``entry`` (:class:`fretc.fretish.entry.RequirementEntry`; none without FRET
    variables), by name (:func:`fretc.fretish.fret_streams.stream_system`, one system per
    stream so that each has its own ``reads``). A boolean stream monotone in its previous
    value is none of them: the analyses read it as its past-time formula, exactly
    (:func:`fretc.fretish.fret_definitions.definitions`' ``pasts``)."""
    from fretc.fretish.fret_definitions import definitions
    from fretc.fretish.fret_streams import stream_system

    variables = tuple(getattr(entry, "variables", ()) or ())
    if not variables:
        return {}
    streams = definitions(variables).streams
    out: dict[str, CheckStream] = {}
    for n in sorted(set(names) & set(streams)):
        system = stream_system(variables, [n])
        if system is None:  # pragma: no cover - a name of ``streams`` has a system
            continue
        k = system.names.index(n)
        out[n] = CheckStream(n, system.inputs, system.texts[k], system.booleans[k])
    return out


def check_streams(items: Sequence[Any]) -> dict[str, CheckStream]:
    """The stream variables the check items ``items`` (:class:`fretc.check.items.CheckItem`)
    read, by name (the first requirement's export when two components define one name)."""
    out: dict[str, CheckStream] = {}
    for x in items:
        for n, s in streams_of_entry(x.compiled.entry, x.variables).items():
            out.setdefault(n, s)
    return out


def _reads(atom: Node) -> list[str]:
    return [ir.name_of(n) for n in ir.walk(atom) if n.op in ("ap", "var")]


def stream_why(atom: Node, streams: dict[str, CheckStream]) -> str | None:
    """The ``abstraction`` note's reason of the atom ``atom`` (a comparison, or a boolean
    variable) when it reads a stream of ``streams``, else None: which stream, the variables
    its definition reads, and that the atom is an independent proposition whose role is
    theirs."""
    names = [n for n in dict.fromkeys(_reads(atom)) if n in streams]
    if not names:
        return None
    parts = [f"{n} (FRET's stream {_short(streams[n].text)}: reads "
             + (", ".join(streams[n].reads) or "no variable") + " now and through pre)"
             for n in names]
    what = (f"comparison reading the stream variable{'s' * (len(names) > 1)} "
            if atom.op == "cmp" else "the boolean stream variable ")
    return (what + "; ".join(parts) + ": an independent proposition at each tick, as a "
            "comparison reading a previous value, the environment's or the controller's as "
            "the variables its definition reads are")


def stream_atoms(formulas: Iterable[Node], streams: dict[str, CheckStream]
                 ) -> list[tuple[str, str]]:
    """``(atom text, why)`` of every atom of ``formulas`` reading a stream of ``streams``
    (comparisons and boolean variables; :func:`stream_why`), sorted by text."""
    if not streams:
        return []
    out: dict[str, str] = {}
    for f in formulas:
        for n in ir.walk(f):
            if n.op == "cmp" or (n.op == "ap" and ir.name_of(n) in streams):
                why = stream_why(n, streams)
                if why is not None:
                    out.setdefault(to_smv(n), why)
    return sorted(out.items())


def stream_roles(streams: dict[str, CheckStream], inputs: Sequence[str],
                 outputs: Sequence[str]) -> tuple[dict[str, str], dict[str, list[str]]]:
    """Each stream's role by the rule of every atom (:mod:`fretc.check.realizability`):
    ``"output"`` when its definition reads an output, else ``"input"`` (a definition that
    reads no variable: the environment's, as an atom reading no output is), and the
    variables its definition reads declared neither, each with the streams reading them
    (the streams reading one have no role: ``(roles, undeclared)``)."""
    declared = set(inputs) | set(outputs)
    roles: dict[str, str] = {}
    undeclared: dict[str, list[str]] = {}
    for n in sorted(streams):
        missing = [v for v in streams[n].reads if v not in declared]
        for v in missing:
            undeclared.setdefault(v, []).append(n)
        if not missing:
            roles[n] = "output" if set(streams[n].reads) & set(outputs) else "input"
    return roles, undeclared


def _short(text: str, limit: int = 100) -> str:
    one = " ".join(text.split())
    return one if len(one) <= limit else one[:limit - 3] + "..."
