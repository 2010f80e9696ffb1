"""The language server's memory of parsed sentences: a keystroke changes one requirement of a
document, so each sentence is parsed once (:class:`SentenceCache`) and compiled once
(:class:`CompileCache`) however often the document around it is read again.

Positions are relative: a sentence is parsed as if it started on line 1 (at its own column),
so the same sentence moved to another line by an edit above it is the same entry; whoever
shows a position adds the sentence's line offset (:mod:`fretc.editor.document`). A parse error
kept here is relative too, and handed out as a copy.

Also the two facts the server needs of a sentence that the compiler does not keep: where each
variable is written (:func:`variable_spans`) and whether each variable is read as a boolean
or a number (:func:`variable_uses`, from the formula's atoms: an ``ap`` is a boolean, a
``var`` a number).
"""

from __future__ import annotations

import copy
import dataclasses
from typing import TYPE_CHECKING
from collections import OrderedDict

from fretc.common.errors import FretishSyntaxError
from fretc.fretish import ast as A
from fretc.fretish.parser import parse

if TYPE_CHECKING:
    from fretc.fretish.entry import RequirementEntry
    from fretc.compiler.semantics import Formalization
    from fretc.compiler.build import Compiled

__all__ = ["SentenceCache", "CompileCache", "variable_spans", "variable_uses", "Span"]

Span = tuple[str, int, int, int]  # (variable, relative 1-based line, 0-based col, end col)


def variable_spans(node: A.Requirement) -> list[Span]:
    """Every variable written in the requirement ``node`` (:class:`fretc.fretish.ast.Requirement`),
    in text order: (name, 1-based line, 0-based column, 0-based end column) of its text, the
    line as parsed (relative for this module's sentences). A name written across lines
    (never in FRETish) is left out."""
    out: list[Span] = []
    stack = [node]
    while stack:
        n = stack.pop()
        if isinstance(n, A.Var):
            s = n.span
            if s.line and s.line == s.end_line:
                out.append((n.name, s.line, s.column - 1, s.end_column - 1))
            continue
        if isinstance(n, (tuple, list)):
            stack.extend(reversed(n))
        elif dataclasses.is_dataclass(n):
            stack.extend(reversed([getattr(n, f.name) for f in dataclasses.fields(n)
                                   if f.name != "span"]))
    return sorted(out, key=lambda s: (s[1], s[2]))


def variable_uses(formalization: Formalization) -> dict[str, str]:
    """Variable -> ``"boolean"`` or ``"number"``: how the requirement's formulas read it
    (``"both"`` when they do both, which the compiler never makes)."""
    from fretc.compiler import ir

    out: dict[str, str] = {}
    for f in (formalization.ft, formalization.pt):
        if f is None:
            continue
        for n in ir.walk(f):
            kind = "boolean" if n.op == "ap" else "number" if n.op == "var" else None
            if kind is not None:
                name = ir.name_of(n)
                out[name] = kind if out.get(name, kind) == kind else "both"
    return out


class SentenceCache:
    """Parsed sentences by (text, column), least recently used first out past ``limit``.
    :meth:`parse` has :func:`fretc.fretish.parser.parse`'s signature (the hook of
    :func:`fretc.fretish.files.load_fret_text`) and returns the requirement parsed at line 1;
    :attr:`hits` and :attr:`misses` count the calls."""

    def __init__(self, limit: int = 50_000):
        self.limit = limit
        self._items: OrderedDict = OrderedDict()
        self.hits = self.misses = 0

    def parse(self, text: str, *, source: str = "<string>", line: int = 1,
              column: int = 1) -> A.Requirement:
        """The requirement ``text`` parsed at line 1, ``column``; raises a copy of its
        :class:`FretishSyntaxError` (relative line). ``line`` is not used (module
        docstring)."""
        key = (text, column)
        got = self._items.get(key)
        if got is None:
            self.misses += 1
            try:
                got = (parse(text, source=source, line=1, column=column), None)
            except FretishSyntaxError as exc:
                got = (None, exc)
            self._items[key] = got
            if len(self._items) > self.limit:
                self._items.popitem(last=False)
        else:
            self.hits += 1
            self._items.move_to_end(key)
        if got[1] is not None:
            raise copy.copy(got[1])
        assert got[0] is not None  # (parsed, or the error raised above)
        return got[0]

    def spans(self, requirement: A.Requirement) -> list[Span]:
        """:func:`variable_spans` of a requirement this cache parsed, computed once."""
        key = ("spans", id(requirement))
        got = self._items.get(key)
        if got is None or got[0] is not requirement:
            got = (requirement, variable_spans(requirement))
            self._items[key] = got
        return got[1]


class CompileCache:
    """Compiled requirements (:func:`fretc.compiler.build.compile_entry`) of relative
    entries, by everything the compilation reads: id, source, text, column, tick period, the
    parsed requirement object (the same object for the same sentence: :class:`SentenceCache`;
    a new one when named durations were resolved in it), its error, the file's inputs and
    outputs."""

    def __init__(self, limit: int = 50_000):
        self.limit = limit
        self._items: OrderedDict = OrderedDict()

    def compile(self, entry: RequirementEntry) -> tuple[Compiled, dict[str, str]]:
        """The :class:`fretc.compiler.build.Compiled` of ``entry`` (whose positions are relative);
        its :func:`variable_uses` as ``compiled.uses`` is kept beside it: (compiled, uses)."""
        from fretc.compiler.build import compile_entry

        err = entry.error
        key = (entry.id, entry.source, entry.text, entry.column, entry.tick_period,
               id(entry.requirement),
               err and (err.message, err.line, err.column),  # type: ignore[attr-defined]  # (a positioned FretishError)
               entry.inputs, entry.outputs, entry.rationale, entry.parent)
        got = self._items.get(key)
        if got is None or got[2] is not entry.requirement:
            c = compile_entry(entry)
            got = (c, variable_uses(c.formalization) if c.formalization is not None else {},
                   entry.requirement)
            self._items[key] = got
            if len(self._items) > self.limit:
                self._items.popitem(last=False)
        else:
            self._items.move_to_end(key)
        return got[0], got[1]
