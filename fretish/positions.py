"""Positions for the AST builder of :mod:`fretish.parser`: the per-parse context (the text
and where it starts in its file), spans in file coordinates from text offsets, and the
builder's error for a rule the grammar accepts but FRETish forbids."""

from __future__ import annotations

import functools
import re

from . import ast as A


class _Ctx:
    """Per-parse state read by the AST builder (one for all parses: :func:`fretish.parser._run`
    holds ``fretish.parser._parsing`` while it is set and read, so parses in several threads take turns
    instead of mixing their states; a plain object's attributes are read several times
    faster than a ``threading.local``'s, and the builder reads them for every node); set by
    :meth:`set`. ``flat``: (file line, file column) of the text's first character when the
    text has one line (a span is then plain arithmetic), else None and ``line``/``col``
    are those and ``starts`` the offsets where the text's lines 2, 3 ... begin."""
    text = ""
    line = 1
    col = 1
    starts: list = []
    flat: tuple | None = (1, 1)   # (line, col) when the text has one line, else None

    def set(self, text: str, dl: int, dc: int) -> None:
        """Parse ``text``, whose first character is at file line ``dl + 1``, column
        ``dc + 1``."""
        self.text = text
        if "\n" in text:
            self.line, self.col = dl + 1, dc + 1
            self.starts = [m.end() for m in _NEWLINE.finditer(text)]
            self.flat = None
        else:                  # (line and col are read only for a text of several lines)
            self.flat = (dl + 1, dc + 1)


_NEWLINE = re.compile("\n")
_ctx = _Ctx()


# Tokens, of the fast path and (converted, :class:`_LarkBuilder`) of Lark's: plain tuples
# ``(terminal, text, start, end)`` with 0-based offsets into the text (a tuple is the
# cheapest object Python makes; a node is never a plain tuple: ``A.Span`` is a subclass).
_TYPE, _VALUE, _START, _END = 0, 1, 2, 3


#: ``A.Span`` from one tuple of its six fields, without the named tuple's Python-level
#: ``__new__`` (the parser makes one per node): the same class, the same value.
_new_span = functools.partial(tuple.__new__, A.Span)


def _mk(s: int, e: int) -> A.Span:
    """The span of text offsets ``s`` to ``e`` (0-based, end excluded) in file coordinates
    (:class:`_Ctx`): 1-based lines and columns as Lark counts them (a line starts after
    each ``"\\n"``; only the text's first line is shifted by its starting column)."""
    flat = _ctx.flat
    if flat is not None:
        line, col = flat
        return _new_span((line, s + col, line, e + col, s, e))
    from bisect import bisect_right
    c = _ctx
    starts = c.starts
    i = bisect_right(starts, s)
    j = bisect_right(starts, e)
    return _new_span((c.line + i, s + c.col if i == 0 else s - starts[i - 1] + 1,
                      c.line + j, e + c.col if j == 0 else e - starts[j - 1] + 1, s, e))


def _span_of(x) -> A.Span:
    """The span of a token or a node."""
    if type(x) is tuple:
        return _mk(x[2], x[3])
    return x.span


def _join(a, b) -> A.Span:
    """Span from the start of ``a`` to the end of ``b`` (tokens or nodes)."""
    return _mk(a[2] if type(a) is tuple else a.span[4], b[3] if type(b) is tuple else b.span[5])


class _Fail(Exception):
    """A rule the grammar accepts but FRETish forbids, found while building the AST."""

    def __init__(self, where, message: str, hint: str | None = None):
        super().__init__(message)
        self.span = _span_of(where)
        self.message = message
        self.hint = hint
