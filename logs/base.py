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
from collections.abc import Iterable, Iterator
from typing import Any, NamedTuple

from fretc.common.units import NS_PER_S

from fretc.common.problems import DataProblem, ProblemLog

__all__ = ["Message", "Gap", "LogSource", "header_stamp", "LOST_TIMES_CAP"]

#: Log times kept per (kind, topic, channel) of messages present but not decoded; past it,
#: the rest of them is one gap from the first one past the cap to the last one.
LOST_TIMES_CAP = 100_000


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


class Gap(NamedTuple):
    """A span of a log whose messages were lost (../shared/DESIGN.md, "Damage is a gap").

    Attributes:
        start: log time (ns) from which messages may be missing; None: from the log's start.
        end: log time (ns, inclusive) up to which they may be missing; None: to the end of
            the log (a cut: nothing after it was read).
        topics: the topics whose messages it may have held; None: any topic (a ULog
            dropout, a chunk whose channels are not known).
        cause: the data problem kind behind it (``dropout``, ``chunk_crc``, ``truncated``,
            ``undecodable``, ...), as in the log's problems.
    """

    start: int | None
    end: int | None
    topics: frozenset | None = None
    cause: str = ""

    def affects(self, topic: str) -> bool:
        """Whether the gap may have held messages of ``topic``."""
        return self.topics is None or topic in self.topics


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
        gaps: the :class:`Gap` s of the latest pass (log-time spans, ns, inclusive, of the
            data skipped; ``end`` None when nothing after it was read), in the order found.
            A gap whose end was not known when it was found (a record that does not parse,
            read without an index) ends at the log time of the next message read after it
            (:meth:`_close_gaps`).
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
        self.gaps: list[Gap] = []
        self._open_gaps: list[int] = []  # indexes in gaps whose end comes with the next message
        self._open_damage = False  # damage found at open time (summary): every pass is partial
        self._open_problems = ProblemLog()
        self._pass_problems = ProblemLog()
        self._start_time: int | None = None
        self._end_time: int | None = None
        self._decoders: dict[int, Any] = {}  # channel/connection id -> decoder or None
        #: channel/connection id -> (problem kind, reason) of a channel without a decoder
        self._no_decoder: dict[int, tuple[str, str]] = {}
        self.lost: dict[tuple[str, str, int | None], list] = {}
        #: the log times of the messages counted in :attr:`lost` (the first
        #: :data:`LOST_TIMES_CAP` of each key)
        self.lost_times: dict[tuple[str, str, int | None], list[int]] = {}
        #: topic -> field paths to decode (:func:`fretc.logs.ros.selective.install`); None: all
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
            self.lost_times[key] = [log_time]
        else:
            got[0] = min(got[0], log_time)
            got[1] = max(got[1], log_time)
            got[2] += 1
            times = self.lost_times[key]
            if len(times) < LOST_TIMES_CAP:
                times.append(log_time)

    def lost_gaps(self) -> list[Gap]:
        """The messages present but not decoded (:attr:`lost`) as gaps of their own topic:
        one point gap per message (its log time), or past :data:`LOST_TIMES_CAP` of them
        one gap to the last; cause the problem kind (``undecodable``, ...)."""
        out: list[Gap] = []
        for key, (_first, last, count, _why) in sorted(self.lost.items(),
                                                       key=lambda kv: (kv[1][0], kv[0][0],
                                                                       kv[0][1])):
            kind, topic, _ch = key
            times = sorted(self.lost_times.get(key, ()))
            topics = frozenset((topic,))
            out.extend(Gap(t, t, topics, kind) for t in times)
            if count > len(times) and times:
                out.append(Gap(times[-1], last, topics, kind))
        return out

    def lost_from(self, topics: Iterable[str]) -> int | None:
        """The earliest log time (ns) of a message of ``topics`` lost in the latest pass
        (:attr:`lost`), or None."""
        firsts = [v[0] for (_k, t, _c), v in self.lost.items() if t in topics]
        return min(firsts) if firsts else None

    def intact_end_of(self, topics: Iterable[str]) -> int | None:
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
        self._open_gaps = []
        self._pass_problems = ProblemLog()
        self.lost = {}
        self.lost_times = {}

    def _gap(self, start: int | None, end: int | None = None, *,
             topics: frozenset | None = None, cause: str = "", open_end: bool = False
             ) -> None:
        """Record data lost from log time ``start`` (None: from the start of the log) to
        ``end`` (None: to its end) on ``topics`` (None: any), for the problem kind
        ``cause``: the log is partial. ``open_end``: the end is not known yet; it is the
        log time of the next message read (:meth:`_close_gaps`), or the log's end when
        none comes (a cut)."""
        self.partial = True
        self.damage_cut = True
        if open_end:
            self._open_gaps.append(len(self.gaps))
        self.gaps.append(Gap(start, end, topics, cause))
        if start is not None and (self.damage_time is None or start < self.damage_time):
            self.damage_time = start

    def _close_gaps(self, log_time: int) -> None:
        """A message at ``log_time`` (ns) was read after gaps of unknown end: they end
        there."""
        for i in self._open_gaps:
            g = self.gaps[i]
            self.gaps[i] = g._replace(end=log_time if g.start is None
                                      else max(log_time, g.start))
        self._open_gaps = []

    @property
    def cut_start(self) -> int | None:
        """Log time (ns) from which nothing was read to the end of the log (the start of a
        gap without an end: truncation), or None when the log was read to its end. A value
        below every log time when the cut's start is not known."""
        starts = [g.start for g in self.gaps if g.end is None]
        if not starts:
            return None
        if any(s is None for s in starts):
            return -(2**63)
        return min(s for s in starts if s is not None)

    @property
    def intact_end(self) -> int | None:
        """Exclusive log-time bound (ns) of the span read completely in the latest pass: None
        when no message was lost (``damage_cut`` False); a value below every log time when
        nothing before the damage is intact."""
        if not self.damage_cut:
            return None
        if self.damage_time is None or any(g.start is None for g in self.gaps):
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

    def reopen(self) -> LogSource | None:
        """A new source of this file for another pass (its own counts, problems and times)
        without reading the file again, or None: open it again (the default; a reader that
        streams keeps nothing to reopen from)."""
        return None

    def close(self) -> None:
        """Release resources (sources open files only while iterating; this is a no-op)."""

    def integrity_note(self) -> str | None:
        """Why a changed byte of this log would read as data (a sentence), or None when the
        format checks every byte read (an MCAP file with its CRCs). A source of a format
        without checksums (ROS 1 bags, rosbag2's SQLite, CSV traces, ULog, DataFlash)
        says so; :class:`fretc.logs.mcap.source.McapSource` tells from the file."""
        what = {"csv": "a CSV trace", "bag": "a ROS 1 bag", "rosbag2": "a rosbag2 folder",
                "ulog": "a PX4 ULog", "dataflash": "a DataFlash log"}.get(
                    self.kind, f"a {self.kind} log")
        return f"{what} carries no checksum: a changed byte reads as data"

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.kind} {self.path!r}>"



    def _fields_for(self, topic: str) -> frozenset[tuple] | None:
        """The field paths of ``topic`` to decode (None: every field)."""
        return (self._wanted_fields or {}).get(topic)
