"""``fretc export`` into FRET's project export (the JSON file FRET's "Export" writes and its
"Import" reads): every requirement object the audit judged gains one member, ``fretc``, with
fretc's results; every other member and object is kept as it was, in its order.

``fretc``: ``{"verdict", "evidence", "ft", "pt", "audit_id", "audit_date"}`` (the fields of
:class:`~fretc.reports.export_results.RequirementResult`), and for a requirement others name as
their ``parent_reqid`` also ``"rollup"`` and ``"rollup_path"`` (:mod:`fretc.reports.rollup`). FRET keeps requirement objects as
documents and ignores members it does not know, so the file still imports into FRET's GUI;
FRET's own ``semantics`` are not touched (fretc's formulas sit beside them, to compare).

The file is written with the indentation of the original (2 or 4 spaces, measured from its
second line), UTF-8, keys in their order: the same inputs give the same bytes.
"""

from __future__ import annotations

import json
import re

from fretc.common.errors import FretishFileError

from fretc.reports.export_results import RequirementResult

__all__ = ["export_fret", "FRETC_MEMBER"]

FRETC_MEMBER = "fretc"


def _indent(text: str) -> int | None:
    """The original's indentation: the leading spaces of its second line (None: one line)."""
    lines = text.split("\n", 2)
    if len(lines) < 2:
        return None
    m = re.match(r" *", lines[1])
    assert m is not None  # (" *" matches any text)
    return len(m.group(0)) or 2


def export_fret(src: str, results: dict[str, RequirementResult]) -> tuple[bytes, int]:
    """(the FRET export at ``src`` with the results added, how many requirements got them).
    Raises :class:`FretishFileError` when ``src`` is not a FRET export. Writes nothing."""
    def no_constant(name: str):
        raise ValueError(f"{name} is not JSON")

    try:
        with open(src, encoding="utf-8-sig") as f:
            text = f.read()
        data = json.loads(text, parse_constant=no_constant)
    except (OSError, ValueError) as e:
        raise FretishFileError(f"not a FRET export: {e}", source=src) from None
    except RecursionError:
        raise FretishFileError("not a FRET export: JSON nested too deeply", source=src) from None
    reqs = data.get("requirements") if isinstance(data, dict) else data
    if not isinstance(reqs, list):
        raise FretishFileError("not a FRET export (no list of requirements)", source=src)
    done = 0
    for obj in reqs:
        if not isinstance(obj, dict):
            continue
        result = results.get(obj.get("reqid", ""))
        if result is None:
            continue
        obj[FRETC_MEMBER] = {"verdict": result.verdict, "evidence": result.evidence,
                             "ft": result.ft, "pt": result.pt, "audit_id": result.audit_id,
                             "audit_date": result.audit_date}
        if result.rollup is not None:
            obj[FRETC_MEMBER].update(rollup=result.rollup, rollup_path=result.rollup_path)
        done += 1
    try:  # a number past float's range (1e999) would be written as Infinity: not JSON
        out = json.dumps(data, indent=_indent(text), ensure_ascii=False, allow_nan=False)
    except ValueError:
        raise FretishFileError("holds a number too large for a float (such as 1e999): it "
                               "could not be written back as it was; not exported",
                               source=src) from None
    try:
        return (out + "\n").encode("utf-8"), done
    except UnicodeEncodeError:  # a lone surrogate (\ud800): kept as its escape
        out = json.dumps(data, indent=_indent(text), ensure_ascii=True, allow_nan=False)
        return (out + "\n").encode("utf-8"), done
