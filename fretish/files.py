"""Requirement files: fretc's ``.fret`` text format and FRET's JSON exports.

``.fret``: one requirement per line (``ID: sentence``, UTF-8), ``#`` comments, indented
continuation lines and ``rationale:``/``parent:``/``tick_period:`` attributes, and the
directives ``@tick_period`` (a duration of :mod:`fretc.common.units`, kept as an exact
:class:`~fractions.Fraction` of seconds), ``@inputs`` and ``@outputs``. FRET exports
(``.json``): a list of requirement objects (``reqid``, ``fulltext``, ``rationale``,
``parent_reqid``; the rest in :attr:`RequirementEntry.extra`) or an object whose
``"requirements"`` member is that list. Every span and error position is a file position.
The format in full: ARCHITECTURE.md ("Requirement files").
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable
from typing import NoReturn

from fretc.common.errors import FretishError, FretishFileError, FretishSyntaxError
from fretc.fretish.entry import Fraction, Requirement, RequirementEntry  # entry's imports
from fretc.fretish.entry_cache import cached_entries
from fretc.fretish.sources import fret_origin, load_tool_source, tool_source_kind
from fretc.fretish.directives import name_tokens, parse_tick_period, split_names
from fretc.fretish.fret_variables import declare, fret_variables

__all__ = ["RequirementEntry", "load_requirements", "load_fret_text", "parse_tick_period",
           "is_fret_export", "split_names"]

PathLike = str | os.PathLike


# --------------------------------------------------------------------------- .fret files
_ID_LINE = re.compile(r"([A-Za-z0-9_.-]+)[ \t]*:")
# Patterns of rare lines, compiled on first use by re's own cache (re.match(pattern, ...)):
# a file without them does not pay for their compilation (start-up time)
_ATTRIBUTE = r"[ \t]+(rationale|parent|tick_period)[ \t]*:[ \t]*(.*)\Z"
_DIRECTIVE = r"@([A-Za-z_]+)(?:[ \t]+(.*))?\Z"


def _strip_comment(line: str) -> str:
    """``line`` without its ``#`` comment (a ``#`` inside double quotes is text) and
    without trailing whitespace."""
    if "#" not in line:
        return line.rstrip()
    quoted = False
    i, n = 0, len(line)
    while i < n:
        ch = line[i]
        if quoted and ch == "\\":
            i += 2
            continue
        if ch == '"':
            quoted = not quoted
        elif ch == "#" and not quoted:
            return line[:i].rstrip()
        i += 1
    return line.rstrip()


class _Pending:
    """A requirement being read from a .fret file."""

    def __init__(self, rid: str, line: int):
        self.id = rid
        self.id_line = line
        self.pieces: list[tuple[int, int, str]] = []   # (line, column, text from column)
        self.attrs: dict[str, tuple[str, int, int]] = {}
        self.last_attr: str | None = None


def _read_text(path: str) -> str:
    """The file's text (UTF-8, a BOM dropped). Raises :class:`FretishFileError`: an
    unreadable file, or a byte that is not UTF-8 (at its line and column)."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise FretishFileError(f"cannot read: {e.strerror}", source=str(path)) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        skip = 3 if raw.startswith(b"\xef\xbb\xbf") else 0
        start = e.start + skip if e.object is not raw else e.start
        line = raw.count(b"\n", 0, start) + 1
        head = raw[raw.rfind(b"\n", 0, start) + 1:start]
        col = len(head.decode("utf-8", errors="replace")) + 1
        raise FretishFileError(f"not UTF-8 text: byte 0x{raw[start]:02x} ({e.reason})",
                               source=str(path), line=line, column=col) from None


def _load_fret(path: str) -> list[RequirementEntry]:
    text = _read_text(path)
    return cached_entries(str(path), text, lambda: _FretReader(path, text).read())


