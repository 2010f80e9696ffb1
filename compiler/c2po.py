"""R2U2's C2PO specifications of a requirement set (``fretc FILE --emit c2po``).

R2U2 (Johannsen et al., CAV 2023) monitors Mission-time LTL in C, Rust and on FPGAs; C2PO is
its specification compiler. fretc writes, per requirement file, one C2PO file: an ``INPUT``
section (FRET's variables as ``bool`` or ``float`` signals) and a ``PTSPEC`` section with
each requirement's **pt formula** (FRET's past-time formalization, the formula fretc's own
monitors step), so R2U2's verdict at a tick is the pt verdict there and at the run's last
tick FRET's finite-trace verdict. The translation, from the formula IR:

Design notes: ARCHITECTURE.md, `compiler/c2po.py`."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from decimal import Decimal
from typing import TYPE_CHECKING

from fretc.compiler import ir
from fretc.compiler.codegen import file_stems
from fretc.compiler.ir import Node, name_of
from fretc.compiler.pt_step import CodegenError, check_monitorable

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["C2PO_KEYWORDS", "emit_c2po", "mltl"]

#: C2PO's reserved words (its lexer), which no signal or label may be
C2PO_KEYWORDS = frozenset((
    "STRUCT", "INPUT", "DEFINE", "FTSPEC", "PTSPEC", "ATOMIC", "foreach", "forsome",
    "forexactly", "foratleast", "foratmost", "TAU", "pow", "sqrt", "abs", "xor", "rate",
    "prev", "min", "max", "G", "F", "H", "O", "U", "R", "S", "T", "M", "true", "false",
    "bool", "int", "float"))
_BIN = {"&": "&&", "|": "||", "xor": "xor", "->": "->", "<->": "<->"}
_CMP = {"=": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
_ARITH = {"+": "+", "-": "-", "*": "*", "/": "/", "mod": "%", "^": "pow"}


def _symbol(name: str, used: set[str], limit: int = 50) -> str:
    """A C2PO symbol for ``name`` (letters, digits, ``_``; not a keyword; distinct)."""
    base = re.sub(r"[^A-Za-z0-9_]", "_", name)[:limit - 4] or "v"
    if base[0].isdigit() or base in C2PO_KEYWORDS:
        base = "v_" + base
    out, k = base, 2
    while out in used:
        out, k = f"{base}_{k}", k + 1
    used.add(out)
    return out


def _number(text: str) -> str:
    value = float(text)
    if not math.isfinite(value):
        raise CodegenError(f"the number {text} has no C2PO literal")
    out = format(Decimal(repr(abs(value))), "f")
    out = out if "." in out else out + ".0"
    return f"(-{out})" if value < 0 else out


def mltl(n: Node, names: dict[str, str]) -> str:
    """The C2PO text of the pt formula ``n`` (module docstring); ``names`` maps each FRET
    variable to its signal. Raises :class:`CodegenError` naming what C2PO cannot express."""
    memo: dict[Node, str] = {}

    def go(x: Node) -> str:
        got = memo.get(x)
        if got is None:
            got = memo[x] = _text(x, [go(a) for a in x.args], names)
        return got

    return go(n)


def _text(n: Node, a: list[str], names: dict[str, str]) -> str:
    op = n.op
    if op in ("true", "false"):
        return op
    if op in ("ap", "var"):
        return names[name_of(n)]
    if op == "num":
        return _number(name_of(n))
    if op == "FTP":
        return "(H[1,1] false)"
    if op == "past":
        return a[0]
    if op == "!":
        return f"(!{a[0]})"
    if op in _BIN:
        return f"({a[0]} {_BIN[op]} {a[1]})"
    if op == "cmp":
        return f"({a[0]} {_CMP[name_of(n)]} {a[1]})"
    if op == "arith":
        return f"({a[0]} {_ARITH[name_of(n)]} {a[1]})"
    if op == "neg":
        return f"(- {a[0]})"
    if op == "fn" and n.name in ("absReal", "absInt"):
        return f"abs({a[0]})"
    if op in ("Y", "Z"):
        return f"({'O' if op == 'Y' else 'H'}[1,1] {a[0]})"
    if op in ("O", "H"):
        bound = "[0,M]" if n.hi is None else f"[{n.lo},{n.hi}]"
        return f"({op}{bound} {a[0]})"
    if op in ("S", "T"):
        return f"({a[0]} {op}[0,M] {a[1]})"
    what = {"fn": f"the function {n.name}", "pre": f"{n.name} (a previous value)",
            "ite": "an if-then-else of numbers", "call": f"the function {n.name}"}
    raise CodegenError(f"C2PO cannot express {what.get(op, repr(op))}")


def emit_c2po(compiled: Sequence[Compiled]) -> tuple[dict[str, str], list[tuple[str, str, str]]]:
    """Per requirement file (``compiler.build.Compiled`` list, in input order) its C2PO
    text: ``({file stem: text}, [(stem, requirement id, why it is left out)])``."""
    groups: dict[str, list] = {}
    for c in compiled:
        groups.setdefault(c.entry.source, []).append(c)
    stems = file_stems(groups)
    out: dict[str, str] = {}
    skipped = []
    for source, items in groups.items():
        text, left_out = _file(source, items)
        out[stems[source]] = text
        skipped += [(stems[source], rid, why) for rid, why in left_out]
    return out, skipped


def _file(source: str, items) -> tuple[str, list[tuple[str, str]]]:
    used: set[str] = set()
    names: dict[str, str] = {}
    kinds: dict[str, str] = {}
    specs, left_out = [], []
    labels: set[str] = set()
    for c in items:
        f = c.formalization
        if f is None:
            left_out.append((c.id, "free-form" if c.freeform else "not formalized"))
            continue
        try:
            check_monitorable(f.pt)
            own = [v for v in ir.variables(f.pt) if v not in names]
            trial, taken = dict(names), set(used)
            for name in own:
                trial[name] = _symbol(name, taken)
            mltl(f.pt, trial)
        except CodegenError as exc:
            left_out.append((c.id, str(exc)))
            continue
        for name in own:
            names[name] = _symbol(name, used)
        for x in _walk(f.pt):
            if x.op in ("ap", "var"):
                kinds[x.name] = "float" if x.op == "var" or kinds.get(x.name) == "float" \
                    else "bool"
        body = mltl(f.pt, names)
        specs.append((_symbol(c.id, labels), c, body))
    return _render(source, names, kinds, specs, left_out), left_out


def _walk(n: Node):
    stack, seen = [n], set()
    while stack:
        x = stack.pop()
        if id(x) in seen:
            continue
        seen.add(id(x))
        yield x
        stack.extend(x.args)


def _comment(text: str) -> str:
    return " ".join(text.split())


def _render(source, names, kinds, specs, left_out) -> str:
    lines = [f"-- C2PO specification (R2U2) written by fretc from {_comment(source)}",
             "-- Each formula is the requirement's pt formula (FRET's past-time form): R2U2's",
             "-- verdict at a tick is the pt verdict there, at the last tick FRET's verdict.",
             "-- Unbounded past operators read [0,M]: compile with --mission-time N, N at",
             "-- least the ticks of the run. One tick = one step of the requirement's clock."]
    for name, sym in names.items():
        if sym != name:
            lines.append(f"-- signal {sym}: FRET variable {_comment(name)}")
    for rid, why in left_out:
        lines.append(f"-- not here: {_comment(rid)}: {_comment(why)}")
    if not specs:
        return "\n".join(lines) + "\n"
    lines += ["", "INPUT"]
    for kind in ("bool", "float"):
        group = [names[n] for n in names if kinds.get(n) == kind]
        if group:
            lines.append(f"    {', '.join(group)}: {kind};")
    lines += ["", "PTSPEC"]
    for label, c, body in specs:
        lines.append(f"    -- {_comment(c.id)}: {_comment(c.text)}")
        lines.append(f"    {label}: {body};")
    return "\n".join(lines) + "\n"
