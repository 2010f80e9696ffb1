"""The language server's view of a workspace: its requirement files (``*.fret``) and bindings
files (``*.bindings.toml``), for what crosses files: every place a variable or a requirement
id is written (references, rename), and how the other requirement files read each variable
(the boolean-or-number diagnostic of :func:`fretc.editor.document.analyse`).

A variable is written in requirement sentences (their spans, :mod:`fretc.editor.sentences`), as
a key of a bindings file's ``[variables]`` table, and as a reference inside another variable's
expression (the binding language's ``Ref``, at its column in the expression text). A
requirement id is written on its ``ID:`` line and in ``parent:`` lines. Files are found under
the workspace folders (at most :data:`MAX_FILES` of each kind and :data:`MAX_WORKSPACE_BYTES` in
all, hidden folders skipped) and read again when their size or modification time changes; an
open document is read from the editor.
"""

from __future__ import annotations

import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

from fretc.editor.bindings_info import bindings_beside
from fretc.editor.document import MAX_DOCUMENT, Analysis, Memory, analyse

__all__ = ["Workspace", "Place", "MAX_FILES", "valid_variable_name", "valid_id"]

#: the most requirement files (and bindings files) a workspace is searched for
MAX_FILES = 2_000
#: the most bytes of the files of one kind the workspace is read for (about 20,000
#: requirements: the first analysis of them all takes a few seconds)
MAX_WORKSPACE_BYTES = 2_000_000
#: the most folders a listing of the workspace looks into
MAX_FOLDERS = 5_000
#: seconds a listing of the workspace's files is used before the folders are walked again
LIST_AGAIN = 5.0
_ID = re.compile(r"[A-Za-z0-9_.-]+\Z")
_PARENT = re.compile(r"([ \t]+parent[ \t]*:[ \t]*)([A-Za-z0-9_.-]+)[ \t]*(?:#.*)?\Z")
_ID_LINE = re.compile(r"([A-Za-z0-9_.-]+)[ \t]*:")


@dataclass(frozen=True)
class Place:
    """Where a name is written: the file, 0-based line, col and end col."""

    path: str
    line: int
    col: int
    end_col: int


def valid_variable_name(name: str) -> bool:
    """A bare FRETish variable name that a bindings file can take as a bare key."""
    from fretc.fretish.words import FRET_RESERVED, RESERVED_LETTERS, RESERVED_WORDS

    return (re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name) is not None
            and name.lower() not in RESERVED_WORDS and name not in RESERVED_LETTERS
            and name not in FRET_RESERVED)


def valid_id(rid: str) -> bool:
    """A requirement id of a ``.fret`` file."""
    return _ID.match(rid) is not None