class _FretReader:
    """One pass over the lines of a .fret file (the format of this module's docstring):
    requirements, their attributes and the file's directives; then the entries."""

    def __init__(self, path: str, text: str | None = None, parse_sentence=None):
        self.source = str(path)
        if parse_sentence is None:  # lazy: Lark only when a file is parsed (start-up time)
            from fretc.fretish.parser import parse as parse_sentence
        self.parse = parse_sentence
        self.lines = (_read_text(path) if text is None else text).split("\n")
        self.pending: list[_Pending] = []
        self.seen: dict[str, int] = {}
        self.file_period: Fraction | None = None
        self.period_line = 0
        self.io: dict[str, tuple[str, ...]] = {}
        self.io_line: dict[str, int] = {}
        self.current: _Pending | None = None
        #: ``@constant NAME DURATION``: name -> (amount, unit), and its line
        self.constants: dict[str, tuple[str, str]] = {}
        self.constant_line: dict[str, int] = {}

    def fail(self, msg: str, ln: int, col: int = 1, hint: str | None = None) -> NoReturn:
        raise FretishFileError(msg, source=self.source, line=ln, column=col,
                               text_line=self.lines[ln - 1].rstrip("\r"), hint=hint)

    def read(self) -> list[RequirementEntry]:
        for ln, raw in enumerate(self.lines, start=1):
            # (_strip_comment's result without its call on a line without "#")
            content = _strip_comment(raw.rstrip("\r")) if "#" in raw else raw.rstrip()
            if not content:
                continue
            if content[0] in " \t":                           # indented: belongs above
                self._indented(ln, content)
            elif content.startswith("@"):
                self._directive(ln, content)
            else:
                self._id_line(ln, content)
        return [self._entry(p) for p in self.pending]

    def _indented(self, ln: int, content: str) -> None:
        current = self.current
        if current is None:
            self.fail("indented line outside a requirement", ln,
                      len(content) - len(content.lstrip()) + 1,
                      "start a requirement with 'ID: sentence' at column 1")
        m = re.match(_ATTRIBUTE, content)
        if m:
            key, value = m.group(1), m.group(2).strip()
            if key in current.attrs:
                self.fail(f"duplicate attribute '{key}' for requirement {current.id}", ln,
                          m.start(1) + 1)
            current.attrs[key] = (value, ln, m.start(2) + 1)
            current.last_attr = key
        elif current.last_attr == "rationale":
            value, aln, acol = current.attrs["rationale"]
            current.attrs["rationale"] = (f"{value} {content.strip()}".strip(), aln, acol)
        elif current.last_attr is not None:
            col = len(content) - len(content.lstrip()) + 1
            self.fail(f"the sentence of {current.id} must come before its attributes", ln,
                      col, "put continuation lines right under the 'ID:' line")
        elif current.pieces:
            current.pieces.append((ln, 1, content))
        else:                                                 # sentence starts here
            col = len(content) - len(content.lstrip()) + 1
            current.pieces.append((ln, col, content[col - 1:]))

    def _directive(self, ln: int, content: str) -> None:
        m = re.match(_DIRECTIVE, content)
        if m and m.group(1) in ("inputs", "outputs"):
            self._io_directive(ln, content, m)
            return
        if m and m.group(1) == "constant":
            self._constant(ln, content, m)
            return
        if not m or m.group(1) != "tick_period":
            self.fail(f"unknown directive '{content.split()[0]}'", ln, 1,
                      "the directives are '@tick_period <number> <unit>', '@inputs NAMES', "
                      "'@outputs NAMES' and '@constant NAME <number> <unit>'")
        if self.period_line:
            self.fail(f"second @tick_period (the first is on line {self.period_line})", ln)
        try:
            self.file_period = parse_tick_period(m.group(2) or "")
        except ValueError as e:
            self.fail(f"bad @tick_period: {e}", ln, (m.start(2) + 1) if m.group(2) else 1)
        self.period_line = ln
        self.current = None

    def _io_directive(self, ln: int, content: str, m: re.Match) -> None:
        kind = m.group(1)
        if kind in self.io_line:
            self.fail(f"second @{kind} (the first is on line {self.io_line[kind]})", ln)
        try:
            names = [n for n, _at in name_tokens(m.group(2) or "", identifiers=True)]
        except ValueError as exc:
            why, token, at = exc.args
            self.fail(f"bad variable name '{token}' in @{kind} ({why})", ln,
                      m.start(2) + at + 1)
        self.io[kind] = tuple(names)
        self.io_line[kind] = ln
        clash = sorted(set(self.io.get("inputs", ())) & set(self.io.get("outputs", ())))
        if clash:
            self.fail("declared both @inputs and @outputs: " + ", ".join(clash), ln)
        self.current = None

    def _constant(self, ln: int, content: str, m: re.Match) -> None:
        """``@constant T_stop 1.5 s``: a named duration (:mod:`fretc.fretish.constants`)."""
        from fretc.fretish.constants import CONSTANT_NAME, parse_constant

        name, _, value = (m.group(2) or "").strip().partition(" ")
        if not CONSTANT_NAME.match(name):
            self.fail(f"bad constant name {name!r}: write '@constant T_stop 1.5 s'", ln,
                      (m.start(2) + 1) if m.group(2) else 1)
        if name in self.constants:
            self.fail(f"second @constant {name} (the first is on line "
                      f"{self.constant_line[name]})", ln)
        try:
            self.constants[name] = parse_constant(value)
        except ValueError as e:
            self.fail(f"bad @constant {name}: {e}", ln, content.index(name) + len(name) + 2)
        self.constant_line[name] = ln
        self.current = None

    def _id_line(self, ln: int, content: str) -> None:
        m = _ID_LINE.match(content)
        if not m:
            self.fail("expected 'ID: requirement' (an id of letters, digits, '_', '.' or '-', "
                      "then ':')", ln, 1,
                      "begin each requirement with its id, e.g. 'R1: the sw shall ...'; "
                      "indent continuation lines")
        rid = m.group(1)
        if rid in self.seen:
            self.fail(f"duplicate requirement id '{rid}' (first defined on line "
                      f"{self.seen[rid]})", ln, 1)
        self.seen[rid] = ln
        self.current = _Pending(rid, ln)
        self.pending.append(self.current)
        rest = content[m.end():]
        if rest.strip():
            col = m.end() + (len(rest) - len(rest.lstrip())) + 1
            self.current.pieces.append((ln, col, content[col - 1:]))

    def _entry(self, p: _Pending) -> RequirementEntry:
        source, lines = self.source, self.lines
        period = self.file_period
        if "tick_period" in p.attrs:
            value, aln, acol = p.attrs["tick_period"]
            try:
                period = parse_tick_period(value)
            except ValueError as e:
                raise FretishFileError(f"bad tick_period for {p.id}: {e}", source=source,
                                       line=aln, column=acol,
                                       text_line=lines[aln - 1].rstrip("\r")) from None
        if len(p.pieces) == 1:                              # a sentence on one line
            line0, col0, text = p.pieces[0]
        elif p.pieces:
            line0, col0, _ = p.pieces[0]
            chunks, prev = [], line0
            for ln, _col, piece in p.pieces:
                chunks.append("\n" * (ln - prev) + piece)
                prev = ln
            text = "".join(chunks)
        else:
            line0, col0, text = p.id_line, len(lines[p.id_line - 1].rstrip()) + 2, ""
        attrs = p.attrs
        # the fields in order (positional: half the keywords' cost; the order is
        # checked by tests/fretish/test_files.py)
        entry = RequirementEntry(
            p.id, text, source, line0, col0,
            attrs["rationale"][0] if "rationale" in attrs else None,
            (attrs["parent"][0] or None) if "parent" in attrs else None,
            period, None, None, {}, self.io.get("inputs", ()), self.io.get("outputs", ()))
        try:
            entry.requirement = self.parse(text, source=source, line=line0, column=col0)
            if self.constants:
                from fretc.fretish.constants import resolve

                entry.requirement = resolve(entry.requirement, self.constants)
        except FretishSyntaxError as e:
            if 0 < e.line <= len(lines):                      # show the whole file line
                e.text_line = lines[e.line - 1].rstrip("\r")
                e.text_line_column = 1
            entry.error = e
        return entry


