"""The report of ``fretc estimate`` (:mod:`fretc.sim.estimate`, :mod:`fretc.sim.rare`), in the output
folder:

Design notes: ARCHITECTURE.md, `reports/estimate.py`."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from fretc.common.outputs import output_folder, write_file
from fretc.common.textsafe import file_stems
from fretc.reports.statistics import COLUMNS, statistics_rows, summary_line

if TYPE_CHECKING:
    from fretc.sim.rare import RareResult
    from fretc.sim.estimate import Estimate

__all__ = ["write_estimate", "exit_code_of"]


def exit_code_of(doc: dict) -> int:
    """``fretc estimate``'s exit code from the report document (:mod:`fretc.cli.estimate`),
    first that applies: 2 a run could not be judged (an ``error`` verdict: as ``fretc
    audit``, nothing it could not check supports an answer); 1 a probability requirement
    fails or a requirement without a bound was violated on a run; 130 interrupted; 5 a
    probability requirement undecided; 2 a --rare target without levels; else 0."""
    stats = doc.get("statistics", [])
    if doc.get("errors") or any(s["error"] for s in stats):
        return 2
    if any(s["verdict"] == "fails" or (s["bound"] is None and s["violated"]) for s in stats):
        return 1
    if doc.get("interrupted"):
        return 130
    if any(s["verdict"] == "undecided" for s in stats):
        return 5
    if doc.get("rare", {}).get("errors"):
        return 2
    return 0


def _svg(st: dict) -> str:
    """The test's path as an SVG (matplotlib, fixed ids and no date)."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams["svg.hashsalt"] = "fretc-estimate"
    seq = st["sequential"]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    if seq["test"] == "sprt":
        for key, label in (("path", "log-likelihood ratio"),
                           ("path_fails", "ratio with the unknown trials for the bound")):
            if key not in seq:
                continue
            path = [x if isinstance(x, float) else None for x in seq[key]]
            ax.plot(range(1, len(path) + 1),
                    [x if x is not None else float("nan") for x in path], lw=1.2, label=label)
        ax.axhline(seq["upper"], color="green", lw=0.8, ls="--", label="holds")
        ax.axhline(seq["lower"], color="red", lw=0.8, ls="--", label="fails")
        ax.set_ylabel("log-likelihood ratio")
    else:
        looks = seq["path"]
        if looks:
            n, lo, hi = zip(*looks)
            ax.fill_between(n, lo, hi, alpha=0.3, step="post", label="interval at each look")
        ax.axhline(st["bound"]["p"], color="black", lw=0.8, label="p")
        ax.set_ylabel("P(satisfied trial)")
    ax.set_xlabel("runs")
    b = st["bound"]
    ax.set_title(f"{st['id']}: P(satisfied {st['trial']}) {b['op']} {b['p']:g} -> "
                 f"{st['verdict']}")
    ax.legend(loc="best", fontsize=8)
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    plt.close(fig)
    return buf.getvalue()


def _fmt(x) -> str:
    return "-" if x is None else f"{x:.4g}" if isinstance(x, float) else str(x)


