"""Code generation of standalone Python runtime monitors (``fretc FILE --emit monitor``).

One module per requirement file, rendered from ``templates/monitor_module.py.j2``. The module
imports only the standard library and exposes ``MONITORS: dict[str, type]``; each monitor
class has ``VARIABLES``, ``step(sample) -> bool``, ``status``, ``finish() -> bool`` and
``reset()`` (see the template's docstring).

* ``step`` evaluates the pt formula with the Havelund-Rosu dynamic-programming scheme
  (Havelund & Rosu, "Synthesizing monitors for safety properties", TACAS 2002): the formula's
  sub-formulas in post-order, each computed from this tick's values and its own value at the
  previous tick, so time and memory per tick are constant whatever the trace length.
  Bounded past operators keep a counter (``O[0,h]``) or a bit history of ``h + 1`` ticks
  (``O[l,h]``, ``H[l,h]``): memory sized by the bound.
* ``status`` follows two deterministic monitors Spot builds from ft_inf and from its
  negation (``spot.translate(f, 'monitor', 'det')``): a prefix with no run in the first is a
  bad prefix (no infinite continuation satisfies ft_inf: *violated*), a prefix with no run in
  the second a good prefix (*satisfied*); otherwise *unknown* (LTL3; Bauer, Leucker &
  Schallhart, TOSEM 2011).

Hostile input: requirement ids, texts and variable names reach the module only as Python
string literals made by ``repr``; identifiers in the code are generated (``v0``, ``n3``,
``Monitor_R1_0``), never copied from the requirement file.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

from fretish.errors import FretishError

from . import ir
from .ir import Node
from .printers import to_smv, to_spot

#: Above this many atomic propositions the automaton step uses condition chains instead of a
#: letter-indexed table.
TABLE_MAX_APS = 10
#: Above this many states a Spot monitor is not embedded (status stays "unknown").
MAX_AUTOMATON_STATES = 5000
#: Spot's determinization of bounded operators (``F[0,n]`` unrolls into n nested ``X``) grows
#: exponentially with the bounds: measured 0.7 s for ``in m upon p ... within 12 ticks`` and
#: over a minute for 16. Spot's monitors are built only when ft_inf's largest bound and the
#: sum of its bounds stay within these limits (a deterministic rule, so the same input always
#: gives the same module); beyond them the LTL3 automaton comes from formula progression
#: (:mod:`compiler.ltl3`: sound, bounds kept symbolic) and ``STATUS_NOTE`` says so.
MAX_LTL3_BOUND = 12
MAX_LTL3_BOUND_SUM = 96
#: LTL3 monitors are built for at most this many atoms: beyond it an edge condition written
#: as Boolean code can be exponential (``a xor b xor ...``: minutes for 16 atoms) and Spot's
#: determinization can take minutes and gigabytes (fuzzing: ``only after m ... finally
#: satisfy r & w0 & ... & w29``); status stays "unknown" with a note.
MAX_LTL3_ATOMS = 10
#: An expression read once is inlined into the expression that reads it up to this nesting
#: depth; deeper ones get a local of their own, so the emitted code's nesting is bounded
#: whatever the requirement's (CPython rejects about 200 nested parentheses and runs out of
#: recursion compiling deeper expressions).
MAX_INLINE_DEPTH = 16


class CodegenError(FretishError):
    """A requirement that has no monitor (e.g. its pt needs future values)."""


# --------------------------------------------------------------------------- pt -> code
_PY_CMP = {"=": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}


@dataclass
class _StepCode:
    """Straight-line code of one tick: ``lines`` compute locals from ``sample`` and the
    previous state; ``slots`` are (initial value literal, local holding the next value)."""

    lines: List[str] = field(default_factory=list)
    slots: List[Tuple[str, str]] = field(default_factory=list)
    variables: Dict[str, str] = field(default_factory=dict)  # FRET name -> local
    locals: Dict[Node, str] = field(default_factory=dict)
    uses_first: bool = False
    counter: int = 0
    numeric_reads: set = field(default_factory=set)
    bool_reads: set = field(default_factory=set)
    uses: Dict[Node, int] = field(default_factory=dict)
    depth: Dict[Node, int] = field(default_factory=dict)  # nesting of inlined expressions

    def new(self, prefix: str = "n") -> str:
        self.counter += 1
        return f"{prefix}{self.counter}"

    def slot(self, init: str) -> Tuple[str, int]:
        """Reserve a state slot; returns (name of the local holding its previous value,
        index)."""
        idx = len(self.slots)
        self.slots.append((init, ""))
        return f"s{idx}", idx

    def set_slot(self, idx: int, local: str) -> None:
        self.slots[idx] = (self.slots[idx][0], local)


def _compile_nodes(roots: List[Node], code: _StepCode) -> List[str]:
    """Emit code for ``roots`` (sharing common sub-formulas); returns their locals."""
    post: List[Node] = []
    seen = set()

    def visit(n: Node) -> None:
        stack = [(n, False)]
        while stack:
            node, done = stack.pop()
            if node in seen or node in code.locals:
                continue
            if done:
                seen.add(node)
                post.append(node)
                continue
            stack.append((node, True))
            for a in reversed(node.args):
                stack.append((a, False))

    for r in roots:
        visit(r)
    # how many times each node's value is read: single-use pure expressions are inlined
    for n in post:
        for a in n.args:
            code.uses[a] = code.uses.get(a, 0) + 1
    for r in roots:
        code.uses[r] = code.uses.get(r, 0) + 2  # roots are read by the template
    deferred: List[Tuple[int, str]] = []  # slots whose next value is a child's value
    for n in post:
        code.locals[n] = _emit(n, code, deferred)
    for idx, local in deferred:
        code.set_slot(idx, local)
    return [code.locals[r] for r in roots]


def _emit(n: Node, code: _StepCode, deferred) -> str:
    op = n.op
    L = code.locals
    a = [L[x] for x in n.args]
    out = code.new()
    line = None
    if op == "true":
        return "True"
    if op == "false":
        return "False"
    if op == "FTP":
        code.uses_first = True
        return "first"
    if op in ("ap", "var"):
        return _read(n.name, code, numeric=op == "var")
    if op == "num":
        return _number(n.name)
    expr = None  # a pure expression: inlined where it is read once
    if op == "cmp":
        expr = f"{a[0]} {_PY_CMP[n.name]} {a[1]}"
    elif op == "arith":
        if n.name in ("+", "-", "*"):
            expr = f"{a[0]} {n.name} {a[1]}"
        else:
            fn = {"/": "_div", "mod": "_mod", "^": "_pow"}[n.name]
            expr = f"{fn}({a[0]}, {a[1]})"
    elif op == "neg":
        expr = f"-{a[0]}"
    elif op == "fn":
        fn = {"absReal": "abs", "absInt": "abs", "minReal": "min", "minInt": "min",
              "maxReal": "max", "maxInt": "max"}.get(n.name)
        if fn is None:
            return _opaque(n, code, numeric=True)
        expr = f"{fn}({', '.join(a)})"
    elif op == "ite":
        expr = f"{a[1]} if {a[0]} else {a[2]}"
    elif op == "pre":
        prev, idx = code.slot("0")
        code.uses_first = True
        expr = f"{a[0]} if first else {prev}"
        deferred.append((idx, a[1]))
    elif op == "call":
        return _opaque(n, code, numeric=False)
    elif op == "past":
        return a[0]
    elif op == "future":
        raise CodegenError(
            f"the pt formula needs the future-time function {n.name}, which a tick-by-tick "
            "monitor cannot know yet; write the requirement with past-time functions "
            "(persisted, occurred) or audit it offline")
    elif op == "!":
        expr = f"not {a[0]}"
    elif op == "&":
        expr = f"{a[0]} and {a[1]}"
    elif op == "|":
        expr = f"{a[0]} or {a[1]}"
    elif op == "xor":
        expr = f"{a[0]} != {a[1]}"
    elif op == "->":
        expr = f"(not {a[0]}) or {a[1]}"
    elif op == "<->":
        expr = f"{a[0]} == {a[1]}"
    if expr is not None:
        depth = 1 + max((code.depth.get(x, 0) for x in n.args), default=0)
        if code.uses.get(n, 0) <= 1 and depth <= MAX_INLINE_DEPTH:
            code.depth[n] = depth
            return f"({expr})"
        line = f"{out} = {expr}"
    elif op in ("Y", "Z"):
        prev, idx = code.slot("False" if op == "Y" else "True")
        deferred.append((idx, a[0]))
        return prev
    elif op in ("O", "H") and n.hi is None:
        prev, idx = code.slot("False" if op == "O" else "True")
        line = (f"{out} = {a[0]} or {prev}" if op == "O" else f"{out} = {a[0]} and {prev}")
        code.set_slot(idx, out)
    elif op in ("O", "H"):
        lo, hi = n.lo, n.hi
        if op == "O" and lo == 0:
            # ticks since the argument last held, capped at hi + 1
            prev, idx = code.slot(str(hi + 1))
            cnt = code.new("c")
            code.lines.append(f"{cnt} = 0 if {a[0]} else ({prev} + 1 if {prev} <= {hi} "
                              f"else {hi + 1})")
            code.set_slot(idx, cnt)
            line = f"{out} = {cnt} <= {hi}"
        else:
            # bit history of the last hi+1 ticks (bit k = k ticks ago); for H, of "not arg"
            prev, idx = code.slot("0")
            hist = code.new("h")
            bit = a[0] if op == "O" else f"not {a[0]}"
            # a decimal literal of more than sys.get_int_max_str_digits() digits (4300)
            # would not load: large masks are written as an expression
            mask = str((1 << (hi + 1)) - 1) if hi < 64 else f"((1 << {hi + 1}) - 1)"
            code.lines.append(f"{hist} = (({prev} << 1) | ({bit})) & {mask}")
            code.set_slot(idx, hist)
            test = "!= 0" if op == "O" else "== 0"
            line = f"{out} = ({hist} >> {lo}) {test}" if lo else f"{out} = {hist} {test}"
    elif op in ("S", "T"):
        prev, idx = code.slot("False" if op == "S" else "True")
        if op == "S":
            line = f"{out} = {a[1]} or ({a[0]} and {prev})"
        else:
            line = f"{out} = {a[1]} and ({a[0]} or {prev})"
        code.set_slot(idx, out)
    else:
        raise CodegenError(f"no monitor code for the future-time operator {op!r} in pt")
    code.lines.append(line)
    return out


def _number(text: str) -> str:
    """Python code of a FRETish number literal (``3``, ``-2.5e3``): an int when it is
    written without a point or exponent, else a float; a float that overflows is written
    ``float('inf')`` / ``float('-inf')`` (``repr`` would give the name ``inf``)."""
    if not any(c in text for c in ".eE"):
        return str(int(text))
    value = float(text)
    if math.isinf(value):
        return "float('-inf')" if value < 0 else "float('inf')"
    return repr(value)


def _opaque(n: Node, code: _StepCode, numeric: bool) -> str:
    """An uninterpreted function: read from the sample under its printed name."""
    return _read(to_smv(n), code, numeric)


def _read(name: str, code: _StepCode, numeric: bool) -> str:
    """The local holding sample[name] (numeric) or bool(sample[name])."""
    if name not in code.variables:
        code.variables[name] = f"v{len(code.variables)}"
    v = code.variables[name]
    if numeric:
        code.numeric_reads.add(v)
        return v
    code.bool_reads.add(v)
    return f"b_{v}"


# --------------------------------------------------------------------------- automata
@dataclass
class _Automaton:
    """A deterministic Spot monitor as tables: ``table[state][letter]`` (letter = bits of the
    atoms, -1 = no transition) or ``chains[state]`` = [(condition code, destination)]."""

    atoms: List[Node]
    initial: int
    table: Optional[List[List[int]]]
    chains: Optional[List[List[Tuple[str, int]]]]
    empty: bool  # the automaton accepts nothing at all
    sub_code: str = "0"  # Python expression of the letter, set once atoms have locals
    complete: bool = False  # every state has a transition for every letter: never rejects


def _bdd_code(f, aps: List[str]) -> str:
    """Python code of a Spot Boolean formula over the letter bits ``a[i]``."""
    import spot

    k = f.kind()
    if k == spot.op_tt:
        return "True"
    if k == spot.op_ff:
        return "False"
    if k == spot.op_ap:
        return f"(sub >> {aps.index(f.ap_name())} & 1)"
    if k == spot.op_Not:
        return f"(not {_bdd_code(f[0], aps)})"
    if k == spot.op_And:
        return "(" + " and ".join(_bdd_code(x, aps) for x in f) + ")"
    if k == spot.op_Or:
        return "(" + " or ".join(_bdd_code(x, aps) for x in f) + ")"
    raise CodegenError(f"unexpected Boolean operator in an automaton edge: {f}")


def _check_monitorable(pt: Node) -> None:
    """Raise :class:`CodegenError` at once when pt needs the future (so such a requirement
    costs no automaton construction before it is skipped)."""
    for n in ir.walk(pt):
        if n.op == "future":
            raise CodegenError(
                f"the pt formula needs the future-time function {n.name}, which a "
                "tick-by-tick monitor cannot know yet; write the requirement with past-time "
                "functions (persisted, occurred) or audit it offline")


def ltl3_automata(ft_inf: Node) -> Tuple[Optional[_Automaton], Optional[_Automaton], str]:
    """The LTL3 automata of ``ft_inf``: ``(bad, good, note)``. ``bad`` rejects exactly the bad
    prefixes (violated), ``good`` the good ones (satisfied); None when not built, with the
    reason in ``note`` ("" when both come from Spot).

    Built once per shape of ft_inf (:func:`compiler.ltl3.canonical_shape`: atoms renamed, so
    requirements of the same template, bounds and atom pattern share it) and kept in fretc's
    disk cache (:func:`compiler.ltl3.shape_automata`); the tables are canonical, so the
    generated module is the same with a cold or a warm cache. Spot (exact LTL3) while
    ft_inf's bounds are at most :data:`MAX_LTL3_BOUND` ticks and sum to at most
    :data:`MAX_LTL3_BOUND_SUM`; formula progression (sound, bounds symbolic) beyond, unless
    a bound exceeds :data:`compiler.ltl3.MAX_STATES` (progression would need at least that
    many residuals: decided before any construction)."""
    from . import ltl3

    shape, atoms = ltl3.canonical_shape(ft_inf)
    if len(atoms) > MAX_LTL3_ATOMS:
        return None, None, (
            f"no LTL3 monitor: ft_inf has {len(atoms)} atoms (more than {MAX_LTL3_ATOMS}: "
            "the deterministic monitors can take minutes and gigabytes to build); status "
            "stays 'unknown' (step and finish unaffected)")
    bounds = [n.hi for n in ir.walk(ft_inf) if n.hi is not None]
    if bounds and (max(bounds) > MAX_LTL3_BOUND or sum(bounds) > MAX_LTL3_BOUND_SUM):
        why = (f"ft_inf's bounds (largest {max(bounds)}, sum {sum(bounds)} ticks) exceed what "
               f"Spot determinizes quickly (largest {MAX_LTL3_BOUND}, sum "
               f"{MAX_LTL3_BOUND_SUM})")
        if max(bounds) >= ltl3.MAX_STATES or len(atoms) > ltl3.MAX_ATOMS:
            data = {"bad": None, "good": None}
        else:
            data = ltl3.shape_automata("progression", shape, len(atoms), ltl3.MAX_STATES,
                                       TABLE_MAX_APS)
        if data["bad"] is None or data["good"] is None:
            return None, None, (
                f"no LTL3 monitor: {why}, and formula progression needs more than "
                f"{ltl3.MAX_STATES} residuals, {ltl3.MAX_ATOMS} atoms or "
                f"{ltl3.MAX_PROGRESSIONS} progressions; status stays "
                "'unknown' (step and finish unaffected)")
        bad, good = _automaton(data["bad"], atoms), _automaton(data["good"], atoms)
        return bad, good, (
            f"LTL3 by formula progression ({data['bad']['states']} residual states): {why}; "
            "verdicts are sound but may come later than the exact LTL3 verdict when a "
            "residual is unsatisfiable without simplifying to FALSE")
    data = ltl3.shape_automata("spot", shape, len(atoms), MAX_AUTOMATON_STATES, TABLE_MAX_APS)
    bad, good = _automaton(data["bad"], atoms), _automaton(data["good"], atoms)
    note = "" if bad is not None and good is not None else (
        f"Spot's deterministic monitor exceeds {MAX_AUTOMATON_STATES} states: no early "
        "verdict")
    return bad, good, note


def _automaton(data: Optional[dict], atoms: List[Node]) -> Optional[_Automaton]:
    """An :class:`_Automaton` over ``atoms`` (bit i of a letter = atoms[i]) from the data of
    :func:`compiler.ltl3.shape_automata`."""
    if data is None:
        return None
    chains = None
    if data["chains"] is not None:
        chains = [[(cond, dst) for cond, dst in row] for row in data["chains"]]
    return _Automaton(list(atoms), data["initial"], data["table"], chains, data["empty"],
                      complete=data["complete"])


# --------------------------------------------------------------------------- per requirement
@dataclass
class MonitorSource:
    """Everything the template needs for one requirement's monitor class."""

    index: int
    class_name: str
    id: str
    text: str
    key: str
    ft: str
    ft_inf: str
    pt: str
    source_hash: str
    variables: List[str]
    var_locals: List[Tuple[str, str, bool, bool]]
    slots_init: str
    slots_unpack: str
    slots_next: str
    step_lines: List[str]
    verdict: str
    atom_locals: List[str]
    good: Optional[_Automaton]
    bad: Optional[_Automaton]
    uses_first: bool
    status_note: str
    bad_table: Optional[int] = None  # index in the module's _TABLES (render_module)
    good_table: Optional[int] = None

    @property
    def verdict_expr(self) -> str:
        """The verdict as a Python bool: locals computed from boolean reads are bools
        already; numeric reads may bring other types (e.g. numpy scalars)."""
        if any(numeric for _, _, numeric, _ in self.var_locals) or self.verdict in (
                "True", "False", "first"):
            return f"bool({self.verdict})"
        return self.verdict

    @property
    def status_live(self) -> bool:
        """Can the status still change after reset()? (some automaton can reject)"""
        return any(a is not None and not a.complete for a in (self.good, self.bad))


