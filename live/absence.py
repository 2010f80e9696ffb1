"""Spans in which a bound topic of a watched run had no publisher (:class:`Absences`).

Design notes: ARCHITECTURE.md, `live/absence.py`."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from fretc.logs.base import Gap

__all__ = ["Absences", "NO_TIME", "WatchedRun", "recorded_gaps", "run_gaps"]

#: The start of a span opened before any message was used: below every log time.
NO_TIME = -(2**63)


class Absences:
    """Per topic, its spans without a publisher: ``[start, end, used]`` with ``start`` the
    log time (ns) of the last message used before it left (:data:`NO_TIME`: none), ``end``
    the log time of its own next message (None: not back yet), ``used`` the count of
    messages used when it left (the run went on without it when more were used since)."""

    def __init__(self) -> None:
        self.spans: dict[str, list[list]] = {}

    def __bool__(self) -> bool:
        return bool(self.spans)

    def left(self, topic: str, last_time: int | None, used: int) -> None:
        """``topic``'s publisher left after the message at ``last_time`` (``used`` messages
        used so far); nothing when a span of it is already open."""
        spans = self.spans.setdefault(topic, [])
        if not spans or spans[-1][1] is not None:
            spans.append([NO_TIME if last_time is None else last_time, None, used])

    def open_span(self, topic: str) -> list | None:
        """``topic``'s open span, or None."""
        spans = self.spans.get(topic)
        return spans[-1] if spans and spans[-1][1] is None else None

    def back(self, topic: str, log_time: int, silent: bool = False
             ) -> tuple[int | None, str] | None:
        """A message of ``topic`` at ``log_time`` (ns) closes its open span: (its start,
        None when before any message; the event's text, which says whether the span was a
        silence, ``silent``, or may have lost messages), or None when none was open."""
        span = self.open_span(topic)
        if span is None:
            return None
        span[1], start = log_time, span[0]
        how = (f"advertised again as channel {span[3]}" if len(span) > 3
               else "its messages came again")
        since = "the start of the run" if start == NO_TIME else f"log time {start}"
        what = ("it had no publisher, so nothing was sent: the time since its last message "
                "is known, its values are not" if silent else
                "messages its new publisher sent before the watch subscribed again may be lost")
        return (None if start == NO_TIME else start,
                f"the publisher of {topic} restarted (unadvertised, then {how}): no message "
                f"of {topic} from {since} to log time {log_time} ({what}): ticks inside are "
                f"not evaluated (unknown) for the requirements that read its values, never "
                "held over; the monitors keep their state")

    def at(self, topics: Iterable[str], t: int) -> bool:
        """Whether some topic of ``topics`` had no publisher at log time ``t`` (ns)."""
        for topic in topics:
            for start, end, *_rest in self.spans.get(topic, ()):
                if start < t and (end is None or t < end):
                    return True
        return False

    def left_for_good(self, topics: Iterable[str], used: int) -> int | None:
        """The earliest start of a span of ``topics`` still open at the run's end while the
        run went on without it (``used``: messages used in all); None when there is none (a
        topic that left with every other, at the run's end, is the run's end)."""
        starts = [s[0] for s in (self.open_span(t) for t in topics)
                  if s is not None and used > s[2]]
        return min(starts) if starts else None

    def lost_start(self, hears_new_publishers: bool) -> int | None:
        """The earliest start of a span that may have cost the run messages, or None: a
        closed span (a restart) where the client subscribes again only after the new
        advertisement (``hears_new_publishers`` False); a span open at the end (left for
        good) and every span on a client that hears a new publisher at once are silences."""
        if hears_new_publishers:
            return None
        starts = [s[0] for spans in self.spans.values() for s in spans if s[1] is not None]
        return min(starts) if starts else None


class WatchedRun(Protocol):
    """What the gaps of a watched run are read from (:class:`fretc.live.source.WatchSource`):
    its lost connections (``gaps``: pairs of the log times around each, ns), its topics'
    spans without a publisher (``absent``), whether its client hears a new publisher from its
    first message (``hears_new_publishers``) and, per topic, where its publisher left for
    good (``left_for_good``)."""

    gaps: list[tuple[int, int]]

    @property
    def absent(self) -> Absences | None:
        """The bound topics' spans without a publisher (None: not kept)."""

    @property
    def hears_new_publishers(self) -> bool:
        """Whether the client reads a new publisher from its first message."""

    def left_for_good(self, topics: Iterable[str]) -> int | None:
        """The earliest start (ns) of a span of ``topics`` open at the run's end while the
        run went on, or None."""


def recorded_gaps(src: WatchedRun) -> list[Gap]:
    """The gaps a recording of the watched run carries (``fretc watch --record``), so that
    the audit of the recording judges what the watch judged: :func:`run_gaps`, and per
    topic whose publisher left for good while the run went on, a gap of that topic from the
    last message used before it left (exclusive; from the start when none was) to the end
    of the run (:data:`fretc.logs.recorded_gaps.RUN_END`): the audit leaves the variables
    reading it unknown from there (:func:`fretc.audit.passes.mark_gaps`), as the watch
    does."""
    from fretc.logs.base import Gap
    from fretc.logs.recorded_gaps import LEFT_FOR_GOOD, RUN_END

    out = run_gaps(src)
    absent = src.absent
    if absent is not None:
        for topic in sorted(absent.spans):
            start = src.left_for_good((topic,))
            if start is not None:
                out.append(Gap(None if start == NO_TIME else start + 1, RUN_END,
                               frozenset((topic,)), LEFT_FOR_GOOD))
    return out


def run_gaps(src: WatchedRun) -> list[Gap]:
    """The gaps of a watched run (``src``: its :class:`fretc.live.source.WatchSource`) as
    the audit's (:class:`fretc.logs.base.Gap`): a lost connection (every topic, between the
    last message before it and the first after it) and a publisher that left and came back
    (its topic, until its next message: a silence where the client hears a new publisher
    at once, module docstring); the messages lost lie strictly inside. Messages
    received but not used at a known log time (a clock reset) are point gaps of their topic
    (:meth:`fretc.logs.base.LogSource.lost_gaps`)."""
    from fretc.logs.base import Gap

    from fretc.logs.recorded_gaps import PUBLISHER_ABSENT

    cause = PUBLISHER_ABSENT if src.hears_new_publishers else "publisher_left"
    out = [Gap(a + 1, e - 1, None, "connection_gap") for a, e in src.gaps if e - a > 1]
    for topic, spans in (src.absent.spans if src.absent else {}).items():
        for start, end, *_rest in spans:
            if end is not None:
                out.append(Gap(None if start == NO_TIME else start + 1, end - 1,
                               frozenset((topic,)), cause))
    lost = getattr(src, "lost_gaps", None)  # messages received but not used, at their times
    if lost is not None:
        out += lost()
    return out
