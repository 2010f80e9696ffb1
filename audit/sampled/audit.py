"""The audit of a sampled trace of several clocks (:func:`audit_clocks`): the CSV that
``fretc audit --write-csv`` writes (:mod:`fretc.audit.sampled.csv`) names, in its
``# fretc clock N: ...`` lines, the requirements judged on each clock of the log; each
requirement is audited on its own clock's rows alone, as it was on the log
(../shared/DESIGN.md, "Each verdict stands alone"), and a requirement no clock names is an
error (the trace does not carry its ticks; a ``# fretc not sampled`` line says why).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from fretc.audit.entities.log import entity_of_requirements
from fretc.audit.model import AuditPlan
from fretc.audit.verdict import LogAudit, Verdict
from fretc.common.problems import CsvError, LogError
from fretc.logs.csv.source import CsvSource, SampledHeader

__all__ = ["audit_clocks"]


def audit_clocks(plan: AuditPlan, path: str, head: SampledHeader,
                 run: Callable[[AuditPlan, str], LogAudit]) -> LogAudit:
    """Audit the sampled trace ``path`` whose comment lines say ``head`` (its clocks,
    label -> requirement ids; the requirements it does not carry; its per-entity ones:
    :func:`fretc.logs.csv.source.sampled_header`).

    Args:
        plan: the audit plan (requirements matched to clocks by id).
        run: audits a plan on one clock's rows (``run(sub_plan, label)``).

    Returns:
        One :class:`~fretc.audit.verdict.LogAudit`: the verdicts in the plan's order, each
        from its clock's audit, the per-entity requirements' after the others as the audit
        of the log gives them (each its verdict over its entities, then one per entity,
        :mod:`fretc.audit.sampled.entities`); the log's figures merged over the clocks.
    """
    clocks = head.clocks
    entities = {rid: ent for rid, ent in head.per_entity.items()
                if any(r.id == rid for r in plan.requirements)}
    owner = {rid: label for label, ids in clocks.items() for rid in ids}
    instance_of = {i: rid for rid, (_n, ids) in entities.items() for i in ids}
    parts: list[LogAudit] = []
    verdicts: dict[str, Verdict] = {}
    for label, ids in clocks.items():
        rs = [r for r in plan.requirements if owner.get(r.id) == label and r.id not in entities]
        rs += [replace(r, id=i) for i in ids if i in instance_of
               for r in plan.requirements if r.id == instance_of[i]]
        if not rs:
            continue
        # (binding files selecting logs by name: the trace's columns are the variables)
        sub = replace(plan, requirements=rs, variants=[],
                      bindings=None if plan.variants else plan.bindings)
        la = run(sub, label)
        parts.append(la)
        for r, v in zip(rs, la.verdicts):
            verdicts[r.id] = v
    merged = _merge(path, parts)
    if not parts:  # no clock judged: the file is still read, and refused if it is bad
        try:
            CsvSource(path)
        except (CsvError, LogError) as exc:
            merged.error = str(exc)
            return _all_error(plan, path, merged, f"log not audited: {exc}")
    named = ", ".join(sorted(i for i in owner if i not in instance_of)) or "none"
    left_out = head.not_sampled
    # (the log's audit gives the per-entity requirements after the others, those it judged
    # as a whole too: an error, or unknown before any tick)
    groups = entity_of_requirements(plan) if plan.bindings is not None else {}
    later = set(entities) | {r.id for r in plan.requirements if r.index in groups}
    out: list[Verdict] = []
    for r in [r for r in plan.requirements if r.id not in later] + [
            r for r in plan.requirements if r.id in later]:
        if r.id in entities:
            out += _per_entity(r, path, entities[r.id], verdicts, left_out)
            continue
        got = verdicts.get(r.id)
        if got is None:
            why = r.error or (f"{path} is a sampled trace (fretc audit --write-csv) that "
                              f"carries no clock of {r.id}: " + (
                                  f"not sampled: {left_out[r.id]}" if r.id in left_out else
                                  f"it holds the clocks of {named} (a requirement the audit "
                                  "of the log could not judge has none)"))
            got = _error(r, path, why)
        out.append(got)
    merged.verdicts = out
    return merged


def _all_error(plan: AuditPlan, path: str, la: LogAudit, why: str) -> LogAudit:
    """``la`` with every requirement of ``plan`` an error saying ``why``."""
    la.verdicts = [_error(r, path, r.error or why) for r in plan.requirements]
    return la


def _error(r, path: str, why: str, rid: str | None = None) -> Verdict:
    return Verdict(log=path, requirement=rid or r.id, text=r.text, source=r.source,
                   notes=list(r.notes), verdict="error", error=why)


def _per_entity(r, path: str, entity: tuple[str, list[str]], verdicts: dict[str, Verdict],
                left_out: dict[str, str]) -> list[Verdict]:
    """A per-entity requirement's verdicts from its entities' clocks: its verdict over them
    (:func:`fretc.audit.entities.summary.summary_verdict`), then theirs in the file's order."""
    from fretc.audit.entities.summary import summary_note, summary_verdict

    name, ids = entity
    if r.error:
        return [_error(r, path, r.error)]
    if not ids:
        return [Verdict(log=path, requirement=r.id, text=r.text, source=r.source,
                        notes=[*r.notes, f"no entity {name} appeared in the log: the "
                               "requirement holds of none"], verdict="vacuous")]
    out = [verdicts.get(i) or _error(r, path, left_out.get(i) or f"no clock of {i} in "
                                     f"{path}", rid=i) for i in ids]
    # (the entities past --max-entities, ``R[track=...]``, are not counted among them)
    summary = summary_note(r.id, name, [v for v in out if not v.requirement.endswith("=...]")])
    for v in out:
        v.notes.append(summary)
    return [summary_verdict(r, path, out, summary)] + out


