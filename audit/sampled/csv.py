"""A log's FRET variables as the audit judged them, written as a CSV trace
(``fretc audit ... --write-csv DIR``): the input of ``fretc audit`` on CSV, of the C
monitors' runner (``fretc --emit c``) and of any other tool.

Design notes: ARCHITECTURE.md, `audit/sampled/csv.py`."""

from __future__ import annotations

import csv
import os
from dataclasses import replace
from pathlib import Path
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

from fretc.common.outputs import open_output, output_folder
from fretc.common.problems import SignalError
from fretc.logs.csv.source import (CLOCK_COLUMN, CLOCK_LINE, CUT_CELL, NOT_SAMPLED_LINE,
                                   PER_ENTITY_LINE, SAMPLED_MARK, escape_id)

from fretc.audit.entities.log import entity_of_requirements
from fretc.audit.sampled.clock import SampledClock, pass_cells, seconds
from fretc.audit.log import KeptPasses, audit_keeping_passes
from fretc.audit.model import AuditPlan
from fretc.audit.plan import select_variant
from fretc.audit.passes import clock_key

if TYPE_CHECKING:
    from fretc.audit.model import RequirementPlan
    from fretc.audit.verdict import LogAudit

__all__ = ["SampledClock", "sampled_clocks", "csv_name", "sampled_variables",
           "write_sampled_csv", "pass_cells", "seconds"]


