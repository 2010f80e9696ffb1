"""AJPF property files (``fretc FILE --emit psl``) for the MCAPL/AJPF model checker of
Gwendolen BDI agents (Dennis et al., "Practical verification of decision-making in agent-based
autonomous systems", ASE 2016; the MCAPL manual's property specification language).

Design notes: ARCHITECTURE.md, `compiler/ajpf.py`."""

from __future__ import annotations

import re
import tomllib
from collections.abc import Sequence
from typing import TYPE_CHECKING

from fretc.common.errors import FretishError
from fretc.common.textsafe import one_line

from fretc.compiler.codegen import by_source, file_stems
from fretc.compiler.ir import Node, name_of
from fretc.compiler.printers import mangle, to_smv

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

_TERM = re.compile(r"[a-z][A-Za-z0-9_]*")  # fullmatch: "$" would take a final newline


class AjpfError(FretishError):
    """A requirement or mapping AJPF cannot take; the message says why and what to do."""

    # set on a requirement's error (its position in the file)
    source: str
    line: int
    column: int
    message: str


def load_mapping(path: str | None) -> dict:
    """Read a ``--psl-map`` TOML file. Raises :class:`AjpfError` naming the file."""
    if path is None:
        return {}
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise AjpfError(f"{path}: cannot read the AJPF mapping: {exc}") from None
    _check_mapping(path, data)
    return data


def _toml_type(value: object) -> str:
    """A decoded TOML value's type, in words."""
    return {dict: "a table", list: "an array", bool: "a boolean", int: "an integer",
            float: "a float", str: "a string"}.get(type(value), type(value).__name__)


def _check_mapping(path: str, data: dict) -> None:
    """Every value of a ``--psl-map`` file of the type the module docstring gives: a top
    ``agent`` string, ``[variables.NAME]`` tables of strings (``kind`` one of belief,
    percept, action), ``[comparisons]`` of strings. Raises :class:`AjpfError` naming the
    file and the key."""
    def want_str(value: object, key: str) -> None:
        if not isinstance(value, str):
            raise AjpfError(f"{path}: {key} must be a string, not {_toml_type(value)}")

    if "agent" in data:
        want_str(data["agent"], "agent")
    for table in ("variables", "comparisons"):
        if not isinstance(data.get(table, {}), dict):
            raise AjpfError(f"{path}: {table} must be a table, not "
                            f"{_toml_type(data[table])}")
    for var, spec in data.get("variables", {}).items():
        if not isinstance(spec, dict):
            raise AjpfError(f"{path}: variables.{one_line(var)} must be a table, not "
                            f"{_toml_type(spec)}")
        for key in ("kind", "name", "agent"):
            if key in spec:
                want_str(spec[key], f"variables.{one_line(var)}.{key}")
        kind = spec.get("kind", "belief")
        if kind not in ("belief", "percept", "action"):
            raise AjpfError(f"{path}: variables.{one_line(var)}.kind must be belief, percept "
                            f"or action, not {one_line(repr(kind))}")
    for text, name in data.get("comparisons", {}).items():
        want_str(name, f"comparisons.{one_line(repr(text))}")


def psl_label(rid: str, used: set[str]) -> str:
    """The AJPF property label of requirement ``rid``: its characters outside
    ``[A-Za-z0-9_]`` made ``_`` (a name a ``.psl`` line may start with),
    ``_2``, ``_3``, ... appended until it is not in ``used``, to which it is added."""
    base = re.sub(r"[^A-Za-z0-9_]", "_", rid) or "req"
    label, k = base, 2
    while label in used:
        label, k = f"{base}_{k}", k + 1
    used.add(label)
    return label


def _term(name: str, what: str) -> str:
    if not isinstance(name, str) or not _TERM.fullmatch(name):
        raise AjpfError(
            f"{what} '{one_line(repr(name))[1:-1]}' is not a Gwendolen term (it must start with a lower-case letter "
            "and hold only letters, digits and '_'); give it a name in the --psl-map file")
    return name


def to_ajpf(node: Node, agent: str, mapping: dict) -> str:
    """AJPF text of an ft_inf formula. Raises :class:`AjpfError` for what AJPF cannot
    express."""
    variables = mapping.get("variables", {})
    comparisons = mapping.get("comparisons", {})

    def atom_for_var(name: str) -> str:
        spec = variables.get(name, {})
        kind = spec.get("kind", "belief")
        term = _term(spec.get("name", mangle(name)), "variable")
        ag = _term(spec.get("agent", agent), "agent")
        if kind == "percept":
            return f"P({term})"
        if kind == "action":
            return f"D({ag},{term})"
        return f"B({ag},{term})"

    # same shape as bench/bench_monitor.py's to_rye: a case per IR operator (kept: AJPF spells
    # every case its own way)
    def go(n: Node) -> str:
        op = n.op
        if op == "ap":
            return atom_for_var(name_of(n))
        if op == "cmp":
            text = to_smv(n)
            if text not in comparisons:
                raise AjpfError(
                    f"the comparison {text} has no belief name: AJPF checks beliefs, not "
                    f"numbers; map it in the --psl-map file ([comparisons] \"{text}\" = "
                    "\"some_belief\")")
            return f"B({_term(agent, 'agent')},{_term(comparisons[text], 'belief')})"
        if op == "!":
            return f"~{go(n.args[0])}"
        if op == "&":
            return f"({go(n.args[0])} & {go(n.args[1])})"
        if op == "|":
            return f"({go(n.args[0])} || {go(n.args[1])})"
        if op == "->":
            return f"({go(n.args[0])} -> {go(n.args[1])})"
        if op == "<->":
            a, b = go(n.args[0]), go(n.args[1])
            return f"(({a} -> {b}) & ({b} -> {a}))"
        if op == "xor":
            a, b = go(n.args[0]), go(n.args[1])
            return f"(({a} & ~{b}) || (~{a} & {b}))"
        if op in ("G", "F"):
            if n.hi is not None:
                raise AjpfError(
                    f"AJPF has no bounded operators ({op}[{n.lo},{n.hi}] here, from a "
                    "'within/for/after N' timing); state the property without a deadline "
                    "(e.g. 'eventually') for model checking and keep the deadline for the "
                    "runtime monitor")
            return ("[] " if op == "G" else "<> ") + go(n.args[0])
        if op == "U":
            return f"({go(n.args[0])} U {go(n.args[1])})"
        if op == "V":
            return f"({go(n.args[0])} R {go(n.args[1])})"
        if op == "X":
            raise AjpfError(
                "AJPF has no next operator (X here, from a regular condition 'upon/when/if', "
                "a mode scope or 'at the next timepoint'); use 'whenever' with a null scope, "
                "or check this requirement with the runtime monitor")
        if op in ("true", "false"):
            raise AjpfError(
                f"the infinite-trace formula is {op.upper()}: there is nothing for AJPF to "
                "check (e.g. 'finally' only speaks of the last point of a finite run)")
        if op in ("past", "FTP"):
            raise AjpfError(f"AJPF has no past-time operators ({to_smv(n)}); express the "
                            "condition as a belief the agent maintains")
        if op == "call":
            raise AjpfError(f"the function {to_smv(n)} has no AJPF form")
        raise AjpfError(f"no AJPF form for {to_smv(n)}")

    return go(node)