def _merge(path: str, parts: list[LogAudit]) -> LogAudit:
    """The log's figures over the audits of its clocks."""
    la = LogAudit(log=path, kind="csv")
    if not parts:
        return la
    first = parts[0]
    la.tick, la.time_base = first.tick, first.time_base
    la.partial = any(p.partial for p in parts)
    la.damage_cut = any(p.damage_cut for p in parts)
    la.damage_time_ns = _least(p.damage_time_ns for p in parts)
    la.cut_time_ns = _least(p.cut_time_ns for p in parts)
    la.start_time_ns = _least(p.start_time_ns for p in parts)
    la.first_time_ns = _least(p.first_time_ns for p in parts)
    ends = [p.end_time_ns for p in parts if p.end_time_ns is not None]
    la.end_time_ns = max(ends) if ends else None
    la.ticks_evaluated = max(p.ticks_evaluated for p in parts)
    la.warmup_ticks = max(p.warmup_ticks for p in parts)
    la.ticks_after_damage = max(p.ticks_after_damage for p in parts)
    la.waiting_for = sorted({t for p in parts for t in p.waiting_for})
    la.missing_topics = sorted({t for p in parts for t in p.missing_topics})
    for p in parts:
        for topic, n in p.messages.items():
            la.messages[topic] = la.messages.get(topic, 0) + n
        for k, n in p.problem_counts.items():
            la.problem_counts[k] = la.problem_counts.get(k, 0) + n
        la.problems += p.problems
        la.gaps += [g for g in p.gaps if g not in la.gaps]
        la.warnings += [w for w in p.warnings if w not in la.warnings]
    errors = [p.error for p in parts if p.error]
    la.error = errors[0] if len(errors) == len(parts) else None
    engines = sorted({p.engine for p in parts if p.engine is not None})
    la.engine = engines[0] if len(engines) == 1 else ("mixed" if engines else None)
    return la


def _least(values) -> int | None:
    got = [x for x in values if x is not None]
    return min(got) if got else None
