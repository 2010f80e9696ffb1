"""Errors of the FRETish front end, rendered like a compiler's diagnostics.

A :class:`FretishSyntaxError` renders as::

    r1.fret:3:17: error: unexpected 'and' in an expression
    R1: the sw shall always satisfy p and q
                                      ^
    expected: an operator, the end of the sentence
    hint: FRETish writes conjunction as '&' ...

Lines and columns are 1-based and in the coordinates of the file the text came from.
"""

from __future__ import annotations

from typing import List, Optional, Sequence

__all__ = ["FretishError", "FretishSyntaxError", "FretishFileError", "render_diagnostic"]


class FretishError(Exception):
    """Base class of every error fretc reports about requirement text or files.

    Constructed like any exception (``FretishError(message)``); subclasses add positions.
    """


def render_diagnostic(source: str, line: int, column: int, message: str, *,
                      text_line: Optional[str] = None, text_line_column: int = 1,
                      expected: Sequence[str] = (), hint: Optional[str] = None) -> str:
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
                 hint: Optional[str] = None, text_line_column: int = 1,
                 offset: Optional[int] = None):
        self.message = message
        self.source = source
        self.line = line
        self.column = column
        self.text_line = text_line
        self.text_line_column = text_line_column
        self.expected: List[str] = list(expected)
        self.hint = hint
        #: 0-based offset of the error in the parsed text (None if unknown).
        self.offset = offset
        super().__init__(message)

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
                 text_line: Optional[str] = None, hint: Optional[str] = None):
        self.message = message
        self.source = source
        self.line = line
        self.column = column
        self.text_line = text_line
        self.hint = hint
        super().__init__(message)

    def __str__(self) -> str:
        return render_diagnostic(self.source, self.line, self.column, self.message,
                                 text_line=self.text_line, hint=self.hint)