def _class_name(rid: str, index: int) -> str:
    safe = re.sub(r"[^A-Za-z0-9_]", "_", rid)[:40]
    return f"Monitor_{safe}_{index}"


def monitor_source(compiled, index: int) -> MonitorSource:
    """Generate the code pieces of one compiled requirement (``compiler.build.Compiled``).
    Raises :class:`CodegenError` when no monitor can be built."""
    f = compiled.formalization
    _check_monitorable(f.pt)  # before any expensive work
    code = _StepCode()
    bad, good, note = ltl3_automata(f.ft_inf)
    atom_nodes: List[Node] = []
    for aut in (bad, good):
        if aut is not None:
            for a in aut.atoms:
                if a not in atom_nodes:
                    atom_nodes.append(a)
    roots = [f.pt] + atom_nodes
    locals_ = _compile_nodes(roots, code)
    verdict, atom_locals = locals_[0], locals_[1:]
    # map automata atoms to indices in atom_locals
    for aut in (bad, good):
        if aut is not None:
            idx = [atom_nodes.index(a) for a in aut.atoms]
            if aut.table is not None:
                aut.sub_code = " | ".join(f"({1 << j} if {atom_locals[b]} else 0)"
                                          for j, b in enumerate(idx)) or "0"
            else:  # the atoms' values, indexed by the BDD nodes' atom numbers
                aut.sub_code = "(" + "".join(f"{atom_locals[b]}, " for b in idx) + ")"
    var_locals = [(name, local, local in code.numeric_reads, local in code.bool_reads)
                  for name, local in code.variables.items()]
    # the state tuple: pt slots, then the tick count, then the last verdict
    slots_init = "(" + "".join(f"{init}, " for init, _ in code.slots) + "0, None)"
    slots_next = "(" + "".join(f"{nxt}, " for _, nxt in code.slots) + "tick + 1, verdict)"
    return MonitorSource(
        index=index, class_name=_class_name(compiled.id, index), id=compiled.id,
        text=compiled.text, key=f.key, ft=compiled.smv("ft"), ft_inf=compiled.smv("ft_inf"),
        pt=compiled.smv("pt"), source_hash=compiled.source_hash,
        variables=[v[0] for v in var_locals], var_locals=var_locals,
        slots_init=slots_init,
        slots_unpack="".join(f"s{i}, " for i in range(len(code.slots))) + "tick, _",
        slots_next=slots_next, step_lines=code.lines,
        verdict=verdict, atom_locals=atom_locals, good=good, bad=bad,
        uses_first=code.uses_first, status_note=note)