# --------------------------------------------------------------------------- JSON exports
_FULLTEXT = r'"fulltext"\s*:\s*"'  # compiled on first use (re's cache), as _ATTRIBUTE
_KNOWN = ("reqid", "parent_reqid", "rationale", "fulltext")


def load_fret_text(text: str, source: str, parse_sentence: Callable[..., Requirement] | None = None
                   ) -> list[RequirementEntry]:
    """The requirements of a ``.fret`` document given as text (an editor's buffer), as
    :func:`load_requirements` reads a ``.fret`` file named ``source``. ``parse_sentence``:
    called instead of :func:`fretc.fretish.parser.parse` with the same arguments (the
    language server's cache of parsed sentences, :mod:`fretc.editor.document`).

    Raises:
        FretishFileError: the file structure is wrong (positioned, as for a file)."""
    return _FretReader(source, text, parse_sentence).read()


def _line_col(raw: str, offset: int) -> tuple[int, int]:
    line = raw.count("\n", 0, offset) + 1
    return line, offset - (raw.rfind("\n", 0, offset) + 1) + 1


def _load_json(path: str) -> list[RequirementEntry]:
    source = str(path)
    raw = _read_text(path)
    import json  # lazy: only FRET's JSON exports need it (start-up time)
    try:
        data = json.loads(raw)
    except RecursionError:
        raise FretishFileError("invalid FRET export: nested too deeply", source=source) from None
    except json.JSONDecodeError as e:
        lines = raw.split("\n")
        raise FretishFileError(f"invalid JSON: {e.msg}", source=source, line=e.lineno,
                               column=e.colno, text_line=lines[e.lineno - 1]
                               if e.lineno <= len(lines) else None) from None
    if isinstance(data, dict) and isinstance(data.get("requirements"), list):
        reqs = data["requirements"]
    elif isinstance(data, list):
        reqs = data
    else:
        raise FretishFileError("expected a list of FRET requirements or an object with a "
                               "\"requirements\" list", source=source)
    declared = fret_variables(data, source)
    starts = [m.end() for m in re.finditer(_FULLTEXT, raw)]
    exact_positions = len(starts) == len(reqs)
    entries = []
    seen: dict[str, tuple[int, int, int, str | None]] = {}
    for k, obj in enumerate(reqs):
        where = f"requirement #{k + 1}"
        line, col = _line_col(raw, starts[k]) if exact_positions else (1, 1)
        if not isinstance(obj, dict):
            raise FretishFileError(f"{where} is not a JSON object", source=source,
                                   line=line, column=col)
        rid = obj.get("reqid")
        if not isinstance(rid, str) or not rid.strip():
            raise FretishFileError(f"{where} has no \"reqid\"", source=source, line=line,
                                   column=col)
        text = obj.get("fulltext")
        if not isinstance(text, str):
            raise FretishFileError(f"requirement {rid} has no \"fulltext\" string",
                                   source=source, line=line, column=col)
        _check_json_strings(obj, where, source, line, col)
        project = obj.get("project")
        first = seen.get(rid)
        if first is not None:  # ids are unique across a run, whatever their project
            k0, line0, col0, project0 = first
            raise FretishFileError(
                f"duplicate requirement id {rid!r}"
                + (f" (project {project!r})" if project is not None else "")
                + f": requirement #{k0 + 1} at {source}:{line0}:{col0}"
                + (f" (project {project0!r})" if project0 is not None else "")
                + " has it too; ids are unique across a run", source=source, line=line,
                column=col)
        seen[rid] = (k, line, col, project)
        rationale = obj.get("rationale")
        parent = obj.get("parent_reqid")
        entry = RequirementEntry(
            id=rid, text=text, source=source, line=line, column=col,
            rationale=rationale if isinstance(rationale, str) and rationale else None,
            parent=parent if isinstance(parent, str) and parent else None,
            extra={k2: v for k2, v in obj.items() if k2 not in _KNOWN},
            origin=fret_origin(source, obj))
        try:
            from fretc.fretish.parser import parse  # lazy: as _FretReader
            entry.requirement = parse(text, source=source, line=line, column=col,
                                      letters_as_names=True)  # (FRET's names: T)
        except FretishSyntaxError as e:
            entry.error = e
        if declared and entry.requirement is not None:
            declare(entry, declared)
        entries.append(entry)
    return entries


