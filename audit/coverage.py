"""Coverage of recorded runs (``fretc audit --coverage``): which coverage obligations of each
requirement (:mod:`fretc.compiler.coverage`) each log exercised, at which tick, and over the
fleet which runs cover each obligation and which obligations no run covers.

Per log, a requirement's obligations are evaluated on the columns its verdict was judged on
(its own clock, :func:`fretc.monitors.coverage.exercised`). A requirement whose clock has
unknown ticks (a gap of the log, a comparison with NaN) gets no coverage on that log: its
obligations are ``unknown`` there, with the reason, never met; an ``error`` verdict read
nothing and covers nothing. Over the fleet an obligation is ``covered`` when some run met
it, else ``unknown`` when some run could not tell, else ``uncovered``.

The audit JSON carries each verdict's ``coverage`` (a list of ``{"obligation", "status",
"tick", "time_ns", "margin"}``, or ``{"unknown": reason}``) and a top-level ``coverage``
object (:func:`fleet_coverage`; docs/reference/audit-json.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.compiler.coverage import obligations
from fretc.monitors.coverage import exercised

if TYPE_CHECKING:
    from fretc.audit.verdict import LogAudit, Verdict
    from fretc.audit.columns import ClockPass
    from fretc.audit.model import AuditPlan, RequirementPlan

__all__ = ["record_coverage", "fleet_coverage", "coverage_text", "margin_json", "margin_value"]


def record_coverage(r: RequirementPlan, res: ClockPass, v: Verdict, unknown: np.ndarray) -> None:
    """Set ``v.coverage`` (:class:`fretc.audit.verdict.Verdict`) of requirement plan ``r``
    from its judged clock pass ``res`` (``res.columns``: FRET variable -> column, ``res.times``
    tick times in ns); ``unknown``: bool per tick, True where a value is unknown."""
    if v.error is not None or r.formalization is None:
        return
    n = len(res.times)
    if n == 0:
        v.coverage = {"unknown": "no tick was evaluated"}
        return
    if unknown is not None and bool(np.asarray(unknown).any()):
        k = int(np.asarray(unknown).sum())
        v.coverage = {"unknown": f"{k} of its ticks are unknown (a gap of the log or a "
                                 "comparison with NaN): no obligation is counted on this log"}
        return
    assert r.requirement is not None and r.formalization is not None  # (judged: formalized)
    obs = obligations(r.id, r.requirement, r.formalization.ticks)
    got = exercised(obs, r.requirement, res.columns, n, r.formalization.ticks)
    out = []
    for ob, e in zip(obs, got):
        item: dict[str, Any] = {"obligation": ob.id, "status": e.status, "tick": e.tick,
                "time_ns": int(res.times[e.tick]) if e.tick is not None else None}
        if e.margin is not None and e.margin == e.margin:  # (NaN: no margin)
            item["margin"] = margin_json(e.margin)
        if e.why:
            item["why"] = e.why
        out.append(item)
    v.coverage = out


def margin_json(x: float) -> float | str:
    """A margin as the audit JSON writes it: a number, or the strings ``inf`` / ``-inf``
    (JSON has no infinity: ``max`` over a filter that keeps nothing is -inf)."""
    if x in (float("inf"), float("-inf")):
        return "inf" if x > 0 else "-inf"
    return float(x)


def margin_value(x: float | str) -> float:
    """The number :func:`margin_json` wrote."""
    return float(x)


def fleet_coverage(plan: AuditPlan, logs: Sequence[LogAudit]) -> dict:
    """The top-level ``coverage`` object of the audit JSON: per requirement of ``plan``
    (formalized ones) its obligations with their description, status over the fleet
    (``covered``, ``unknown``, ``uncovered``), the runs covering each (``runs``: log, tick,
    margin) and those that could not tell (``unknown_runs``); counts per requirement and in
    all."""
    reqs = []
    for r in plan.requirements:
        if r.formalization is None:
            continue
        assert r.requirement is not None  # (formalized: parsed)
        obs = obligations(r.id, r.requirement, r.formalization.ticks)
        rows: dict[str, dict[str, Any]] = {ob.id: {"obligation": ob.id, "kind": ob.kind, "description": ob.description,
                        "runs": [], "unknown_runs": []} for ob in obs}
        for la in logs:
            for v in la.verdicts:
                if v.requirement != r.id:
                    continue
                if v.coverage is None:  # an error verdict: nothing of the log was read
                    if v.verdict == "error":
                        for row in rows.values():
                            row["unknown_runs"].append(la.log)
                    continue
                if isinstance(v.coverage, dict):
                    for row in rows.values():
                        row["unknown_runs"].append(la.log)
                    continue
                for c in v.coverage:
                    got = rows.get(c["obligation"])
                    if got is None:
                        continue
                    row = got
                    if c["status"] == "met":
                        run = {"log": la.log, "tick": c["tick"]}
                        if "margin" in c:
                            run["margin"] = c["margin"]
                        row["runs"].append(run)
                    elif c["status"] == "unknown":
                        row["unknown_runs"].append(la.log)
        for row in rows.values():
            row["status"] = ("covered" if row["runs"] else
                             "unknown" if row["unknown_runs"] else "uncovered")
            sides = [margin_value(x["margin"]) for x in row["runs"] if "margin" in x]
            if sides:
                row["closest_margin"] = margin_json(min(sides))
        items = list(rows.values())
        reqs.append({"requirement": r.id, "obligations": items,
                     "covered": sum(x["status"] == "covered" for x in items),
                     "total": len(items)})
    return {"requirements": reqs, "covered": sum(x["covered"] for x in reqs),
            "total": sum(x["total"] for x in reqs)}


def coverage_text(cov: dict) -> str:
    """A short plain-text summary of :func:`fleet_coverage`: one line per requirement
    (covered of total) and one per obligation not covered."""
    lines = [f"coverage: {cov['covered']} of {cov['total']} obligations exercised by the runs"]
    for r in cov["requirements"]:
        lines.append(f"  {r['requirement']}: {r['covered']} of {r['total']}")
        for o in r["obligations"]:
            if o["status"] != "covered":
                lines.append(f"    {o['status']}: {o['obligation']}: {o['description']}")
    return "\n".join(lines) + "\n"
