"""The pt formula as the straight-line Python code of one monitor tick.

The Havelund-Rosu dynamic-programming scheme (Havelund & Rosu, "Synthesizing monitors for
safety properties", TACAS 2002): the formula's sub-formulas in post-order, each computed from
this tick's values and its own value at the previous tick, so time and memory per tick are
constant whatever the trace length. Bounded past operators keep a counter (``O[0,h]``,
``H[0,h]``) or the runs of ticks where their argument held within the window (``O[l,h]``,
``H[l,h]``): constant time per tick whatever the bound (:func:`_bounded`).

Identifiers in the code are generated (``v0``, ``n3``, ``s1``), never copied from the
requirement: a variable's FRET name reaches the module only as a string literal
(:mod:`fretc.compiler.codegen` writes it with ``repr``).
"""

from __future__ import annotations

import math
from collections.abc import Container
from dataclasses import dataclass, field

from fretc.common.errors import FretishError

from fretc.compiler.ir import Node, name_of, window
from fretc.compiler.printers import to_smv

#: An expression read once is inlined into the expression that reads it up to this nesting
#: depth; deeper ones get a local of their own, so the emitted code's nesting is bounded
#: whatever the requirement's (CPython rejects about 200 nested parentheses and runs out of
#: recursion compiling deeper expressions).
MAX_INLINE_DEPTH = 16


class CodegenError(FretishError):
    """A requirement that has no monitor (e.g. its pt needs future values)."""