def _check_json_strings(obj: dict, where: str, source: str, line: int, col: int) -> None:
    """The fields of one FRET JSON requirement that fretc reads: ``project`` absent, null
    or a string, and no lone surrogate (a JSON
    ``\\ud800`` escape, which no UTF-8 output can hold) in any string. Raises
    :class:`FretishFileError` at the requirement."""
    project = obj.get("project")
    if project is not None and not isinstance(project, str):
        raise FretishFileError(f"{where}: \"project\" must be a string, not "
                               f"{_json_type(project)}", source=source, line=line,
                               column=col)
    for key in ("reqid", "project", "fulltext", "rationale", "parent_reqid"):
        value = obj.get(key)
        if isinstance(value, str) and any(0xD800 <= ord(ch) <= 0xDFFF for ch in value):
            raise FretishFileError(f"{where}: \"{key}\" holds a lone surrogate (a "
                                   "\\uD800-\\uDFFF escape without its pair), which is not "
                                   "text", source=source, line=line, column=col)


def _json_type(value: object) -> str:
    """The JSON type of a decoded value, in words."""
    return {list: "a list", dict: "an object", bool: "a boolean", int: "a number",
            float: "a number", str: "a string"}.get(type(value), type(value).__name__)


# --------------------------------------------------------------------------- entry point
def _path_text(p) -> str:
    """``str(pathlib.Path(p))`` without importing pathlib (start-up time): on POSIX
    the path with empty and ``.`` parts dropped (one or three-plus leading slashes are
    ``/``, exactly two stay ``//``), ``.`` when nothing is left; elsewhere pathlib itself."""
    p = os.fspath(p)
    if os.name != "posix" or not isinstance(p, str):
        from pathlib import Path
        return str(Path(p))
    root = "//" if p.startswith("//") and not p.startswith("///") else \
        "/" if p.startswith("/") else ""
    parts = [x for x in p.split("/") if x and x != "."]
    return root + "/".join(parts) if root or parts else "."


