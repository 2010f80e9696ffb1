"""CoCoSpec contracts for Kind 2 (``fretc FILE --emit cocospec``), as FRET's CoCoSpec export
makes them.

One Lustre file per component, ``<component>Spec.lus``: a library of past-time operators as
Lustre nodes, then the contract ``<component>Spec`` (inputs and outputs the component's Input
and Output variables, types from the glossary, Internal variables as ``var``, one
``guarantee "ID" EXPR;`` per requirement, EXPR its pt formula in Lustre, from the IR, never
from printed text). What Lustre cannot say (``^``, ``mod`` of reals, uninterpreted
functions, the future) leaves the requirement out with the reason. The translation operator
by operator and Kind 2's types: ARCHITECTURE.md ("CoCoSpec contracts"); each node's meaning
is tested in ``tests/compiler/test_cocospec.py``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from fretc.common.textsafe import one_line

from fretc.compiler import ir
from fretc.compiler.ir import Node, name_of
from fretc.compiler.printers import mangle

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["CocospecUnsupported", "Contract", "LIBRARY", "component_of", "contracts",
           "declared_variables", "emit_cocospec", "library_text", "lustre", "lustre_type",
           "used_types"]


class CocospecUnsupported(ValueError):
    """A pt formula Lustre (or Kind 2's typing) cannot say; the message names what."""


#: Kind 2's keywords (its Lustre lexer's, ``lsh`` and ``rsh`` included), which no variable
#: may be named (renamed ``NAME_v``)
LUSTRE_KEYWORDS = frozenset("""
    type datatype int uint sint real bool subrange of subtype struct enum history map set
    const param transparent opaque imported rec lemma node function returns var let tel con
    noc assert check reachable invariant provided from at within contract import true false
    not and xor forall exists or in if then else elsif fi when cond otherwise auto end frame
    div mod any choose current condact activate initial default every restart merge pre fby
    last mode assume guarantee require ensure weakly assumption_vars decreases with match
    int8 int16 int32 int64 uint8 uint16 uint32 uint64 lsh rsh
""".split())

#: FRET's operator nodes as fretc writes them: name -> (the nodes it calls, its Lustre text).
#: ``delay`` is written per file (:func:`_delay_nodes`).
LIBRARY: dict[str, tuple[tuple[str, ...], str]] = {
    "H": ((), """-- H(X): X has held at every tick so far
node H(X: bool) returns (Y: bool);
let
  Y = X -> (X and pre Y);
tel"""),
    "O": ((), """-- O(X): X has held at some tick so far
node O(X: bool) returns (Y: bool);
let
  Y = X or (false -> pre Y);
tel"""),
    "S": ((), """-- S(X, Y): Y since X (X now, or Y now and S(X, Y) a tick ago)
node S(X, Y: bool) returns (Z: bool);
let
  Z = X or (Y and (false -> pre Z));
tel"""),
    "T": ((), """-- T(X, Y): Y triggered X (X now, and Y now or T(X, Y) a tick ago, true before
-- the first tick)
node T(X, Y: bool) returns (Z: bool);
let
  Z = X and (Y or (true -> pre Z));
tel"""),
    "YtoPre": ((), """-- YtoPre(X): X a tick ago (false at the first tick)
node YtoPre(X: bool) returns (Y: bool);
let
  Y = false -> pre X;
tel"""),
    "ZtoPre": ((), """-- ZtoPre(X): X a tick ago (true at the first tick)
node ZtoPre(X: bool) returns (Y: bool);
let
  Y = true -> pre X;
tel"""),
    "OTlore": ((), """-- OTlore(N, X): X held at one of the last N+1 ticks (this one included)
node OTlore(N: int; X: bool) returns (Y: bool);
var C: int;
let
  -- ticks since X last held, -1 before it ever did, counted no further than N+1
  C = if X then 0
      else (-1 -> if pre C < 0 or pre C > N then pre C else pre C + 1);
  Y = 0 <= C and C <= N;
tel"""),
    "OT": (("delay", "OTlore"), """-- OT(L, R, X): X held at some tick between L and R ticks ago (L >= R >= 0)
node OT(L: int; R: int; X: bool) returns (Y: bool);
let
  Y = OTlore(L - R, delay(X, R));
tel"""),
    "HT": (("OT",), """-- HT(L, R, X): X held at every tick between L and R ticks ago (L >= R >= 0)
node HT(L: int; R: int; X: bool) returns (Y: bool);
let
  Y = not OT(L, R, not X);
tel"""),
    "preBool": ((), """-- preBool(I, X): X a tick ago, I at the first tick
node preBool(I, X: bool) returns (Y: bool);
let
  Y = I -> pre X;
tel"""),
    "preInt": ((), """-- preInt(I, X): X a tick ago, I at the first tick
node preInt(I, X: int) returns (Y: int);
let
  Y = I -> pre X;
tel"""),
    "preReal": ((), """-- preReal(I, X): X a tick ago, I at the first tick
node preReal(I, X: real) returns (Y: real);
let
  Y = I -> pre X;
tel"""),
    "absReal": ((), """node absReal(X: real) returns (Y: real);
let
  Y = if X >= 0.0 then X else -X;
tel"""),
    "absInt": ((), """node absInt(X: int) returns (Y: int);
let
  Y = if X >= 0 then X else -X;
tel"""),
    "maxReal": ((), """node maxReal(A, B: real) returns (Z: real);
let
  Z = if A >= B then A else B;
tel"""),
    "maxInt": ((), """node maxInt(A, B: int) returns (Z: int);
let
  Z = if A >= B then A else B;
tel"""),
    "minReal": ((), """node minReal(A, B: real) returns (Z: real);
let
  Z = if A <= B then A else B;
tel"""),
    "minInt": ((), """node minInt(A, B: int) returns (Z: int);
let
  Z = if A <= B then A else B;
tel"""),
}

_BOOL_BIN = {"&": "and", "|": "or", "xor": "xor", "->": "=>", "<->": "="}
_CMP = {"=": "=", "!=": "<>", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
_FN_TYPE = {"absReal": "real", "maxReal": "real", "minReal": "real", "absInt": "int",
            "maxInt": "int", "minInt": "int", "preReal": "real", "preInt": "int"}


def lustre_type(data_type: str) -> str | None:
    """The Lustre type of FRET's glossary ``dataType``, as FRET's CoCoSpec export maps it:
    ``boolean`` -> ``bool``, a name with ``int`` in it (``integer``, ``unsigned integer``,
    ``int32`` ...) -> ``int``, another (``single``, ``double``) -> ``real``; None for ``""``
    (not given)."""
    if not data_type:
        return None
    if data_type == "boolean":
        return "bool"
    return "int" if "int" in data_type else "real"


def lustre(n: Node, names: dict[str, str], types: dict[str, str],
           used: set[str] | None = None) -> str:
    """The Lustre text of the pt formula ``n`` (module docstring). ``names`` maps each FRET
    variable to its Lustre name, ``types`` each numeric one to ``int`` or ``real`` (absent:
    real). ``used`` (when given) gets the library nodes the text calls and ``delayN`` for
    each delay. Raises :class:`CocospecUnsupported` naming what Lustre or Kind 2's typing
    cannot say."""
    calls: set[str] = set() if used is None else used
    memo: dict[Node, str] = {}

    def go(x: Node) -> str:
        got = memo.get(x)
        if got is None:
            got = memo[x] = _formula(x, go, names, types, calls)
        return got

    return go(n)


def _formula(n: Node, go, names, types, calls: set[str]) -> str:
    op, a = n.op, n.args
    if op in ("true", "false"):
        return op
    if op == "ap":
        return names[name_of(n)]
    if op == "FTP":
        calls.add("ZtoPre")
        return "ZtoPre(false)"
    if op == "past":
        return go(a[0])
    if op == "!":
        return f"(not {go(a[0])})"
    if op in _BOOL_BIN:
        return f"({go(a[0])} {_BOOL_BIN[op]} {go(a[1])})"
    if op == "cmp":
        return _cmp_text(n, names, types, calls)
    if op == "pre" and n.name == "preBool":
        calls.add("preBool")
        return f"preBool({go(a[0])}, {go(a[1])})"
    if op in ("Y", "Z"):
        name = "YtoPre" if op == "Y" else "ZtoPre"
        calls.add(name)
        return f"{name}({go(a[0])})"
    if op in ("O", "H"):
        if n.hi is None:
            calls.add(op)
            return f"{op}({go(a[0])})"
        lo, hi = ir.window(n)
        calls.update((f"{op}T", "OT"))
        if lo:
            calls.add(f"delay{lo}")
        return f"{op}T({hi}, {lo}, {go(a[0])})"
    if op in ("S", "T"):
        calls.add(op)
        return f"{op}({go(a[1])}, {go(a[0])})"
    raise CocospecUnsupported(_refusal(n))


def _refusal(n: Node) -> str:
    op = n.op
    if op == "future":
        return (f"the pt formula needs the future-time function {n.name}, which a "
                "past-time Lustre contract cannot read")
    if op == "call" or op == "fn":
        return f"the function {n.name} has no Lustre node here (uninterpreted)"
    return f"Lustre has no form of {op!r} here"


def _number(text: str, kind: str) -> str:
    """The Lustre literal of the number ``text`` as an ``int`` or a ``real``."""
    try:
        value = float(text)
    except ValueError as exc:
        raise CocospecUnsupported(f"the number {text} has no Lustre literal") from exc
    if value != value or value in (float("inf"), float("-inf")):
        raise CocospecUnsupported(f"the number {text} has no Lustre literal")
    if kind == "int":
        return text
    from decimal import Decimal
    out = format(Decimal(text), "f")
    return out if "." in out else out + ".0"


#: a term's Lustre type (``int``, ``real``; None: an integer literal, either) and its text
#: in a given type
_Typed = tuple


def _cmp_text(n: Node, names, types, calls: set[str]) -> str:
    """A comparison of two terms, both in one type: ``real`` when either is real (an
    integer term then converted by Kind 2's ``real``), else ``int``."""
    left = _typed(n.args[0], names, types, calls)
    right = _typed(n.args[1], names, types, calls)
    kind = "real" if "real" in (left[0], right[0]) else "int"
    return f"({left[1](kind)} {_CMP[name_of(n)]} {right[1](kind)})"


def _as(kind_of: str | None, text: str):
    """The text-in-a-type function of a term of type ``kind_of`` written ``text``."""
    def render(kind: str) -> str:
        if kind_of == kind:
            return text
        if kind_of == "int" and kind == "real":
            return f"(real {text})"
        raise CocospecUnsupported(f"a real term ({text}) where Lustre needs an integer")
    return render


def _typed(n: Node, names, types, calls: set[str]) -> _Typed:
    """``(type, render)`` of the term ``n`` (:data:`_Typed`). Raises
    :class:`CocospecUnsupported`."""
    op, a = n.op, n.args
    if op == "var":
        return _typed_leaf(types.get(name_of(n), "real"), names[name_of(n)])
    if op == "num":
        text = name_of(n)
        if re.fullmatch(r"[0-9]+", text):
            return None, lambda kind: _number(text, kind)
        return "real", _as("real", _number(text, "real"))
    if op == "neg":
        kind, render = _typed(a[0], names, types, calls)
        return kind, lambda k: f"(- {render(k)})"
    if op == "arith":
        return _typed_arith(n, names, types, calls)
    if op in ("fn", "pre") and n.name in _FN_TYPE:
        calls.add(name_of(n))
        result = _FN_TYPE[name_of(n)]
        args = [_typed(x, names, types, calls)[1](result) for x in a]
        return _typed_leaf(result, f"{n.name}({', '.join(args)})")
    if op == "ite":
        raise CocospecUnsupported("an if-then-else of numbers (not translated to Lustre)")
    raise CocospecUnsupported(_refusal(n))


def _typed_leaf(kind: str, text: str) -> _Typed:
    return kind, _as(kind, text)


def _typed_arith(n: Node, names, types, calls: set[str]) -> _Typed:
    sym = name_of(n)
    if sym == "^":
        raise CocospecUnsupported("Lustre has no power operator (^)")
    (ka, ra), (kb, rb) = (_typed(x, names, types, calls) for x in n.args)
    if sym == "mod":
        if "real" in (ka, kb):
            raise CocospecUnsupported("mod of real numbers: Lustre's mod takes integers")
        return "int", _as("int", f"({ra('int')} mod {rb('int')})")
    if sym == "/":  # FRET's division is the reals' (Lustre's / of reals; div is another)
        return "real", _as("real", f"({ra('real')} / {rb('real')})")
    kind = "real" if "real" in (ka, kb) else ("int" if "int" in (ka, kb) else None)
    if kind is None:
        return None, lambda k: f"({ra(k)} {sym} {rb(k)})"
    return kind, lambda k: _as(kind, f"({ra(kind)} {sym} {rb(kind)})")(k)


def library_text(used: set[str]) -> str:
    """The Lustre of the library nodes ``used`` names and of the nodes they call, in
    :data:`LIBRARY`'s order, then ``delay`` and its ``delayN`` nodes when a bounded
    operator needs them (``delayN`` in ``used``)."""
    need: set[str] = set()
    stack = [u for u in used if u in LIBRARY]
    while stack:
        name = stack.pop()
        if name in need:
            continue
        need.add(name)
        stack.extend(d for d in LIBRARY[name][0] if d in LIBRARY)
    parts = [LIBRARY[name][1] for name in LIBRARY if name in need]
    if "OT" in need:
        delays = sorted(int(u[5:]) for u in used if re.fullmatch(r"delay[0-9]+", u))
        parts.append(_delay_nodes(delays))
    return "\n\n".join(parts)


def _delay_nodes(delays: list[int]) -> str:
    """``delay(X, R)`` (X R ticks ago, false before tick R) for the ``delays`` used, with one
    ``delayN`` node per N > 0."""
    cases = "".join(f"\n       else if R = {d} then delay{d}(X)" for d in delays)
    out = ["-- delay(X, R): X R ticks ago, false before; R is 0 or one of the file's delays\n"
           "node delay(X: bool; R: int) returns (Y: bool);\nlet\n"
           f"  Y = if R = 0 then X{cases}\n       else false;\ntel"]
    for d in delays:
        names = [f"X{k}" for k in range(d + 1)]
        body = "\n".join(f"  X{k} = false -> pre X{k - 1};" for k in range(1, d + 1))
        out.append(f"node delay{d}(X: bool) returns (Y: bool);\nvar {', '.join(names)}: bool;\n"
                   f"let\n  X0 = X;\n{body}\n  Y = X{d};\ntel")
    return "\n\n".join(out)


@dataclass
class Contract:
    """One component's contract: ``name`` (``<component>Spec``), ``inputs`` and ``outputs``
    (``[(Lustre name, type)]``), ``internals`` (``[(name, type, Lustre definition)]``, each
    definition as :mod:`fretc.compiler.cocospec_definitions` re-prints it), ``guarantees``
    (``[(requirement id, text, Lustre expression, assume?)]``), ``used`` (the library nodes
    called), ``notes`` (comment lines), ``skipped`` (``[(requirement id, why)]``),
    ``left_out`` (``[(variable, why)]``: definitions not written), ``names`` (each FRET
    variable's Lustre name: :meth:`lustre_name`)."""

    component: str
    name: str
    inputs: list[tuple[str, str]] = field(default_factory=list)
    outputs: list[tuple[str, str]] = field(default_factory=list)
    internals: list[tuple[str, str, str]] = field(default_factory=list)
    guarantees: list[tuple[str, str, str, bool]] = field(default_factory=list)
    used: set[str] = field(default_factory=set)
    notes: list[str] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)
    left_out: list[tuple[str, str]] = field(default_factory=list)
    names: dict[str, str] = field(default_factory=dict)
    taken: set[str] = field(default_factory=set)

    def lustre_name(self, name: str) -> str:
        """The Lustre name of the FRET variable ``name`` in this contract, the same
        wherever the file writes it (signature, ghosts, guarantees; Ogma's names): FRET's
        mangling, ``_v`` after a Kind 2 keyword or a library node's name, ``_2``, ``_3`` ...
        after a name already taken. Named on first use."""
        got = self.names.get(name)
        if got is None:
            got = self.names[name] = _lustre_name(name, self.taken)
        return got


def contracts(compiled: Sequence[Compiled]) -> list[Contract]:
    """One :class:`Contract` per component of ``compiled`` (``compiler.build.Compiled``, in
    input order; components in order of first appearance, FRET's ``<component>Spec``). A
    requirement that did not parse (its error is the compiler's) or is free-form names no
    component and is in none."""
    groups: dict[str, list] = {}
    for c in compiled:
        if c.requirement is not None and not c.freeform:  # (no component: no contract)
            groups.setdefault(component_of(c), []).append(c)
    return [_contract(comp, items) for comp, items in groups.items()]


def component_of(c: Compiled) -> str:
    """The component of the compiled requirement ``c`` (its sentence's, as FRET groups
    requirements), ``"component"`` for one without (free-form, not parsed)."""
    r = c.requirement
    return (r.component if r is not None and not r.freeform else "") or "component"


def declared_variables(items: Sequence[Compiled]) -> tuple[dict[str, str], dict[str, object],
                                                            list[str], list[str]]:
    """``(types, FRET variables by name, inputs, outputs)`` the entries of ``items``
    declare: Lustre types from FRET's glossary (:func:`lustre_type`), the
    :class:`fretc.fretish.fret_variables.FretVariable` of each name, and the ``@inputs`` /
    ``@outputs`` (a FRET export: the component's Input and Output variables) in order."""
    types: dict[str, str] = {}
    fret: dict[str, object] = {}
    inputs: list[str] = []
    outputs: list[str] = []
    for c in items:
        for v in c.entry.variables:
            fret.setdefault(v.name, v)
            t = lustre_type(v.data_type)
            if t is not None:
                types.setdefault(v.name, t)
        inputs += [x for x in c.entry.inputs if x not in inputs]
        outputs += [x for x in c.entry.outputs if x not in outputs]
    return types, fret, inputs, outputs


def used_types(items: Sequence[Compiled], types: dict[str, str]) -> None:
    """Add to ``types`` (variable -> ``bool``/``int``/``real``) the type of each variable the
    pt formulas of ``items`` read that it has none for (the glossary gives none): ``bool``
    for a boolean variable, ``real`` for a number (fretc's numbers are reals)."""
    for c in items:
        f = c.formalization
        if f is not None and c.error is None:
            for x in ir.walk(f.pt):
                if x.op in ("ap", "var") and name_of(x) not in types:
                    types[name_of(x)] = "bool" if x.op == "ap" else "real"


def _lustre_name(name: str, taken: set[str]) -> str:
    """A Lustre name for the FRET variable ``name`` not in ``taken`` (added to it): FRET's
    mangling; ``v_`` before a name starting with ``then`` or ``else`` (Kind 2's lexer reads
    ``and then...`` and ``or else...`` as its short-circuit operators, whatever follows);
    ``_v`` after a keyword (:data:`LUSTRE_KEYWORDS`) or a library node's name; then ``_2``,
    ``_3`` ... until it is free."""
    base = mangle(name)
    if base.startswith(("then", "else")):
        base = "v_" + base
    elif base in LUSTRE_KEYWORDS or base in LIBRARY or re.fullmatch(r"delay[0-9]*", base):
        base += "_v"
    out, k = base, 2
    while out in taken:
        out, k = f"{base}_{k}", k + 1
    taken.add(out)
    return out


def _contract(comp: str, items) -> Contract:
    out = Contract(comp, _lustre_name(comp + "Spec", set()))
    types, fret, inputs, outputs = declared_variables(items)
    out.taken.add(out.name)
    used_types(items, types)
    for name in inputs + outputs:
        out.lustre_name(name)
    for c in items:
        f = c.formalization
        if f is None or c.error is not None:
            why = "free-form" if c.freeform else "not formalized"
            out.skipped.append((c.id, why))
            continue
        trial = set(out.taken)  # (a requirement left out names nothing)
        own = {v: _lustre_name(v, trial) for v in ir.variables(f.pt) if v not in out.names}
        used: set[str] = set()
        try:
            lustre(f.pt, {**out.names, **own}, types, used)
        except CocospecUnsupported as exc:
            out.skipped.append((c.id, str(exc)))
            continue
        for v in own:
            out.lustre_name(v)
        expr = lustre(f.pt, out.names, types, used)
        out.used |= used
        out.guarantees.append((c.id, c.text, expr, "assumption" in c.id.lower()))
    _signature(out, types, fret, inputs, outputs)
    return out


def _signature(out: Contract, types, fret, inputs, outputs) -> None:
    """Inputs, outputs and Internal variables of ``out``: the declared ones, every Internal
    variable of the glossary with a definition fretc reads (as FRET's export, those a
    definition reads first; :func:`fretc.compiler.cocospec_definitions.ghost_definitions`,
    the others left out with the reason), then each variable a guarantee or a definition
    reads that is declared neither way nor defined, as an input (with a note)."""
    from fretc.compiler.cocospec_definitions import ghost_definitions

    out.outputs = [(out.names[n], types.get(n, "bool")) for n in outputs]
    out.inputs = [(out.names[n], types.get(n, "bool")) for n in inputs]
    internal = [v for name, v in fret.items()
                if getattr(v, "kind", "") == "Internal" and v.assignment.strip()
                and name not in inputs and name not in outputs]
    ghosts = ghost_definitions(internal, types, out.lustre_name)
    out.internals = [(g.lustre, g.type, g.text) for g in ghosts.written]
    out.used |= ghosts.used
    defined = {g.name for g in ghosts.written}
    out.left_out = ghosts.left_out
    for name, lname in list(out.names.items()):
        if name in inputs or name in outputs or name in defined:
            continue
        kind = getattr(fret.get(name), "kind", "")
        out.inputs.append((lname, types.get(name, "bool")))
        what = f"a FRET {kind} variable" if kind else "declared neither input nor output"
        here = "" if lname == name else f" ({lname} here)"
        out.notes.append(f"{one_line(name)}{here}: {what}; read as an input")


def _comment(text: str) -> str:
    return one_line(text).replace("*)", "* )")


def _label(rid: str) -> str:
    """The text of a property's string label showing the requirement id ``rid``: one line
    (:func:`fretc.common.textsafe.one_line`, as every target folds ids), ``\\`` and ``"``
    escaped (Kind 2's lexer reads ``\\c`` as ``c``), so no content closes the string."""
    return one_line(rid).replace("\\", "\\\\").replace('"', '\\"')


def _render(c: Contract, source: str) -> str:
    lines = [f"-- CoCoSpec contract for Kind 2, written by fretc from {_comment(source)}",
             "-- (FRET's CoCoSpec export): each guarantee is the requirement's pt formula,",
             "-- past-time LTL, with FRET's operators as the Lustre nodes below.",
             f"-- Use it from a node: (*@contract import {c.name}(...) returns (...); *)"]
    lines += [f"-- note: {_comment(n)}" for n in c.notes]
    lines += [f"-- not here: {_comment(rid)}: {_comment(why)}" for rid, why in c.skipped]
    lines += [f"-- not defined here: {_comment(name)}: {_comment(why)}"
              for name, why in c.left_out]
    if not c.guarantees and not c.internals:  # (Kind 2: a contract holds at least one item)
        lines.append(f"-- no contract: none of {_comment(c.component)}'s requirements could "
                     "be written")
        return "\n".join(lines) + "\n"
    lib = library_text(c.used)
    if lib:
        lines += ["", lib]
    ins = "; ".join(f"{n}: {t}" for n, t in c.inputs) or "lustreC: bool"
    outs = "; ".join(f"{n}: {t}" for n, t in c.outputs)
    lines += ["", f"contract {c.name}({ins}) returns ({outs});", "let"]
    for name, t, definition in c.internals:
        lines.append(f"  var {name}: {t} = {definition};")
    for rid, text, expr, assume in c.guarantees:
        label = _label(rid)
        lines.append(f"  (* {_comment(rid)}: {_comment(text)} *)")
        lines.append(f"  {'assume' if assume else 'guarantee'} \"{label}\" {expr};")
    lines.append("tel")
    return "\n".join(lines) + "\n"


def emit_cocospec(compiled: Sequence[Compiled]) -> tuple[dict[str, str],
                                                         list[tuple[str, str, str]],
                                                         list[str]]:
    """The CoCoSpec files of ``compiled`` (``compiler.build.Compiled`` list): ``({file stem:
    Lustre text}, [(stem, requirement id, why it is left out)], [notes])``, one file per
    component (stem ``-`` for a free-form requirement, in none), stem ``<component>Spec`` as
    FRET names it (written as ``STEM.lus``); the notes (``STEM: ...``, also comments of the
    file) name the definitions left out (with the reason) and the variables read as inputs
    that are not declared so. Same input, same bytes."""
    out: dict[str, str] = {}
    notes: list[str] = []
    skipped = [("-", c.id, "free-form: no formula, no component") for c in compiled
               if c.freeform]
    for c in contracts(compiled):
        sources = dict.fromkeys(x.entry.source for x in compiled
                                if component_of(x) == c.component)
        out[c.name] = _render(c, ", ".join(sources) or "(no file)")
        skipped += [(c.name, rid, why) for rid, why in c.skipped]
        notes += [f"{c.name}: {one_line(name)} is not defined in the contract: {why}"
                  for name, why in c.left_out]
        notes += [f"{c.name}: {note}" for note in c.notes]
    return out, skipped, notes
