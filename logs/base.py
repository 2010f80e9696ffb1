"""The source interface shared by every log format: :class:`Message`, :class:`LogSource`.

A source reads a recorded run as a stream of decoded messages in non-decreasing log time,
streaming (memory does not grow with the length of the log). Damage is recorded as
:class:`~fretc.common.problems.DataProblem` in ``source.problems`` and reading goes on; the
span read completely before the damage is ``source.intact_end`` (../shared/DESIGN.md
"Damage is never evidence").

Times are integer nanoseconds since the epoch of the recording clock (MCAP ``log_time``,
rosbag ``timestamp``).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any, NamedTuple

from fretc.common.units import NS_PER_S

from fretc.common.problems import DataProblem, ProblemLog

__all__ = ["Message", "LogSource", "header_stamp"]


class Message(NamedTuple):
    """One decoded message.

    Attributes:
        topic: the topic name (``/scan``), or :data:`CSV_TOPIC` for CSV rows.
        log_time: ns, when the recorder received it (MCAP ``log_time``; rosbag timestamp).
        publish_time: ns, when it was published (MCAP ``publish_time``; for bags and CSV, equal
            to ``log_time`` since they do not record it).
        header_stamp: ns, ``data.header.stamp`` (``sec * 1e9 + nanosec``) when the message has
            a std_msgs/Header, else None.
        data: the decoded message: a rosbags message object (attribute access:
            ``data.twist.linear.x``; primitive arrays are numpy arrays), or for CSV a
            SimpleNamespace of the row's values.
    """

    topic: str
    log_time: int
    publish_time: int
    header_stamp: int | None
    data: Any


def header_stamp(data: Any) -> int | None:
    """``data.header.stamp`` in ns (std_msgs/Header: ``stamp.sec * 1e9 + stamp.nanosec``), or None."""
    header = getattr(data, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is None:
        return None
    try:
        return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)
    except AttributeError:
        return None


class LogSource:
    """A recorded run, read as a stream of :class:`Message` in log-time order.

    Attributes:
        path: the file or folder given to :func:`open_log`.
        kind: ``"mcap"``, ``"bag"`` (ROS 1), ``"rosbag2"`` or ``"csv"``.
        counts: messages delivered per topic by the most recent :meth:`messages` pass
            (filled while iterating).
        records: messages read per topic by that pass, decoded or not (a message whose
            encoding or schema cannot be decoded counts here, not in ``counts``); sources
            that decode every message they read leave it empty.
        partial: True when the log is damaged: it ends early (truncated or unreadable from
            some point on), a part of it was skipped (a chunk failing its CRC, a record that
            does not parse: a *gap*), or its summary or data-section CRC is damaged.
        damage_time: where the intact span ends: the log time (ns) of the last good message
            read before a truncation, or the first log time of the first gap; None when the
            damage loses no message (summary, data CRC) or when nothing was read before it.
            Only ticks strictly before it are judged (../shared/DESIGN.md "Damage is never evidence").
        gaps: ``(start, end)`` log-time spans (ns, inclusive; ``end`` None when unknown) of the
            data skipped in the latest pass, in the order found.
        damage_cut: True when the damage loses messages (truncation or gap), so that only the
            span before ``damage_time`` was read completely; False for damage that loses none
            (summary, data-section CRC).
        lost: the messages of the latest pass that were present but not decoded (a schema
            that lies or cannot be read, an unknown message encoding, a payload that does not
            deserialize): ``(kind, topic, channel) -> [first, last, count, reason]`` (log
            times in ns). Each one ends the held value of its topic at its log time, as a
            cut does (:meth:`intact_end_of`); ../shared/DESIGN.md "Damage is never evidence".

    ``problems`` lists the damage found at open time and during the most recent pass (capped
    per kind and topic, see :mod:`fretc.common.problems`); ``problem_counts`` counts all of it.
    """

    path: str
    kind: str

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = str(path)
        self.counts: dict[str, int] = {}
        self.records: dict[str, int] = {}
        self.partial = False
        self.damage_time: int | None = None
        self.damage_cut = False
        self.gaps: list[tuple[int | None, int | None]] = []
        self._open_damage = False  # damage found at open time (summary): every pass is partial
        self._open_problems = ProblemLog()
        self._pass_problems = ProblemLog()
        self._start_time: int | None = None
        self._end_time: int | None = None
        self._decoders: dict[int, Any] = {}  # channel/connection id -> decoder or None
        #: channel/connection id -> (problem kind, reason) of a channel without a decoder
        self._no_decoder: dict[int, tuple[str, str]] = {}
        self.lost: dict[tuple[str, str, int | None], list] = {}
        #: topic -> field paths to decode (:func:`fretc.logs.selective.install`); None: all
        self._wanted_fields: dict[str, frozenset[tuple]] | None = None

    # -- problems -------------------------------------------------------------------------------
    @property
    def problems(self) -> list[DataProblem]:
        """Damage found when opening and during the latest pass, in the order found, then
        one problem per channel whose messages were not decoded (:attr:`lost`)."""
        return (self._open_problems.problems + self._pass_problems.problems
                + self.lost_problems())

    @property
    def problem_counts(self) -> dict[tuple[str, str | None], int]:
        """Number of problems per (kind, topic), including those beyond the kept cap; for
        messages not decoded, the number of messages lost."""
        out = dict(self._open_problems.counts)
        for k, v in self._pass_problems.counts.items():
            out[k] = out.get(k, 0) + v
        for (kind, topic, _ch), (_a, _b, count, _why) in self.lost.items():
            out[(kind, topic)] = out.get((kind, topic), 0) + count
        return out

    def lost_problems(self) -> list[DataProblem]:
        """One :class:`DataProblem` per (kind, topic, channel) of :attr:`lost`, earliest
        first: the count of messages lost, the channel, the first and last log time."""
        out = []
        for (kind, topic, channel), (first, last, count, why) in sorted(
                self.lost.items(), key=lambda kv: (kv[1][0], kv[0][0], kv[0][1],
                                                   -1 if kv[0][2] is None else kv[0][2])):
            on = f" on channel {channel}" if channel is not None else ""
            plural = "message" if count == 1 else "messages"
            out.append(DataProblem(
                kind, topic, first,
                f"{count} {plural}{on} not decoded ({why}); the held value of {topic} ends "
                f"at log time {first} ns: ticks from there on are not judged for the "
                f"requirements that read it", last))
        return out

    def _lose(self, kind: str, topic: str, channel: int | None, log_time: int,
              why: str) -> None:
        """A message of ``topic`` present at ``log_time`` (ns) but not decoded: counted in
        :attr:`lost` under ``(kind, topic, channel)``; ``why`` (the first one's) says why."""
        key = (kind, topic, channel)
        got = self.lost.get(key)
        if got is None:
            self.lost[key] = [log_time, log_time, 1, why]
        else:
            got[0] = min(got[0], log_time)
            got[1] = max(got[1], log_time)
            got[2] += 1

    def lost_from(self, topics) -> int | None:
        """The earliest log time (ns) of a message of ``topics`` lost in the latest pass
        (:attr:`lost`), or None."""
        firsts = [v[0] for (_k, t, _c), v in self.lost.items() if t in topics]
        return min(firsts) if firsts else None

    def intact_end_of(self, topics) -> int | None:
        """Exclusive log-time bound (ns) of the span of ``topics`` read completely in the
        latest pass: :attr:`intact_end`, or earlier when a message of one of ``topics`` was
        present but not decoded (its log time); None when nothing was lost."""
        ends = [e for e in (self.intact_end, self.lost_from(topics)) if e is not None]
        return min(ends) if ends else None

    def _problem(self, kind: str, topic: str | None, log_time: int | None, detail: str,
                 end_time: int | None = None) -> None:
        self._pass_problems.add(DataProblem(kind, topic, log_time, detail, end_time))

    def _begin_pass(self) -> None:
        self.counts = {}
        self.records = {}
        self.partial = self._open_damage
        self.damage_time = None
        self.damage_cut = False
        self.gaps = []
        self._pass_problems = ProblemLog()
        self.lost = {}

    def _gap(self, start: int | None, end: int | None = None) -> None:
        """Record data lost from log time ``start`` (None: unknown, then the intact span
        ends at ``start``'s best bound the caller passes) to ``end``: the log is partial and
        its intact span ends at the earliest gap."""
        self.partial = True
        self.damage_cut = True
        self.gaps.append((start, end))
        if start is not None and (self.damage_time is None or start < self.damage_time):
            self.damage_time = start

    @property
    def intact_end(self) -> int | None:
        """Exclusive log-time bound (ns) of the span read completely in the latest pass: None
        when no message was lost (``damage_cut`` False); a value below every log time when
        nothing before the damage is intact."""
        if not self.damage_cut:
            return None
        if self.damage_time is None or any(start is None for start, _ in self.gaps):
            return -(2**63)
        return self.damage_time

    # -- interface ------------------------------------------------------------------------------
    @property
    def start_time(self) -> int | None:
        """Log time (ns) of the first message, when known (index, or after a full pass)."""
        return self._start_time

    @property
    def end_time(self) -> int | None:
        """Log time (ns) of the last message, when known (index, or after a full pass)."""
        return self._end_time

    def topics(self) -> dict[str, str]:
        """Topic → message type name (rosbags' normalized ``pkg/msg/Type``), sorted by topic."""
        raise NotImplementedError

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """Decoded messages of ``topics`` (all when None), in non-decreasing log time.

        Each call is a fresh pass over the log; ``counts``, ``partial``, ``damage_time`` and
        the pass's problems are reset at its start and filled while iterating.
        """
        raise NotImplementedError

    def reopen(self) -> "LogSource | None":
        """A new source of this file for another pass (its own counts, problems and times)
        without reading the file again, or None: open it again (the default; a reader that
        streams keeps nothing to reopen from)."""
        return None

    def close(self) -> None:
        """Release resources (sources open files only while iterating; this is a no-op)."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.kind} {self.path!r}>"



    def _fields_for(self, topic: str) -> frozenset[tuple] | None:
        """The field paths of ``topic`` to decode (None: every field)."""
        return (self._wanted_fields or {}).get(topic)
