"""``fretc export --sdoc FILE``: an audit's results as a StrictDoc document (``.sdoc``) of test
results linked to the requirements, for a StrictDoc project that holds the requirements
(StrictDoc resolves a relation by the UID of a node of any document of the project).

Design notes: ARCHITECTURE.md, `reports/export_sdoc.py`."""

from __future__ import annotations

import re

from fretc.reports.export_results import RequirementResult

__all__ = ["sdoc_text", "UID_PATTERN"]

#: StrictDoc's UID (REGEX_UID of its grammar)
UID_PATTERN = re.compile(r"[\w]+[\w()\-/.: ]*\Z")

_GRAMMAR = """[GRAMMAR]
ELEMENTS:
- TAG: VERIFICATION
  FIELDS:
{verification}
  RELATIONS:
  - TYPE: Parent
- TAG: TEST_RESULT
  FIELDS:
{test}
  RELATIONS:
  - TYPE: Parent
"""
_VERIFICATION = ("UID", "TITLE", "STATUS", "VERDICT", "STATEMENT", "ROLLUP", "ROLLUP_PATH",
                 "FT", "PT", "AUDIT_ID", "AUDIT_DATE")
_TEST = ("UID", "TITLE", "STATUS", "VERDICT", "VACUOUS", "LOG",
         "FIRST_VIOLATION_LOG_TIME_NS", "FIRST_VIOLATION", "ROBUSTNESS")
_REQUIRED = ("UID", "TITLE", "STATUS")
_STATUS = {"satisfied": "PASSED", "vacuous": "PASSED", "violated": "FAILED"}


def _fields(names: tuple[str, ...]) -> str:
    return "\n".join(f"  - TITLE: {n}\n    TYPE: String\n    REQUIRED: "
                     f"{'True' if n in _REQUIRED else 'False'}" for n in names)


def _value(text) -> str | None:
    """A single-line field value as StrictDoc reads it (module docstring), or None."""
    if text is None:
        return None
    s = " ".join(str(text).split())
    # "[LINK: X]" and "[ANCHOR: X]" are StrictDoc markup inside any text
    s = s.replace("[LINK: ", "[ LINK: ").replace("[ANCHOR: ", "[ ANCHOR: ")
    return s or None


def _node(tag: str, values: dict, parent: str | None) -> list[str]:
    out = [f"[{tag}]"]
    for name, value in values.items():
        v = _value(value)
        if v is not None:
            out.append(f"{name}: {v}")
    if parent is not None and UID_PATTERN.match(parent):
        out += ["RELATIONS:", "- TYPE: Parent", f"  VALUE: {parent}"]
    return out + [""]


def _uid(text: str, used: set[str]) -> str:
    """``text`` as a UID (characters StrictDoc's UID does not take replaced by ``_``), made
    unique among ``used`` (``-(2)``, ``-(3)``, ...; StrictDoc compares UIDs as written) and
    added to it."""
    s = re.sub(r"[^\w()\-/.: ]", "_", text)
    s = s if UID_PATTERN.match(s) else "X" + s
    out, k = s, 2
    while out in used:
        out, k = f"{s}-({k})", k + 1
    used.add(out)
    return out


def _run_node(rid: str, n: int, log: str, v: dict, used: set[str]) -> list[str]:
    fv = v.get("first_violation") or {}
    at = fv.get("log_time_ns")
    where = None
    if fv:
        where = (f"tick {fv.get('tick')}"
                 + (f" ({fv.get('tick_time_s'):g} s)" if isinstance(fv.get("tick_time_s"),
                                                               (int, float)) else "")
                 + (f": {fv.get('reason')}" if fv.get("reason") else ""))
    rob = (v.get("robustness") or {}).get("value")
    verdict = v.get("verdict") or "error"
    return _node("TEST_RESULT", {
        "UID": _uid(f"FRETC-{rid}/run-{n}", used), "TITLE": f"{rid} on {log}",
        "STATUS": _STATUS.get(verdict, "ERROR"), "VERDICT": verdict,
        "VACUOUS": str(verdict == "vacuous").lower(), "LOG": log,
        "FIRST_VIOLATION_LOG_TIME_NS": at, "FIRST_VIOLATION": where,
        "ROBUSTNESS": None if rob is None else rob}, rid)


def sdoc_text(doc: dict, results: dict[str, RequirementResult],
              title: str = "fretc audit results", notes: list[str] | None = None) -> str:
    """The ``.sdoc`` text (module docstring) of the audit document ``doc`` and its results
    (:func:`fretc.reports.export_results.requirement_results`); ``notes`` (when given) gets
    a sentence per requirement whose id is no StrictDoc UID (its results have no Parent
    relation)."""
    out = ["[DOCUMENT]", f"TITLE: {_value(title) or 'fretc audit results'}", "",
           _GRAMMAR.format(verification=_fields(_VERIFICATION), test=_fields(_TEST))]
    runs: dict[str, list[tuple[int, str, dict]]] = {}
    for n, la in enumerate(doc.get("logs") or [], start=1):
        for v in la.get("verdicts") or []:
            runs.setdefault(v.get("requirement"), []).append((n, la.get("log") or "", v))
    used: set[str] = set()
    for rid, r in results.items():
        if notes is not None and not UID_PATTERN.match(rid):
            notes.append(f"{rid!r} is no StrictDoc UID: its results in the .sdoc have no "
                         "Parent relation (their TITLE names it)")
        out += _node("VERIFICATION", {
            "UID": _uid(f"FRETC-{rid}", used), "TITLE": f"{rid}: result over {r.runs} runs",
            "STATUS": _STATUS.get(r.verdict, "ERROR"), "VERDICT": r.verdict,
            "STATEMENT": r.evidence, "ROLLUP": r.rollup, "ROLLUP_PATH": r.rollup_path,
            "FT": r.ft, "PT": r.pt, "AUDIT_ID": r.audit_id, "AUDIT_DATE": r.audit_date}, rid)
        for n, log, v in runs.get(rid, []):
            out += _run_node(rid, n, log, v, used)
    return "\n".join(out).rstrip("\n") + "\n"
