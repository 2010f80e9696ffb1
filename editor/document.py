"""What the FRETish language server knows about one ``.fret`` document, without the
protocol (:mod:`fretc.editor.server` speaks LSP): its diagnostics, the requirement at a line,
the hover text of a requirement or a variable, the completions at a position, where each
variable is written and where it is bound.

Design notes: ARCHITECTURE.md, `editor/document.py`."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING
from dataclasses import dataclass, field
from pathlib import Path

from fretc.common.errors import FretishError
from fretc.fretish.files import load_fret_text
from fretc.fretish.words import RESERVED_WORDS

from fretc.editor.bindings_info import VariableInfo, bindings_beside
from fretc.editor.sentences import CompileCache, SentenceCache

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled
    from fretc.check.solver import SpotWorker

__all__ = ["Problem", "Analysis", "Memory", "analyse", "check_problems", "KEYWORDS",
           "SAVE_WORK", "MAX_DOCUMENT", "MAX_PROBLEMS", "MAX_HOVER", "MAX_DIAGRAM_TICKS"]

#: The work budget of each check query on save (check.budget's units): small, so that a
#: save answers in about a second; past it a query is unknown and says nothing.
SAVE_WORK = 2_000_000
#: the largest document analysed (characters, about 20,000 requirements)
MAX_DOCUMENT = 2_000_000
#: the most diagnostics published for one document
MAX_PROBLEMS = 1_000
#: the longest hover text (characters)
MAX_HOVER = 64_000
#: the widest diagram a hover draws (ticks)
MAX_DIAGRAM_TICKS = 200

#: FRETish's words offered by completion (the reserved words of the grammar).
KEYWORDS = sorted(w for w in RESERVED_WORDS if w.isalpha())
_ERROR, _WARNING = 1, 2  # LSP DiagnosticSeverity


@dataclass
class Problem:
    """One diagnostic: 0-based ``line``/``col`` to ``end_col`` on that line, ``severity``
    (1 error, 2 warning), the message."""

    line: int
    col: int
    end_col: int
    severity: int
    message: str


@dataclass
class Memory:
    """What a session of the server keeps between analyses: the parsed sentences and the
    compiled requirements."""

    sentences: SentenceCache = field(default_factory=SentenceCache)
    compiled: CompileCache = field(default_factory=CompileCache)


@dataclass
class Analysis:
    """A document read: ``problems``, the compiled requirements (positions relative to each
    one's first line: add ``offsets[i]``), the first line (0-based) of each requirement, the
    variables the bindings files beside the document bind (name -> (file, 0-based line), and
    with their type and unit in ``variables``), how each requirement reads each variable
    (``uses[i]``: name -> ``boolean``/``number``), the components the document names."""

    problems: list[Problem] = field(default_factory=list)
    compiled: list = field(default_factory=list)
    starts: list[int] = field(default_factory=list)
    offsets: list[int] = field(default_factory=list)
    uses: list[dict] = field(default_factory=list)
    bound: dict[str, tuple[str, int]] = field(default_factory=dict)
    variables: dict[str, VariableInfo] = field(default_factory=dict)
    components: list[str] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    memory: Memory | None = None

    def requirement_at(self, line: int) -> Compiled | None:
        """The compiled requirement whose text spans 0-based ``line``, or None."""
        best = None
        for c, start in zip(self.compiled, self.starts):
            if start <= line:
                best = c
        return best

    def occurrences(self) -> list[tuple[str, int, int, int]]:
        """Every variable written in the document: (name, 0-based line, col, end col)."""
        out = []
        for c, off in zip(self.compiled, self.offsets):
            req = c.requirement
            if req is None or req.freeform:
                continue
            spans = (self.memory.sentences.spans(req) if self.memory is not None
                     else _spans(req))
            out += [(name, off + ln - 1, col, end) for name, ln, col, end in spans]
        return out

    def word_at(self, line: int, col: int) -> str | None:
        """The variable written at 0-based ``line``/``col`` (on its characters or just
        after), or None."""
        for name, ln, a, b in self.occurrences():
            if ln == line and a <= col <= b:
                return name
        return None

    def hover(self, line: int, col: int | None = None) -> str | None:
        """Markdown for the variable at ``line``/``col`` (its binding, type and unit, and how
        the requirements read it), else for the requirement at ``line``: its key, ft,
        ft_inf and pt (FRET/SMV text) and its diagram, or its error. At most
        :data:`MAX_HOVER` characters."""
        name = self.word_at(line, col) if col is not None else None
        text = self._variable_hover(name) if name else self._requirement_hover(line)
        if text is not None and len(text) > MAX_HOVER:
            text = text[:MAX_HOVER] + "\n\n(cut: the hover is at most " \
                                      f"{MAX_HOVER:,} characters)"
        return text

    def _variable_hover(self, name: str) -> str:
        info = self.variables.get(name)
        readers = [(c.id, u[name]) for c, u in zip(self.compiled, self.uses) if name in u]
        out = [f"**{name}**"]
        if info is None:
            out.append("not bound in a bindings file beside this file")
        else:
            out += [f"type: {info.type}" + (f", unit: {info.unit}" if info.unit else
                                            ", unit: not known" if info.type == "number"
                                            else ""), f"({info.how})", "",
                    f"`{info.expr}`", "", f"bound in {Path(info.file).name}:{info.line + 1}"]
        if readers:
            out += ["", "read as " + ", ".join(f"{kind} by {rid}" for rid, kind in readers[:20])
                    + (f" and {len(readers) - 20} more" if len(readers) > 20 else "")]
        return "\n".join(out)

    def _requirement_hover(self, line: int) -> str | None:
        c = self.requirement_at(line)
        if c is None:
            return None
        if c.error is not None:
            return f"**{c.id}**: {getattr(c.error, 'message', c.error)}"
        f = c.formalization
        if f is None:
            return f"**{c.id}**: free-form (no formalization)"
        smv = c.smv_text
        out = [f"**{c.id}** `{f.key}`", "", f"ft_inf: `{smv['ft_inf']}`", "",
               f"ft: `{smv['ft']}`", "", f"pt: `{smv['pt']}`"]
        if f.warnings:
            out += [""] + [f"note: {w}" for w in f.warnings]
        if (f.ticks or 0) > MAX_DIAGRAM_TICKS:
            out += ["", f"(no diagram: {f.ticks:,} ticks is wider than the "
                        f"{MAX_DIAGRAM_TICKS} a hover draws; fretc explain -o DIR draws it)"]
        else:
            picture = _diagram_image(c)
            if picture:
                out += ["", picture]
        return "\n".join(out)

    def completions(self, line: int, col: int) -> list[tuple[str, str]]:
        """(label, kind) pairs at 0-based ``line``/``col``: the FRETish words the grammar
        accepts there (Lark's interactive parser on the sentence so far), and where a name
        may come the components the document names and the variables of the bindings;
        ``kind`` is ``keyword``, ``component`` or ``variable``. After a condition the
        components come first."""
        text = self.lines[line][:col] if line < len(self.lines) else ""
        m = re.match(r"\s*[A-Za-z0-9_.\-]+\s*:", text)
        sentence = text[m.end():] if m and not text.lstrip().startswith("@") else text
        accepted = _accepted(sentence[-2000:])
        words = re.findall(r"[A-Za-z_][A-Za-z0-9_]*", sentence)
        lowered = [w.lower() for w in words]
        after_condition = any(w in ("upon", "when", "whenever", "if", "unless", "where")
                              for w in lowered) and "shall" not in lowered
        if accepted is None:
            keywords = [(k, "keyword") for k in KEYWORDS]
            names = True
        else:
            keywords = [(k, "keyword") for k in KEYWORDS
                        if k.upper() in accepted and k.upper() not in _UNITS]
            keywords += [(u, "keyword") for t, u in _UNITS.items() if t in accepted]
            names = bool(accepted & {"NAME", "STRING"})
        components = [(c, "component") for c in self.components] if names else []
        variables = [(v, "variable") for v in sorted(self.bound)] if names else []
        if after_condition:
            return components + keywords + variables
        return variables + components + keywords

    def definition(self, word: str) -> tuple[str, int] | None:
        """Where variable ``word`` is bound: (bindings file, 0-based line), or None."""
        return self.bound.get(word)


#: Unit terminals of the grammar -> the word completion offers.
_UNITS = {"TICK": "ticks", "MICROSECOND": "microseconds", "MILLISECOND": "milliseconds",
          "SECOND": "seconds", "MINUTE": "minutes", "HOUR": "hours"}


def _spans(req):
    from fretc.editor.sentences import variable_spans

    return variable_spans(req)


def _accepted(sentence: str) -> set | None:
    """The grammar's terminals accepted after ``sentence`` (None when it cannot tell)."""
    from fretc.fretish.diagnostics import accepted_before
    from fretc.fretish.parser import cached_lark

    try:
        return accepted_before(cached_lark(), sentence, "start", len(sentence))
    except Exception:  # completion must never fail: offer everything then
        return None


def _diagram_image(compiled) -> str | None:
    """``fretc explain``'s reading and diagram as Markdown (the SVG as a data URI image, for
    the clients that show one), or None when there is none."""
    import base64

    from fretc.monitors.explain import explain
    from fretc.reports.explanation import svg

    try:
        x = explain(compiled)
    except (ValueError, KeyError):
        return None
    data = base64.b64encode(svg(x).encode("utf-8")).decode("ascii")
    return f"{x.reading}\n\n![diagram of {compiled.id}](data:image/svg+xml;base64,{data})"


def analyse(text: str, path: str, memory: Memory | None = None,
            elsewhere: dict[str, tuple[str, str]] | None = None) -> Analysis:
    """Read the document ``text`` (the file ``path``, whose folder gives the bindings):
    syntax and file errors at their line and column, formalization errors (a duration that
    is not a whole number of ticks, an undeclared constant), variables that no bindings file
    beside it binds (warnings, when one exists), and variables read as a boolean in one
    requirement and as a number in another (or bound to the other type: errors).
    ``memory``: the session's :class:`Memory` (a new one when None); ``elsewhere``: how other
    requirement files of the workspace read variables (name -> (``boolean``/``number``,
    where)). Never raises on a bad document."""
    memory = memory or Memory()
    a = Analysis(lines=text.split("\n"), memory=memory)
    if len(text) > MAX_DOCUMENT:
        a.problems.append(Problem(0, 0, 1, _WARNING,
                                  f"this document has {len(text):,} characters: the language "
                                  f"server analyses documents of at most {MAX_DOCUMENT:,} "
                                  "(run fretc on the file)"))
        return a
    try:
        entries = load_fret_text(text, path, memory.sentences.parse)
    except FretishError as exc:
        a.problems.append(_problem_of(exc, a.lines))
        return a
    files = bindings_beside(path)
    for bf in files:
        for name, info in bf.variables.items():
            a.variables.setdefault(name, info)
            a.bound.setdefault(name, (info.file, info.line))
    for e in entries:
        off = max(e.line - 1, 0)
        e.line = 1  # relative, as its parse (the entry is this analysis's own)
        c, uses = memory.compiled.compile(e)
        a.compiled.append(c)
        a.uses.append(uses)
        a.offsets.append(off)
        a.starts.append(off)
        _entry_problems(a, c, uses, off)
    _type_problems(a, elsewhere or {})
    if len(a.problems) > MAX_PROBLEMS:
        more = len(a.problems) - MAX_PROBLEMS
        a.problems = a.problems[:MAX_PROBLEMS] + [Problem(0, 0, 1, _WARNING, f"{more:,} more "
                                                          "problems are not shown")]
    return a


def _entry_problems(a: Analysis, c, uses: dict, off: int) -> None:
    """The problems of one requirement: its error, its unbound variables."""
    req = c.requirement
    if c.error is not None:
        p = _problem_of(c.error, a.lines, off)
        a.problems.append(p)
        return
    if req is not None and not req.freeform and req.component:
        if req.component not in a.components:
            a.components.append(req.component)
    if a.bound and c.formalization is not None:
        for v in c.formalization.variables:
            if v not in a.bound:
                a.problems.append(Problem(off, 0, _width(a.lines, off), _WARNING,
                                          f"{c.id}: variable {v!r} is not bound in the "
                                          "bindings file beside this file"))


def _type_problems(a: Analysis, elsewhere: dict[str, tuple[str, str]]) -> None:
    """Errors at each use of a variable read as a boolean in one requirement and as a number
    in another (of this document or, by ``elsewhere``, another file), or as the other type
    than its binding gives."""
    first: dict[str, tuple[str, str]] = {}
    for c, uses in zip(a.compiled, a.uses):
        for name, kind in uses.items():
            first.setdefault(name, (kind, c.id))
    spans = None
    for i, (c, uses) in enumerate(zip(a.compiled, a.uses)):
        for name, kind in uses.items():
            other = None
            info = a.variables.get(name)
            if info is not None and info.type not in ("unknown", kind):
                other = f"bound to a {info.type} in {Path(info.file).name}:{info.line + 1}"
            elif first[name][0] != kind:
                other = f"read as a {first[name][0]} by {first[name][1]}"
            elif name in elsewhere and elsewhere[name][0] != kind:
                other = f"read as a {elsewhere[name][0]} by {elsewhere[name][1]}"
            if other is None:
                continue
            if spans is None:
                spans = a.occurrences()
            ln, col, end = next(((ln, x, y) for n, ln, x, y in spans if n == name
                                 and a.offsets[i] <= ln and (i + 1 == len(a.offsets) or
                                                             ln < a.offsets[i + 1])),
                                (a.offsets[i], 0, _width(a.lines, a.offsets[i])))
            a.problems.append(Problem(ln, col, end, _ERROR,
                                      f"{c.id} reads {name!r} as a {kind}, but it is "
                                      f"{other}: a variable is a boolean or a number"))


def _width(lines: list[str], ln: int) -> int:
    return len(lines[ln]) if ln < len(lines) else 0


def check_problems(a: Analysis, work: int = SAVE_WORK, worker: SpotWorker | None = None
                   ) -> list[Problem]:
    """``fretc check``'s conflicts, unsatisfiable and vacuous requirements of the analysed
    document, under a work budget of ``work`` units a query (answers past it say nothing
    here): one diagnostic per requirement involved, at its first line (error for a
    conflict or an unsatisfiable requirement, warning for vacuity). ``worker``: the
    :class:`fretc.check.solver.SpotWorker` to ask (default: a forked one of its own)."""
    from fretc.check.analysis import check_requirements
    from fretc.check.budget import Budget

    ok = [c for c in a.compiled if c.error is None and c.formalization is not None]
    if not ok:
        return []
    res = check_requirements(ok, budget=Budget(work), redundancy=False, mus_budget=20,
                             worker=worker)
    first = {c.id: start for c, start in zip(a.compiled, a.starts)}
    out = []
    for f in res.findings:
        if f.kind not in ("unsatisfiable", "conflict", "vacuous"):
            continue
        for rid in f.requirements:
            ln = first.get(rid, 0)
            out.append(Problem(ln, 0, _width(a.lines, ln),
                               _ERROR if f.severity == "error" else _WARNING,
                               f"{f.kind}: {f.message}"))
    return out


def _problem_of(exc: Exception, lines: list[str], offset: int = 0) -> Problem:
    """A diagnostic for a positioned error (its line and column, 1-based; ``offset`` lines
    added to a position relative to a sentence), or line 1."""
    line = (getattr(exc, "line", None) or 1) + offset
    col = getattr(exc, "column", None) or 1
    ln = min(max(line - 1, 0), max(len(lines) - 1, 0))
    end = len(lines[ln]) if ln < len(lines) else col
    message = getattr(exc, "message", None) or str(exc).split("\n")[0]
    return Problem(ln, max(col - 1, 0), max(end, col), _ERROR, message)
