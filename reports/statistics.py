"""The fleet statistics in the terminal (``fretc audit`` of several logs, ``fretc estimate``):
one row per requirement: runs of each verdict, what one trial is (a trigger or a run), the
triggers per run, the estimate, its interval and, for a probability requirement, the bound
and its statistical verdict (:mod:`fretc.audit.fleet.statistics`)."""

from __future__ import annotations

from typing import TYPE_CHECKING
from rich.table import Table
from rich.markup import escape

if TYPE_CHECKING:
    from rich.console import Console

__all__ = ["print_statistics", "statistics_rows", "summary_line", "COLUMNS", "per_run"]

_STYLE = {"holds": "green", "fails": "red", "undecided": "yellow"}
#: the table's columns
COLUMNS = ("requirement", "trial", "sat", "vac", "viol", "unk", "err", "triggers/run",
           "estimate", "interval", "bound", "verdict")


def per_run(st: dict) -> str:
    """The triggers per run of a statistics object (``min-max``, mean), or ``-``."""
    t = st.get("triggers_per_run")
    if not t:
        return "-"
    lo, hi = t["min"], t["max"]
    span = f"{lo}" if lo == hi else f"{lo}-{hi}"
    return f"{span} (mean {t['mean']:.3g})" if lo != hi else span


def statistics_rows(stats: list) -> list[tuple[str, ...]]:
    """The table's rows as plain text, one per statistics object (the audit JSON's, or
    :class:`fretc.audit.fleet.statistics.RequirementStatistics`), in :data:`COLUMNS`' order."""
    rows: list[tuple[str, ...]] = []
    for st in stats:
        s = st if isinstance(st, dict) else st.to_json()
        lo, hi = s["interval"]
        est = "-" if s["estimate"] is None else f"{s['estimate']:.4g}"
        bound = "" if s["bound"] is None else f"{s['bound']['op']} {s['bound']['p']:g}"
        rows.append((s["id"], s["trial"], str(s["satisfied"]), str(s["vacuous"]),
                     str(s["violated"]), str(s["unknown"]), str(s["error"]), per_run(s),
                     est, f"[{lo:.4g}, {hi:.4g}]", bound, s["verdict"] or ""))
    return rows


def summary_line(s: dict) -> str:
    """One sentence of a statistics object: the estimate of the probability of a satisfied
    trial, its interval, the trials behind it, the bound and verdict (and why)."""
    lo, hi = s["interval"]
    est = "-" if s["estimate"] is None else f"{s['estimate']:.4g}"
    unit = s["trial"]
    seen = f"{s['trials']} {unit}{'s' if s['trials'] != 1 else ''}"
    if unit == "trigger":
        seen += f" of {s['runs']} run{'s' if s['runs'] != 1 else ''}"
    if s.get("unknown_trials"):
        seen += f", {s['unknown_trials']} of unknown outcome"
    text = (f"{s['id']}: P(satisfied {unit}) {est} in [{lo:.4g}, {hi:.4g}] "
            f"({100 * s['confidence']:g} %, {seen})")
    if s["error"]:
        text += f"; {s['error']} run{'s' if s['error'] != 1 else ''} not judged (error)"
    b = s["bound"]
    if b is not None:
        text += f"; {b['op']} {b['p']:g}: {s['verdict']}"
        if s["why"]:
            text += f" ({s['why']})"
    return text


def print_statistics(console: Console, stats: list) -> None:
    """Print the table of ``stats`` to the rich ``console``, then a line per undecided
    requirement saying why, and the unknown-outcome policy and confidence used."""
    if not stats:
        return
    conf = stats[0].confidence
    t = Table(title=f"Fleet statistics ({stats[0].runs} runs, {100 * conf:g} % "
                    "Clopper-Pearson intervals, triggers clustered by run; unknown outcomes: "
                    f"{stats[0].unknown_policy})", title_justify="left")
    for col in COLUMNS:
        t.add_column(col, justify="left" if col in ("requirement", "trial", "interval",
                                                     "triggers/run") else "right")
    for row in statistics_rows(stats):
        verdict = row[-1]
        shown = f"[{_STYLE[verdict]}]{verdict}[/]" if verdict else ""
        t.add_row(*(escape(x) for x in row[:-1]), shown)
    console.print(t)
    for st in stats:
        if st.verdict == "undecided" and st.why:
            console.print(f"[yellow]{escape(st.id)} undecided:[/yellow] {escape(st.why)}")