def sampled_variables(plan: AuditPlan) -> list[str]:
    """The FRET variables of the plan's requirements that its bindings bind (per entity or
    not), in order of first use."""
    names: list[str] = []
    bound = ({**plan.bindings.variables, **plan.bindings.per_entity}
             if plan.bindings is not None else {})
    for r in plan.requirements:
        for v in r.variables:
            if v in bound and v not in names:
                names.append(v)
    return names


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
    return SampledClock([r.id], res.times, {n: pass_cells(res, n) for n in names if n in
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


def _rows(clocks: list[SampledClock], names: list[str]) -> Iterator[list[str]]:
    """Every clock's rows (time, [clock,] cells) in time order, then clock order, made one
    at a time (the order sorted once over the ticks' keys, not over rows held)."""
    n = [len(c.times) + (c.cut is not None) for c in clocks]
    if not sum(n):
        return
    times = np.concatenate([np.append(c.times, c.cut).astype(np.int64) if c.cut is not None
                            else c.times.astype(np.int64) for c in clocks])
    which = np.repeat(np.arange(len(clocks), dtype=np.int64), n)
    starts = np.concatenate(([0], np.cumsum(n)[:-1])).astype(np.int64)
    index = np.arange(len(times), dtype=np.int64) - np.repeat(starts, n)
    several = len(clocks) > 1
    for at in np.lexsort((index, which, times)).tolist():
        t, k, i = int(times[at]), int(which[at]), int(index[at])
        c = clocks[k]
        lead = [str(k + 1)] if several else []
        if i < len(c.times):
            yield [seconds(t)] + lead + [c.columns[m][i] if m in c.columns else ""
                                         for m in names]
        else:
            yield [seconds(t)] + lead + [CUT_CELL if m in c.columns else "" for m in names]


def write_sampled_csv(plan: AuditPlan, log_path: str, out: str | os.PathLike
                      ) -> tuple[LogAudit, list[SampledClock]]:
    """Write what the audit of ``log_path`` judged to the CSV file ``out`` (module
    docstring). Returns the log's audit and the clocks written (the per-entity
    requirements' entities' clocks after the others, :attr:`SampledClock.entity_of` set).

    Raises:
        ValueError: the plan binds no variable of its requirements (nothing to write).
        SignalError: the log could not be read (the audit's error).
        OSError: ``out`` cannot be written."""
    from fretc.audit.entities.log import NOT_AUDITED
    from fretc.audit.sampled.entities import entity_blocks

    plan, ent_plan = _split_per_entity(plan, log_path)
    if not sampled_variables(plan) and not sampled_variables(ent_plan) \
            and plan.bindings is not None:
        raise ValueError("the requirements' variables have no bindings: nothing to sample")
    audits: list[LogAudit] = []
    clocks: list[SampledClock] = []
    if plan.requirements or not ent_plan.requirements:
        kept = audit_keeping_passes(plan, log_path)
        plan = kept.plan
        audits.append(kept.audit)
        clocks = sampled_clocks(kept)
        if kept.passes is None and _all_errors(kept.audit) and not ent_plan.requirements:
            raise SignalError(_all_errors(kept.audit)[0])  # nothing read: nothing to write
    blocks: list = []
    if ent_plan.requirements:
        la, blocks = entity_blocks(ent_plan, log_path)
        audits.append(la)
        errors = _all_errors(la)
        if not plan.requirements and errors and all(e.startswith(NOT_AUDITED)
                                                    for e in errors):
            raise SignalError(errors[0][len(NOT_AUDITED):])  # nothing read
    lines = [f"{CLOCK_LINE}{k}: {' '.join(escape_id(i) for i in c.ids)}"
             for k, c in enumerate(clocks, 1)]
    left_out: list[tuple[str, str]] = []
    for b in blocks:
        if b.clock is not None:
            clocks.append(b.clock)
            lines.append(f"{CLOCK_LINE}{len(clocks)}: {escape_id(b.rid)}")
        elif b.entity is None:
            left_out.append((b.rid, b.why or "not judged"))
            continue
        else:
            lines.append(f"{PER_ENTITY_LINE}{escape_id(b.rid)}: {b.entity}")
        for iid, c, why in b.items:
            if c is None:
                lines.append(f"{NOT_SAMPLED_LINE}{escape_id(iid)}: {_one_line(why)}")
            else:
                c.entity_of = b.rid
                clocks.append(c)
                lines.append(f"{CLOCK_LINE}{len(clocks)}: {escape_id(iid)}")
    lines += [f"{NOT_SAMPLED_LINE}{escape_id(rid)}: {_one_line(why)}" for rid, why in left_out]
    names = [n for n in _order(plan) + _order(ent_plan) if any(n in c.columns for c in clocks)]
    names = list(dict.fromkeys(names))
    output_folder(Path(out).parent)
    with open_output(out, "w", newline="") as f:  # (never through a link planted there)
        f.write(f"{SAMPLED_MARK} of {escape_id(Path(log_path).name)}: the FRET variables as fretc "
                "audit judged them (bindings applied), each requirement on its own clock; "
                "time in seconds\n")
        f.writelines(line + "\n" for line in lines)
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["time"] + ([CLOCK_COLUMN] if len(clocks) > 1 else []) + names)
        w.writerows(_rows(clocks, names))
    return _joined(log_path, audits), clocks


def _all_errors(la: LogAudit) -> list[str]:
    """The errors of an audit whose verdicts are all errors (else none)."""
    if not all(v.verdict == "error" for v in la.verdicts):
        return []
    return [e for e in [la.error] + [v.error for v in la.verdicts] if e]


def _one_line(why: str) -> str:
    """``why`` on one line (a comment line of the file)."""
    return " ".join(why.split())


def _joined(path: str, audits: list[LogAudit]) -> LogAudit:
    """One audit of the plain and the per-entity requirements (the log's figures of the
    first)."""
    la = audits[0]
    for other in audits[1:]:
        la.verdicts = la.verdicts + other.verdicts
    return la


def _split_per_entity(plan: AuditPlan, log_path: str) -> tuple[AuditPlan, AuditPlan]:
    """``plan`` (its binding file's variant for ``log_path``, when one selects it) as its
    plain requirements and its per-entity ones (two plans)."""
    if plan.variants:
        sub, _err = select_variant(plan, log_path)
        if sub is None:  # (the audit says why: every verdict an error)
            return plan, replace(plan, requirements=[])
        plan = sub
    groups = entity_of_requirements(plan) if plan.bindings is not None else {}
    return (replace(plan, requirements=[r for r in plan.requirements if r.index not in groups]),
            replace(plan, requirements=[r for r in plan.requirements if r.index in groups]))


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