def emit_psl(compiled: Sequence[Compiled], mapping_path: str | None = None) -> dict[str, str]:
    """One ``.psl`` text per requirement file: ``{file stem: text}``. Requirements AJPF
    cannot take appear as comment lines with the reason (and so do failed ones). A comment
    line starts with ``#`` in column 0: AJPF's property-file reader skips exactly those and
    reads every other line as ``label: formula`` (a ``//`` line would be read as a property
    labelled ``//...``, or glued onto the property above)."""
    mapping = load_mapping(mapping_path)
    for c in compiled:
        refuse_probability(c)
    groups = by_source(compiled)
    stems = file_stems(groups)
    out: dict[str, str] = {}
    for source, items in groups.items():
        used: set = set()
        lines = [f"# AJPF properties generated by fretc from {_comment(source)}"]
        for c in items:
            lines.append(f"# {_comment(c.id)}: {_comment(c.text)}")
            lines += [f"#   {_comment(n)}" for n in _named(c)]
            if c.formalization is None:
                lines.append("#   not formalized: " + _comment(
                    getattr(c.error, "message", "free-form requirement")))
                continue
            agent = mapping.get("agent") or c.requirement.component
            try:
                formula = to_ajpf(c.formalization.ft_inf, agent, mapping)
            except AjpfError as exc:
                lines.append("#   no AJPF property: " + _comment(str(exc)))
                continue
            lines.append(f"{psl_label(c.id, used)}: {formula}")
        out[stems[source]] = "\n".join(lines) + "\n"
    return out


def refuse_probability(compiled: Compiled) -> None:
    """Raise :class:`AjpfError` positioned at the ``with probability`` phrase of a
    probability requirement (``file:line:col: error: ...``): AJPF checks that *every*
    execution of the agent satisfies a property and has no probability operator, so a .psl
    property of the path formula alone would claim more than the requirement does (a bound
    of 95 % at each trigger checked as 100 %). Nothing is written for the file then."""
    b = getattr(compiled, "probability", None)
    if b is None:
        return
    from fretc.common.errors import render_diagnostic

    req = compiled.requirement
    assert req is not None and req.probability is not None  # (b is its bound)
    e, span = compiled.entry, req.probability.span
    line = span.line if span.line else e.line
    column = span.column if span.line else e.column
    msg = (f"requirement {one_line(compiled.id)} has 'with probability {b.op} {b.text}': "
           "AJPF has no probabilities (it checks that every run satisfies a property), so "
           "no .psl property states this requirement (a bound at each trigger); judge it "
           "over triggers instead (fretc audit of several logs, fretc estimate), write its "
           "PCTL for PRISM (--emit prism), or drop the probability field to demand it on "
           "every run")
    err = AjpfError(render_diagnostic(e.source, line, column, msg))
    err.source, err.line, err.column, err.message = e.source, line, column, msg
    raise err


def psl_label_and_formula(compiled: Compiled, mapping: dict | None = None
                          ) -> tuple[str | None, str]:
    """``(label, formula)`` of one compiled requirement, or ``(None, reason)``."""
    if compiled.formalization is None:
        return None, "not formalized"
    if compiled.probability is not None:
        return None, ("AJPF has no probabilities: 'with probability' bounds each trigger's "
                      "chance and is judged over triggers, not by a .psl property")
    mapping = mapping or {}
    try:
        assert compiled.requirement is not None  # (it formalized)
        agent = mapping.get("agent") or compiled.requirement.component
        return psl_label(compiled.id, set()), to_ajpf(compiled.formalization.ft_inf, agent,
                                                    mapping)
    except AjpfError as exc:
        return None, str(exc)


def _named(c) -> list[str]:
    """The named durations of ``c``'s requirement with their values (a comment each)."""
    from fretc.fretish.constants import constant_notes

    return constant_notes(c.requirement)


def _comment(text: str) -> str:
    """One ``#`` comment line's text: white space folded, control and bidi characters escaped
    (:func:`fretc.common.textsafe.one_line`; a NUL or U+202E in an id must not reach the file)."""
    return one_line(text)