_PY_CMP = {"=": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
#: Pure expressions of the Boolean and arithmetic operators, over the arguments' code.
_FORMS = {"!": "not {0}", "&": "{0} and {1}", "|": "{0} or {1}", "xor": "{0} != {1}",
          "->": "(not {0}) or {1}", "<->": "{0} == {1}", "neg": "-{0}",
          "ite": "{1} if {0} else {2}"}
_PY_FN = {"absReal": "abs", "absInt": "abs", "minReal": "min", "minInt": "min",
          "maxReal": "max", "maxInt": "max"}
_PY_ARITH_FN = {"/": "_div", "mod": "_mod", "^": "_pow"}


@dataclass
class StepCode:
    """Straight-line code of one tick: ``lines`` compute locals from ``sample`` and the
    previous state; ``slots`` are (initial value literal, local holding the next value);
    ``variables`` maps a sample key (FRET variable name, or the printed form of an opaque
    function call) to the local holding its value."""

    lines: list[str] = field(default_factory=list)
    slots: list[tuple[str, str]] = field(default_factory=list)
    variables: dict[str, str] = field(default_factory=dict)  # FRET name -> local
    locals: dict[Node, str] = field(default_factory=dict)
    uses_first: bool = False
    counter: int = 0
    numeric_reads: set[str] = field(default_factory=set)
    bool_reads: set[str] = field(default_factory=set)
    uses: dict[Node, int] = field(default_factory=dict)
    depth: dict[Node, int] = field(default_factory=dict)  # nesting of inlined expressions

    def new(self, prefix: str = "n") -> str:
        """A fresh local name (``n1``, ``c2``, ...)."""
        self.counter += 1
        return f"{prefix}{self.counter}"

    def slot(self, init: str) -> tuple[str, int]:
        """Reserve a state slot; returns (name of the local holding its previous value,
        index)."""
        idx = len(self.slots)
        self.slots.append((init, ""))
        return f"s{idx}", idx

    def set_slot(self, idx: int, local: str) -> None:
        """The local whose value slot ``idx`` holds at the next tick."""
        self.slots[idx] = (self.slots[idx][0], local)


def check_monitorable(pt: Node) -> None:
    """Raise :class:`CodegenError` at once when pt needs the future (so such a requirement
    costs no automaton construction before it is skipped)."""
    # pre-order, each node object once (a formula is a DAG: a tree walk visits a shared
    # sub-formula once per path to it); a node's sub-DAG is done before its next sibling, so
    # the first future found is the first of a tree walk, the one the error names
    stack, seen = [pt], set()
    while stack:
        n = stack.pop()
        if id(n) in seen:
            continue
        seen.add(id(n))
        if n.op == "future":
            raise _future_error(n)
        stack.extend(reversed(n.args))


def _future_error(n: Node) -> CodegenError:
    return CodegenError(
        f"the pt formula needs the future-time function {n.name}, which a tick-by-tick "
        "monitor cannot know yet; write the requirement with past-time functions "
        "(persisted, occurred) or audit it offline")


def compile_nodes(roots: list[Node], code: StepCode) -> list[str]:
    """Emit code for ``roots`` (sharing common sub-formulas) into ``code``; returns the
    Python expressions (locals or literals) of their values. Raises :class:`CodegenError`
    for a future-time operator or function."""
    post = post_order(roots, code.locals)
    # how many times each node's value is read: single-use pure expressions are inlined
    for n in post:
        for a in n.args:
            code.uses[a] = code.uses.get(a, 0) + 1
    for r in roots:
        code.uses[r] = code.uses.get(r, 0) + 2  # roots are read by the template
    deferred: list[tuple[int, str]] = []  # slots whose next value is a child's value
    for n in post:
        code.locals[n] = _emit(n, code, deferred)
    for idx, local in deferred:
        code.set_slot(idx, local)
    return [code.locals[r] for r in roots]


def opaque(n: Node) -> bool:
    """Whether ``n`` is an uninterpreted function application (a ``call``, or an ``fn``
    other than FRET's ``absReal``/``absInt``/``minReal``/``minInt``/``maxReal``/``maxInt``):
    a generated monitor reads its value as an input named by its printed text."""
    return n.op == "call" or (n.op == "fn" and n.name not in _PY_FN)


def post_order(roots: list[Node], compiled: Container[Node]) -> list[Node]:
    """The nodes under ``roots`` not in ``compiled`` (the nodes a step code has a local of
    already), each once, children first: the order their code is emitted in (Python here,
    C in :mod:`fretc.compiler.c_step`). An uninterpreted function application (a ``call``,
    or an ``fn`` fretc does not compute) is read as an input of its own, so its arguments
    are not visited: no code computes a value nothing reads (C's ``-Wunused-variable``)."""
    post: list[Node] = []
    seen: set[Node] = set()
    for r in roots:
        stack = [(r, False)]
        while stack:
            node, done = stack.pop()
            if node in seen or node in compiled:
                continue
            if done:
                seen.add(node)
                post.append(node)
                continue
            stack.append((node, True))
            if opaque(node):
                continue
            for a in reversed(node.args):
                stack.append((a, False))
    return post


def _emit(n: Node, code: StepCode, deferred: list[tuple[int, str]]) -> str:
    """The code of node ``n`` (its arguments compiled already): a literal, a local or an
    inlined expression; lines and state slots it needs are added to ``code``."""
    # (an uninterpreted application is an input: its arguments have no code, post_order)
    a = [] if opaque(n) else [code.locals[x] for x in n.args]
    out = code.new()
    direct = _direct(n, a, code)
    if direct is not None:
        return direct
    expr = _expression(n, a, code, deferred)
    if expr is None:
        return _temporal(n, a, out, code, deferred)
    depth = 1 + max((code.depth.get(x, 0) for x in n.args), default=0)
    if code.uses.get(n, 0) <= 1 and depth <= MAX_INLINE_DEPTH:
        code.depth[n] = depth
        return f"({expr})"
    code.lines.append(f"{out} = {expr}")
    return out


def _direct(n: Node, a: list[str], code: StepCode) -> str | None:
    """Constants, reads of the sample and pass-through nodes: their code, or None."""
    op = n.op
    if op == "true":
        return "True"
    if op == "false":
        return "False"
    if op == "FTP":
        code.uses_first = True
        return "first"
    if op in ("ap", "var"):
        return _read(name_of(n), code, numeric=op == "var")
    if op == "num":
        return _number(name_of(n))
    if (op == "fn" and n.name not in _PY_FN) or op == "call":
        return _opaque(n, code, numeric=op == "fn")
    if op == "past":
        return a[0]
    if op == "future":
        raise _future_error(n)
    return None


def _expression(n: Node, a: list[str], code: StepCode,
                deferred: list[tuple[int, str]]) -> str | None:
    """A pure expression of this tick (inlined where it is read once), or None."""
    op = n.op
    if op == "cmp":
        return f"{a[0]} {_PY_CMP[name_of(n)]} {a[1]}"
    if op == "arith":
        if n.name in ("+", "-", "*"):
            return f"{a[0]} {n.name} {a[1]}"
        return f"{_PY_ARITH_FN[name_of(n)]}({a[0]}, {a[1]})"
    if op == "fn":
        return f"{_PY_FN[name_of(n)]}({', '.join(a)})"
    if op == "pre":
        prev, idx = code.slot("0")
        code.uses_first = True
        deferred.append((idx, a[1]))
        return f"{a[0]} if first else {prev}"
    form = _FORMS.get(op)
    return None if form is None else form.format(*a)


def _temporal(n: Node, a: list[str], out: str, code: StepCode,
              deferred: list[tuple[int, str]]) -> str:
    """The past-time operators (Y, Z, O, H, S, T): state slots and the local of the value.
    Raises :class:`CodegenError` for any other operator (a future-time one)."""
    op = n.op
    if op in ("Y", "Z"):
        prev, idx = code.slot("False" if op == "Y" else "True")
        deferred.append((idx, a[0]))
        return prev
    if op in ("O", "H") and n.hi is None:
        prev, idx = code.slot("False" if op == "O" else "True")
        line = (f"{out} = {a[0]} or {prev}" if op == "O" else f"{out} = {a[0]} and {prev}")
        code.set_slot(idx, out)
    elif op in ("O", "H"):
        line = _bounded(n, a[0], out, code)
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


def _bounded(n: Node, arg: str, out: str, code: StepCode) -> str:
    """The line of a bounded ``O[lo,hi]`` / ``H[lo,hi]`` (lines it needs first are added), in
    constant time per tick whatever the bound: ``H[lo,hi] p`` is ``!O[lo,hi] !p``.

    ``lo = 0``: a counter of the ticks since the argument (of O; for H its negation) last
    held, capped at ``hi + 1``. ``lo > 0``: the runs of ticks where it held, as a queue of
    ``[start, end]`` pairs (the module's ``_once_within``: amortized O(1) per tick, memory at
    most the runs within the last ``hi + 1`` ticks); ticks before the first count as not
    holding, so ``O`` is false and ``H`` true there (FRET's past-time semantics)."""
    op, (lo, hi) = n.op, window(n)
    bit = arg if op == "O" else f"not {arg}"
    if lo == 0:
        # ticks since the argument last held, capped at hi + 1
        prev, idx = code.slot(str(hi + 1))
        cnt = code.new("c")
        code.lines.append(f"{cnt} = 0 if {bit} else ({prev} + 1 if {prev} <= {hi} "
                          f"else {hi + 1})")
        code.set_slot(idx, cnt)
        return f"{out} = {cnt} <= {hi}" if op == "O" else f"{out} = {cnt} > {hi}"
    prev, idx = code.slot("deque()")
    code.set_slot(idx, prev)  # the queue is updated in place
    once = f"_once_within({prev}, {bit}, tick, {lo}, {hi})"
    return f"{out} = {once}" if op == "O" else f"{out} = not {once}"


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


def _opaque(n: Node, code: StepCode, numeric: bool) -> str:
    """An uninterpreted function: read from the sample under its printed name."""
    return _read(to_smv(n), code, numeric)


def _read(name: str, code: StepCode, numeric: bool) -> str:
    """The local holding sample[name] (numeric) or bool(sample[name])."""
    if name not in code.variables:
        code.variables[name] = f"v{len(code.variables)}"
    v = code.variables[name]
    if numeric:
        code.numeric_reads.add(v)
        return v
    code.bool_reads.add(v)
    return f"b_{v}"
