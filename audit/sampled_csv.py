"""A log's FRET variables as the audit judged them, written as a CSV trace
(``fretc audit ... --write-csv DIR``): the input of ``fretc audit`` on CSV, of the C
monitors' runner (``fretc --emit c``) and of any other tool.

One file per log holding every requirement's own clock (../shared/DESIGN.md, "Each verdict
stands alone"): the ticks the audit of the log judged, with the values of the requirement's
variables there (the same sample-and-hold, time base, warm-up and gaps; written from the
audit's own columns, :func:`fretc.audit.log.audit_keeping_passes`), so that the audit of
the file and the C runner on it judge what the audit of the log judged. Requirements whose
clocks agree (the same ticks, the same values of the variables they share) share one clock
of the file.

Format (:class:`fretc.logs.csv_source.CsvSource`):

* a first comment line starting with :data:`~fretc.logs.csv_source.SAMPLED_MARK` (so an
  audit with binding files reads the columns as the variables they are,
  :func:`fretc.audit.checks.csv_bindings`), then one line
  ``# fretc clock N: R1 R2`` per clock naming the requirements judged on it
  (:func:`~fretc.logs.csv_source.escape_id`), and one line ``# fretc not sampled: T: why``
  per requirement left out (a per-entity requirement: a value per entity at each tick);
* a header: ``time`` (the tick's time in seconds, exact), with several clocks ``tick`` (the
  row's clock N), then one column per variable in the requirements' order; one row per tick
  of each clock, in time order; a row's cells of the variables of other clocks are empty;
* cells: booleans ``true``/``false``, numbers as Python prints a float (``nan``, ``inf`` and
  ``-inf`` included); ``unknown`` where a gap of the log left the variable unknown; a row of
  ``gap`` cells for a tick standing for the ticks a gap of the tick topic lost; a last row of
  ``cut`` cells at the time the log's damage ends the span read (only the ticks before it
  were judged).

A requirement judged without ticks (``unknown`` because the damage may have taken its
topic) has a clock of one ``cut`` row; one whose audit is an error, and a per-entity one,
have no clock (an error on the file too, saying why).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fretc.common.problems import SignalError
from fretc.logs.csv_source import (CLOCK_COLUMN, CLOCK_LINE, CUT_CELL, GAP_CELL,
                                   NOT_SAMPLED_LINE, SAMPLED_MARK, UNKNOWN_CELL, escape_id)

from fretc.audit.entities import entity_of_requirements
from fretc.audit.log import KeptPasses, audit_keeping_passes, per_entity_refusal
from fretc.audit.model import AuditPlan
from fretc.audit.plan import select_variant
from fretc.audit.passes import ClockPass, clock_key

if TYPE_CHECKING:
    from fretc.audit.model import RequirementPlan
    from fretc.audit.verdict import LogAudit

__all__ = ["SampledClock", "sampled_clocks", "csv_name", "sampled_variables",
           "write_sampled_csv"]


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


@dataclass
class SampledClock:
    """One clock of a sampled trace.

    Attributes:
        ids: the requirements judged on it.
        times: its tick times (ns).
        columns: variable -> its cells, one per tick (text, marks included).
        cut: the time (ns) where the damage ends the span read, or None.
    """

    ids: list[str]
    times: np.ndarray
    columns: dict[str, list[str]] = field(default_factory=dict)
    cut: int | None = None

    def agrees(self, other: SampledClock) -> bool:
        """The same ticks and cut, and the same cells of the variables both have."""
        return (self.cut == other.cut and np.array_equal(self.times, other.times)
                and all(self.columns[n] == other.columns[n]
                        for n in self.columns.keys() & other.columns.keys()))


def _cells(res: ClockPass, name: str) -> list[str]:
    """The cells of variable ``name`` over the ticks of ``res``: values, ``unknown`` where a
    gap leaves it unknown, ``gap`` at the ticks standing for a gap's lost ticks."""
    col = res.columns[name]
    if col.dtype == np.bool_:
        out = ["true" if x else "false" for x in col.tolist()]
    else:
        out = [repr(float(x)) for x in col.tolist()]
    mask = res.unknown.get(name)
    if mask is not None:
        for i in np.flatnonzero(mask[:len(out)]).tolist():
            out[i] = UNKNOWN_CELL
    for i in res.tick_gaps:
        if i < len(out):
            out[i] = GAP_CELL
    return out


def _own_clock(kept: KeptPasses, r: RequirementPlan) -> SampledClock | None:
    """What ``r`` was judged on (None: nothing, its verdict an error)."""
    v = dict(zip((x.index for x in kept.plan.requirements), kept.audit.verdicts))[r.index]
    if v.verdict == "error":
        return None
    names = [n for n in r.variables if kept.bindings is None or n in kept.bindings.variables]
    res = (kept.passes.passes.get(clock_key(r, kept.bindings))
           if kept.passes is not None else None)
    if r.index in kept.unjudged or res is None:  # unknown before its ticks were judged
        at = kept.audit.start_time_ns if kept.audit.start_time_ns is not None else 0
        return SampledClock([r.id], np.zeros(0, np.int64), {n: [] for n in names}, at)
    return SampledClock([r.id], res.times, {n: _cells(res, n) for n in names if n in
                                            res.columns}, res.intact_end)


