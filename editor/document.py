"""What the FRETish language server knows about one ``.fret`` document, without the
protocol (:mod:`fretc.editor.server` speaks LSP): its diagnostics, the requirement at a line, the
hover text of a requirement, the completions at a position and where a variable is bound.

Positions here are 0-based lines and UTF-16-agnostic character columns as LSP counts them
for ASCII text (FRETish sentences are ASCII; other text is counted in code points).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from fretc.common.errors import FretishError
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_fret_text
from fretc.fretish.words import RESERVED_WORDS

__all__ = ["Problem", "Analysis", "analyse", "check_problems", "KEYWORDS", "SAVE_WORK"]

#: The work budget of each check query on save (check.budget's units): small, so that a
#: save answers in about a second; past it a query is unknown and says nothing.
SAVE_WORK = 2_000_000

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
class Analysis:
    """A document read: ``problems``, the compiled requirements, the first line (0-based)
    of each requirement, the variables bound by the bindings file beside the document
    (name -> (file, 0-based line)), and the components the document names."""

    problems: list[Problem] = field(default_factory=list)
    compiled: list = field(default_factory=list)
    starts: list[int] = field(default_factory=list)
    bound: dict[str, tuple[str, int]] = field(default_factory=dict)
    components: list[str] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)

    def requirement_at(self, line: int):
        """The compiled requirement whose text spans 0-based ``line``, or None."""
        best = None
        for c, start in zip(self.compiled, self.starts):
            if start <= line:
                best = c
        return best

    def hover(self, line: int) -> str | None:
        """Markdown for the requirement at ``line``: its key, ft, ft_inf and pt (FRET/SMV
        text), or its error."""
        c = self.requirement_at(line)
        if c is None:
            return None
        if c.error is not None:
            return f"**{c.id}**: {c.error}"
        f = c.formalization
        if f is None:
            return f"**{c.id}**: free-form (no formalization)"
        smv = c.smv_text
        out = [f"**{c.id}** `{f.key}`", "", f"ft_inf: `{smv['ft_inf']}`", "",
               f"ft: `{smv['ft']}`", "", f"pt: `{smv['pt']}`"]
        if f.warnings:
            out += [""] + [f"note: {w}" for w in f.warnings]
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
        accepted = _accepted(sentence)
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


def _bindings_of(path: Path) -> dict[str, tuple[str, int]]:
    """The variables bound by the ``*.bindings.toml`` files beside ``path``: name ->
    (file, 0-based line of its key)."""
    out: dict[str, tuple[str, int]] = {}
    if not path.parent.is_dir():
        return out
    for f in sorted(path.parent.glob("*.bindings.toml")):
        try:
            lines = f.read_text(encoding="utf-8").splitlines()
        except (OSError, UnicodeDecodeError):
            continue
        table = None
        for i, raw in enumerate(lines):
            s = raw.strip()
            if s.startswith("["):
                table = s.strip("[] ")
                continue
            m = re.match(r'("?)([^"=]+?)\1\s*=', s)
            if table == "variables" and m:
                out.setdefault(m.group(2).strip(), (str(f), i))
    return out


def analyse(text: str, path: str) -> Analysis:
    """Read the document ``text`` (the file ``path``, whose folder gives the bindings):
    syntax and file errors at their line and column, formalization errors (a duration that
    is not a whole number of ticks, an undeclared constant), and variables that no
    bindings file beside it binds (warnings, when one exists). Never raises on a bad
    document."""
    a = Analysis(lines=text.split("\n"))
    try:
        entries = load_fret_text(text, path)
    except FretishError as exc:
        a.problems.append(_problem_of(exc, a.lines))
        return a
    a.compiled = compile_entries(entries)
    a.starts = [max(e.line - 1, 0) for e in entries]
    a.bound = _bindings_of(Path(path))
    for c in a.compiled:
        req = c.requirement
        if c.error is not None:
            a.problems.append(_problem_of(c.error, a.lines))
            continue
        if req is not None and not req.freeform and req.component:
            if req.component not in a.components:
                a.components.append(req.component)
        if a.bound and c.formalization is not None:
            for v in c.formalization.variables:
                if v not in a.bound:
                    ln = max(c.entry.line - 1, 0)
                    a.problems.append(Problem(ln, 0, len(a.lines[ln]) if ln < len(a.lines)
                                              else 0, _WARNING,
                                              f"{c.id}: variable {v!r} is not bound in the "
                                              "bindings file beside this file"))
    return a


def check_problems(a: Analysis, work: int = SAVE_WORK) -> list[Problem]:
    """``fretc check``'s conflicts, unsatisfiable and vacuous requirements of the analysed
    document, under a work budget of ``work`` units a query (answers past it say nothing
    here): one diagnostic per requirement involved, at its first line (error for a
    conflict or an unsatisfiable requirement, warning for vacuity)."""
    from fretc.check.analysis import check_requirements
    from fretc.check.budget import Budget

    ok = [c for c in a.compiled if c.error is None and c.formalization is not None]
    if not ok:
        return []
    res = check_requirements(ok, budget=Budget(work), redundancy=False, mus_budget=20)
    first = {c.id: start for c, start in zip(a.compiled, a.starts)}
    out = []
    for f in res.findings:
        if f.kind not in ("unsatisfiable", "conflict", "vacuous"):
            continue
        for rid in f.requirements:
            ln = first.get(rid, 0)
            out.append(Problem(ln, 0, len(a.lines[ln]) if ln < len(a.lines) else 0,
                               _ERROR if f.severity == "error" else _WARNING,
                               f"{f.kind}: {f.message}"))
    return out


def _problem_of(exc: Exception, lines: list[str]) -> Problem:
    """A diagnostic for a positioned error (its line and column, 1-based), or line 1."""
    line = getattr(exc, "line", None) or 1
    col = getattr(exc, "column", None) or 1
    ln = min(max(line - 1, 0), max(len(lines) - 1, 0))
    end = len(lines[ln]) if ln < len(lines) else col
    message = getattr(exc, "message", None) or str(exc).split("\n")[0]
    return Problem(ln, max(col - 1, 0), max(end, col), _ERROR, message)
