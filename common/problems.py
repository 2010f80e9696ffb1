"""What can go wrong with recorded data and signal declarations.

Two kinds of trouble are kept apart:

* A :class:`DataProblem` is damage *inside* a log that the audit can live with: a chunk whose
  CRC does not match, a message that does not deserialize, a topic whose schema is unknown,
  a header stamp that goes backwards.  It is recorded (with the topic and log time, so a
  report can point at it) and reading goes on.
* An exception derived from :class:`FretcInputError` is input that cannot be used at all:
  a file that is not a log, a CSV row with a bad cell, a binding that does not parse.  Its
  message always names *where*: the file, and a line:col, topic or log time.

Times are integer nanoseconds (MCAP log time convention, MCAP spec "Message" record).
"""

from __future__ import annotations

from dataclasses import dataclass

from fretc.common.errors import InputError, Where

# Kinds of DataProblem.  Strings (not an Enum) so reports and JSON stay plain.
TRUNCATED = "truncated"  # the log ends inside a record (crashed recording)
CORRUPT_RECORD = "corrupt_record"  # a record outside chunks cannot be read; reading stops
CHUNK_CRC = "chunk_crc"  # MCAP Chunk uncompressed_crc mismatch; chunk skipped
CHUNK_CORRUPT = "chunk_corrupt"  # chunk cannot be decompressed or parsed; chunk skipped
DATA_CRC = "data_crc"  # MCAP DataEnd data_section_crc mismatch
SUMMARY_CORRUPT = "summary_corrupt"  # footer/summary unreadable or its CRC is wrong; index ignored
INDEX_MISMATCH = "index_mismatch"  # the summary's index disagrees with the data; read linearly
# a watch's recording whose record of the run's gaps cannot be read (fretc.logs.recorded_gaps)
RECORDED_GAPS = "recorded_gaps_unreadable"
UNKNOWN_SCHEMA = "unknown_schema"  # schema missing, of an unsupported encoding, or unparsable
UNKNOWN_ENCODING = "unknown_encoding"  # message encoding other than cdr / ros1
UNKNOWN_CHANNEL = "unknown_channel"  # message refers to a channel never defined (lost chunk)
UNDECODABLE = "undecodable"  # one message's payload does not deserialize; message skipped
OUT_OF_ORDER = "out_of_order"  # message later than the reorder window allows; skipped
HEADER_BACKWARDS = "header_backwards"  # header.stamp earlier than the previous one on the topic
HEADER_LATE = "header_late"  # header.stamp older than a tick already emitted; skipped
HEADER_JUMP = "header_jump"  # live: header.stamp too far past the newest one to tick over; skipped
NO_HEADER = "no_header"  # time base "header" but the message has no header.stamp; skipped
NAN = "nan"  # a requirement's comparison read NaN at a tick: that tick's value is unread

#: At most this many problems of one (kind, topic) are kept in ``problems``; the rest are only
#: counted in ``problem_counts`` so memory stays flat on a badly damaged log.
MAX_PROBLEMS_PER_KIND = 50


@dataclass(frozen=True)
class DataProblem:
    """One piece of damage found while reading a log; reading went on.

    Attributes:
        kind: one of the module constants (``"chunk_crc"``, ``"undecodable"``, ...).
        topic: the topic concerned, or None when the damage is not tied to one topic
            (a chunk holds many topics).
        log_time: log time (ns) where the damage starts: the message's log time, or a chunk's
            ``message_start_time``; None when unknown.
        detail: a sentence for a person: what was found, where in the file (byte offset),
            and what was done about it.
        end_time: for damage that covers a span (a skipped chunk), the last log time (ns) in
            it, else None.
    """

    kind: str
    topic: str | None
    log_time: int | None
    detail: str
    end_time: int | None = None

    def __str__(self) -> str:
        where = []
        if self.topic is not None:
            where.append(self.topic)
        if self.log_time is not None:
            span = f"{self.log_time}" if self.end_time is None else f"{self.log_time}..{self.end_time}"
            where.append(f"log time {span} ns")
        head = f"{self.kind} ({', '.join(where)})" if where else self.kind
        return f"{head}: {self.detail}"


class ProblemLog:
    """An append-only list of DataProblems, capped per (kind, topic).

    ``problems`` keeps the first :data:`MAX_PROBLEMS_PER_KIND` of each (kind, topic) in the
    order found; ``counts`` counts all of them.
    """

    def __init__(self) -> None:
        self.problems: list[DataProblem] = []
        self.counts: dict[tuple[str, str | None], int] = {}

    def add(self, problem: DataProblem) -> None:
        """Record ``problem`` (kept if fewer than the cap of its kind and topic so far)."""
        key = (problem.kind, problem.topic)
        n = self.counts.get(key, 0) + 1
        self.counts[key] = n
        if n <= MAX_PROBLEMS_PER_KIND:
            self.problems.append(problem)


#: The audit's input errors derive from :class:`fretc.common.errors.InputError` (kept here under
#: its former name; ``except FretcError`` catches them with every other stage's errors).
FretcInputError = InputError


class LogError(FretcInputError):
    """A log file or folder that cannot be opened or read at all.

    Attributes:
        path: the log's path as given.
    """

    def __init__(self, path: object, message: str) -> None:
        self.path = str(path)
        super().__init__(f"{self.path}: {message}", where=Where(file=self.path))


class CsvError(LogError):
    """A CSV trace with a bad header or row.

    Attributes:
        path: the file; line: 1-based line number; column: the column's header name or None.
    """

    def __init__(self, path: object, line: int, message: str, column: str | None = None) -> None:
        self.line = line
        self.column = column
        where = f"{line}" if column is None else f"{line} (column {column!r})"
        LogError.__init__(self, f"{path}:{where}", message)
        self.path = str(path)
        self.where = Where(file=self.path, line=line)


class BindingError(FretcInputError):
    """A signal binding that cannot be read, compiled or evaluated.

    Attributes:
        source: the binding file path, or ``"<--bind NAME>"`` for an inline binding.
        line, col: 1-based position in ``source`` (col points into the expression when the
            error is inside it), or None when not known.
        variable: the FRET variable being bound, or None for file-level errors.
    """

    def __init__(
        self,
        source: str,
        message: str,
        *,
        line: int | None = None,
        col: int | None = None,
        variable: str | None = None,
    ) -> None:
        self.source = source
        self.line = line
        self.col = col
        self.variable = variable
        where = source
        if line is not None:
            where += f":{line}"
            if col is not None:
                where += f":{col}"
        who = f" variable {variable!r}:" if variable else ""
        super().__init__(f"{where}:{who} {message}", where=Where(source, line, col))
        self.message = message


class SignalError(FretcInputError):
    """A binding that cannot be evaluated on a particular log (missing topic or field).
    ``variable`` names the FRET variable whose binding failed, when one did."""

    def __init__(self, message: str, variable: str | None = None) -> None:
        super().__init__(message)
        self.variable = variable
