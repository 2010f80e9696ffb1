"""The exception tree of fretc, and diagnostics rendered like a compiler's.

Design notes: ARCHITECTURE.md, `common/errors.py`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Where", "FretcError", "FretishError", "FretishSyntaxError", "FretishFileError",
           "CheckError", "InputError", "render_diagnostic", "error_text"]


@dataclass(frozen=True)
class Where:
    """Where an input error is: a file position (``file``, 1-based ``line`` and ``column``)
    and/or a place in a log (``topic``, ``log_time_ns``: MCAP log time, integer ns). Any
    field may be None (not known). ``str()``: ``file:line:column`` then ``topic @ t ns``."""

    file: str | None = None
    line: int | None = None
    column: int | None = None
    topic: str | None = None
    log_time_ns: int | None = None

    def __str__(self) -> str:
        parts = [str(x) for x in (self.file, self.line, self.column) if x is not None]
        out = ":".join(parts)
        if self.topic is not None:
            out += (" " if out else "") + self.topic
        if self.log_time_ns is not None:
            out += (" " if out else "") + f"@ {self.log_time_ns} ns"
        return out


class FretcError(Exception):
    """Root of every input error fretc reports (any stage); the ``fretc`` command prints it
    and exits with code 2.

    Constructed like any exception, with an optional keyword ``where`` (:class:`Where`);
    ``exc.where`` is None when the error names no place beyond its message. The message
    itself always names the place (file:line:col, topic, log time) when one is known.
    """

    where: Where | None = None

    def __init__(self, *args: object, where: Where | None = None) -> None:
        super().__init__(*args)
        if where is not None:
            self.where = where


class FretishError(FretcError):
    """Requirement text or files that fretc cannot use (parse, file structure, and the
    compiler stages on top: semantics, code generation, AJPF). ``str(e)`` of the subclasses
    with a position is the full compiler-style diagnostic."""


class CheckError(FretcError):
    """Input that ``fretc check`` cannot use (e.g. a variable declared both input and
    output)."""


class InputError(FretcError):
    """Audit input fretc cannot use: a log, a binding, a signal. The message names where
    (file, line:col, topic, log time). Formerly ``common.problems.FretcInputError`` (still
    exported under that name)."""


def error_text(exc: FretcError) -> str:
    """The text the ``fretc`` command prints for ``exc``: a :class:`FretishError` is its
    own diagnostic (``file:line:col: error: ...`` where it has a position); any other error
    is ``error: <message>``."""
    return str(exc) if isinstance(exc, FretishError) else f"error: {exc}"


def render_diagnostic(source: str, line: int, column: int, message: str, *,
                      text_line: str | None = None, text_line_column: int = 1,
                      expected: Sequence[str] = (), hint: str | None = None) -> str:
    """Compiler-style text: ``source:line:column: error: message``, then (if known) the
    source line with a caret under ``column``, ``expected: ...`` and ``hint: ...`` lines.

    ``text_line_column`` is the file column of ``text_line``'s first character (1 when
    ``text_line`` is the whole file line)."""
    out = [f"{source}:{line}:{column}: error: {message}"]
    if text_line is not None:
        shown = text_line.rstrip("\r\n")
        out.append(shown)
        k = max(0, column - text_line_column)
        # keep tabs so the caret lines up with the text above it
        pad = "".join("\t" if ch == "\t" else " " for ch in shown[:k])
        pad += " " * max(0, k - len(shown))
        out.append(pad + "^")
    if expected:
        out.append("expected: " + ", ".join(expected))
    if hint:
        out.append("hint: " + hint)
    return "\n".join(out)


class FretishSyntaxError(FretishError):
    """A FRETish sentence that does not parse.

    Attributes: ``source`` (file name or ``"<string>"``), ``line``/``column`` (1-based, file
    coordinates), ``text_line`` (the source line holding the error), ``text_line_column``
    (file column of ``text_line``'s first character; 1 when it is the whole file line),
    ``expected`` (human names such as ``"'shall'"``, ``"an expression"``, ``"a timing"``),
    ``hint`` (advice for a common mistake, or None) and ``message`` (the one-line
    description). ``str(e)`` is the full diagnostic (:func:`render_diagnostic`).
    """

    def __init__(self, message: str, *, source: str = "<string>", line: int = 1,
                 column: int = 1, text_line: str = "", expected: Sequence[str] = (),
                 hint: str | None = None, text_line_column: int = 1,
                 offset: int | None = None):
        # same attribute stores as FretishFileError.__init__ below (kept: each error its own fields
        # and defaults)
        self.message = message
        self.source = source
        self.line = line
        self.column = column
        self.text_line = text_line
        self.text_line_column = text_line_column
        self.expected: list[str] = list(expected)
        self.hint = hint
        #: 0-based offset of the error in the parsed text (None if unknown).
        self.offset = offset
        super().__init__(message, where=Where(source, line, column))

    def __str__(self) -> str:
        return render_diagnostic(self.source, self.line, self.column, self.message,
                                 text_line=self.text_line,
                                 text_line_column=self.text_line_column,
                                 expected=self.expected, hint=self.hint)


class FretishFileError(FretishError):
    """A structural problem of a requirement file (bad JSON, a line without ``ID:``, a
    duplicate id, a bad ``tick_period``...). Attributes ``source``, ``line``, ``column``
    (1-based), ``message``, ``text_line`` (the offending line, or None) and ``hint``.
    """

    def __init__(self, message: str, *, source: str, line: int = 1, column: int = 1,
                 text_line: str | None = None, hint: str | None = None):
        # same attribute stores as FretishSyntaxError.__init__ above and compiler.ir.Node.__init__
        # (kept: each class its own fields)
        self.message = message
        self.source = source
        self.line = line
        self.column = column
        self.text_line = text_line
        self.hint = hint
        super().__init__(message, where=Where(source, line, column))

    def __str__(self) -> str:
        return render_diagnostic(self.source, self.line, self.column, self.message,
                                 text_line=self.text_line, hint=self.hint)
