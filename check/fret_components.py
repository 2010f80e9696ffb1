"""FRET's realizability table: a FRET project checked component by component.

FRET declares a project's variables per component (its glossary: a variable is an Input,
Output, Internal or Mode of one component) and checks realizability per component: the
requirements whose text names the component (``Autopilot shall ...``) with that component's
Inputs as the environment's and its Outputs as the controller's (FRET's Analysis Portal,
"Realizability Checking"; Katis et al., "Realizability Checking of Requirements in FRET",
NASA/TM-20220007610). An Output of one component read as an Input of another is, for the
second, an input like any other: each component is judged alone, so a project with such a
variable is no conflict (fretc refused it before there was a per-component run).

Design notes: ARCHITECTURE.md, `check/fret_components.py`."""

from __future__ import annotations

from typing import Any

from fretc.check.findings import CheckResult

__all__ = ["component_row", "table_text", "project_json", "project_exit"]


def component_row(name: str, ids: list[str], result: CheckResult) -> dict[str, Any]:
    """The table row of component ``name`` (its requirement ``ids`` in order) from its
    check ``result``: ``{"component", "requirements", "realizability", "conflicts",
    "reason", "exit_code"}``. ``realizability`` is ``"realizable"`` (every group decided
    realizable), ``"unrealizable"`` (a group is; ``conflicts`` the minimal unrealizable
    subsets found, else the group's ids), ``"unknown"`` (a group past its budget; ``reason``
    the finding's words) or ``"not checked"`` (the component declares no Input or Output, a
    variable of a group is declared neither, or ``result.not_checked``: ``reason`` says
    which)."""
    row: dict[str, Any] = {"component": name, "requirements": ids, "conflicts": [],
                           "reason": "", "exit_code": result.exit_code}
    rz = result.realizability
    if result.not_checked:
        row.update(realizability="not checked", reason=result.not_checked)
        return row
    if rz is None:
        row.update(realizability="not checked",
                   reason="the component declares no Input or Output variable")
        return row
    unreal = [f for f in result.findings if f.kind == "unrealizable"]
    unknown = [f for f in result.findings if f.kind == "unknown"
               and f.message.startswith("realizability")]
    undeclared = [f for f in result.findings if f.kind == "undeclared"]
    if unreal:
        row["realizability"] = "unrealizable"
        row["conflicts"] = [s for f in unreal for s in (f.subsets or [f.requirements])]
    elif unknown:
        row.update(realizability="unknown", reason="; ".join(f.message for f in unknown))
    elif undeclared:
        names = sorted({n for f in undeclared for n in f.details.get("undeclared", {})})
        why = {n: w for f in undeclared for n, w in f.details.get("free_definitions",
                                                                    {}).items()}
        plain = [n for n in names if n not in why]
        causes = [f"{n}: FRET defines it, but {w}: a free variable to fretc, which is "
                  "declared neither Input nor Output" for n, w in sorted(why.items())]
        if plain:
            causes.append(", ".join(plain) + " declared neither Input nor Output")
        row.update(realizability="not checked", reason="; ".join(causes))
    elif rz.get("groups") and all(g.get("realizable") is True for g in rz["groups"]):
        row["realizability"] = "realizable"
    else:
        row.update(realizability="unknown", reason="no group was decided")
    return row


def table_text(rows: list[dict[str, Any]]) -> str:
    """FRET's realizability table of :func:`component_row` rows, one line per component
    (the conflicts and reasons indented under it) and a last line with the counts."""
    width = max((len(r["component"]) for r in rows), default=0)
    lines = ["FRET components (realizability of each component's requirements with its "
             "Inputs and Outputs):"]
    for r in rows:
        n = len(r["requirements"])
        word = {"realizable": "realizable", "unrealizable": "UNREALIZABLE"}.get(
            r["realizability"], r["realizability"])
        lines.append(f"  {r['component']:<{width}}  {n:3d} requirement{'s' * (n != 1)}  "
                     f"{word}  (exit {r['exit_code']})")
        for c in r["conflicts"]:
            lines.append("      conflict {" + ", ".join(c) + "}")
        if r["reason"]:
            lines.append(f"      {r['reason']}")
    counts: dict[str, int] = {}
    for r in rows:
        counts[r["realizability"]] = counts.get(r["realizability"], 0) + 1
    lines.append(f"{len(rows)} components: " + ", ".join(
        f"{counts[k]} {k}" for k in ("realizable", "unrealizable", "unknown", "not checked")
        if k in counts))
    return "\n".join(lines)


def project_json(parts: list[tuple[str, list[str], CheckResult]]) -> dict[str, Any]:
    """The document of ``fretc check --json`` / ``-o`` on a project checked per component:
    ``{"tool", "exit_code", "fret_components": [{"component", "requirements",
    "realizability", "conflicts", "reason", "exit_code", "check"}]}``, ``check`` the
    component's own check document (:meth:`CheckResult.to_json`); ``exit_code`` the
    largest of :func:`project_exit`'s."""
    comps = []
    for name, ids, result in parts:
        row = component_row(name, ids, result)
        row["check"] = result.to_json()
        comps.append(row)
    return {"tool": "fretc check",
            "exit_code": max((project_exit(r, result) for r, (_n, _i, result)
                              in zip(comps, parts)), default=0),
            "fret_components": comps}


def project_exit(row: dict[str, Any], result: CheckResult) -> int:
    """What component ``row`` (:func:`component_row` of ``result``) adds to a whole
    project's exit code: its own, but a component not checked counts as an unknown answer
    (1: nothing is called fine that was not checked), and its undeclared variables are no
    input error of the project (2 only for another input error: a requirement that does not
    formalize)."""
    if row["realizability"] != "not checked":
        return row["exit_code"]
    other = result.input_errors or any(f.severity == "input" and f.kind != "undeclared"
                                       for f in result.findings)
    return 2 if other else 1
