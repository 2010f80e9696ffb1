"""ArduPilot flight logs (DataFlash binary, ``*.bin``) as a :class:`~fretc.logs.base.LogSource`,
read with ``pymavlink``'s ``DFReader`` (ArduPilot's own log library; format: ArduPilot
"Downloading and Analyzing Data Logs", the self-describing ``FMT`` records).

Design notes: ARCHITECTURE.md, `logs/flight/dataflash.py`."""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

from fretc.common import problems as P
from fretc.common.problems import LogError
from fretc.logs.base import LogSource, Message
from fretc.logs.reorder import REORDER_WINDOW_NS, ReorderQueue

__all__ = ["DataflashSource", "dataflash_definition"]

#: DataFlash format characters -> ROS field types (pymavlink ``FORMAT_TO_STRUCT``; scaled
#: ones are float64 after pymavlink's multiplier)
_TYPES = {"b": "int8", "B": "uint8", "h": "int16", "H": "uint16", "i": "int32",
          "I": "uint32", "f": "float32", "d": "float64", "q": "int64", "Q": "uint64",
          "n": "string", "N": "string", "Z": "string", "a": "int16[32]", "g": "float32",
          "M": "uint8", "c": "float64", "C": "float64", "e": "float64", "E": "float64",
          "L": "float64"}
_META = ("FMT", "FMTU", "MULT", "UNIT")


def dataflash_definition(fmt: Any) -> str:  # fmt: pymavlink's DFFormat (untyped)
    """The ROS 2 message definition of one DataFlash format (pymavlink ``DFFormat``): one
    field per column, typed by its format character. Raises KeyError for an unknown
    character."""
    return "".join(f"{_TYPES[c]} {name}\n" for c, name in zip(fmt.format, fmt.columns))


