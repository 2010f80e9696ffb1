"""A reader of printed PCTL for the tests: FRET 3.1's ``pctl``/``pctlExpanded`` texts
(``../shared/fretish/fret_probabilistic_vectors.jsonl``: ``P>=0.9[(F[<=1] x)]``,
``F<=(5+1)``, ``=>``, ``R``, ``LAST``), fretc's PRISM text (``P>=0.9 [ (F<=1 x) ]``) and the
FRET/SMV text of ft_inf (``F[0,1]``, ``->``, ``V``) into one small tree, so the tests can
compare where the bounds sit and hand the path formulas (bounds removed) to Spot.

Tree nodes are tuples: ``("P", bound, child)``, ``("!", x)``, ``("bin", op, a, b)`` with op
in ``& | -> <-> U R``, ``("temp", op, lo, hi, x)`` with op in ``X F G`` (``hi`` None:
unbounded), ``("atom", text)``. A comparison ``(speed <= 2.0)`` is one atom.
"""

from __future__ import annotations

import re

_TOKEN = re.compile(r"\s*(<=>|=>|->|<=|>=|!=|[<>=!&|()\[\],+]|[A-Za-z_][A-Za-z0-9_]*|"
                    r"\d+(?:\.\d+)?)")
_CMP = ("<=", ">=", "!=", "<", ">", "=")
_BIN = {"&": "&", "|": "|", "->": "->", "=>": "->", "<=>": "<->", "<->": "<->",
        "U": "U", "R": "R", "V": "R"}


def tokens(text: str) -> list[str]:
    """The tokens of ``text``; ``ValueError`` on a character no token starts with."""
    out, i = [], 0
    text = text.rstrip()
    while i < len(text):
        m = _TOKEN.match(text, i)
        if not m:
            raise ValueError(f"cannot read {text[i:i + 20]!r}")
        out.append(m.group(1))
        i = m.end()
    return out


class _Reader:
    def __init__(self, text: str):
        self.t = tokens(text)
        self.i = 0

    def peek(self, k: int = 0):
        j = self.i + k
        return self.t[j] if j < len(self.t) else None

    def take(self, want: str | None = None) -> str:
        tok = self.peek()
        if tok is None or (want is not None and tok != want):
            raise ValueError(f"expected {want!r} at token {self.i}, got {tok!r}")
        self.i += 1
        return tok

    def number(self) -> int:
        """``5``, ``5+1``, ``(5+1)``."""
        if self.peek() == "(":
            self.take("(")
            v = self.number()
            self.take(")")
            return v
        v = int(self.take())
        while self.peek() == "+":
            self.take("+")
            v += int(self.take())
        return v

    def temporal_bounds(self):
        """``<=k`` / ``[<=k]`` / ``[l,h]`` after X F G, or nothing."""
        if self.peek() == "<=":
            self.take()
            return 0, self.number()
        if self.peek() == "[":
            self.take("[")
            if self.peek() == "<=":
                self.take()
                lo, hi = 0, self.number()
            else:
                lo = self.number()
                self.take(",")
                hi = self.number()
            self.take("]")
            return lo, hi
        return None, None

    def unary(self):
        tok = self.peek()
        if tok == "!":
            self.take()
            return ("!", self.unary())
        if tok == "P" and self.peek(1) in _CMP:
            self.take()
            op = self.take()
            bound = f"P{op}{self.take()}"
            self.take("[")
            x = self.expr()
            self.take("]")
            return ("P", bound, x)
        if tok in ("X", "F", "G"):
            self.take()
            lo, hi = self.temporal_bounds()
            return ("temp", tok, lo, hi, self.unary())
        if tok == "(":
            self.take("(")
            x = self.expr()
            self.take(")")
            return x
        self.take()
        return ("atom", tok)

    def expr(self):
        a = self.unary()
        op = self.peek()
        if op in _CMP:  # a comparison of two terms: one atom
            self.take()
            b = self.unary()
            return ("atom", f"{_text(a)} {op} {_text(b)}")
        if op in _BIN:
            self.take()
            return ("bin", _BIN[op], a, self.unary())
        return a


def _text(x) -> str:
    if x[0] != "atom":
        raise ValueError(f"not a term: {x}")
    return x[1]


def read(text: str):
    """The tree of a printed formula (module docstring); ``ValueError`` on text it cannot
    read or tokens left over."""
    r = _Reader(text)
    x = r.expr()
    if r.peek() is not None:
        raise ValueError(f"left over from token {r.i}: {r.t[r.i:r.i + 5]}")
    return x


def bounds(tree) -> list[tuple]:
    """``(bound, parent index, temporal operators between the parent bound and it)`` of each
    bound in pre-order (``U.1``/``U.2``, ``R.1``/``R.2`` name the operand): the shape
    :func:`fretc.compiler.pctl.bound_structure` gives."""
    out: list[tuple] = []

    def go(x, parent, under):
        kind = x[0]
        if kind == "P":
            out.append((x[1], parent, tuple(under)))
            go(x[2], len(out) - 1, ())
        elif kind == "!":
            go(x[1], parent, under)
        elif kind == "bin":
            t = x[1] if x[1] in ("U", "R") else None
            for i, a in enumerate(x[2:]):
                go(a, parent, under + ((f"{t}.{i + 1}",) if t else ()))
        elif kind == "temp":
            go(x[4], parent, under + (x[1],))

    go(tree, None, ())
    return out


_SPOT_CONST = {"TRUE": "true", "true": "true", "FALSE": "false", "false": "false",
               "LAST": "false"}


#: Spot's largest bound of F[l..h] and G[l..h]
SPOT_MAX_BOUND = 254


def spot_text(tree, big: dict | None = None) -> str:
    """Spot's syntax of the tree with its bounds removed (``LAST`` false: infinite traces);
    atoms other than plain names are double-quoted propositions. A time bound above
    :data:`SPOT_MAX_BOUND` is renamed by ``big`` (shared by the formulas compared: the same
    number gets the same stand-in, 200 and up, in all of them)."""
    big = {} if big is None else big
    kind = tree[0]
    if kind == "P":
        return spot_text(tree[2], big)
    if kind == "!":
        return f"(!{spot_text(tree[1], big)})"
    if kind == "bin":
        return f"({spot_text(tree[2], big)} {tree[1]} {spot_text(tree[3], big)})"
    if kind == "temp":
        _, op, lo, hi, x = tree
        if hi is not None and hi > SPOT_MAX_BOUND:
            hi = big.setdefault(hi, 200 + len(big))
        b = "" if hi is None else f"[{lo}..{hi}]"
        return f"({op}{b} {spot_text(x, big)})"
    text = tree[1]
    if text in _SPOT_CONST:
        return _SPOT_CONST[text]
    return text if re.fullmatch(r"[a-z_][A-Za-z0-9_]*", text) else '"' + text + '"'


def equivalent(f, g) -> bool:
    """Spot formulas ``f`` and ``g`` are equivalent: neither ``f & !g`` nor ``g & !f`` has an
    accepting run (Spot's translation at its 'low' optimization: the same answer as
    ``spot.are_equivalent``, in a second instead of a minute for the scoped bounded
    responses)."""
    import spot

    def empty(x) -> bool:
        return spot.translate(x, "low", "any").is_empty()

    return (empty(spot.formula.And([f, spot.formula.Not(g)]))
            and empty(spot.formula.And([g, spot.formula.Not(f)])))
