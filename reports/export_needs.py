"""``fretc export --needs FILE``: an audit's results as a ``needs.json``, the import format
of sphinx-needs (its ``needimport`` directive and ``needs_external_needs`` read it; the
envelope of ``sphinx_needs.needsfile``: ``project``, ``current_version``, ``versions`` ->
version -> ``needs`` by id, ``needs_amount``, ``creator``).

Design notes: ARCHITECTURE.md, `reports/export_needs.py`."""

from __future__ import annotations

import json
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from fretc.common.textsafe import xml_text
from fretc.reports.export_results import RequirementResult
from fretc.reports.rollup import parents_of

__all__ = ["needs_json", "NEED_TYPE", "FIELDS", "NEEDS_VERSION"]

NEED_TYPE = "req"
#: the version the needs are filed under (``current_version``)
NEEDS_VERSION = "1.0"
#: the extra need fields fretc fills (strings; empty when there is no value)
FIELDS = ("fretc_verdict", "fretc_verdicts", "fretc_evidence", "fretc_rollup",
          "fretc_rollup_path", "fretc_tool", "fretc_tool_id", "fretc_ft", "fretc_pt",
          "fretc_parents", "fretc_audit_id", "fretc_audit_date")


def _fretc_version() -> str:
    try:
        return version("fretc")
    except PackageNotFoundError:  # pragma: no cover - a source tree that is not installed
        return "unknown"


def _runs(doc: dict) -> dict[str, str]:
    """Requirement id -> ``log: verdict; log: verdict`` over the runs of ``doc``."""
    out: dict[str, list[str]] = {}
    for la in doc.get("logs") or []:
        for v in la.get("verdicts") or []:
            out.setdefault(v.get("requirement"), []).append(f"{la.get('log')}: "
                                                            f"{v.get('verdict')}")
    return {k: "; ".join(v) for k, v in out.items()}


def _need(item: dict, result: RequirementResult, parents: tuple[str, ...], known: set[str],
          runs: str) -> dict:
    origin: dict[str, Any] = item["origin"] if isinstance(item.get("origin"), dict) else {}
    fields = {"fretc_verdict": result.verdict, "fretc_verdicts": runs,
              "fretc_evidence": result.evidence, "fretc_rollup": result.rollup,
              "fretc_rollup_path": result.rollup_path, "fretc_tool": origin.get("format"),
              "fretc_tool_id": origin.get("tool_id"), "fretc_ft": result.ft,
              "fretc_pt": result.pt, "fretc_parents": ", ".join(parents),
              "fretc_audit_id": result.audit_id, "fretc_audit_date": result.audit_date}
    need = {"id": _id(item["id"]), "type": NEED_TYPE,
            "title": origin.get("long_name") or item["id"],
            "content": item.get("text") or (origin.get("text") or ""),
            "status": result.verdict, "tags": ["fretc", result.verdict.replace(" ", "_")],
            "links": [_id(p) for p in parents if p in known],
            **{k: "" if v is None else str(v) for k, v in fields.items()}}
    return {k: v if k in ("id", "links") else _inert(v) for k, v in need.items()}


def _id(rid: str) -> str:
    """A requirement id as the need's id: as JUnit's ``verifies`` property has it (an XML
    attribute: :func:`fretc.common.textsafe.xml_text` with nothing kept)."""
    return xml_text(rid, keep="")


def _inert(value):
    """A need's value with ``[[`` written ``[ [`` (no sphinx-needs dynamic function)."""
    if isinstance(value, list):
        return [_inert(v) for v in value]
    return value.replace("[[", "[ [") if isinstance(value, str) else value


def needs_json(doc: dict, results: dict[str, RequirementResult],
               project: str = "fretc audit") -> str:
    """The ``needs.json`` text (module docstring) of the audit document ``doc`` and its
    results (:func:`fretc.reports.export_results.requirement_results`, which has every id
    of ``doc``). ``project``: the project name written in the envelope."""
    parents = parents_of(doc)
    items = list(doc.get("requirements") or []) + list(doc.get("not_formalized") or [])
    known = {i["id"] for i in items}
    runs = _runs(doc)
    needs = {}
    for item in items:
        if _id(item["id"]) in needs:
            continue
        needs[_id(item["id"])] = _need(item, results[item["id"]], parents.get(item["id"], ()),
                                  known, runs.get(item["id"], ""))
    date = next(iter(results.values())).audit_date if results else ""
    envelope = {"created": date, "current_version": NEEDS_VERSION, "project": project,
                "versions": {NEEDS_VERSION: {
                    "created": date, "creator": {"program": "fretc",
                                                 "version": _fretc_version()},
                    "needs": needs, "needs_amount": len(needs)}}}
    return json.dumps(envelope, indent=2, sort_keys=True, ensure_ascii=False) + "\n"
