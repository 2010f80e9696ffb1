"""A log's FRET variables as the audit samples them, written as a CSV trace
(``fretc audit ... --write-csv DIR``): the input of ``fretc audit`` on CSV, of the C
monitors' runner (``fretc --emit c``) and of any other tool.

One file per log, on one clock: the bindings' tick over the topics of every variable of
the audit's requirements (:func:`fretc.signals.sample`: the same sample-and-hold, time base
and warm-up as the audit). Each requirement of an audit has its own clock, from the topics of
its own variables (../shared/DESIGN.md, "Each verdict stands alone"), so a requirement whose
clock starts at another time or tick than the file's (a topic that starts later, a first
message off the tick grid) may get another verdict from the file than from the log:
:func:`clock_notes` names them, from the audit of the same log.

Format (:class:`fretc.logs.csv_source.CsvSource`): a first comment line starting with
:data:`fretc.logs.csv_source.SAMPLED_MARK` (so an audit with binding files reads the columns
as the variables they are, :func:`fretc.audit.checks.csv_bindings`), ``time`` (the tick's
time in seconds, exact) then one column per variable in the requirements' order; booleans
``true``/``false``, numbers as Python prints a float (``nan``, ``inf`` and ``-inf``
included).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import TYPE_CHECKING

from fretc.logs import open_log
from fretc.logs.csv_source import SAMPLED_MARK
from fretc.signals import sample

from fretc.audit.model import AuditPlan
from fretc.audit.passes import restrict

if TYPE_CHECKING:
    from fretc.audit.verdict import LogAudit

__all__ = ["clock_notes", "csv_name", "sampled_variables", "write_sampled_csv"]


def sampled_variables(plan: AuditPlan) -> list[str]:
    """The FRET variables of the plan's requirements that its bindings bind, in order of
    first use."""
    names: list[str] = []
    bound = plan.bindings.variables if plan.bindings is not None else {}
    for r in plan.requirements:
        for v in r.variables:
            if v in bound and v not in names:
                names.append(v)
    return names


def seconds(ns: int) -> str:
    """Integer nanoseconds as exact decimal seconds (``1700000000.1``)."""
    sign = "-" if ns < 0 else ""
    whole, frac = divmod(abs(int(ns)), 1_000_000_000)
    return f"{sign}{whole}" + (f".{frac:09d}".rstrip("0") if frac else "")


def _cell(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(float(value))


def write_sampled_csv(plan: AuditPlan, log_path: str, out: str | os.PathLike
                      ) -> tuple[int, int | None, int | None]:
    """Write the sampled variables of ``log_path`` to the CSV file ``out`` (module
    docstring). Returns ``(ticks, first tick time, last tick time)`` (ns; None without a
    tick).

    Raises:
        SignalError, LogError: the log cannot be read or sampled (as the audit would say).
        ValueError: the plan binds no variable of its requirements (nothing to write)."""
    names = sampled_variables(plan)
    if not names:
        raise ValueError("the requirements' variables have no bindings: nothing to sample")
    assert plan.bindings is not None  # (names are bound)
    bindings = restrict(plan.bindings, names)
    source = open_log(log_path, msg_path=plan.config.msg_path)
    first = last = None
    count = 0
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="", encoding="utf-8") as f:
        f.write(f"{SAMPLED_MARK} of {Path(log_path).name}: the FRET variables as fretc "
                "audit samples them (bindings applied); time in seconds\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time"] + names)
        for tick in sample(source, bindings):
            w.writerow([seconds(tick.time)] + [_cell(tick.values[n]) for n in names])
            first = tick.time if first is None else first
            last = tick.time
            count += 1
    return count, first, last


def clock_notes(log_audit: LogAudit, ticks: int, first: int | None, last: int | None) -> list[str]:
    """The requirements of ``log_audit`` (:class:`fretc.audit.verdict.LogAudit` of the same
    log) whose own clock is not the file's (another first or last tick, or another number
    of ticks): one sentence each."""
    out = []
    for v in log_audit.verdicts:
        if v.verdict == "error":
            continue
        if (v.first_tick_ns, v.last_tick_ns, v.ticks_evaluated) != (first, last, ticks):
            own = (f"{v.ticks_evaluated} ticks from {seconds(v.first_tick_ns)} s"
                   if v.first_tick_ns is not None else "no tick")
            here = f"{ticks} ticks from {seconds(first)} s" if first is not None else "none"
            out.append(f"{v.requirement}: its own clock has {own}, this file {here}; its "
                       "verdict on the file may differ from the log's")
    return out


def csv_name(log_path: str, used: set[str]) -> str:
    """A file name for the CSV of ``log_path``: its stem + ``.csv`` (``_2``, ... when two
    logs share a stem); records it in ``used``."""
    stem = Path(log_path.rstrip("/")).name
    stem = stem.rsplit(".", 1)[0] if "." in stem else stem
    name, k = f"{stem}.csv", 2
    while name in used:
        name, k = f"{stem}_{k}.csv", k + 1
    used.add(name)
    return name
