"""The problems of one log audit: the data problems of every pass kept once each with their
counts (:func:`collect_problems`), the damage met before any pass (a log cut inside its only
chunk: :func:`damage_before_topics`), and why a silent topic gave nothing."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, TYPE_CHECKING

from fretc.common import problems as P
from fretc.common.problems import DataProblem, FretcInputError
from fretc.logs import open_log

if TYPE_CHECKING:
    from fretc.audit.verdict import LogAudit
    from fretc.logs.base import LogSource

__all__ = ["DAMAGE_KINDS", "problem_json", "collect_problems", "silent_reasons", "damage_of",
           "damage_before_topics"]


#: Problem kinds that are damage to the log (not to one message's data).
DAMAGE_KINDS = (P.TRUNCATED, P.CHUNK_CRC, P.CHUNK_CORRUPT, P.CORRUPT_RECORD, P.SUMMARY_CORRUPT,
                P.DATA_CRC, P.UNKNOWN_CHANNEL, P.OUT_OF_ORDER)


def problem_json(p: DataProblem) -> dict:
    """A data problem as the audit JSON lists it (times in ns)."""
    return {"kind": p.kind, "topic": p.topic, "log_time_ns": p.log_time,
            "end_time_ns": p.end_time, "detail": p.detail}


def collect_problems(source: LogSource, sampling: Any, problems: dict[tuple, DataProblem],
                     counts: dict[str, int]) -> None:
    """Add the problems of one pass (the source's and the clock's) to ``problems`` (kept
    once each) and ``counts`` ("kind topic" -> number, including those beyond the cap)."""
    found = list(sampling.problems) if sampling is not None else list(source.problems)
    for p in found:
        problems.setdefault((p.kind, p.topic, p.log_time, p.detail), p)
    for (kind, topic), n in source.problem_counts.items():
        k = f"{kind} {topic or '-'}"
        counts[k] = max(counts.get(k, 0), n)
    if sampling is not None:
        mine: dict[str, int] = {}
        for p in sampling.signal_problems:
            k = f"{p.kind} {p.topic or '-'}"
            mine[k] = mine.get(k, 0) + 1
        for k, n in mine.items():
            counts[k] = max(counts.get(k, 0), n)


def silent_reasons(silent: Iterable[str], problems: Iterable[DataProblem],
                   lost: dict | None = None) -> dict[str, str]:
    """Topic -> why it gave no message: messages present but not decoded (how many, and
    why: a schema or encoding that cannot be read, payloads that do not deserialize), or
    none in the log. ``lost``: the source's :attr:`fretc.logs.LogSource.lost`."""
    kinds = (P.UNKNOWN_SCHEMA, P.UNKNOWN_ENCODING, P.UNDECODABLE)
    out = {}
    for t in silent:
        n = sum(v[2] for (_k, topic, _c), v in (lost or {}).items() if topic == t)
        why = next((f"{kind}: {v[3]}" for (kind, topic, _c), v in sorted(
            (lost or {}).items(), key=lambda kv: kv[1][0]) if topic == t), None)
        detail = why or next((f"{p.kind}: {p.detail}" for p in problems
                              if p.topic == t and p.kind in kinds), None)
        if n:
            out[t] = (f"{n} message{'s' if n != 1 else ''} of {t} could not be decoded "
                      f"({detail}); none was read")
        elif detail:
            out[t] = f"topic {t} cannot be read ({detail})"
        else:
            out[t] = f"topic {t} has no message in the log"
    return out


def damage_of(path: str, la: LogAudit) -> str | None:
    """Open ``path`` and read its topics; when that meets damage, mark ``la`` partial and
    return the reason (:func:`damage_before_topics`), else None (also when it cannot be
    opened at all: that is an input error, not damage)."""
    try:
        source = open_log(path)
        source.topics()
    except (FretcInputError, OSError):
        return None
    return damage_before_topics(source, la)


def damage_before_topics(source: LogSource, la: LogAudit) -> str | None:
    """When finding the log's topics met damage (a log cut inside its only chunk, say): mark
    ``la`` partial with the problems, and return the reason in words (else None).
    The reason for the damage is kept even when nothing readable is left."""
    if not source.partial:
        return None
    la.partial = True
    la.damage_time_ns = source.damage_time
    la.damage_cut = bool(source.damage_cut)
    probs = [p for p in source.problems if p.kind in DAMAGE_KINDS]
    la.problems = [problem_json(p) for p in source.problems]
    la.problem_counts = {f"{k} {t or '-'}": n for (k, t), n in sorted(
        source.problem_counts.items(), key=lambda kv: (kv[0][0], kv[0][1] or ""))}
    if not probs:
        return "the log is damaged"
    return "the log is damaged: " + "; ".join(str(p) for p in probs[:3])

