"""Reader of FRET's printed formulas (SMV flavour), for differential tests only: turns the
ft / ft_inf / pt strings of ``shared/fretish/fret_vectors.jsonl`` into our IR so both can be
evaluated on the same traces. FRET parenthesizes every operation, so the grammar needs no
precedence."""

from __future__ import annotations

from lark import Lark, Transformer

from fretc.compiler import ir
from fretc.compiler.ir import Node

_GRAMMAR = r"""
start: f
?f: "(" f BIN f ")"              -> binary
  | "(" UNARY f ")"              -> unary
  | "(" f ")"
  | atom
?atom: NAME "(" [arg ("," arg)*] ")"  -> call
     | NAME                        -> name
     | NUMBER                      -> number
?arg: f
UNARY.3: /(!|X|F|G|Y|Z|H|O)(\[[^\]]*\])?(?=[\s(])/
BIN.2: "<->" | "->" | "&" | "|" | "xor" | "!=" | "<=" | ">=" | "<" | ">" | "=" | "+" | "-"
     | "*" | "/" | "mod" | "^" | /[UVST](\[\d+,\d+\])?(?=\s)/
NAME.1: /[A-Za-z_][A-Za-z0-9_]*/
NUMBER.1: /-?\d+(\.\d+)?([eE][-+]?\d+)?/
%import common.WS
%ignore WS
"""

_parser = Lark(_GRAMMAR, parser="earley", lexer="dynamic")

_BOOL_OPS = {"&", "|", "xor", "->", "<->", "U", "V", "S", "T"}
_CMP = {"=", "!=", "<", "<=", ">", ">="}
_TEMPORAL_FUNCS = {"persisted", "occurred", "preBool", "prevOcc", "persists", "occurs",
                   "nextOcc"}


class _Raw(Transformer):
    def start(self, c):
        return c[0]

    def binary(self, c):
        return ("bin", str(c[1]), c[0], c[2])

    def unary(self, c):
        tok = str(c[0])
        op, _, rest = tok.partition("[")
        lo = hi = None
        if rest:
            lo_s, hi_s = rest.rstrip("]").split(",")
            lo, hi = int(lo_s), int(hi_s)
        return ("un", op, lo, hi, c[1])

    def call(self, c):
        return ("call", str(c[0]), [x for x in c[1:] if x is not None])

    def name(self, c):
        return ("name", str(c[0]))

    def number(self, c):
        return ("num", str(c[0]))


def parse_fret(text: str, derived: dict | None = None) -> Node:
    """IR of a FRET formula. ``derived`` maps the printed text of a temporal-function call
    (``persisted(3,p)``) to the node that gives it meaning (FRET leaves such calls
    unexpanded in the formula of the other direction)."""
    derived = derived or {}
    raw = _Raw().transform(_parser.parse(text))

    def boolean(t) -> Node:
        kind = t[0]
        if kind == "name":
            n = t[1]
            if n == "TRUE":
                return ir.TRUE
            if n == "FALSE":
                return ir.FALSE
            if n == "LAST":
                return ir.LAST
            if n == "FTP":
                return ir.FTP
            return ir.ap(n)
        if kind == "call":
            text_ = _text(t)
            if t[1] in _TEMPORAL_FUNCS:
                if text_ not in derived:
                    raise KeyError(f"no meaning for {text_}")
                return derived[text_]
            return Node("call", tuple(arg(a) for a in t[2]), name=t[1])
        if kind == "un":
            _, op, lo, hi, sub = t
            x = boolean(sub)
            if op == "!":
                return Node("!", (x,))
            return Node(op, (x,), lo=lo, hi=hi)
        if kind == "bin":
            _, op, l, r = t
            if op in _CMP:
                return Node("cmp", (term(l), term(r)), name=op)
            if op in _BOOL_OPS:
                return Node(op, (boolean(l), boolean(r)))
            if op[0] in "SU" and "[" in op:
                return _bounded(op, boolean(l), boolean(r))
        raise ValueError(f"not a condition: {t}")

    def term(t) -> Node:
        kind = t[0]
        if kind == "name":
            return ir.var(t[1])
        if kind == "num":
            return ir.num(t[1])
        if kind == "bin":
            return ir.arith(t[1], term(t[2]), term(t[3]))
        if kind == "call":
            if t[1] in ("preInt", "preReal") and len(t[2]) == 2:
                # FRET never expands these: give them our meaning (value one step back)
                return Node("pre", (term(t[2][0]), term(t[2][1])), name=t[1])
            return Node("fn", tuple(term(a) for a in t[2]), name=t[1])
        raise ValueError(f"not a number: {t}")

    def arg(t) -> Node:
        try:
            return boolean(t)
        except ValueError:
            return term(t)

    return boolean(raw)


def _bounded(op: str, a: Node, b: Node) -> Node:
    """FRET's bounded since/until by its definition: ``a S[m,n] b`` holds when b held k
    steps ago for some k in [m, n] and a held at each of the k positions since; ``U``
    mirrors it in the future."""
    m, n = (int(x) for x in op[2:-1].split(","))
    once, hist = ("O", "H") if op[0] == "S" else ("F", "G")
    out = None
    for k in range(m, n + 1):
        x = Node(once, (b,), lo=k, hi=k) if k else b
        if k:
            x = Node("&", (x, Node(hist, (a,), lo=0, hi=k - 1)))
        out = x if out is None else Node("|", (out, x))
    return out


def _text(t) -> str:
    kind = t[0]
    if kind in ("name", "num"):
        return t[1]
    if kind == "call":
        return f"{t[1]}({','.join(_text(a) for a in t[2])})"
    if kind == "bin":
        return f"({_text(t[2])} {t[1]} {_text(t[3])})"
    if kind == "un":
        _, op, lo, hi, sub = t
        b = "" if lo is None else f"[{lo},{hi}]"
        return f"({op}{b} {_text(sub)})"
    raise ValueError(t)