class Workspace:
    """The files under ``roots`` (folders), with the open documents' texts given by
    ``open_text(path)`` (None when the file is not open)."""

    def __init__(self, roots: list[str], memory: Memory, open_text=lambda path: None):
        self.roots = [r for r in roots if r and os.path.isdir(r)]
        self.memory = memory
        self.open_text = open_text
        self._analyses: dict[str, tuple[tuple, Analysis]] = {}
        self._uses: tuple[tuple, dict] | None = None
        self._listed: dict[str, tuple[float, list[str]]] = {}

    def forget(self) -> None:
        """List the files again at the next request (a file was saved, opened or closed)."""
        self._listed.clear()

    def files(self, suffix: str) -> list[str]:
        """The files under the roots whose name ends in ``suffix``, sorted, at most
        :data:`MAX_FILES`; listed again when :data:`LIST_AGAIN` seconds have passed or after
        :meth:`forget` (a keystroke does not walk the folders)."""
        got = self._listed.get(suffix)
        if got is not None and time.monotonic() - got[0] < LIST_AGAIN:
            return got[1]
        out = self._walk(suffix)
        self._listed[suffix] = (time.monotonic(), out)
        return out

    def _walk(self, suffix: str) -> list[str]:
        """The walk of :meth:`files`: at most :data:`MAX_FOLDERS` folders are looked into,
        and the files found add up to at most :data:`MAX_WORKSPACE_BYTES`."""
        out: list[str] = []
        folders, size = 0, 0
        for root in self.roots:
            for folder, dirs, names in os.walk(root):
                dirs[:] = sorted(d for d in dirs if not d.startswith(".")
                                 and d not in ("node_modules", "__pycache__"))
                for n in sorted(names):
                    if not n.endswith(suffix):
                        continue
                    path = os.path.join(folder, n)
                    try:
                        size += os.stat(path).st_size
                    except OSError:
                        continue
                    if size > MAX_WORKSPACE_BYTES or len(out) >= MAX_FILES:
                        return out
                    out.append(path)
                folders += 1
                if folders >= MAX_FOLDERS:
                    return out
        return out

    def _text(self, path: str) -> tuple[tuple, str | None]:
        text = self.open_text(path)
        if text is not None:
            return ("open", hash(text)), text
        try:
            st = os.stat(path)
            if st.st_size > MAX_DOCUMENT:
                return ("big", st.st_size), None
            with open(path, encoding="utf-8") as f:
                return (st.st_size, st.st_mtime_ns), f.read()
        except (OSError, UnicodeDecodeError):
            return ("unreadable",), None

    def analysis(self, path: str) -> Analysis | None:
        """The analysis of the requirement file ``path`` (kept while it is unchanged)."""
        stamp, text = self._text(path)
        got = self._analyses.get(path)
        if got is not None and got[0] == stamp:
            return got[1]
        if text is None:
            return None
        a = analyse(text, path, self.memory)
        self._analyses[path] = (stamp, a)
        return a

    def uses_elsewhere(self, path: str) -> dict[str, tuple[str, str]]:
        """How the requirement files other than ``path`` read each variable: name ->
        (``boolean``/``number``, ``R5 (other.fret:7)``), the first reading found."""
        paths = [p for p in self.files(".fret") if os.path.abspath(p) != os.path.abspath(path)]
        stamp = tuple((p, self._text(p)[0]) for p in paths)
        if self._uses is not None and self._uses[0] == stamp:
            return self._uses[1]
        out: dict[str, tuple[str, str]] = {}
        for p in paths:
            a = self.analysis(p)
            if a is None:
                continue
            for c, uses, off in zip(a.compiled, a.uses, a.offsets):
                for name, kind in uses.items():
                    out.setdefault(name, (kind, f"{c.id} ({Path(p).name}:{off + 1})"))
        self._uses = (stamp, out)
        return out

    # ---------------------------------------------------------------- references
    def variable_places(self, name: str) -> list[Place]:
        """Every place the variable ``name`` is written in the workspace (module
        docstring), requirement files first, each file's places in order."""
        out = []
        for p in self.files(".fret"):
            a = self.analysis(p)
            if a is not None:
                out += [Place(p, ln, a_, b_) for n, ln, a_, b_ in a.occurrences() if n == name]
        for p in self.files(".bindings.toml"):
            out += _binding_places(p, name)
        return out

    def id_places(self, rid: str) -> list[Place]:
        """Every place the requirement id ``rid`` is written: its ``ID:`` line and the
        ``parent:`` lines naming it, in the workspace's requirement files."""
        out = []
        for p in self.files(".fret"):
            _stamp, text = self._text(p)
            if text is None or rid not in text:
                continue
            for i, raw in enumerate(text.split("\n")):
                m = _ID_LINE.match(raw)
                if m and m.group(1) == rid and not raw.startswith("@"):
                    out.append(Place(p, i, 0, len(rid)))
                    continue
                m = _PARENT.match(raw.rstrip("\r"))
                if m and m.group(2) == rid:
                    out.append(Place(p, i, m.start(2), m.end(2)))
        return out

    def ids(self) -> set[str]:
        """The requirement ids of the workspace's requirement files."""
        out: set[str] = set()
        for p in self.files(".fret"):
            a = self.analysis(p)
            if a is not None:
                out.update(c.id for c in a.compiled)
        return out


def _binding_places(path: str, name: str) -> list[Place]:
    """The places of ``name`` in the bindings file ``path``: its key, and its references in
    the other variables' expressions (only where the expression is written without escapes,
    so its columns are the file's)."""
    from fretc.common.errors import FretcError
    from fretc.signals.bindings.expression import ExprLocation, Ref, walk
    from fretc.signals.bindings.files import parse_bindings
    from fretc.signals.bindings.parse import parse_expression

    files = [bf for bf in bindings_beside(path) if bf.path == str(Path(path))]
    if not files:
        return []
    out = []
    info = files[0].variables.get(name)
    if info is not None and info.end_col > info.col:
        out.append(Place(path, info.line, info.col, info.end_col))
    try:
        text = Path(path).read_text(encoding="utf-8")
        b = parse_bindings(text, path)
    except (OSError, UnicodeDecodeError, FretcError):
        return out
    for other in b.variables.values():
        if name not in other.expr or other.line is None or other.col is None \
                or not other._exact:
            continue
        try:
            tree, _topics = parse_expression(other.expr, ExprLocation(path, other.name, None,
                                                                      None))
        except FretcError:
            continue
        for n in walk(tree):
            if isinstance(n, Ref) and n.name == name:
                col = other.col - 1 + n.col - 1
                out.append(Place(path, other.line - 1, col, col + len(name)))
    return out
