"""The gaps of a watched run, carried by its recording (``fretc watch --record``), and the
damage of a recording a shield was replayed over, carried by the shielded recording
(``fretc shield-replay``: :data:`REPLAY_LIBRARY`).

Design notes: ARCHITECTURE.md, `logs/recorded_gaps.py`."""

from __future__ import annotations

import json
from collections.abc import Sequence

from fretc.common.problems import DataProblem
from fretc.logs.base import Gap

__all__ = ["GAPS_METADATA", "LEFT_FOR_GOOD", "PUBLISHER_ABSENT", "SILENT_CAUSES", "RUN_END",
           "WATCH_LIBRARY", "REPLAY_LIBRARY", "GAP_LIBRARIES", "gaps_json", "parse_gaps", "read_recorded_gaps", "first_start",
           "gap_problems", "losses"]

#: The cause of the gap of a topic whose publisher left the run for good while the run went
#: on: to the end of the run (:data:`RUN_END`), and no cut of the log (the other topics were
#: read: :func:`fretc.audit.passes.mark_gaps`)
LEFT_FOR_GOOD = "publisher_left_for_good"
#: The cause of a topic's span without a publisher that came back, over a transport whose
#: subscription stays while the publisher is away (DDS, Zenoh: the reader is matched with
#: the new writer as soon as it appears): nothing was sent in it and nothing was lost
PUBLISHER_ABSENT = "publisher_absent"
#: The causes of a silence, not a loss: spans in which a topic had no publisher, so no
#: message of it was sent. The values it last sent are unknown in them (never held over: a
#: requirement over them is not judged on stale values), but the time since its last
#: message is known (``age(/topic)`` reads only that: a staleness requirement is judged),
#: and the log is not damaged by them: what the watch received is whole
#: (:func:`fretc.audit.gaps.unknown_masks`)
SILENT_CAUSES = frozenset({LEFT_FOR_GOOD, PUBLISHER_ABSENT})
#: The end of a gap that lasts to the end of the run: past every tick of the run
RUN_END = 2**63 - 1
#: The name of the Metadata record of a recording's gaps
GAPS_METADATA = "fretc.watch_gaps"
#: The Header library of a watch's recording (only such files carry the record)
WATCH_LIBRARY = "fretc watch"
#: The Header library of a shielded recording (``fretc shield-replay``)
REPLAY_LIBRARY = "fretc shield-replay"
#: The Header libraries whose files may carry the record, and what lost their messages (in
#: the data problem of each gap)
GAP_LIBRARIES = {WATCH_LIBRARY: "the watch that recorded this log lost messages here (its "
                                "gaps are recorded in the log)",
                 REPLAY_LIBRARY: "the recording this shielded run was replayed from is "
                                 "damaged here: nothing from here on was replayed (the damage "
                                 "is recorded in the log)"}
#: Gaps read from one record at most (a watch keeps fewer problems than this)
MAX_GAPS = 100_000
_INT64 = (-(2**63), 2**63 - 1)


def gaps_json(gaps: Sequence[Gap]) -> str:
    """The JSON text of ``gaps`` (in order), as :func:`parse_gaps` reads it."""
    return json.dumps([{"start": g.start, "end": g.end,
                        "topics": None if g.topics is None else sorted(g.topics),
                        "cause": g.cause} for g in gaps], separators=(",", ":"))


def parse_gaps(text: str) -> list[Gap]:
    """The gaps of :func:`gaps_json`'s ``text``.

    Raises:
        ValueError: not that shape (not JSON, a member missing or of another type, a log
            time outside int64 or an end before its start, more than :data:`MAX_GAPS`),
            naming the entry."""
    try:
        doc = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise ValueError(f"not JSON ({exc})") from None
    if not isinstance(doc, list) or len(doc) > MAX_GAPS:
        raise ValueError(f"not a list of at most {MAX_GAPS:,} gaps")
    out = []
    for k, g in enumerate(doc):
        if not isinstance(g, dict) or set(g) != {"start", "end", "topics", "cause"}:
            raise ValueError(f"gap {k}: not an object of start, end, topics and cause")
        start, end, topics, cause = g["start"], g["end"], g["topics"], g["cause"]
        for name, x in (("start", start), ("end", end)):
            if x is not None and (type(x) is not int or not _INT64[0] <= x <= _INT64[1]):
                raise ValueError(f"gap {k}: {name} is not a log time in ns: {x!r}")
        if end is None or (start is not None and end < start):
            raise ValueError(f"gap {k}: its end {end!r} is not a log time at or after its "
                             f"start {start!r}")
        if topics is not None and (not isinstance(topics, list) or not all(
                isinstance(t, str) for t in topics)):
            raise ValueError(f"gap {k}: topics is not a list of topic names")
        if not isinstance(cause, str):
            raise ValueError(f"gap {k}: cause is not a string")
        out.append(Gap(start, end, None if topics is None else frozenset(topics), cause))
    return out


def read_recorded_gaps(path: str) -> list[Gap]:
    """The gaps of the MCAP file ``path``'s :data:`GAPS_METADATA` record, read through its
    summary's MetadataIndex by the ``mcap`` library; none when it has no such record.

    Raises:
        ValueError: the record cannot be read (more than one, other entries, or
            :func:`parse_gaps`'s refusals), in words naming it."""
    from mcap.reader import make_reader

    try:
        with open(path, "rb") as f:
            found = [m.metadata for m in make_reader(f).iter_metadata()
                     if m.name == GAPS_METADATA]
        if not found:
            return []
        if len(found) > 1 or set(found[0]) != {"gaps"}:
            raise ValueError(f"{len(found)} records, or entries other than 'gaps'")
        return parse_gaps(found[0]["gaps"])
    except Exception as exc:  # noqa: BLE001 - the library's own errors, and ours
        raise ValueError(f"the record of the watched run's gaps ({GAPS_METADATA}) cannot be "
                         f"read ({type(exc).__name__}: {str(exc)[:200]}): where the watch "
                         "lost messages is not known") from None


def losses(gaps: Sequence[Gap]) -> list[Gap]:
    """The gaps of ``gaps`` in which messages may have been lost: all but the silences
    (:data:`SILENT_CAUSES`); only these make a log partial and are its data problems."""
    return [g for g in gaps if g.cause not in SILENT_CAUSES]


def first_start(gaps: Sequence[Gap]) -> int | None:
    """The earliest known start (ns) of ``gaps``, None when none has one."""
    starts = [g.start for g in gaps if g.start is not None]
    return min(starts) if starts else None


def gap_problems(gaps: Sequence[Gap], library: str = WATCH_LIBRARY) -> list[DataProblem]:
    """One data problem per recorded gap in which messages were lost (:func:`losses`: its
    cause as the kind, its topics, start and end), as the watch (or the replay: ``library``,
    a key of :data:`GAP_LIBRARIES`) reported them; a silence (a publisher away) is no data
    problem."""
    why = GAP_LIBRARIES.get(library, GAP_LIBRARIES[WATCH_LIBRARY])
    return [DataProblem(g.cause, ", ".join(sorted(g.topics)) if g.topics else None, g.start,
                        why, g.end) for g in losses(gaps)]