def mangled_ap(n: Node) -> str:
    """The name Spot reports for a boolean variable's atomic proposition."""
    from .printers import mangle
    return mangle(n.name)


# --------------------------------------------------------------------------- modules
def _env():
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("templates", ""),
        keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True,
        undefined=jinja2.StrictUndefined, autoescape=False)
    env.filters["py"] = repr
    return env


class InvalidMonitorError(RuntimeError):
    """Internal error: the code generated for a requirement is not a valid, loadable monitor
    (a bug in fretc, never the user's). ``ids`` are the requirements concerned."""

    def __init__(self, message: str, ids=()):
        super().__init__(message)
        self.ids = list(ids)


_ALLOWED_BUILTINS = frozenset(("abs", "min", "max", "bool", "float", "int", "len",
                               "RuntimeError", "KeyError", "ZeroDivisionError",
                               "OverflowError", "ValueError", "complex", "isinstance",
                               "property", "__name__"))


def check_module(text: str, module_name: str) -> None:
    """Check a generated module before it is written or loaded: it compiles, every global
    name its code reads is defined by the module or is one of the builtins the template
    uses (so no ``NameError`` can happen at run time), it loads, and every monitor steps
    through two ticks (all variables 0, then 1) and finishes.

    Raises :class:`InvalidMonitorError` (an internal error) naming the failure."""
    import dis
    import types

    def fail(what, exc=None):
        detail = f": {type(exc).__name__}: {exc}" if exc is not None else ""
        raise InvalidMonitorError(
            f"internal error: the generated monitor module {module_name!r} {what}{detail}; "
            "this is a bug in fretc, please report it with the requirement")

    try:
        code = compile(text, f"<fretc monitors {module_name}>", "exec")
    except (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError) as exc:
        fail("does not compile", exc)
    defined = set()
    reads = set()
    stack = [code]
    while stack:
        co = stack.pop()
        for ins in dis.get_instructions(co):
            if ins.opname in ("STORE_NAME", "STORE_GLOBAL", "IMPORT_NAME") and co is code:
                defined.add(ins.argval)
            elif ins.opname in ("LOAD_GLOBAL", "LOAD_NAME"):
                reads.add(ins.argval)
        stack.extend(c for c in co.co_consts if isinstance(c, types.CodeType))
    unknown = sorted(reads - defined - _ALLOWED_BUILTINS)
    if unknown:
        fail(f"reads undefined names {', '.join(unknown)}")
    ns = {"__name__": module_name}
    try:
        exec(code, ns)  # only the standard library and literals made by repr
        for rid, cls in ns["MONITORS"].items():
            m = cls()
            for value in (0, 1):
                m.step({v: value for v in cls.VARIABLES})
            m.finish()
    except Exception as exc:  # noqa: BLE001 - any failure here is an internal error
        fail("does not load and step", exc)


