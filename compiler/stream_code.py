"""The code that computes FRET's stream variables tick by tick
(:class:`fretc.fretish.fret_streams.StreamSystem`): Python for the audit's columns and the
generated Python monitors, C for the C monitors.

One tick is straight-line code: each node of the definitions, in post-order, a local of its
own (so the code's nesting is bounded whatever the definition's), the variables in the
system's order; then the state, one slot per ``pre`` node, takes its operand's value at this
tick (every operand computed before any slot is written: a ``pre (pre x)`` reads the older
slot's previous value). The first tick is ``FTP`` (Lustre's ``a -> b``: ``a``); a slot's
value at the first tick is ``pre``'s first value (FRET's ``preBool(false, e)``,
``preReal(0, e)``). Numbers are reals (IEEE 754 doubles); ``/`` and ``mod`` by zero are NaN,
as the generated monitors' and the judge's (:mod:`fretc.monitors.arrays`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fretc.fretish import ast as A
from fretc.fretish.fret_streams import FIRST_TICK, StreamSystem, is_boolean

__all__ = ["StreamCode", "stream_code", "stream_columns", "python_tick", "c_tick",
           "python_factory"]

_PRE = frozenset({"preBool", "preInt", "preReal"})
_CMP = {"=": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
_PY = {"&": "{0} and {1}", "|": "{0} or {1}", "xor": "{0} != {1}", "->": "(not {0}) or {1}",
       "<->": "{0} == {1}", "+": "{0} + {1}", "-": "{0} - {1}", "*": "{0} * {1}",
       "/": "_div({0}, {1})", "mod": "_mod({0}, {1})", "^": "_pow({0}, {1})"}
_C = {"&": "({0} && {1})", "|": "({0} || {1})", "xor": "({0} != {1})",
      "->": "(!{0} || {1})", "<->": "({0} == {1})", "+": "({0} + {1})", "-": "({0} - {1})",
      "*": "({0} * {1})", "/": "fretc_div({0}, {1})", "mod": "fretc_mod({0}, {1})",
      "^": "fretc_pow({0}, {1})"}


@dataclass
class StreamCode:
    """One tick of a :class:`StreamSystem` as code (module docstring), in ``lang``
    (``"py"`` or ``"c"``).

    Attributes:
        slots: per ``pre`` node, (its state's name, its first value as a literal, whether
            it is a truth value).
        lines: the tick's assignments ``(local, expression)``, in order; a local of
            ``bools`` is a truth value, the others doubles.
        outputs: per variable of the system, the local holding its value at the tick.
        updates: per slot, the local holding its value at the next tick.
        inputs: per input of the system, the name it is read by (``x0``, ``x1``, ...).
    """

    lang: str
    slots: list[tuple[str, str, bool]] = field(default_factory=list)
    lines: list[tuple[str, str]] = field(default_factory=list)
    bools: set[str] = field(default_factory=set)
    outputs: list[str] = field(default_factory=list)
    updates: list[str] = field(default_factory=list)
    inputs: list[str] = field(default_factory=list)
    #: with ``known`` (:func:`stream_code`): per local, slot and input, the expression
    #: (a local, ``True``) of whether its value is known
    knowns: dict[str, str] = field(default_factory=dict)


def stream_code(system: StreamSystem, lang: str = "py", prefix: str = "",
                known: bool = False) -> StreamCode:
    """The code of one tick of ``system`` in ``lang`` (``"py"``, ``"c"``); ``prefix``
    starts every name (the state's, the locals', the inputs'). The first tick is read from
    a variable ``first`` (``prefix + "first"``) the caller keeps. With ``known`` (Python),
    each value has a truth value of its own, whether it is known (``knowns``), by Kleene's
    logic from whether the inputs are (``k`` + an input's name; a comparison reading NaN is
    unknown where ``nan_unknown`` is true): the audit's unknown ticks.

    Raises:
        ValueError: a node no stream is computed with (the reader keeps those free:
            :func:`fretc.fretish.fret_definitions.definitions`)."""
    code = StreamCode(lang, inputs=[f"{prefix}x{k}" for k in range(len(system.inputs))])
    em = _Emitter(code, system, prefix)
    em.track = known
    code.knowns.update({x: f"k{x}" for x in code.inputs} if known else {})
    for name, e, boolean in zip(system.names, system.exprs, system.booleans):
        local = em.node(e)
        if not local.startswith(f"{prefix}n"):  # (a slot, an input, a literal: a copy, so
            # that its value at this tick outlives the slots' update)
            local = em.knows(em.local(local, boolean), em.k(local))
        em.known[name] = local
        code.outputs.append(local)
    k = 0
    while k < len(em.operands):  # (an operand's own pre nodes add slots as they come)
        code.updates.append(em.node(em.operands[k]))
        k += 1
    return code


class _Emitter:
    """Post-order emission of one system's nodes into a :class:`StreamCode`."""

    def __init__(self, code: StreamCode, system: StreamSystem, prefix: str) -> None:
        self.code, self.prefix = code, prefix
        self.known: dict[str, str] = {n: x for n, x in zip(system.inputs, code.inputs)}
        self.bools = {x for x, b in zip(code.inputs, system.input_booleans) if b}
        self.bools |= {n for n, b in zip(system.names, system.booleans) if b}
        self.types = dict(zip(system.inputs, system.input_booleans))
        self.types.update(zip(system.names, system.booleans))
        self.operands: list[A.Expr] = []
        self.count = 0
        self.track = False

    def k(self, x: str) -> str:
        """Whether the value ``x`` (a local, slot, input or literal) is known."""
        return self.code.knowns.get(x, "True")

    def knows(self, x: str, text: str) -> str:
        """``x``, whose known flag is ``text`` (a local of its own unless a name)."""
        if self.track:
            if text.isidentifier():
                self.code.knowns[x] = text
            else:
                self.code.knowns[x] = self.local(text, True, "k")
        return x

    def local(self, text: str, boolean: bool, kind: str = "n") -> str:
        self.count += 1
        name = f"{self.prefix}{kind}{self.count}"
        self.code.lines.append((name, text))
        if boolean:
            self.code.bools.add(name)
        return name

    def node(self, e: A.Expr) -> str:
        c = self.code.lang == "c"
        if isinstance(e, A.BoolLit):
            return ("1" if e.value else "0") if c else repr(e.value)
        if isinstance(e, A.NumLit):
            return repr(float(e.text))
        if isinstance(e, A.Var):
            if e.name == FIRST_TICK:
                return self.prefix + "first"
            return self.known[e.name]
        if isinstance(e, A.Unary):
            a = self.node(e.operand)
            if e.op == "!":
                return self.knows(self.local(f"!{a}" if c else f"not {a}", True), self.k(a))
            return self.knows(self.local(f"(-{a})" if c else f"-{a}", False), self.k(a))
        if isinstance(e, A.Binary):
            a, b = self.node(e.left), self.node(e.right)
            form = _CMP.get(e.op)
            if form is not None:
                return self.knows(self.local(f"({a} {form} {b})" if c else f"{a} {form} {b}",
                                             True),
                                  f"{self.k(a)} and {self.k(b)} and (not nan_unknown or "
                                  f"({a} == {a} and {b} == {b}))")
            if e.op not in _PY:
                raise ValueError(f"operator {e.op!r} in a stream's definition")
            return self.knows(self.local((_C if c else _PY)[e.op].format(a, b),
                                         e.op in ("&", "|", "xor", "->", "<->")),
                              _kleene(e.op, a, b, self.k(a), self.k(b)))
        if isinstance(e, A.Call) and e.name == "ite":
            x, a, b = (self.node(y) for y in e.args)
            return self.knows(
                self.local(f"({x} ? {a} : {b})" if c else f"{a} if {x} else {b}",
                           is_boolean(e, self.types)),
                f"({self.k(x)} and ({self.k(a)} if {x} else {self.k(b)})) or "
                f"({self.k(a)} and {self.k(b)} and {a} == {b})")
        if isinstance(e, A.Call) and e.name in _PRE and isinstance(
                e.args[0], (A.BoolLit, A.NumLit)):
            slot = f"{self.prefix}s{len(self.code.slots)}"
            boolean = e.name == "preBool"
            self.code.slots.append((slot, self.node(e.args[0]), boolean))
            self.operands.append(e.args[1])
            if boolean:
                self.bools.add(slot)
            if self.track:
                self.code.knowns[slot] = f"k{slot}"
            return slot
        raise ValueError(f"{type(e).__name__} {getattr(e, 'name', '')} in a stream's "
                         "definition")


def _kleene(op: str, a: str, b: str, ka: str, kb: str) -> str:
    """Whether ``a op b`` is known, ``ka``/``kb`` whether its operands are (Kleene's
    logic: ``false and x`` is known whatever ``x``)."""
    both = f"({ka} and {kb})"
    if op == "&":
        return f"{both} or ({ka} and not {a}) or ({kb} and not {b})"
    if op == "|":
        return f"{both} or ({ka} and {a}) or ({kb} and {b})"
    if op == "->":
        return f"{both} or ({ka} and not {a}) or ({kb} and {b})"
    return both


def python_tick(code: StreamCode, indent: str) -> list[str]:
    """The Python lines of one tick of ``code`` (``lang == "py"``) at ``indent``: the
    locals, then the slots set (reading the locals; the first-tick flag is the caller's)."""
    out = [f"{indent}{x} = {text}" for x, text in code.lines]
    slots = [s for s, _i, _b in code.slots]
    nexts = list(code.updates)
    if code.knowns:
        slots += [f"k{s}" for s in slots]
        nexts += [code.knowns.get(u, "True") for u in code.updates]
    if slots:
        out.append(f"{indent}{', '.join(slots)} = {', '.join(nexts)}")
    return out


def python_factory(system: StreamSystem, name: str) -> str:
    """The source of a Python function ``name(K0, K1, ..., N0, N1, ...)`` (the inputs'
    names, then the stream variables') returning ``(init, tick)``: ``init()`` the state
    before the first tick, ``tick(state, sample)`` the next state and ``{variable: value}``
    of the stream variables at the tick of ``sample`` (a mapping from the inputs' names to
    their values; a missing one raises ``KeyError``). Names reach the code only as those
    arguments (the generated monitors' rule: :mod:`fretc.compiler.pt_step`)."""
    code = stream_code(system)
    ks = [f"K{k}" for k in range(len(code.inputs))]
    ns = [f"N{k}" for k in range(len(code.outputs))]
    state = ["first"] + [s for s, _i, _b in code.slots]
    out = [f"def {name}({', '.join(ks + ns)}):",
           "    def init():",
           f"        return ({', '.join(['True'] + [i for _s, i, _b in code.slots])},)",
           "",
           "    def tick(state, sample):",
           f"        {', '.join(state)}, = state"]
    out += [f"        {x} = sample[{k}]" for x, k in zip(code.inputs, ks)]
    out += python_tick(code, "        ")
    out += [f"        return ({', '.join(['False'] + state[1:])},), "
            f"{{{', '.join(f'{n}: {x}' for n, x in zip(ns, code.outputs))}}}",
            "",
            "    return init, tick"]
    return "\n".join(out)


def c_tick(code: StreamCode, indent: str, state: str = "state->") -> list[str]:
    """The C lines of one tick of ``code`` (``lang == "c"``) at ``indent``: each local
    declared (``const bool`` or ``const double``), then the slots set (fields named as the
    slots, each read as ``state`` + its name: the previous value until then)."""
    out = [f"{indent}const {'bool' if x in code.bools else 'double'} {x} = {text};"
           for x, text in code.lines]
    out += [f"{indent}{state}{s} = {u};" for (s, _i, _b), u in zip(code.slots, code.updates)]
    return out


def _div(a: float, b: float) -> float:
    try:
        return a / b
    except ZeroDivisionError:
        return math.nan


def _mod(a: float, b: float) -> float:
    try:
        return math.fmod(a, b)
    except (ZeroDivisionError, ValueError):
        return math.nan


def _pow(a: float, b: float) -> float:
    try:
        r = a ** b
    except (OverflowError, ZeroDivisionError, ValueError):
        return math.nan
    return math.nan if isinstance(r, complex) else r


@functools.lru_cache(maxsize=64)
def _runner(system: StreamSystem) -> Callable[..., tuple[list, ...]]:
    """A Python function ``run(n, nan_unknown, gap, c0, kc0, c1, kc1, ...)`` of the
    system's inputs as lists of ``n`` values and of whether each is known (``gap``: per
    tick, whether it stands for an unknown number of ticks, after which no state is
    known), returning each variable's ``n`` values, then whether each is known (lists)."""
    code = stream_code(system, known=True)
    ins = [f"c{k}, kc{k}" for k in range(len(code.inputs))]
    outs = [f"o{k}" for k in range(len(code.outputs))]
    outs += [f"k{x}" for x in outs]
    src = [f"def run({', '.join(['n', 'nan_unknown', 'gap'] + ins)}):"]
    src += [f"    {x} = [None] * n" for x in outs]
    src += [f"    {s} = {init}\n    k{s} = True" for s, init, _b in code.slots]
    src += ["    first = True", "    for t in range(n):"]
    src += [f"        {x} = c{k}[t]\n        k{x} = kc{k}[t]"
            for k, x in enumerate(code.inputs)]
    src += python_tick(code, "        ")
    src += [f"        o{k}[t] = {x}\n        ko{k}[t] = {code.knowns.get(x, 'True')}"
            for k, x in enumerate(code.outputs)]
    src += ["        if gap[t]:"]
    src += [f"            ko{k}[t] = False" for k in range(len(code.outputs))]
    src += [f"            k{s} = False" for s, _i, _b in code.slots]
    src += ["        first = False", f"    return ({''.join(f'{x}, ' for x in outs)})"]
    space: dict[str, Any] = {"_div": _div, "_mod": _mod, "_pow": _pow}
    exec(compile("\n".join(src), "<fretc streams>", "exec"), space)
    return space["run"]


def stream_columns(system: StreamSystem, values: Mapping[str, np.ndarray], n: int,
                   unknown: Mapping[str, np.ndarray] | None = None,
                   nan_unknown: bool = True, gaps: Sequence[int] = ()
                   ) -> dict[str, np.ndarray]:
    """Each variable of ``system`` over ``n`` ticks (a ``bool`` column for a truth value,
    else ``float64``), from its inputs' columns ``values`` (at least ``n`` values each;
    numbers read as doubles).

    With ``unknown`` (variable -> bool array over the ticks, where its value is unknown;
    absent: known everywhere), also ``name + "?"`` per variable: where its value is
    unknown, by Kleene's logic over the tick's definition (a value held through ``pre``
    is as known as when it was read; with ``nan_unknown``, an input or a comparison that
    reads NaN is unknown: fretc's NaN rule). ``gaps``: ticks that stand for an unknown
    number of ticks (a gap of the tick topic, a ``gap`` row: :attr:`fretc.audit.columns.
    ClockPass.tick_gaps`), at and after which every value is unknown until its definition
    makes it known again (a reset may have happened in the ticks lost).

    Raises:
        KeyError: an input without a column."""
    args: list[list] = []
    for name in system.inputs:
        c = np.asarray(values[name])[:n]
        floats = c.dtype != np.bool_
        col = c.astype(np.float64) if floats else c
        bad = np.zeros(n, np.bool_)
        if unknown is not None and name in unknown:
            bad |= np.asarray(unknown[name][:n], dtype=np.bool_)
        if nan_unknown and floats:
            bad |= np.isnan(col)
        args += [col.tolist(), (~bad).tolist()]
    gap = [False] * n
    for t in gaps:
        if 0 <= t < n:
            gap[t] = True
    got = _runner(system)(n, nan_unknown, gap, *args)
    m = len(system.names)
    out = {name: np.array(col, dtype=np.bool_ if b else np.float64)
           for name, b, col in zip(system.names, system.booleans, got[:m])}
    if unknown is not None:
        out.update({f"{name}?": ~np.array(k, dtype=np.bool_)
                    for name, k in zip(system.names, got[m:])})
    return out