def sampled_clocks(kept: KeptPasses) -> list[SampledClock]:
    """The clocks of a log's audit (:func:`fretc.audit.log.audit_keeping_passes`), those
    that agree merged (:meth:`SampledClock.agrees`), in the requirements' order."""
    out: list[SampledClock] = []
    for r in kept.plan.requirements:
        own = _own_clock(kept, r)
        if own is None:
            continue
        for c in out:
            if c.agrees(own):
                c.ids.append(r.id)
                for n, cells in own.columns.items():
                    c.columns.setdefault(n, cells)
                break
        else:
            out.append(own)
    return out


def _rows(clocks: list[SampledClock], names: list[str]) -> list[list[str]]:
    """Every clock's rows (time, [clock,] cells) in time order, then clock order."""
    keyed = []
    for k, c in enumerate(clocks, 1):
        lead = [str(k)] if len(clocks) > 1 else []
        for i, t in enumerate(c.times.tolist()):
            cells = [c.columns[n][i] if n in c.columns else "" for n in names]
            keyed.append((int(t), k, i, [seconds(t)] + lead + cells))
        if c.cut is not None:
            cells = [CUT_CELL if n in c.columns else "" for n in names]
            keyed.append((c.cut, k, len(c.times), [seconds(c.cut)] + lead + cells))
    keyed.sort(key=lambda x: x[:3])
    return [row for *_k, row in keyed]


def write_sampled_csv(plan: AuditPlan, log_path: str, out: str | os.PathLike
                      ) -> tuple[LogAudit, list[SampledClock]]:
    """Write what the audit of ``log_path`` judged to the CSV file ``out`` (module
    docstring). Returns the log's audit and the clocks written.

    Per-entity requirements (a value of a variable per entity at each tick, where a column
    has one) are left out, each named on a :data:`~fretc.logs.csv_source.NOT_SAMPLED_LINE`
    with why, so the audit of the file gives them an error that says so.

    Raises:
        ValueError: the plan binds no variable of its requirements (nothing to write), or
            all of its requirements are per-entity.
        SignalError: the log could not be read (the audit's error).
        OSError: ``out`` cannot be written."""
    plan, left_out = _without_per_entity(plan, log_path)
    if not sampled_variables(plan) and plan.bindings is not None:
        raise ValueError("the requirements' variables have no bindings: nothing to sample")
    kept = audit_keeping_passes(plan, log_path)
    errors = [e for e in [kept.audit.error] + [v.error for v in kept.audit.verdicts] if e]
    if kept.passes is None and errors and all(v.verdict == "error"
                                              for v in kept.audit.verdicts):
        raise SignalError(errors[0])  # nothing read: nothing to write
    clocks = sampled_clocks(kept)
    names = [n for n in _order(kept.plan) if any(n in c.columns for c in clocks)]
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="", encoding="utf-8") as f:
        f.write(f"{SAMPLED_MARK} of {escape_id(Path(log_path).name)}: the FRET variables as fretc "
                "audit judged them (bindings applied), each requirement on its own clock; "
                "time in seconds\n")
        for k, c in enumerate(clocks, 1):
            f.write(f"{CLOCK_LINE}{k}: {' '.join(escape_id(i) for i in c.ids)}\n")
        for rid, why in left_out.items():
            f.write(f"{NOT_SAMPLED_LINE}{escape_id(rid)}: {why}\n")
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time"] + ([CLOCK_COLUMN] if len(clocks) > 1 else []) + names)
        w.writerows(_rows(clocks, names))
    return kept.audit, clocks


def _without_per_entity(plan: AuditPlan, log_path: str) -> tuple[AuditPlan, dict[str, str]]:
    """``plan`` (its binding file's variant for ``log_path``, when one selects it) without
    its per-entity requirements, and their ids -> why they are left out.

    Raises:
        ValueError: every requirement is per-entity (nothing to write)."""
    if plan.variants:
        sub, _err = select_variant(plan, log_path)
        if sub is None:  # (the audit says why: every verdict an error)
            return plan, {}
        plan = sub
    groups = entity_of_requirements(plan)
    if not groups or plan.bindings is None:
        return plan, {}
    why = per_entity_refusal(plan.bindings)
    rest = [r for r in plan.requirements if r.index not in groups]
    if not rest:
        raise ValueError(why)
    return (replace(plan, requirements=rest),
            {r.id: why for r in plan.requirements if r.index in groups})


def _order(plan: AuditPlan) -> list[str]:
    """Every variable of the plan's requirements, in order of first use."""
    out: list[str] = []
    for r in plan.requirements:
        out += [v for v in r.variables if v not in out]
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