def render_module(compiled_list, module_name: str, errors: Optional[list] = None) -> str:
    """The text of one generated monitor module for a list of compiled requirements
    (``compiler.build.Compiled``); requirements that failed or have no monitor are listed
    in ``SKIPPED`` with the reason.

    The module is checked by :func:`check_module`. Should a requirement's code ever fail
    that check (an internal error), it is listed in ``SKIPPED`` with the error, so the other
    requirements keep their monitors, and the :class:`InvalidMonitorError` is appended to
    ``errors`` when given (``fretc --emit monitor`` then exits non-zero)."""
    monitors: List[MonitorSource] = []
    skipped: List[Tuple[str, str]] = []
    for i, c in enumerate(compiled_list):
        if c.formalization is None:
            reason = "free-form" if c.freeform else getattr(c.error, "message", str(c.error))
            skipped.append((c.id, reason))
            continue
        try:
            monitors.append(monitor_source(c, i))
        except CodegenError as exc:
            skipped.append((c.id, str(exc)))
    text = _render(monitors, skipped, module_name)
    try:
        check_module(text, module_name)
        return text
    except InvalidMonitorError as exc:
        problem = exc
    # find the monitors at fault, one at a time, and skip them
    bad = []
    for m in monitors:
        try:
            check_module(_render([m], [], module_name), module_name)
        except InvalidMonitorError as exc:
            bad.append((m, exc))
    if not bad:  # pragma: no cover - the module itself is broken
        bad = [(m, problem) for m in monitors]
    failed = InvalidMonitorError("; ".join(f"{m.id}: {exc}" for m, exc in bad),
                                 [m.id for m, _ in bad])
    if errors is not None:
        errors.append(failed)
    skipped += [(m.id, str(exc)) for m, exc in bad]
    monitors = [m for m in monitors if m not in [b for b, _ in bad]]
    return _render(monitors, skipped, module_name)