def _suffix(path: str) -> str:
    """``pathlib.PurePath(path).suffix``: the file name's last ``.ext`` (none for a name
    starting with its only dot or ending with a dot)."""
    name = path.rsplit("/", 1)[-1] if os.name == "posix" else os.path.basename(path)
    i = name.rfind(".")
    return name[i:] if 0 < i < len(name) - 1 else ""


def is_fret_export(path: str) -> bool:
    """Whether the JSON file at ``path`` is a FRET export by its content: a non-empty list
    of requirement objects (or an object with such a ``"requirements"`` list), each with a
    ``"reqid"`` or a ``"fulltext"`` (FRET's export format). Unreadable or invalid JSON is
    not one."""
    import json  # lazy: as _load_json
    try:
        data = json.loads(_read_text(path))
    except (OSError, ValueError, FretishError, RecursionError):
        return False
    if isinstance(data, dict):
        data = data.get("requirements")
    return (isinstance(data, list) and bool(data) and all(
        isinstance(x, dict) and ("reqid" in x or "fulltext" in x) for x in data))


#: The files a folder contributes (ReqIF files by their name, :mod:`fretc.fretish.sources`).
_FOLDER_SUFFIXES = (".fret", ".json", ".reqif", ".reqifz")


def _files_of(paths, skipped: list[str] | None = None) -> list[str]:
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    out: list[str] = []
    for p in paths:
        path = _path_text(p)
        if os.path.isdir(path) and tool_source_kind(path) == "doorstop":
            out.append(path)                                  # a Doorstop tree: one source
        elif os.path.isdir(path):
            names = sorted(os.listdir(path))
            for f in (_path_text(os.path.join(path, n)) for n in names):
                if not os.path.isfile(f) or _suffix(f).lower() not in _FOLDER_SUFFIXES:
                    continue
                if _suffix(f) == ".json" and not is_fret_export(f):
                    if skipped is not None:
                        skipped.append(f"{f}: skipped: a JSON file that is not a FRET export "
                                       "(no requirements with \"reqid\" and \"fulltext\")")
                    continue
                out.append(f)
        elif os.path.isfile(path):
            out.append(path)
        else:
            raise FretishFileError("no such file or folder", source=path, line=1, column=1)
    return out


