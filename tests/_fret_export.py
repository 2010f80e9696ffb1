"""A FRET project export written for a test: requirements by id and boolean variables, each
an Input, Output, Internal or Mode of one component (FRET's JSON export's fields)."""

from __future__ import annotations

import json
from pathlib import Path


def fret_export(path: Path, requirements: dict[str, str],
                variables: list[tuple[str, str, str]]) -> str:
    """Write the export of ``requirements`` (id -> FRETish text) and ``variables``
    ``(component, name, idType)`` (boolean) to ``path``; returns the path as a string."""
    doc = {"requirements": [{"reqid": rid, "fulltext": text}
                            for rid, text in requirements.items()],
           "variables": [{"component_name": comp, "variable_name": name, "idType": kind,
                          "dataType": "boolean"} for comp, name, kind in variables]}
    path.write_text(json.dumps(doc), encoding="utf-8")
    return str(path)
