"""FRET's variable declarations in its exports.

FRET 3.0 exports a project's requirements with its variables (``{"requirements": [...],
"variables": [...]}``, the form of FRET's case studies, ``*_reqts_and_vars.json``). A FRET
variable, as FRET's Analysis Portal declares it, is an object with ``variable_name``,
``component_name`` (variables are declared per component), ``idType`` (``Input``,
``Output``, ``Internal``, ``Mode``, ``Function``; ``""`` not declared yet) and ``dataType``
(``boolean``, ``integer``, ``unsigned integer``, ``single``, ``double``), an Internal
variable's ``assignment`` (a Lustre expression defining it) and a Mode's
``modeRequirement``. The export also lists the ports of an imported Simulink model
(``modeldoc: true``, ``portType``): those are no FRET variables and are skipped.

fretc takes a component's Input and Output variables as the ``@inputs``/``@outputs`` of its
requirements (``fretc check``'s realizability, ``fretc shield``). What it does not take
(an Internal variable's assignment: fretc reads the variable as a free one; a Mode's
requirement; an integer type, the numbers being reals) is named by :func:`unused`, never
silently dropped.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fretc.common.errors import FretishFileError

__all__ = ["FretVariable", "fret_variables", "declare", "unused", "INTEGER_TYPES"]

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
        for key in ("variable_name", "component_name", "idType", "dataType", "assignment"):
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
                                fields["dataType"], fields["assignment"]))
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


def unused(variables: list[FretVariable] | tuple[FretVariable, ...], read: set[str]
           ) -> list[str]:
    """What the FRET declarations of the variables in ``read`` say that fretc does not use,
    one sentence per variable (sorted by name)."""
    out = []
    for v in sorted((v for v in variables if v.name in read), key=lambda v: v.name):
        if v.kind == "Internal" and v.assignment.strip():
            out.append(f"{v.name}: FRET defines it (Internal) as {v.assignment.strip()}; "
                       "fretc reads it as a free variable")
        elif v.kind in ("Mode", "Function"):
            out.append(f"{v.name}: declared a {v.kind} in FRET; fretc reads it as a free "
                       "variable")
        if v.data_type in INTEGER_TYPES:
            out.append(f"{v.name}: declared {v.data_type} in FRET; fretc's numbers are "
                       "reals")
    return out