def _render(monitors: List[MonitorSource], skipped, module_name: str) -> str:
    digest = hashlib.sha256("\n".join(f"{m.id}:{m.source_hash}" for m in monitors)
                            .encode()).hexdigest()
    tables: Dict[str, int] = {}  # encoded table -> index: one copy per distinct table
    for m in monitors:
        for which in ("bad", "good"):
            aut = getattr(m, which)
            if aut is not None and aut.table is not None and not aut.complete:
                text = encode_table(aut.table)
                setattr(m, f"{which}_table", tables.setdefault(text, len(tables)))
    return _env().get_template("monitor_module.py.j2").render(
        module_name=module_name, monitors=monitors, skipped=skipped, digest=digest,
        tables=list(tables))


def encode_table(table: List[List[int]]) -> str:
    """A transition table as the generated module stores it: rows separated by ``;``,
    destinations by ``,`` (the module's ``_table`` decodes it)."""
    return ";".join(",".join(map(str, row)) for row in table)


def file_stems(sources, suffix: str = "") -> Dict[str, str]:
    """A distinct Python-identifier stem per requirement file, in order: the file name's
    stem (``requirements/r1.fret`` -> ``r1`` + ``suffix``), with ``_2``, ``_3`` ... added when
    two files of different folders share a name (so no output overwrites another)."""
    out: Dict[str, str] = {}
    used: set = set()
    for source in sources:
        if source in out:
            continue
        base = re.sub(r"[^A-Za-z0-9_]", "_", str(source).rsplit("/", 1)[-1].rsplit(".", 1)[0])
        base = base if base and not base[0].isdigit() else f"m_{base}"
        stem, k = f"{base}{suffix}", 2
        while stem in used:
            stem, k = f"{base}_{k}{suffix}", k + 1
        used.add(stem)
        out[source] = stem
    return out


def emit_monitors(compiled, errors: Optional[list] = None) -> Dict[str, str]:
    """One module per requirement file: ``{module stem: source text}``, in input order
    (stems from :func:`file_stems`, ``r1.fret`` -> ``r1_monitors``). Internal errors
    (:class:`InvalidMonitorError`) are appended to ``errors``, the requirements concerned
    being listed in ``SKIPPED`` with the error (see :func:`render_module`)."""
    groups: Dict[str, list] = {}
    for c in compiled:
        groups.setdefault(c.entry.source, []).append(c)
    stems = file_stems(groups, "_monitors")
    return {stems[source]: render_module(items, stems[source], errors)
            for source, items in groups.items()}