def _markdown(doc: dict) -> tuple[str, list[str]]:
    """The Markdown page and the summary lines printed by the command."""
    lines = [f"# fretc estimate: {doc['space']}", "",
             f"seed {doc['seed']}, budget {doc['budget']}, stopped: {doc.get('stopped', '-')}",
             ""]
    summary = []
    stats = doc.get("statistics", [])
    if stats:
        lines += ["| " + " | ".join(COLUMNS + ("runs", "decided at run")) + " |",
                  "|" + "---|" * (len(COLUMNS) + 2)]
    for s, row in zip(stats, statistics_rows(stats)):
        seq = s.get("sequential") or {}
        lines.append("| " + " | ".join(row + (str(s["runs"]), _fmt(seq.get("at")))) + " |")
        summary.append(summary_line(s))
    errors = doc.get("errors") or []
    if errors:
        first = errors[0]
        text = (f"error: {len(errors)} verdict{'s' if len(errors) != 1 else ''} could not be "
                f"judged, the first run {first['run']}, {first['requirement']}: "
                f"{first['error']}")
        summary.append(text)
        lines += ["", text]
    if stats:
        lines += ["", f"Unknown outcomes: {stats[0]['unknown_policy']} (never counted as "
                  "satisfied). A probability requirement's trials are its triggers (FRET's "
                  "bound is per trigger; `--trial run`: its runs), clustered by run; the "
                  "intervals assume independent runs from the space's distributions "
                  "(docs/guide/statistics.md).", ""]
    for s in stats:
        if s.get("sequential"):
            lines.append(f"![{s['id']}]({_svg_names(doc)[s['id']]})")
    failures = [r for r in doc.get("runs", []) if r["mcap"]]
    if failures:
        lines += ["", "## Example failures", ""]
        for r in failures[:20]:
            viol = [k for k, v in r["verdicts"].items() if v == "violated"]
            params = ", ".join(f"{k}={v:g}" for k, v in r["parameters"].items())
            lines.append(f"- run {r['index']} ({params}): violates {', '.join(viol)}: "
                         f"`{r['mcap']}` (audit: `{r['mcap'][:-5]}.audit.json`)")
        if len(failures) > 20:
            lines.append(f"- ... {len(failures) - 20} more in runs/")
    rare = doc.get("rare")
    if rare:
        lines += ["", "## Rare violations (adaptive multilevel splitting)", "",
                  "| requirement | P(violated) | relative error | interval | levels | runs "
                  "| acceptance |", "|" + "---|" * 7]
        for rid, r in rare["requirements"].items():
            lo, hi = r["interval"]
            lines.append(f"| {rid} | {r['estimate']:.4g} | {_fmt(r['relative_error'])} | "
                         f"[{lo:.4g}, {hi:.4g}] | {len(r['levels'])} | {r['samples']} | "
                         f"{r['acceptance']:.2f} |")
            summary.append(f"{rid}: P(violated) {r['estimate']:.4g} (relative error "
                           f"{_fmt(r['relative_error'])}, interval [{lo:.4g}, {hi:.4g}], "
                           f"{r['samples']} runs)" + (f"; {r['why']}" if r["why"] else ""))
        for rid, why in rare["errors"].items():
            lines.append(f"\n{rid}: no estimate: {why}")
            summary.append(f"{rid}: no estimate: {why}")
    return "\n".join(lines) + "\n", summary


def _svg_names(doc: dict) -> dict[str, str]:
    """Requirement id -> its SVG's file name, distinct even for ids that map to one name
    (:func:`fretc.common.textsafe.file_stems`)."""
    stems = file_stems([s["id"] for s in doc.get("statistics", [])])
    return {rid: stem + ".svg" for rid, stem in stems.items()}


def write_estimate(out: str | Path, result: Estimate | None = None,
                   rare: RareResult | None = None) -> dict:
    """Write ``estimate.json``, ``estimate.md`` and the SVGs (module docstring) for a
    campaign ``result`` (:class:`fretc.sim.estimate.Estimate`) or a ``rare`` result
    (:class:`fretc.sim.rare.RareResult`); returns the JSON document with ``summary_lines`` (the
    command's output) added after writing. Raises ``OSError`` when ``out`` is not
    writable."""
    outp = Path(output_folder(out))
    if result is not None:
        doc = result.to_json()
    else:
        assert rare is not None  # (one of the two is given)
        doc = {"schema": "fretc-estimate/1", "space": rare.space.path, "seed": rare.seed,
               "budget": None, "rare": rare.to_json()}
    doc["exit_code"] = exit_code_of(doc)
    write_file(outp / "estimate.json",
               json.dumps(doc, indent=2, sort_keys=True, allow_nan=False) + "\n")
    for s in doc.get("statistics", []):
        if s.get("sequential"):
            write_file(outp / _svg_names(doc)[s["id"]], _svg(s))
    md, summary = _markdown(doc)
    write_file(outp / "estimate.md", md)
    return dict(doc, summary_lines=summary)
