"""FRET's variable declarations in its exports.

Design notes: ARCHITECTURE.md, `fretish/fret_variables.py`."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from collections.abc import Collection
from typing import Any

from fretc.common.errors import FretishFileError
from fretc.fretish import ast as A
from fretc.fretish.fret_definitions import constant_of, definitions, substitute
from fretc.fretish.fret_streams import STREAM_NOTE, stream_system, stream_why

__all__ = ["FretVariable", "fret_variables", "declare", "unused", "INTEGER_TYPES",
           "with_fret_definitions", "constant_of", "names_read", "fret_declarations"]


#: FRET's ``dataType`` values of whole numbers
INTEGER_TYPES = frozenset({"integer", "unsigned integer"})
_KINDS = ("Input", "Output", "Internal", "Mode", "Function", "")


@dataclass(frozen=True)
class FretVariable:
    """One FRET variable of an export: ``component`` and ``name``, ``kind`` (FRET's
    ``idType``), ``data_type`` (FRET's ``dataType``; ``""`` not given), ``assignment`` (an
    Internal variable's Lustre expression; ``""`` none)."""

    component: str
    name: str
    kind: str
    data_type: str = ""
    assignment: str = ""
    mode_requirement: str = ""


def fret_variables(data: Any, source: str) -> list[FretVariable]:
    """The FRET variables of an export's top-level object ``data`` (none when it has no
    ``variables`` list), in the export's order.

    Raises:
        FretishFileError: ``variables`` is not a list, or a FRET variable's name,
            component, ``idType``, ``dataType`` or ``assignment`` is not a string (or
            ``idType`` not one of FRET's), naming the entry, at ``source``."""
    if not isinstance(data, dict) or "variables" not in data:
        return []
    items = data["variables"]
    if not isinstance(items, list):
        raise FretishFileError("\"variables\" is not a list of FRET variables", source=source)
    out = []
    for k, v in enumerate(items):
        where = f"variable #{k + 1}"
        if not isinstance(v, dict):
            raise FretishFileError(f"{where} is not a JSON object", source=source)
        if v.get("modeldoc") is True or "portType" in v or "variable_name" not in v:
            continue  # (a Simulink model's port, or the model's own entry)
        fields = {}
        for key in ("variable_name", "component_name", "idType", "dataType", "assignment",
                    "modeRequirement"):
            x = v.get(key, "")
            if not isinstance(x, str):
                raise FretishFileError(f"{where}: \"{key}\" is not a string but "
                                       f"{type(x).__name__}", source=source)
            fields[key] = x
        name = fields["variable_name"]
        if not name.strip():
            raise FretishFileError(f"{where} has an empty \"variable_name\"", source=source)
        if fields["idType"] not in _KINDS:
            raise FretishFileError(f"{where} ({name}): \"idType\" {fields['idType']!r} is none "
                                   f"of FRET's ({', '.join(k for k in _KINDS if k)})",
                                   source=source)
        out.append(FretVariable(fields["component_name"], name, fields["idType"],
                                fields["dataType"], fields["assignment"],
                                fields["modeRequirement"]))
    return out


def declare(entry: Any, declared: list[FretVariable]) -> None:
    """The FRET variables of the requirement entry ``entry``'s component (those declared for
    no component: every component's) as its ``variables``, and their Input and Output ones
    as its ``inputs`` and ``outputs`` (:class:`fretc.fretish.entry.RequirementEntry`)."""
    comp = entry.requirement.component if entry.requirement is not None else ""
    own = tuple(v for v in declared if v.component in (comp, ""))
    entry.variables = own
    entry.inputs = tuple(dict.fromkeys(v.name for v in own if v.kind == "Input"))
    entry.outputs = tuple(dict.fromkeys(v.name for v in own if v.kind == "Output"))


def with_fret_definitions(entry: Any, keep: Collection[str] = (), streams: bool = False,
                          bits: bool = False) -> Any:
    """``entry`` (:class:`fretc.fretish.entry.RequirementEntry`) with each Internal variable
    of its FRET export that FRET defines replaced by its definition in its requirement's
    expressions (conditions, response, stop condition, a scope's condition or mode): a
    literal by that constant, a Lustre expression by its FRETish reading with the Internal
    variables it reads expanded (:mod:`fretc.fretish.fret_definitions`); those fretc keeps
    free stay variables, and so do those in ``keep`` (``fretc audit``: the variables the
    bindings bind, read from the log). With ``streams`` (the audit, the runtime monitors),
    the stream variables it then reads (a definition reading itself through ``pre``) are
    its ``streams``, computed tick by tick from the variables they read
    (:func:`fretc.fretish.fret_streams.stream_system`). The entry itself when there is
    none of either. Without ``streams`` (the analyses), a boolean stream monotone in its
    previous value is its past-time formula (:mod:`fretc.fretish.fret_since`), exact; with
    ``bits`` too (``fretc check``, ``fretc shield``), a boolean stream of booleans is its
    one-bit machine (:func:`fretc.fretish.fret_definitions.definitions`' ``bits``)."""
    # (the monitors compute every stream tick by tick: no since there)
    defs = definitions(tuple(entry.variables), not streams, bits and not streams)
    values = {k: v for k, v in defs.values.items() if k not in keep}
    req = entry.requirement
    if req is None or req.freeform:
        return entry
    out = _substituted(entry, values) if values else entry
    if streams:
        system = stream_system(tuple(entry.variables), names_read([out]), keep)
        if system is not None:
            out = dataclasses.replace(out, streams=system)
    return out


def _substituted(entry: Any, values: dict[str, A.Expr]) -> Any:
    """``entry`` with the variables of ``values`` replaced by their expressions
    (:func:`with_fret_definitions`)."""
    req = entry.requirement

    def sub(e: Any) -> Any:
        return substitute(e, lambda v: values.get(v.name, v))

    scope = req.scope
    if scope.mode is not None and not (isinstance(scope.mode, A.Var) and isinstance(
            values.get(scope.mode.name), A.NumLit)):  # (a mode named by a number: kept)
        scope = dataclasses.replace(scope, mode=sub(scope.mode))
    cond = dataclasses.replace(req.condition, expr=sub(req.condition.expr), parts=tuple(
        dataclasses.replace(p, expr=sub(p.expr)) for p in req.condition.parts))
    new = dataclasses.replace(req, scope=scope, condition=cond, response=sub(req.response),
                              timing=dataclasses.replace(req.timing, stop=sub(req.timing.stop)))
    return dataclasses.replace(entry, requirement=new)


def names_read(entries: Any) -> set[str]:
    """The FRET variables the requirements of ``entries`` read as written (before
    :func:`with_fret_definitions`)."""
    out: set[str] = set()
    for e in entries:
        req = e.requirement
        if req is None or req.freeform:
            continue
        for x in (req.scope.mode, req.condition.expr, req.response, req.timing.stop):
            if x is not None:
                out.update(n.name for n in A.walk(x) if isinstance(n, A.Var))
    return out


#: what the notes say of a boolean stream monotone in its previous value, which the
#: analyses read as its past-time formula (:mod:`fretc.fretish.fret_since`)
PAST_NOTE = ("that definition is a stream with state monotone in its previous value: "
             "exactly the past-time formula P S psi (P: the definition with its pre true, "
             "psi: with its pre false, or its first value at the first tick)")

#: what the notes say of a boolean stream of booleans read by its state bit
#: (:func:`fretc.fretish.fret_since.stream_expansion`)
BIT_NOTE = ("that definition is a boolean stream with state reading booleans and this "
            "tick's comparisons only: exactly a machine with one state bit, its previous "
            "value")

#: how the analyses use a FRET definition (:func:`unused`'s sentence)
ANALYSIS_USE = "in the analysis (the emitted formulas keep its name)"


def unused(variables: list[FretVariable] | tuple[FretVariable, ...], read: set[str],
           whole: Collection[str] = (), use: str = ANALYSIS_USE,
           streams: bool = False, stream_use: str = "", bits: bool = False) -> list[str]:
    """What the FRET declarations of the variables in ``read`` say, and how fretc reads
    it, one sentence per variable (sorted by name): an Internal variable's definition used
    (:func:`with_fret_definitions`) or why it is not (then a free variable), a Mode or Function
    read as a free variable, an integer type; ``whole``: the variables the shield gives
    whole numbers (its outputs declared ``integer``), whose type is used; ``use`` how a
    definition used is used (after "that definition"). ``read`` is closed over the
    definitions: a variable an expanded definition reads is read. ``streams``: the stream
    variables (a definition reading itself through ``pre``) are computed tick by tick (the
    runtime monitors: :mod:`fretc.fretish.fret_streams`), not free. ``stream_use``: how an
    analysis reads a stream variable instead (``fretc check``: a comparison reading it as
    one reading its definition's variables, after "that definition is a stream with state
    (...): "); either makes the variables a stream reads read. ``bits``: the analysis reads
    a boolean stream of booleans by its state bit (:func:`with_fret_definitions`)."""
    defs = definitions(tuple(variables), not streams, bits and not streams)
    read = _through_definitions(read, {**defs.values, **(defs.streams if streams or stream_use
                                                            else {})})
    out = []
    for v in sorted((v for v in variables if v.name in read), key=lambda v: v.name):
        if v.name in defs.pasts:
            out.append(f"{v.name}: FRET defines it ({v.kind}) as "
                       f"{_short(v.assignment or v.mode_requirement)}; {PAST_NOTE}, {use}")
        elif v.name in defs.bits:
            out.append(f"{v.name}: FRET defines it (Internal) as {_short(v.assignment)}; "
                       f"{BIT_NOTE}, {use}")
        elif v.kind == "Internal" and v.name in defs.values:
            what = "constant" if constant_of(v) is not None else "definition"
            out.append(f"{v.name}: FRET defines it (Internal) as {_short(v.assignment)}; "
                       f"that {what} {use}")
        elif v.kind == "Internal" and stream_use and v.name in defs.streams:
            out.append(f"{v.name}: FRET defines it (Internal) as {_short(v.assignment)}; "
                       "that definition is a stream with state ("
                       + stream_why(defs.free.get(v.name, "")) + f"): {stream_use}")
        elif v.kind == "Internal" and streams and v.name in defs.streams:
            out.append(f"{v.name}: FRET defines it (Internal) as {_short(v.assignment)}; "
                       "that definition is "
                       + STREAM_NOTE.format(why=stream_why(defs.free.get(v.name, "")))
                       + f", {use}")
        elif v.kind == "Internal" and v.assignment.strip():
            out.append(f"{v.name}: FRET defines it (Internal) as {_short(v.assignment)}; "
                       f"fretc reads it as a free variable: {defs.free.get(v.name, '')}")
        elif v.kind == "Mode" and v.name in defs.values:
            out.append(f"{v.name}: FRET defines the mode as {_short(v.mode_requirement)}; "
                       f"that definition {use}")
        elif v.kind == "Mode" and v.mode_requirement.strip():
            out.append(f"{v.name}: FRET defines the mode as {_short(v.mode_requirement)}; "
                       f"fretc reads it as a free variable: {defs.free.get(v.name, '')}")
        elif v.kind in ("Mode", "Function"):
            out.append(f"{v.name}: declared a {v.kind} in FRET; fretc reads it as a free "
                       "variable")
        if v.data_type in INTEGER_TYPES:
            out.append(f"{v.name}: declared {v.data_type} in FRET; "
                       + ("the shield gives it whole numbers" if v.name in whole
                          else "fretc's numbers are reals"))
    return out


def _through_definitions(read: set[str], values: dict[str, A.Expr]) -> set[str]:
    """``read`` with every variable the definitions of its members read, transitively."""
    out, todo = set(read), list(read)
    while todo:
        e = values.get(todo.pop())
        if e is None:
            continue
        for n in A.walk(e):
            if isinstance(n, A.Var) and n.name not in out:
                out.add(n.name)
                todo.append(n.name)
    return out


def _short(text: str, limit: int = 160) -> str:
    """An assignment for a note: its white space folded, at most ``limit`` characters."""
    one = " ".join(text.split())
    return one if len(one) <= limit else one[:limit - 3] + "..."


def fret_declarations(entries: list, whole: Collection[str] = (), use: str = ANALYSIS_USE,
                      streams: bool = False, stream_use: str = "", bits: bool = False
                      ) -> tuple[list, list[str]]:
    """``entries`` with their FRET export's definitions applied
    (:func:`with_fret_definitions`, with ``streams`` as there: the runtime monitors), and
    the notes of :func:`unused` (``whole``, ``use``, ``streams`` and ``stream_use`` as
    there) over the variables they read as written (``fretc check``'s and ``fretc
    shield``'s; ``bits`` as :func:`with_fret_definitions`'); ``entries`` and no note when
    none comes from an export that declares variables."""
    declared = list({(v.component, v.name): v for e in entries for v in e.variables}.values())
    if not declared:
        return entries, []
    notes = unused(declared, names_read(entries), whole, use, streams, stream_use, bits)
    return [with_fret_definitions(e, streams=streams, bits=bits) for e in entries], notes
