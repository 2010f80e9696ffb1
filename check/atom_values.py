"""Numbers for the comparison atoms the propositional abstraction leaves free, by z3.

Spot and the lasso encoding of :mod:`fretc.check.smt` read every comparison as a proposition;
:mod:`fretc.check.numeric_abstraction` ties together the comparisons of *one* variable with
constants (``x <= 0.5``, ``x > 3``) and gives them numbers back. A comparison of terms over
several variables (``yout = timeStep * 0.5 * (xin + xinpv) + ypv``, ``a = b``, ``(p - q) / q
<= 0.1``) stays an independent proposition: a model of the abstraction says at each tick
whether it holds, but nothing chooses numbers that make it so, and a trace with every free
number 0 makes ``yout = ...`` true whatever the model asked.

Design notes: ARCHITECTURE.md, `check/atom_values.py`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from fretc.check.numeric_abstraction import simple_comparison
from fretc.compiler import ir
from fretc.compiler.evaluate import INTERPRETED_FUNCTIONS, ft_at, series
from fretc.compiler.ir import Node, name_of
from fretc.compiler.printers import mangle, to_smv
from fretc.check.stream_rows import (TickTerms, TraceStreams, past_values, value_at,
                                     with_stream_columns)

__all__ = ["free_atoms", "concrete_rows", "RLIMIT"]

#: z3's deterministic resource limit per tick's query (never seconds: same input, same rows)
RLIMIT = 2_000_000

_ABS = ("absReal", "absInt")
_MIN = ("minReal", "minInt")
_MAX = ("maxReal", "maxInt")


def free_atoms(formulas: Sequence[Node], streams: TraceStreams | None = None
               ) -> dict[str, Node]:
    """SMV text -> comparison node of every comparison in ``formulas`` that the numeric
    abstraction does not interpret (not one variable against constants, or one reading a
    stream variable of ``streams``: its value is computed, :mod:`fretc.check.stream_rows`),
    and of the one-variable comparisons of the variables those share or the streams read
    (their numbers must agree with both); empty when the abstraction is exact for every
    comparison."""
    free: dict[str, Node] = {}
    simple: dict[str, tuple[str, Node]] = {}
    computed = set(streams.exprs) if streams is not None else set()
    for f in formulas:
        for n in ir.walk(f):
            if n.op != "cmp":
                continue
            one = simple_comparison(n)
            if one is None or one[0] in computed:
                free[to_smv(n)] = n
            else:
                simple[to_smv(n)] = (one[0], n)
    if not free:
        return {}
    shared = {v for n in free.values() for v in ir.variables(n)}
    if streams is not None and shared & computed:
        shared |= set(streams.inputs)
    free.update({k: n for k, (name, n) in simple.items() if name in shared})
    return free


class _Terms:
    """IR terms as z3 expressions over one Real per numeric variable (and per uninterpreted
    function application, a column of its own); ``prev``: the previous tick's row (None at
    the first tick), whose values make ``pre`` terms constants."""

    def __init__(self, z3, prev: dict | None):
        self.z3 = z3
        self.prev = prev
        self.vars: dict[str, object] = {}
        self.divisors: list = []
        #: the stream variables' terms at this tick (:mod:`fretc.check.stream_rows`)
        self.ticks: TickTerms | None = None

    def var(self, name: str):
        """The z3 Real of variable ``name`` (a stream variable: its definition's term)."""
        if self.ticks is not None and name in self.ticks.streams.exprs:
            return self.ticks.stream(name)
        return self.real(name)

    def real(self, name: str):
        """The z3 Real of the numeric variable ``name``, made at its first use."""
        if name not in self.vars:
            self.vars[name] = self.z3.Real(name)
        return self.vars[name]

    def term(self, n: Node):
        """``n`` as a z3 arithmetic expression; None when it holds an operator outside the
        module docstring's list."""
        z3 = self.z3
        if n.op == "var":
            return self.var(name_of(n))
        if n.op == "fn" and n.name not in INTERPRETED_FUNCTIONS:
            return self.var(to_smv(n))
        if n.op == "num":
            try:
                return _real(z3, Fraction(name_of(n)))
            except (ValueError, ZeroDivisionError):
                return None
        if n.op == "pre":  # FRET's preReal(init, x): init at the first tick, else x before
            v = series(n.args[0] if self.prev is None else n.args[1], [self.prev or {}])[0]
            if isinstance(v, bool) or not math.isfinite(v):
                return None
            return _real(z3, Fraction(v))
        args = [self.term(a) for a in n.args]
        if any(a is None for a in args):
            return None
        if n.op == "neg":
            return -args[0]
        if n.op == "arith" and n.name in ("+", "-", "*"):
            a, b = args
            return a + b if n.name == "+" else a - b if n.name == "-" else a * b
        if n.op == "arith" and n.name == "/":
            self.divisors.append(args[1])
            return args[0] / args[1]
        if n.op == "fn" and len(args) == 1 and n.name in _ABS:
            return z3.If(args[0] >= 0, args[0], -args[0])
        if n.op == "fn" and len(args) == 2 and n.name in _MIN + _MAX:
            a, b = args
            return z3.If(a <= b, a, b) if n.name in _MIN else z3.If(a >= b, a, b)
        return None

    def comparison(self, n: Node):
        """The z3 formula of comparison ``n``; None when a side does not translate."""
        a, b = self.term(n.args[0]), self.term(n.args[1])
        if a is None or b is None:
            return None
        return {"=": a == b, "!=": a != b, "<": a < b, "<=": a <= b, ">": a > b,
                ">=": a >= b}[name_of(n)]


def _real(z3, q: Fraction):
    return z3.RealVal(f"{q.numerator}/{q.denominator}")


def _number(z3, value) -> float:
    if z3.is_rational_value(value):
        return float(Fraction(value.numerator_as_long(), value.denominator_as_long()))
    return float(value.approx(20).as_fraction())  # an algebraic number (products)


def _solve(z3, atoms: dict[str, Node], letter: dict, prev: dict | None,
           streams: _Streams | None = None) -> dict[str, Any] | None:
    """Numbers giving the comparisons of ``atoms`` the truth values ``letter`` names (SMV
    text -> bool), after the row ``prev``; None when z3 finds none within :data:`RLIMIT`.
    ``streams``: the stream variables' terms at this tick and the rows they are read on
    (:mod:`fretc.check.stream_rows`): a boolean stream the letter names takes its value,
    and the boolean inputs the letter leaves free get values too."""
    terms = _Terms(z3, prev)
    wanted = []
    if streams is not None:
        terms.ticks = streams.terms(z3, terms.real)
        for name in terms.ticks.streams.exprs:
            given = streams.letter_bool(name) if terms.ticks.streams.booleans[name] else None
            term = terms.ticks.stream(name) if given is not None else None
            if term is not None:
                wanted.append(term if given else z3.Not(term))
    for key, node in sorted(atoms.items()):
        if key not in letter:
            continue
        f = terms.comparison(node)
        if f is not None:
            wanted.append(f if letter[key] else z3.Not(f))
    if not wanted:
        return {}
    wanted += [d != 0 for d in terms.divisors]
    if terms.ticks is not None:
        wanted += [d != 0 for d in terms.ticks.divisors]
    for integral in (True, False):
        s = z3.Solver()
        s.set("rlimit", RLIMIT)
        s.add(*wanted)
        if integral:
            s.add(*[z3.IsInt(v) for v in terms.vars.values()])
        if s.check() == z3.sat:
            m = s.model()
            got: dict[str, Any] = {name: _number(z3, m.eval(v, model_completion=True))
                                   for name, v in terms.vars.items()}
            if terms.ticks is not None:
                got.update({name: z3.is_true(m.eval(v, model_completion=True))
                            for name, v in terms.ticks.free_bools.items()})
            row = got if streams is None else streams.complete(got)
            trace = [row] if prev is None else [prev, row]
            if all(ft_at(atoms[k], trace, len(trace) - 1) is letter[k]
                   for k in atoms if k in letter):
                return got
            # an irrational model (a product's root) that floats round the other way
    return None


class _Streams:
    """The stream variables at one tick of :func:`concrete_rows`: ``streams``, the rows
    built so far (``done``), the tick's row as the abstraction gave it (``row``) and its
    ``letter``."""

    def __init__(self, streams: TraceStreams, done: list[dict], row: dict, letter: dict):
        self.streams, self.done, self.row, self.letter = streams, done, row, letter

    def letter_bool(self, name: str) -> bool | None:
        """The letter's value of the boolean variable ``name`` (None: left free)."""
        for k in (mangle(name), name):
            if k in self.letter:
                return bool(self.letter[k])
        return None

    def terms(self, z3, real) -> TickTerms:
        """The streams' z3 terms at this tick (``real``: the tick's z3 Real of a name)."""
        return TickTerms(z3, self.streams, self.done, real, self.letter_bool)

    def key(self) -> tuple[Any, ...]:
        """What the tick's query reads besides the letter's comparisons: the letter's
        boolean inputs and streams, and every ``pre`` of the definitions at this tick."""
        names = [n for n, b in self.streams.booleans.items() if b]
        return (tuple(self.letter_bool(n) for n in names),
                past_values(self.streams, self.done))

    def complete(self, got: dict[str, Any]) -> dict:
        """The tick's row with ``got`` (z3's numbers and booleans) and the streams'
        values computed from it (:func:`fretc.check.stream_rows.value_at`)."""
        row = dict(self.row)
        for name, v in got.items():
            if name in row and isinstance(v, bool) == isinstance(row[name], bool):
                row[name] = v
        t = len(self.done)
        trace = self.done + [row]
        for name, expr in self.streams.exprs.items():
            try:
                row[name] = value_at(expr, trace, t)
            except KeyError:  # (an input with no column: the trace cannot compute it)
                row.pop(name, None)
        return row


def concrete_rows(rows: list[dict], letters: list[dict], atoms: dict[str, Node],
                  streams: TraceStreams | None = None) -> list[dict]:
    """``rows`` (one ``{variable: value}`` per tick, from the abstraction's model whose
    letters, SMV text -> bool per tick, are ``letters``) with the numeric variables of the
    free comparison ``atoms`` (:func:`free_atoms`) set, tick by tick, to numbers giving
    those comparisons the letter's truth values (module docstring). Ticks z3 cannot answer
    keep their numbers. With ``streams`` (:mod:`fretc.check.stream_rows`), the stream
    variables' definitions take part in each tick's query, and their columns are then the
    audit's, computed from the rows. Deterministic: z3's answer under a resource limit,
    not a time."""
    if not atoms and streams is None:
        return rows
    import z3
    cache: dict[tuple[Any, ...], dict | None] = {}
    stateful = any(ir.has_op(a, ("pre",)) for a in atoms.values()) or streams is not None
    names = sorted(atoms)
    out: list[dict] = []
    for row, letter in zip(rows, letters):
        prev = out[-1] if out else None
        tick = _Streams(streams, out, row, letter) if streams is not None else None
        key: tuple[Any, ...] = tuple((k, letter.get(k)) for k in names)
        if stateful:
            key += (tuple(sorted(prev.items())) if prev else None,)
        if tick is not None:
            key += tick.key()
        if key not in cache:
            cache[key] = _solve(z3, atoms, letter, prev, tick)
        got = cache[key] or {}
        if tick is not None:
            out.append(tick.complete(got))
            continue
        row = dict(row)
        for name, v in got.items():
            if name in row and not isinstance(row[name], bool):
                row[name] = v
        out.append(row)
    return with_stream_columns(out, streams)
