"""A ``fretc check -o`` document read back (``fretc report --check``, ``fretc export
--check``); what the report shows of it is :mod:`fretc.reports.check_section`'s (a project
checked per FRET component, ``fret_components``, included)."""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["load_check"]


def load_check(path: str) -> dict:
    """Read a ``fretc check -o`` JSON document (one set's, or a project's checked per FRET
    component); ``ValueError`` when it is not one."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    if not isinstance(doc, dict) or doc.get("tool") != "fretc check":
        raise ValueError(f"{path}: not a fretc check result (fretc check -o FILE)")
    return doc
