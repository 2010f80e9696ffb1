"""The verdict of a per-entity requirement over all its entities (:func:`summary_verdict`:
the universal quantifier over the log's entities, :mod:`fretc.audit.entities.log`) and the note
counting their verdicts (:func:`summary_note`).
"""

from __future__ import annotations

from collections import Counter
from operator import attrgetter
from typing import Any

from fretc.audit.verdict import Verdict

__all__ = ["summary_note", "summary_verdict", "LISTED"]


#: The verdict over all entities: the first of these that some entity has. A violated
#: entity decides it (the universal quantifier is false whatever the others are); else an
#: error or an unjudged entity (past the bound) leaves the whole undecided.
_PRECEDENCE = ("violated", "error", "unknown", "satisfied", "vacuous")


def summary_note(rid: str, name: str, out: list[Verdict]) -> str:
    """The note giving how many of requirement ``rid``'s entities ``name`` have each verdict
    (``R over 3 entities track: 1 violated, 2 satisfied``)."""
    counts = Counter(map(attrgetter("verdict"), out))
    return (f"{rid} over {len(out)} entities {name}: "
            + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))


def summary_verdict(r: Any, path: str, out: list[Verdict], summary: str) -> Verdict:
    """The requirement's verdict over its entities' verdicts ``out`` (every entity satisfies
    it: satisfied; one violates it: violated, with the earliest violation's evidence,
    whatever is left unjudged, which its notes name), named ``r.id``; ``summary`` is
    :func:`summary_note`'s. One pass over ``out`` (100,000 entities: a pass each costs).

    Its robustness is the least of the entities' (the universal quantifier's space
    robustness is the minimum over its instances) only where its sign agrees with the
    verdict (:func:`_agreeing`, the rule of :func:`fretc.audit.finalize._robustness_fields`
    for one trace): violated, a negative margin; satisfied or vacuous, one >= 0; unknown or
    error, none. A violated entity without a margin of its own (a violation at distance 0,
    a sign that disagreed) and satisfied ones with positive margins give no margin, never a
    positive one on a violated verdict)."""
    kinds: set[str] = set()
    first: Verdict | None = None  # (the earliest violation, the first in order among equals)
    margin: float | None = None
    errors: list[str] = []
    unknown: list[str] = []
    violated: list[str] = []
    for x in out:
        kind = x.verdict
        kinds.add(kind)
        if kind == "violated":
            violated.append(x.requirement)
            fv = x.first_violation
            if fv is not None and (first is None or fv.at.time_ns
                                   < first.first_violation.at.time_ns):  # type: ignore[union-attr]  # (first: with one)
                first = x
        elif kind == "unknown":
            unknown.append(f"{x.requirement}: {x.unknown_reason}")
        if x.robustness is not None and (margin is None or x.robustness < margin):
            margin = x.robustness
        if x.error:
            errors.append(f"{x.requirement}: {x.error}")
    verdict = next(k for k in _PRECEDENCE if k in kinds)
    v = Verdict(log=path, requirement=r.id, text=r.text, source=r.source, verdict=verdict)
    if verdict == "violated" and first is not None:
        v.first_violation = first.first_violation
        v.notes.append(f"first violated by {first.requirement}")
    v.robustness = _agreeing(verdict, margin, v.notes)
    listed = _listed(errors)
    if verdict == "error":
        v.error = listed
    elif listed:  # violated all the same: what was not judged is said
        v.notes.append(f"not judged: {listed}")
    if verdict == "unknown":
        v.unknown_reason = _listed(unknown)
    v.partial = any(x.partial for x in out)
    v.notes.append(summary)
    v.notes.append("violated by: " + (_listed(violated, ", ") or "none"))
    return v


def _agreeing(verdict: str, margin: float | None, notes: list[str]) -> float | None:
    """``margin`` (the least of the entities', None: none had one) when its sign agrees with
    ``verdict`` (violated: < 0; satisfied, vacuous: >= 0, NaN never), else None and a note
    saying why; None for an unknown or error verdict (no margin decides it)."""
    if margin is None:
        return None
    if verdict == "violated":
        agrees = margin < 0
    elif verdict in ("satisfied", "vacuous"):
        agrees = margin >= 0
    else:
        notes.append(f"robustness unavailable: the verdict over the entities is {verdict}")
        return None
    if not agrees:
        notes.append(f"robustness unavailable: the least margin of the entities ({margin!r}) "
                     f"disagrees in sign with the verdict over them ({verdict}): the "
                     "entities that decide it have no margin of their own")
        return None
    return margin + 0.0  # (never -0.0)


#: Entities named in the requirement's own error, reason and notes (the rest counted).
LISTED = 20


def _listed(items: list[str], sep: str = "; ") -> str:
    """``items`` joined, the first :data:`LISTED` of them and how many more."""
    more = len(items) - LISTED
    return sep.join(items[:LISTED]) + (f"{sep}and {more} more" if more > 0 else "")

