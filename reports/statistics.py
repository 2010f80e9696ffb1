"""The fleet statistics in the terminal (``fretc audit`` of several logs, ``fretc estimate``):
one row per requirement: runs of each verdict, the estimate of P(satisfied), its
Clopper-Pearson interval and, for a probability requirement, the bound and its statistical
verdict (:mod:`fretc.audit.statistics`)."""

from __future__ import annotations

from rich.table import Table
from rich.markup import escape

__all__ = ["print_statistics", "statistics_rows"]

_STYLE = {"holds": "green", "fails": "red", "undecided": "yellow"}


def statistics_rows(stats: list) -> list[tuple[str, ...]]:
    """The table's rows as plain text: ``(id, sat, vac, viol, unknown+error, estimate,
    interval, bound, verdict)``, one per :class:`fretc.audit.statistics.RequirementStatistics`."""
    rows = []
    for st in stats:
        lo, hi = st.interval
        est = "-" if st.estimate is None else f"{st.estimate:.4g}"
        bound = "" if st.bound is None else f"{st.bound['op']} {st.bound['p']:g}"
        rows.append((st.id, str(st.satisfied), str(st.vacuous), str(st.violated),
                     str(st.unknown + st.error), est, f"[{lo:.4g}, {hi:.4g}]", bound,
                     st.verdict or ""))
    return rows


def print_statistics(console, stats: list) -> None:
    """Print the table of ``stats`` to the rich ``console``, then a line per undecided
    requirement saying why, and the unknown-run policy and confidence used."""
    if not stats:
        return
    conf = stats[0].confidence
    t = Table(title=f"Fleet statistics ({stats[0].runs} runs, {100 * conf:g} % Clopper-Pearson "
                    f"intervals, unknown runs: {stats[0].unknown_policy})",
              title_justify="left")
    for col in ("requirement", "sat", "vac", "viol", "unk/err", "P(sat)", "interval", "bound",
                "verdict"):
        t.add_column(col, justify="left" if col in ("requirement", "interval") else "right")
    for row in statistics_rows(stats):
        verdict = row[-1]
        shown = f"[{_STYLE[verdict]}]{verdict}[/]" if verdict else ""
        t.add_row(*(escape(x) for x in row[:-1]), shown)
    console.print(t)
    for st in stats:
        if st.verdict == "undecided" and st.why:
            console.print(f"[yellow]{escape(st.id)} undecided:[/yellow] {escape(st.why)}")