class DataflashSource(LogSource):
    """An ArduPilot DataFlash ``.bin`` log (module docstring). Opening reads it once to list
    its topics.

    Raises:
        LogError: a file pymavlink cannot open as a DataFlash binary log.
    """

    kind = "dataflash"

    def __init__(self, path: str | os.PathLike) -> None:
        super().__init__(path)
        #: the earliest TimeUS (ns) of a record the latest pass read, of any topic: the log's
        #: start whichever topics a pass delivers (the origin of an audit's times)
        self._first_any: int | None = None
        #: the latest TimeUS (ns) of a record the latest pass read, of any topic
        self._last_any: int | None = None
        self._formats: dict[str, object] = {}
        self._topics: dict[str, str] = {}
        for topic, fmt, _lt, _m, _at in self._records(None):
            if topic not in self._topics:
                self._topics[topic] = f"ardupilot/msg/{fmt.name}"
                self._formats[topic] = fmt
        self._topics = dict(sorted(self._topics.items()))
        if not self._topics:
            raise LogError(self.path, "not an ArduPilot DataFlash log: no record with a "
                                      "TimeUS column (a .bin log starts with FMT records)")
        #: the log's end (ns): the latest TimeUS of a record of any topic, found by the scan
        #: of the whole file when it was opened (whichever topics a pass reads). A clock
        #: reading ``age()`` ticks to it, as on an MCAP to its summary's end
        #: (:func:`fretc.signals.clock.silence_end`; issue 91: a GPS that died before the
        #: end of the flight was never stale)
        self.log_end: int | None = self._last_any
        self._begin_pass()  # the problems of the scan belong to the first pass

    def _reader(self):
        from pymavlink import DFReader  # lazy: only for DataFlash logs

        try:
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()), _c_stdout_closed():
                return DFReader.DFReader_binary(self.path, zero_time_base=False)
        except Exception as exc:  # pymavlink raises plain exceptions on malformed input
            raise LogError(self.path, f"not a readable ArduPilot DataFlash log "
                                      f"({type(exc).__name__}: {exc})") from None

    def _records(self, want: set[str] | None):
        """(topic, format, log time ns, message, offset) in file order. Bytes pymavlink skips
        between two records are a gap (``corrupt_record``) between their log times; bytes
        left at the end that do not make a record, or a parse failure, end the read with a
        ``truncated`` gap. pymavlink's own prints of skipped bytes are kept off the
        terminal."""
        reader = self._reader()
        sink = io.StringIO()
        prev_end, prev_time = 0, None
        while True:
            try:
                with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
                    m = reader.recv_msg()
            except Exception as exc:  # a record pymavlink cannot parse: the read ends here
                self._truncated(prev_time, f"{type(exc).__name__}: {exc}")
                return
            if m is None:
                left = reader.data_len - prev_end  # (pymavlink may have read a header past it)
                if left > 0:
                    self._truncated(prev_time,
                                    f"the last {left} bytes of the file are no whole record")
                return
            fmt = m.fmt
            start = reader.offset - fmt.len
            if start > prev_end:
                lt = int(m.TimeUS) * 1000 if "TimeUS" in fmt.colhash else None
                self._gap(prev_time, lt, cause=P.CORRUPT_RECORD)
                self._problem(P.CORRUPT_RECORD, None, prev_time,
                              f"{start - prev_end} bytes at offset {prev_end} are no record "
                              "(skipped): messages may be lost there", end_time=lt)
            prev_end = reader.offset
            if fmt.name in _META or "TimeUS" not in fmt.colhash:
                continue
            prev_time = int(m.TimeUS) * 1000
            topic = fmt.name
            inst = fmt.instance_field
            if inst is not None:
                k = getattr(m, inst, 0)
                if isinstance(k, int) and k > 0:
                    topic = f"{fmt.name}/{k}"
            if self._first_any is None or prev_time < self._first_any:
                self._first_any = prev_time  # (every record's: the log's start)
            if self._last_any is None or prev_time > self._last_any:
                self._last_any = prev_time  # (every record's: the log's end)
            if want is not None and topic not in want:
                continue
            yield topic, fmt, int(m.TimeUS) * 1000, m, start

    def _truncated(self, at: int | None, why: str) -> None:
        """The read ends after the message read last (log time ``at``, ns)."""
        self._gap(at, None, cause=P.TRUNCATED)
        self._problem(P.TRUNCATED, None, at, f"the log cannot be read past log time {at} "
                                             f"({why}); read up to there")

    def topics(self) -> dict[str, str]:
        """Topic -> message type (``ardupilot/msg/TYPE``)."""
        return dict(self._topics)

    def definitions(self) -> dict[str, tuple[str, str]]:
        """Topic -> (message type, ROS 2 definition text) of every topic."""
        return {t: (typ, dataflash_definition(self._formats[t]))
                for t, typ in self._topics.items()}

    def _dated(self, want: set[str] | None):
        """:meth:`_records` with the records whose TimeUS cannot be right left out: one
        dated more than :data:`REORDER_WINDOW_NS` after the record before it and followed by
        one more than that before it (a bit flipped in its time stamp: a log's time runs on)
        is a ``corrupt_record`` problem naming its type, offset and TimeUS, and a gap where
        it was. Every record is looked at, whatever ``want`` keeps (the problems of a log
        never depend on the topics read)."""
        pending, prev = None, None
        for rec in self._records(None):
            lt = rec[2]
            if pending is not None:
                p, pending = pending, None
                if lt < p[2] - REORDER_WINDOW_NS:
                    self._gap(prev, lt, cause=P.CORRUPT_RECORD)
                    self._problem(P.CORRUPT_RECORD, p[0], prev,
                                  f"the {p[1].name} record at offset {p[4]} has TimeUS "
                                  f"{p[2] // 1000} us, {(p[2] - prev) / 1e9:.6g} s after the "
                                  f"record before it and {(p[2] - lt) / 1e9:.6g} s after the "
                                  "one that follows it: its time stamp is damaged (a bit "
                                  "flipped?); skipped", end_time=lt)
                else:
                    prev = p[2]
                    if want is None or p[0] in want:
                        yield p[:4]
            if prev is not None and lt > prev + REORDER_WINDOW_NS:
                pending = rec  # dated far after the record before it: judged by the next
                continue
            prev = lt if prev is None else max(prev, lt)
            if want is None or rec[0] in want:
                yield rec[:4]
        if pending is not None and (want is None or pending[0] in want):
            yield pending[:4]

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """The messages of ``topics`` (all when None) in non-decreasing log time."""
        self._begin_pass()
        want = None if topics is None else set(topics)
        queue = ReorderQueue()
        position = 0
        for topic, fmt, lt, m in self._dated(want):
            late = queue.late_by(lt)
            if late > 0:
                self._problem(P.OUT_OF_ORDER, topic, lt,
                              f"TimeUS {lt // 1000} us is {late / 1e9:.3f} s before a message "
                              f"already delivered, past the {REORDER_WINDOW_NS / 1e9:g} s "
                              "window; message skipped")
                continue
            data = SimpleNamespace(**{c: getattr(m, c) for c in fmt.columns})
            queue.push(lt, position, (topic, data))
            position += 1
            yield from self._release(queue, lt)
        yield from self._release(queue, None)
        if self._first_any is not None and (self._start_time is None
                                            or self._first_any < self._start_time):
            self._start_time = self._first_any

    def _release(self, queue: ReorderQueue, watermark: int | None) -> Iterator[Message]:
        for lt, (topic, data) in queue.due(watermark):
            queue.delivered(lt)
            self.counts[topic] = self.counts.get(topic, 0) + 1
            if self._start_time is None or lt < self._start_time:
                self._start_time = lt
            self._end_time = lt
            yield Message(topic, lt, lt, None, data)


@contextlib.contextmanager
def _c_stdout_closed():
    """File descriptors 1 and 2 to the null device for the block: pymavlink's C indexer of
    DataFlash records prints every bad header (``bad header 0x0000 at N``, thousands on a
    zeroed span) with C's stdio, which Python's ``redirect_stdout`` does not reach; the
    damage is reported as problems instead, and the terminal stays readable."""
    import os
    import sys

    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
    except (OSError, ValueError, AttributeError):  # no such descriptors: nothing to quiet
        yield
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        for fd, old in ((1, saved[0]), (2, saved[1])):
            os.dup2(old, fd)
            os.close(old)
        os.close(null)
