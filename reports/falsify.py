"""The report of a falsification search (:mod:`fretc.sim.falsify`), written to its output folder:

* ``falsify.json`` - schema ``fretc-falsify/1``: the space, the seed, the budget, the target
  requirements, every run (its parameters, each requirement's verdict and robustness, the
  objective, the MCAP kept), each requirement's smallest robustness over the runs (run and
  tick), ``falsified`` and the exit code (1 when a run violated a target, else 0);
* ``falsify.md`` - the same as tables: the smallest margins, and robustness against runs;
* ``falsify.svg`` - robustness against runs, one line per requirement with a finite value;
* ``runs/run-NNNN.audit.json`` - the audit (``fretc audit --json`` document) of each kept
  run, beside its ``runs/run-NNNN.mcap``.

Robustness values are numbers, or the strings ``inf`` / ``-inf`` (decided by a boolean), or
null (unknown or error). Same search, same bytes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

from fretc.common.outputs import write_file
from fretc.reports.terminal import robustness_text

from fretc.sim.falsify import Search

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan

__all__ = ["write_search", "search_json", "SCHEMA"]

SCHEMA = "fretc-falsify/1"


def _num(v: float | None):
    if v is None:
        return None
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return v


def search_json(search: Search) -> dict:
    """The search as the ``falsify.json`` document (a dict)."""
    sp = search.space
    smallest = {}
    for rid, best in search.smallest().items():
        smallest[rid] = (None if best is None else
                         {"value": _num(best[0]), "run": best[1], "tick": best[2]})
    return {
        "schema": SCHEMA,
        "space": {"file": sp.path, "scenario": sp.scenario.name, "sim_seed": sp.seed,
                  "parameters": [{"name": n, "low": lo, "high": hi}
                                 for n, lo, hi in sp.parameters]},
        "seed": search.seed, "budget": search.budget, "targets": search.targets,
        "runs": [{"run": r.index, "parameters": r.parameters,
                  "verdicts": r.verdicts,
                  "robustness": {k: _num(v) for k, v in r.robustness.items()},
                  "objective": _num(r.objective), "violated": r.violated,
                  "mcap": r.mcap,
                  "audit": r.mcap[:-len(".mcap")] + ".audit.json" if r.mcap else None}
                 for r in search.runs],
        "smallest": smallest,
        "falsified": search.falsified,
        "interrupted": search.interrupted,
        "exit_code": 1 if search.falsified else (130 if search.interrupted else 0),
    }


def _markdown(doc: dict) -> str:
    sp = doc["space"]
    names = [p["name"] for p in sp["parameters"]]
    lines = [f"# Falsification of {sp['scenario']} over {sp['file']}", "",
             f"CMA-ES seed {doc['seed']}, budget {doc['budget']} runs, {len(doc['runs'])} "
             f"run{'' if len(doc['runs']) == 1 else 's'} made; targets {', '.join(doc['targets'])}; simulator seed {sp['sim_seed']}.", "",
             ("**Falsified**: a run violates a target requirement (exit 1)."
              if doc["falsified"] else
              "**Interrupted** (Ctrl-C) before the budget ended, not falsified by the runs "
              "made (exit 130)." if doc.get("interrupted") else
              "**Not falsified** within the budget (exit 0)."), "",
             "## Smallest robustness per requirement", "",
             "| requirement | smallest robustness | run | tick |", "|---|---|---|---|"]
    for rid, s in doc["smallest"].items():
        value = robustness_text(s and s["value"], "-")
        lines.append(f"| {rid} | {value} | {s['run'] if s else '-'} | "
                     f"{s['tick'] if s and s['tick'] is not None else '-'} |")
    lines += ["", "## Robustness against runs", "",
              "| run | " + " | ".join(names + doc["targets"]) + " | violated | MCAP |",
              "|---" * (len(names) + len(doc["targets"]) + 3) + "|"]
    for r in doc["runs"]:
        cells = [f"{r['parameters'][n]:g}" for n in names]
        cells += [robustness_text(r["robustness"].get(t), "-") for t in doc["targets"]]
        lines.append(f"| {r['run']} | " + " | ".join(cells) + f" | "
                     f"{', '.join(r['violated']) or '-'} | {r['mcap'] or '-'} |")
    lines += ["", "Robustness: the margin to the threshold in the variable's unit, negative "
              "exactly when violated; +inf / -inf: decided by a boolean; -: unknown or "
              "error.", ""]
    return "\n".join(lines)


def _svg(doc: dict) -> str:
    """Robustness against runs (matplotlib, SVG with fixed ids and no date)."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams["svg.hashsalt"] = "fretc-falsify"
    fig, ax = plt.subplots(figsize=(8, 4))
    for rid in doc["targets"]:
        pts = [(r["run"], r["robustness"].get(rid)) for r in doc["runs"]]
        pts = [(i, v) for i, v in pts if isinstance(v, (int, float))]
        if pts:
            ax.plot(*zip(*pts), marker="o", ms=3, lw=1, label=rid)
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xlabel("run")
    ax.set_ylabel("robustness (finite values)")
    ax.set_title(f"{doc['space']['scenario']}: robustness against runs")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    plt.close(fig)
    return buf.getvalue()


def write_search(search: Search, out: str | Path, plan: AuditPlan) -> dict:
    """Write the report files (module docstring) to ``out``; returns the JSON document.

    Raises:
        OSError: a file cannot be written.
    """
    from fretc.audit.verdict import audit_json

    outp = Path(out)
    doc = search_json(search)
    for r in search.runs:
        if r.mcap:
            text = audit_json([r.audit], plan.requirements_json(), plan.bindings_json())
            write_file(outp / (r.mcap[:-len(".mcap")] + ".audit.json"), text)
    write_file(outp / "falsify.json",
               json.dumps(doc, indent=2, sort_keys=True, allow_nan=False) + "\n")
    write_file(outp / "falsify.md", _markdown(doc))
    write_file(outp / "falsify.svg", _svg(doc))
    return doc
