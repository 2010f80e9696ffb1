"""The "Check findings" section of the traceability report (``fretc report --check FILE``,
``FILE`` written by ``fretc check -o``): every finding of the check document, the
unrealizable ones included (a finding names its requirements; a requirement's row lists
each finding that names it, by the finding's index or by its ``requirements``), the
realizability of each group of requirements checked together, and the check's notes and
input errors. Plain functions of the JSON document, no I/O; the templates
(``templates/report.{html,md}.j2``) place the section before the page's footer and link it
from the table of contents.
"""

from __future__ import annotations

import json
from typing import Any

__all__ = ["check_context"]


def _yn(v: Any) -> str:
    """A yes/no/unknown cell: True "yes", False "no", None "-", a text as it is."""
    if isinstance(v, str):
        return v
    return {True: "yes", False: "no", None: "-"}.get(v, str(v))


def _finding(k: int, f: dict) -> dict:
    """One finding as the section shows it: ``index``, ``kind``, ``severity``,
    ``requirements`` (ids), ``message``, ``witness`` (a file, or None) and ``details``
    (a list of ``(label, text)``: the inputs that defeat every controller of an
    unrealizable set, ...)."""
    details: list[tuple[str, str]] = []
    d = f.get("details") or {}
    env = d.get("environment") if isinstance(d, dict) else None
    if isinstance(env, dict):
        prefix = json.dumps(env.get("prefix") or [], sort_keys=True)
        cycle = json.dumps(env.get("cycle") or [], sort_keys=True)
        details.append(("inputs that defeat every controller",
                        f"{prefix} then forever {cycle}"))
    for s in f.get("subsets") or []:
        details.append(("subset", ", ".join(map(str, s))))
    return {"index": k, "anchor": f"check-finding-{k}", "kind": str(f.get("kind", "")),
            "severity": str(f.get("severity", "")),
            "requirements": [str(r) for r in f.get("requirements") or []],
            "message": str(f.get("message", "")), "witness": f.get("witness"),
            "details": details}


def check_context(doc: dict) -> dict:
    """What the report shows of a ``fretc check -o`` document ``doc`` (its ``tool`` is
    ``"fretc check"``, read by :func:`fretc.check.report.load_check`).

    Returns:
        ``{"rows": [{"id", "source", "satisfiable", "non_vacuous", "redundant",
        "findings": [finding, ...]}], "findings": [finding, ...] (all, in the document's
        order), "components": [{"requirements", "realizable", "method"}] (the realizability of
        each group checked together: ``realizability.groups``, ``components`` in older
        documents), "notes",
        "input_errors", "exit_code", "semantics", "fret_components"}``; a finding as
        :func:`_finding` gives it. ``fret_components`` is FRET's table of a project checked
        one component at a time (:mod:`fretc.check.fret_components`: ``[{"component",
        "requirements", "realizability", "conflicts", "reason"}]``), empty otherwise; the
        rows, findings and groups are then every component's, in order (findings numbered
        through the whole project, each group named with its component).
    """
    if "fret_components" in doc:
        return _project_context(doc)
    findings = [_finding(k, f) for k, f in enumerate(doc.get("findings") or [])]
    rows = []
    for r in doc.get("requirements") or []:
        rid = str(r.get("id"))
        mine = [f for f in findings if f["index"] in (r.get("findings") or [])
                or rid in f["requirements"]]
        line = r.get("line")
        rows.append({"id": rid, "source": f"{r.get('source', '')}"
                                          + (f":{line}" if line is not None else ""),
                     "satisfiable": _yn(r.get("satisfiable")),
                     "non_vacuous": _yn(r.get("non_vacuous")),
                     "redundant": _yn(r.get("redundant")), "findings": mine})
    real = doc.get("realizability") or {}
    comps = [{"requirements": [str(x) for x in c.get("requirements") or []],
              "realizable": _yn(c.get("realizable")), "method": str(c.get("method") or "")}
             for c in (real.get("groups") or real.get("components") or [])
             if isinstance(c, dict)]
    return {"rows": rows, "findings": findings, "components": comps,
            "notes": [str(n) for n in doc.get("notes") or []],
            "input_errors": [str(n) if not isinstance(n, dict) else str(n.get("message", n))
                             for n in doc.get("input_errors") or []],
            "exit_code": doc.get("exit_code"), "semantics": str(doc.get("semantics") or ""),
            "fret_components": []}


def _project_context(doc: dict) -> dict:
    """:func:`check_context` of a project document (``fret_components``, each with its own
    ``check`` document): the components' contexts joined, findings renumbered."""
    out: dict[str, Any] = {"rows": [], "findings": [], "components": [], "notes": [],
                           "input_errors": [], "exit_code": doc.get("exit_code"),
                           "semantics": "", "fret_components": []}
    for comp in doc.get("fret_components") or []:
        name = str(comp.get("component", ""))
        part = check_context(comp.get("check") or {})
        for f in part["findings"]:  # (the same dicts the rows list: renumbered once)
            f["index"] = len(out["findings"])
            f["anchor"] = f"check-finding-{f['index']}"
            out["findings"].append(f)
        out["rows"] += part["rows"]
        out["components"] += [dict(g, requirements=[f"{name}:"] + g["requirements"])
                              for g in part["components"]]
        out["notes"] += [f"{name}: {n}" for n in part["notes"]]
        out["input_errors"] += [f"{name}: {n}" for n in part["input_errors"]]
        out["semantics"] = out["semantics"] or part["semantics"]
        out["fret_components"].append({
            "component": name, "requirements": [str(x) for x in comp.get("requirements") or []],
            "realizability": str(comp.get("realizability", "")),
            "conflicts": [", ".join(map(str, c)) for c in comp.get("conflicts") or []],
            "reason": str(comp.get("reason") or "")})
    return out
