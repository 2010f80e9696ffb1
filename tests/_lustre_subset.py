"""A small reader and stream interpreter of the Lustre subset ``fretc --emit cocospec`` writes
(and FRET's CoCoSpec formulas use), written for the tests, independent of
``fretc.compiler.cocospec``, and stricter than Kind 2 where fretc's output must be (no
keyword of Kind 2 names a variable, a label is one line, no comment is unclosed, nothing Kind
2's lexer reads otherwise; :func:`tokens`): ``node``s (parameters, ``var`` locals, equations), Kind 2
``contract`` nodes (``var`` ghosts, ``guarantee``/``assume``), expressions with ``->``,
``pre``, ``if then else``, ``not and or xor =>``, comparisons, ``+ - * / div mod``, unary
minus, Kind 2's conversions ``real e`` and ``int e``, and node calls, read with Kind 2's
precedences (lowest first: ``if``, ``->``, ``=>``,
``or xor``, ``and``, comparisons, ``+ -``, ``* / div mod``, ``not``, ``pre``, unary minus).

Semantics (Lustre's): a stream per expression; ``a -> b`` is ``a`` at the first tick and
``b`` after; ``pre e`` is ``e`` a tick ago (nil at the first tick: ``None`` here, and any
operation on nil is nil); each call site is an instance of its node with its own memory.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass, field
from typing import Any

_TOKEN = re.compile(r"""
    (?P<annotation>--[%!]|\(\*[%!@]|/\*|//|\*\)|and\s+then|or\s+else)
  | (?P<space>\s+|--[^\n]*|\(\*.*?\*\))
  | (?P<unclosed>\(\*)
  | (?P<string>"(?:[^"\\\n]|\\[^\n])*")
  | (?P<num>[0-9]+\.[0-9]*(?:[eE][-+]?[0-9]+)?|[0-9]+)
  | (?P<id>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<sym>->|=>|<>|<=|>=|[()\[\],;:=<>+\-*/])
""", re.X | re.S)

#: Kind 2's keywords (its Lustre lexer's table, and ``lsh``/``rsh``): none names a variable
KIND2_KEYWORDS = frozenset("""
    type datatype int uint sint uint8 uint16 uint32 uint64 int8 int16 int32 int64 real bool
    subrange of subtype struct enum history map set const param transparent opaque imported
    node function returns var let tel con noc assert check reachable invariant provided from
    at within contract import true false not and xor forall exists or in if then else elsif
    fi when cond otherwise end frame div mod any choose current condact activate initial
    default every restart merge pre fby mode assume guarantee require ensure weakly
    assumption_vars with match lsh rsh
""".split())
KEYWORDS = KIND2_KEYWORDS


def tokens(text: str) -> list[tuple[str, str]]:
    """``[(kind, text)]``: kinds ``string``, ``num``, ``id``, ``kw``, ``sym``. Raises
    ``SyntaxError`` at a character outside the subset, an unclosed ``(*`` comment, a string
    holding a line break (fretc's labels are one line), and at what Kind 2's lexer reads
    otherwise than this reader would: an annotation (``--%``, ``--!``, ``(*@``, ``(*%``,
    ``(*!``), a ``/*`` or ``//`` comment, a ``*)`` outside a comment, and ``and then`` /
    ``or else`` (Kind 2's short-circuit operators, even before ``then_v``)."""
    out, i = [], 0
    while i < len(text):
        m = _TOKEN.match(text, i)
        if m is None:
            raise SyntaxError(f"unexpected {text[i:i + 20]!r}")
        kind = m.lastgroup or ""
        if kind in ("annotation", "unclosed"):
            raise SyntaxError(f"{kind} {m.group(kind)!r} at character {i}")
        if kind != "space":
            word = m.group(kind)
            out.append(("kw" if kind == "id" and word in KEYWORDS else kind, word))
        i = m.end()
    return out


@dataclass
class Node:
    """A node or a contract: ``params`` and ``returns`` ``[(name, type)]``, ``locals``,
    ``eqs`` (name -> expression), ``props`` (``[(kind, label, expression)]``)."""

    name: str
    kind: str
    params: list = field(default_factory=list)
    returns: list = field(default_factory=list)
    locals: list = field(default_factory=list)
    eqs: dict = field(default_factory=dict)
    props: list = field(default_factory=list)


_BINARY = {"->": (10, "r"), "=>": (20, "r"), "or": (30, "l"), "xor": (30, "l"),
           "and": (40, "l"), "=": (50, "l"), "<>": (50, "l"), "<": (50, "l"),
           "<=": (50, "l"), ">": (50, "l"), ">=": (50, "l"), "+": (60, "l"), "-": (60, "l"),
           "*": (70, "l"), "/": (70, "l"), "div": (70, "l"), "mod": (70, "l")}


class Reader:
    """The recursive-descent reader of a program's text."""

    def __init__(self, text: str):
        self.t = tokens(text)
        self.i = 0

    def peek(self) -> str | None:
        return self.t[self.i][1] if self.i < len(self.t) else None

    def next(self) -> tuple[str, str]:
        if self.i >= len(self.t):
            raise SyntaxError("unexpected end of text")
        self.i += 1
        return self.t[self.i - 1]

    def expect(self, word: str) -> None:
        got = self.next()[1]
        if got != word:
            raise SyntaxError(f"expected {word!r}, got {got!r} at token {self.i}")

    def ident(self) -> str:
        kind, word = self.next()
        if kind != "id":
            raise SyntaxError(f"expected a name, got {word!r}")
        return word

    def program(self) -> dict[str, Node]:
        out: dict[str, Node] = {}
        while self.i < len(self.t):
            kind = self.next()[1]
            if kind not in ("node", "contract"):
                raise SyntaxError(f"expected node or contract, got {kind!r}")
            n = Node(self.ident(), kind)
            if n.name in out:
                raise SyntaxError(f"{n.name} defined twice")
            n.params = self.decls(")")
            self.expect("returns")
            n.returns = self.decls(")")
            self.expect(";")
            if self.peek() == "var":
                self.next()
                while self.peek() != "let":
                    n.locals += self.group()
                    self.expect(";")
            self.expect("let")
            if n.kind == "contract" and self.peek() == "tel":
                raise SyntaxError(f"contract {n.name} is empty (Kind 2 wants one item)")
            while self.peek() != "tel":
                self.item(n)
            self.expect("tel")
            out[n.name] = n
        return out

    def decls(self, end: str) -> list:
        self.expect("(")
        out: list = []
        while self.peek() != end:
            out += self.group()
            if self.peek() == ";":
                self.next()
        self.expect(end)
        return out

    def group(self) -> list:
        names = [self.ident()]
        while self.peek() == ",":
            self.next()
            names.append(self.ident())
        self.expect(":")
        kind, ty = self.next()
        if ty not in ("bool", "int", "real"):
            raise SyntaxError(f"unknown type {ty!r}")
        return [(x, ty) for x in names]

    def item(self, n: Node) -> None:
        word = self.peek()
        if n.kind == "contract" and word in ("guarantee", "assume"):
            self.next()
            kind, label = self.next()
            if kind != "string":
                raise SyntaxError("a property's name is a string")
            n.props.append((word, label, self.expr()))
        elif n.kind == "contract" and word == "var":
            self.next()
            (name, ty), = self.group()
            self.expect("=")
            n.locals.append((name, ty))
            n.eqs[name] = self.expr()
        else:
            name = self.ident()
            self.expect("=")
            if name in n.eqs:
                raise SyntaxError(f"{name} defined twice in {n.name}")
            n.eqs[name] = self.expr()
        self.expect(";")

    def expr(self, bp: int = 0) -> Any:
        left = self.prefix()
        while True:
            op = self.peek()
            if op not in _BINARY or _BINARY[op][0] < bp or (
                    _BINARY[op][0] == bp and _BINARY[op][1] == "l"):
                return left
            self.next()
            power, assoc = _BINARY[op]
            right = self.expr(power if assoc == "r" else power + 1)
            left = ("bin", op, left, right)

    def prefix(self) -> Any:
        kind, word = self.next()
        if kind == "num":
            return ("const", float(word) if "." in word or "e" in word.lower() else int(word))
        if word in ("true", "false"):
            return ("const", word == "true")
        if word == "if":
            c = self.expr()
            self.expect("then")
            a = self.expr()
            self.expect("else")
            return ("if", c, a, self.expr())
        if word == "not":
            return ("not", self.expr(75))
        if word == "pre":
            return ("pre", self.expr(80))
        if word in ("real", "int"):  # Kind 2's conversions
            return ("conv", word, self.expr(78))
        if word == "-":
            return ("neg", self.expr(85))
        if word == "(":
            e = self.expr()
            self.expect(")")
            return e
        if kind == "id":
            if self.peek() == "(":
                self.next()
                args = []
                while self.peek() != ")":
                    args.append(self.expr())
                    if self.peek() == ",":
                        self.next()
                self.expect(")")
                return ("call", word, tuple(args), object())
            return ("id", word)
        raise SyntaxError(f"unexpected {word!r}")


def read(text: str) -> dict[str, Node]:
    """The nodes and contracts of ``text`` by name. Raises ``SyntaxError``."""
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 20000))  # (a reader by recursive descent: deep nesting)
    try:
        return Reader(text).program()
    finally:
        sys.setrecursionlimit(old)


def _op(op: str, a: Any, b: Any) -> Any:
    if a is None or b is None:
        return None
    if op == "and":
        return a and b
    if op == "or":
        return a or b
    if op == "xor":
        return a != b
    if op == "=>":
        return (not a) or b
    if op == "=":
        return a == b
    if op == "<>":
        return a != b
    if op in ("<", "<=", ">", ">="):
        return {"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b}[op]
    if op in ("+", "-", "*"):
        return {"+": a + b, "-": a - b, "*": a * b}[op]
    if op == "/":
        return a / b if b else float("nan")
    if op == "div":
        return a // b if b else 0
    if op == "mod":
        return a % b if b else 0
    raise ValueError(op)


class Instance:
    """One instance of a node: its inputs are functions of the tick."""

    def __init__(self, program: dict[str, Node], node: Node, inputs: dict):
        self.program, self.node, self.inputs = program, node, inputs
        self.memo: dict[tuple[str, int], Any] = {}
        self.calls: dict[int, Instance] = {}

    def value(self, name: str, t: int) -> Any:
        if name in self.inputs:
            return self.inputs[name](t)
        key = (name, t)
        if key not in self.memo:
            if name not in self.node.eqs:
                raise NameError(f"{name} is not defined in {self.node.name}")
            self.memo[key] = self.eval(self.node.eqs[name], t)
        return self.memo[key]

    def eval(self, e: Any, t: int) -> Any:
        tag = e[0]
        if tag == "const":
            return e[1]
        if tag == "id":
            return self.value(e[1], t)
        if tag == "bin" and e[1] == "->":
            return self.eval(e[2], t) if t == 0 else self.eval(e[3], t)
        if tag == "bin":
            return _op(e[1], self.eval(e[2], t), self.eval(e[3], t))
        if tag == "pre":
            return None if t == 0 else self.eval(e[1], t - 1)
        if tag == "not":
            v = self.eval(e[1], t)
            return None if v is None else not v
        if tag == "neg":
            v = self.eval(e[1], t)
            return None if v is None else -v
        if tag == "conv":
            v = self.eval(e[2], t)
            return None if v is None else (float(v) if e[1] == "real" else int(v))
        if tag == "if":
            c = self.eval(e[1], t)
            return None if c is None else self.eval(e[2] if c else e[3], t)
        if tag == "call":
            return self.call(e, t)
        raise ValueError(tag)

    def call(self, e: Any, t: int) -> Any:
        _tag, name, args, key = e
        inst = self.calls.get(id(key))
        if inst is None:
            node = self.program.get(name)
            if node is None or node.kind != "node":
                raise NameError(f"no node {name}")
            if len(node.params) != len(args) or len(node.returns) != 1:
                raise TypeError(f"{name} takes {len(node.params)} arguments")
            inputs = {p: (lambda t, a=a: self.eval(a, t)) for (p, _ty), a in
                      zip(node.params, args)}
            inst = self.calls[id(key)] = Instance(self.program, node, inputs)
        return inst.value(node_output(inst.node), t)


def node_output(node: Node) -> str:
    """The name of a node's one output."""
    return node.returns[0][0]


def run_contract(program: dict[str, Node], name: str, trace: list[dict]) -> dict[str, list]:
    """Each property of contract ``name`` at each tick of ``trace`` (a list of
    ``{variable: value}``, the contract's inputs and outputs): ``{label: [bool, ...]}``.
    A nil value at a tick is an error (``AssertionError``)."""
    node = program[name]
    inputs = {v: (lambda t, v=v: trace[t][v]) for v, _ty in node.params + node.returns}
    inst = Instance(program, node, inputs)
    out: dict[str, list] = {}
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 20000))
    try:
        for _kind, label, e in node.props:
            values = [inst.eval(e, t) for t in range(len(trace))]
            assert all(v is not None for v in values), (label, values)
            out[label] = [bool(v) for v in values]
    finally:
        sys.setrecursionlimit(old)
    return out
