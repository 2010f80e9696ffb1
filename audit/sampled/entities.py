"""The per-entity requirements of a log as ``fretc audit --write-csv`` writes them
(:mod:`fretc.audit.sampled.csv`): each entity of a requirement judged on its own clock
(docs/bindings.md, "One verdict per entity": its life's ticks), so each entity is a clock of
the file named by the entity's verdict (``# fretc clock 9: R[track=7]``), and the audit of
the file and the C runner judge each entity on its clock's rows, then the requirement over
its entities as the audit of the log does (:func:`fretc.audit.entities.summary.summary_verdict`).

Design notes: ARCHITECTURE.md, `audit/sampled/entities.py`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from fretc.audit.entities.log import entity_of_requirements, entity_passes
from fretc.audit.sampled.clock import SampledClock, pass_cells
from fretc.audit.verdict import LogAudit

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan

__all__ = ["EntityBlock", "entity_blocks"]


@dataclass
class EntityBlock:
    """One per-entity requirement of a sampled trace.

    Attributes:
        rid: the requirement's id.
        entity: the entity's name (``track``), or None when the requirement is written as a
            plain one (judged as a whole: ``clock`` or ``why``).
        items: per entity, in the log's audit's order: (the entity's verdict's name
            ``R[track=7]``, its clock or None, why it has none).
        clock: a plain requirement's clock (a ``cut`` row: ``unknown`` before its ticks).
        why: a plain requirement's error (a not-sampled line).
    """

    rid: str
    entity: str | None
    items: list[tuple[str, SampledClock | None, str]] = field(default_factory=list)
    clock: SampledClock | None = None
    why: str | None = None


def entity_blocks(plan: AuditPlan, path: str) -> tuple[LogAudit, list[EntityBlock]]:
    """The per-entity requirements of ``plan`` (all of its requirements must be) on the
    log at ``path``: the log's audit of them and one :class:`EntityBlock` each, in the
    plan's order; every entity judged alone (:func:`fretc.audit.entities.log.entity_passes`)."""
    groups = entity_of_requirements(plan)

    def keep(r, res) -> SampledClock:  # (each entity's pass dropped once its cells are)
        return SampledClock([], res.times, {n: pass_cells(res, n) for n in r.variables
                                            if n in res.columns}, res.intact_end)

    la, clocks = entity_passes(plan, path, keep)
    by_id: dict[str, list] = {}
    for v in la.verdicts:
        owner = v.requirement.split("[", 1)[0] if "[" in v.requirement else v.requirement
        by_id.setdefault(owner, []).append(v)
    out: list[EntityBlock] = []
    for r in plan.requirements:
        vs = [v for v in by_id.get(r.id, []) if v.requirement == r.id
              or v.requirement.startswith(f"{r.id}[")]
        names = list(r.variables)
        if len(vs) == 1 and vs[0].requirement == r.id and not (
                vs[0].verdict == "vacuous" and vs[0].notes
                and vs[0].notes[0].startswith(f"no entity {groups[r.index][0]} ")):
            v = vs[0]
            if v.verdict == "error":
                out.append(EntityBlock(r.id, None, why=v.error or "not judged"))
            else:  # unknown before any tick: the damage may have taken its topic
                at = la.start_time_ns if la.start_time_ns is not None else 0
                out.append(EntityBlock(r.id, None, clock=SampledClock(
                    [r.id], np.zeros(0, np.int64), {n: [] for n in names}, at)))
            continue
        block = EntityBlock(r.id, groups[r.index][0])
        for v in vs[1:]:  # (the first is the requirement's summary)
            c = clocks.get(v.requirement)
            if c is None or v.verdict == "error":
                block.items.append((v.requirement, None, v.error or v.unknown_reason
                                    or "not judged"))
                continue
            c.ids.append(v.requirement)
            block.items.append((v.requirement, c, ""))
        out.append(block)
    return la, out