def requirement_files(paths: PathLike | Iterable[PathLike]) -> list[str]:
    """The requirement files (and Doorstop trees) that ``paths`` (files or folders, as
    ``load_requirements`` takes them) name, in the order they are read: a folder's
    ``.fret``, FRET JSON exports, ReqIF files (a JSON file that is no FRET export left out).

    Raises:
        FretishFileError: a path that is neither a file nor a folder."""
    return _files_of(paths)


def _read_one(f: str, text_attribute: str | None,
              not_formalized: list[RequirementEntry] | None) -> list[RequirementEntry]:
    """The entries of one file or tool source (:func:`load_requirements`)."""
    kind = tool_source_kind(f)
    if kind is not None:
        got, unformalized = load_tool_source(f, kind, text_attribute)
        if not_formalized is not None:
            not_formalized.extend(unformalized)
        return got
    return _load_json(f) if _suffix(f).lower() == ".json" else _load_fret(f)


def load_requirements(paths: PathLike | Iterable[PathLike],
                      skipped: list[str] | None = None, text_attribute: str | None = None,
                      not_formalized: list[RequirementEntry] | None = None
                      ) -> list[RequirementEntry]:
    """Read requirements from files and folders, in the order given.

    ``paths`` is one path or an iterable of paths; a folder contributes its ``*.fret``
    files and its ``*.json`` files that are FRET exports by content (:func:`is_fret_export`;
    another JSON file there, an audit's ``--json`` output say, is skipped and a note for it
    appended to ``skipped``), not recursively, sorted by name; a file named itself is read
    as JSON if its name ends in ``.json`` and as ``.fret`` otherwise (formats: module
    docstring). ReqIF files (``.reqif``, ``.reqifz``, also in folders) and Doorstop trees
    (a folder holding ``.doorstop.yml`` files) are read by :mod:`fretc.fretish.sources`, the
    FRETish text from ``text_attribute`` (default ``FRETish``); their items without FRETish
    text are appended to ``not_formalized`` (when given) and not returned.

    Returns one :class:`RequirementEntry` per requirement. A sentence that does not parse
    gives an entry with ``error`` set (a :class:`FretishSyntaxError` in file coordinates)
    and reading goes on. Structural problems (unreadable file, bad JSON, a line without
    ``ID:``, a duplicate id, a bad tick period, a missing path) raise
    :class:`FretishFileError` naming ``file:line:column``.
    """
    entries: list[RequirementEntry] = []
    read: set = set()
    first: dict[str, RequirementEntry] = {}
    for f in _files_of(paths, skipped):
        key = os.path.realpath(f)
        if key in read:  # the same file named twice (a folder and a file in it)
            continue
        read.add(key)
        got = _read_one(f, text_attribute, not_formalized)
        for e in got:
            # ids are unique across all the files of a run: verdicts, monitors and reports
            # are keyed by id; duplicates inside one file are caught by
            # its reader
            other = first.get(e.id)
            if other is not None and other.source != e.source:
                raise FretishFileError(
                    f"requirement id '{e.id}' is also defined at {other.source}:{other.line}; "
                    "ids must be unique across the requirement files of a run (rename one)",
                    source=e.source, line=e.line,
                    column=e.column if _suffix(f).lower() == ".json" else 1)
            first.setdefault(e.id, e)
        entries.extend(got)
    return entries
