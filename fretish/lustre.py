"""FRET's glossary definitions: the Lustre expressions of Internal variables, read as FRETish
expressions.

FRET's Analysis Portal defines an Internal variable by an expression in a subset of Lustre
(its ``assignment``: ``roll_hold`` is ``autopilot_engaged and not hdg_hold``; ``xinpv`` is
``0.0 -> pre xin``) and its realizability check reads the variable as that definition (FRET's
manual, "Variable Mapping" and "Realizability Checking"; the Lustre of Kind 2 / CoCoSpec).
:func:`parse_definition` reads that subset into :mod:`fretc.fretish.ast` expressions, with the
same meaning:

Design notes: ARCHITECTURE.md, `fretish/lustre.py`."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from fretc.fretish import ast as A
from fretc.fretish.limits import MAX_EXPR_DEPTH, MAX_NUMBER_CHARS, depth

__all__ = ["LustreError", "LustreTooDeep", "PrintedDefinition", "lustre_number",
           "parse_definition", "pre_groups", "print_definition"]

_TOKEN = re.compile(r"\s*(?:(?P<num>(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)"
                    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
                    r"|(?P<op>->|=>|<>|<=|>=|[-+*/=<>(),]))")
_KEYWORDS = frozenset({"and", "or", "xor", "not", "if", "then", "else", "pre", "true",
                       "false", "mod"})
_REFUSED = frozenset({"div", "when", "current", "fby", "merge", "let", "tel", "node"})
_COMPARISONS = {"=": "=", "<>": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
#: Lustre's comment openers: none is an operator of the subset (``--`` is not two minuses)
_COMMENT = re.compile(r"--|\(\*|/\*|//")
#: the subset's binary operators (Lustre's spelling) as FRETish writes them
_FRETISH_OP = {"=>": "->", "or": "|", "xor": "xor", "and": "&", "+": "+", "-": "-",
               "*": "*", "/": "/", "mod": "mod", **_COMPARISONS}


class LustreError(ValueError):
    """A definition outside FRET's Lustre subset (the module docstring), with the reason."""


class LustreTooDeep(LustreError):
    """A definition inside the subset but nested past what fretc reads (a FRETish
    expression's :data:`fretc.fretish.limits.MAX_EXPR_DEPTH` levels)."""


def parse_definition(text: str, is_boolean: Callable[[str], bool]) -> A.Expr:
    """The FRETish expression of the Lustre definition ``text`` (module docstring);
    ``is_boolean(name)`` says whether a variable of the glossary is boolean.

    Raises:
        LustreError: a token or construct outside the subset, or a definition that does
            not end where the expression does, naming what and where (character offset)."""
    p = _Parser(_tokens(text), is_boolean)
    try:
        e = p.expr()
    except RecursionError:
        raise LustreTooDeep("nested too deeply") from None
    if p.peek() is not None:
        raise LustreError(f"unexpected {p.peek()!r} at character {p.offset()}")
    if depth(e) > MAX_EXPR_DEPTH:  # (a long chain: a and b and ..., built without recursion)
        raise LustreTooDeep(f"nested more than {MAX_EXPR_DEPTH} levels deep (the limit of a "
                          "FRETish expression)")
    return e


def pre_groups(text: str, name: str, taken: Callable[[str], bool],
               is_boolean: Callable[[str], bool]) -> list[tuple[str, A.Expr, bool, str]] | None:
    """The Lustre definition ``text`` of the variable ``name`` as equations, one per
    parenthesized ``pre ( e )`` group: the group is a variable of its own, ``name__preK``
    (the first K that ``taken`` refuses not), defined as ``e``, and read as ``pre
    name__preK`` (Lustre's meaning unchanged: a node's local variable). For definitions
    nested past :data:`fretc.fretish.limits.MAX_EXPR_DEPTH` through ``pre``: FRET's tables of
    values over time, ``c0 -> pre(c1 -> pre(c2 -> ...))`` (LMCPS's NN, 199 deep). Read
    without recursion; each equation then as :func:`parse_definition` reads it, the
    innermost first (a group's type is that of its expression).

    Returns:
        ``[(variable, expression, is_boolean, text)]`` the groups innermost first and
        ``name`` last; None when an equation is still too deep or has no ``pre`` group.

    Raises:
        LustreError: a token or construct outside the subset, unbalanced parentheses."""
    toks = [t for t, _at in _tokens(text)]
    opened = sum(1 for a, b in zip(toks, toks[1:]) if a == "pre" and b == "(")
    if not opened:
        return None
    base = f"{name}__pre"
    while any(taken(f"{base}{j}") for j in range(1, opened + 1)):
        base += "_"
    frames: list[list[str]] = [[]]
    plain: list[int] = [0]  # (open plain parentheses in each frame)
    ids: list[int] = [0]  # (each group numbered as it opens: the outermost 1)
    groups: list[tuple[str, list[str]]] = []
    i = count = 0
    while i < len(toks):
        tok = toks[i]
        if tok == "pre" and i + 1 < len(toks) and toks[i + 1] == "(":
            count += 1
            frames.append([])
            plain.append(0)
            ids.append(count)
            i += 2
            continue
        if tok == ")" and plain[-1] == 0:
            if len(frames) == 1:
                raise LustreError(f"unbalanced ')' in {name}'s definition")
            aux = f"{base}{ids.pop()}"
            groups.append((aux, frames.pop()))
            plain.pop()
            frames[-1] += ["pre", aux]
            i += 1
            continue
        plain[-1] += (tok == "(") - (tok == ")")
        frames[-1].append(tok)
        i += 1
    if len(frames) != 1 or plain[0]:
        raise LustreError(f"unbalanced '(' in {name}'s definition")
    types: dict[str, bool] = {}

    def typed(n: str) -> bool:
        return types[n] if n in types else is_boolean(n)

    out: list[tuple[str, A.Expr, bool, str]] = []
    for var, body in [*groups, (name, frames[0])]:
        source = " ".join(body)
        p = _Parser(_tokens(source), typed)
        try:
            e, boolean = p.ite()
        except RecursionError:
            return None
        if p.peek() is not None:
            raise LustreError(f"unexpected {p.peek()!r} in {name}'s definition")
        if depth(e) > MAX_EXPR_DEPTH:
            return None
        types[var] = boolean
        out.append((var, e, boolean, source))
    return out


def _tokens(text: str) -> list[tuple[str, int]]:
    """``(token, offset)`` of ``text``. Raises :class:`LustreError` at a character no token
    starts with, at a Lustre comment opener and at a number longer than
    :data:`fretc.fretish.limits.MAX_NUMBER_CHARS` characters."""
    out: list[tuple[str, int]] = []
    i = 0
    while True:
        while i < len(text) and text[i].isspace():
            i += 1
        if i == len(text):
            return out
        if _COMMENT.match(text, i):
            raise LustreError(f"a Lustre comment ({text[i:i + 2]!r}, character {i}) is "
                              "outside FRET's Lustre subset (a definition is one expression)")
        m = _TOKEN.match(text, i)
        if m is None or m.end() == i:
            raise LustreError(f"unexpected {text[i]!r} at character {i}")
        tok = m.group("num") or m.group("name") or m.group("op")
        if m.group("num") and len(tok) > MAX_NUMBER_CHARS:
            raise LustreError(f"a number of {len(tok)} characters at character {i} (at most "
                              f"{MAX_NUMBER_CHARS})")
        out.append((tok, i))
        i = m.end()


class _Fretish:
    """What :class:`_Parser` builds for fretc's reading: :mod:`fretc.fretish.ast` expressions
    (the module docstring's meaning of each construct)."""

    def ite(self, c: A.Expr, a: A.Expr, b: A.Expr) -> A.Expr:
        return A.Call("ite", (c, a, b))

    def arrow(self, a: A.Expr, b: A.Expr) -> A.Expr:
        return A.Call("ite", (A.Var("FTP"), a, b))

    def binary(self, op: str, a: A.Expr, b: A.Expr, booleans: bool) -> A.Expr:
        if booleans and op in ("=", "<>"):  # (truth values: Lustre's = is iff)
            return A.Binary("<->" if op == "=" else "xor", a, b)
        return A.Binary(_FRETISH_OP[op], a, b)

    def not_(self, a: A.Expr) -> A.Expr:
        return A.Unary("!", a)

    def neg(self, a: A.Expr) -> A.Expr:
        if isinstance(a, A.NumLit) and not a.text.startswith("-"):
            return A.NumLit("-" + a.text)
        return A.Unary("-", a)

    def pre(self, a: A.Expr, boolean: bool) -> A.Expr:
        if boolean:
            return A.Call("preBool", (A.BoolLit(False), a))
        return A.Call("preReal", (A.NumLit("0"), a))

    def literal(self, tok: str) -> A.Expr:
        if tok in ("true", "false"):
            return A.BoolLit(tok == "true")
        return A.NumLit(tok)

    def var(self, name: str) -> A.Expr:
        return A.Var(name)

    def call(self, name: str, args: list[A.Expr]) -> A.Expr:
        return A.Call(name, tuple(args))


class _Lustre:
    """What :class:`_Parser` builds for :func:`print_definition`: the Lustre text of each
    construct, parenthesized (so Kind 2's precedences, which differ from the subset's in
    places, read it as fretc does), each variable as ``rename`` names it."""

    def __init__(self, rename: Callable[[str], str]):
        self.rename = rename
        self.names: dict[str, None] = {}
        self.calls: dict[tuple[str, int], None] = {}

    def ite(self, c: str, a: str, b: str) -> str:
        return f"(if {c} then {a} else {b})"

    def arrow(self, a: str, b: str) -> str:
        return f"({a} -> {b})"

    def binary(self, op: str, a: str, b: str, booleans: bool) -> str:
        return f"({a} {op} {b})"

    def not_(self, a: str) -> str:
        return f"(not {a})"

    def neg(self, a: str) -> str:
        return f"(- {a})"  # (spaced: never "--", a comment)

    def pre(self, a: str, boolean: bool) -> str:
        return f"(pre {a})"

    def literal(self, tok: str) -> str:
        return tok if tok in ("true", "false") else lustre_number(tok)

    def var(self, name: str) -> str:
        if name == "FTP":  # (fretc reads FTP as FRET's first time point, as in ->)
            return "(true -> false)"
        self.names.setdefault(name)
        return self.rename(name)

    def call(self, name: str, args: list[str]) -> str:
        self.calls.setdefault((name, len(args)))
        return f"{name}({', '.join(args)})"


def lustre_number(tok: str) -> str:
    """The number token ``tok`` of the subset (``7``, ``1.``, ``.5``, ``2e3``) in Kind 2's
    form (its lexer: an integer, or digits, ``.``, digits and an exponent): ``7``, ``1.0``,
    ``0.5``, ``2.0e3``."""
    mantissa, e, exponent = tok.replace("E", "e").partition("e")
    if not e and "." not in mantissa:
        return mantissa
    whole, _dot, fraction = mantissa.partition(".")
    return f"{whole or '0'}.{fraction or '0'}" + (f"e{exponent}" if e else "")


@dataclass(frozen=True)
class PrintedDefinition:
    """A definition as :func:`print_definition` writes it: ``text`` (Lustre, one line),
    ``boolean`` (its type is bool), ``names`` (the variables it reads, source names, in order
    of first appearance; ``FTP`` not among them) and ``calls`` (``(function, number of
    arguments)`` it calls, in order)."""

    text: str
    boolean: bool
    names: tuple[str, ...]
    calls: tuple[tuple[str, int], ...]


def print_definition(text: str, is_boolean: Callable[[str], bool],
                     rename: Callable[[str], str] = str) -> PrintedDefinition:
    """The Lustre definition ``text`` written back as Lustre from fretc's reading of it
    (:func:`parse_definition`, the same subset and meaning): each operation parenthesized,
    each variable ``rename(name)`` (the caller's Lustre names: keywords and clashes renamed),
    ``FTP`` as ``(true -> false)``, numbers by :func:`lustre_number`, function calls by
    their name. The text holds only the subset's tokens, so no ``;``, comment, string or
    keyword of the input reaches the output.

    Raises:
        LustreError: as :func:`parse_definition` (outside the subset, a comment, trailing
            text); LustreTooDeep when nested past what it reads."""
    parse_definition(text, is_boolean)  # (what fretc reads, its limits included)
    build = _Lustre(rename)
    p = _Parser(_tokens(text), is_boolean, build)
    try:
        out, boolean = p.ite()
    except RecursionError:
        raise LustreTooDeep("nested too deeply") from None
    return PrintedDefinition(out, boolean, tuple(build.names), tuple(build.calls))


class _Parser:
    """Recursive descent over the tokens, one method per precedence level (lowest first);
    each returns ``(what the builder made, is_boolean)``, the public :meth:`expr` the
    expression. The builder (:class:`_Fretish`, the default, or :class:`_Lustre`) makes
    each construct."""

    def __init__(self, tokens: list[tuple[str, int]], is_boolean: Callable[[str], bool],
                 build: Any = None):
        self.tokens, self.k, self.is_boolean = tokens, 0, is_boolean
        self.build = _Fretish() if build is None else build

    def peek(self) -> str | None:
        return self.tokens[self.k][0] if self.k < len(self.tokens) else None

    def offset(self) -> int:
        return self.tokens[self.k][1] if self.k < len(self.tokens) else -1

    def take(self, want: str | None = None) -> str:
        tok = self.peek()
        if tok is None or (want is not None and tok != want):
            raise LustreError(f"expected {want or 'an expression'} at character "
                              f"{self.offset()}, found {tok!r}" if tok else
                              f"expected {want or 'an expression'} at the end")
        self.k += 1
        return tok

    def expr(self) -> Any:
        return self.ite()[0]

    def ite(self) -> tuple[Any, bool]:
        """The lowest level; ``if`` itself is read where an operand starts (:meth:`atom`),
        its ``else`` branch extending as far right as it can."""
        return self.arrow()

    def if_then_else(self) -> tuple[Any, bool]:
        self.take("if")
        c, _ = self.ite()
        self.take("then")
        a, ab = self.ite()
        self.take("else")
        b, bb = self.ite()
        return self.build.ite(c, a, b), ab and bb

    def arrow(self) -> tuple[Any, bool]:
        a, ab = self.implies()
        if self.peek() != "->":
            return a, ab
        self.take("->")
        b, bb = self.arrow()  # (right associative)
        return self.build.arrow(a, b), ab and bb

    def implies(self) -> tuple[Any, bool]:
        a, ab = self.disjunction()
        if self.peek() != "=>":
            return a, ab
        self.take("=>")
        b, _ = self.implies()
        return self.build.binary("=>", a, b, True), True

    def disjunction(self) -> tuple[Any, bool]:
        a, ab = self.conjunction()
        while self.peek() in ("or", "xor"):
            op = self.take()
            b, _ = self.conjunction()
            a, ab = self.build.binary(op, a, b, True), True
        return a, ab

    def conjunction(self) -> tuple[Any, bool]:
        a, ab = self.comparison()
        while self.peek() == "and":
            self.take()
            b, _ = self.comparison()
            a, ab = self.build.binary("and", a, b, True), True
        return a, ab

    def comparison(self) -> tuple[Any, bool]:
        a, ab = self.negation()
        if self.peek() in _COMPARISONS:
            op = self.take()
            b, bb = self.negation()
            return self.build.binary(op, a, b, ab and bb), True
        return a, ab

    def negation(self) -> tuple[Any, bool]:
        if self.peek() == "not":
            self.take()
            a, _ = self.negation()
            return self.build.not_(a), True
        return self.additive()

    def additive(self) -> tuple[Any, bool]:
        a, ab = self.multiplicative()
        while self.peek() in ("+", "-"):
            op = self.take()
            b, _ = self.multiplicative()
            a, ab = self.build.binary(op, a, b, False), False
        return a, ab

    def multiplicative(self) -> tuple[Any, bool]:
        a, ab = self.unary()
        while self.peek() in ("*", "/", "mod"):
            op = self.take()
            b, _ = self.unary()
            a, ab = self.build.binary(op, a, b, False), False
        return a, ab

    def unary(self) -> tuple[Any, bool]:
        tok = self.peek()
        if tok == "-":
            self.take()
            a, _ = self.unary()
            return self.build.neg(a), False
        if tok == "pre":
            self.take()
            a, ab = self.unary()
            return self.build.pre(a, ab), ab
        return self.atom()

    def atom(self) -> tuple[Any, bool]:
        if self.peek() == "if":
            return self.if_then_else()
        at, tok = self.offset(), self.take()
        if tok == "(":
            e = self.ite()
            self.take(")")
            return e
        if tok in ("true", "false"):
            return self.build.literal(tok), True
        if tok[0].isdigit() or tok[0] == ".":
            return self.build.literal(tok), False
        if tok in _REFUSED:
            raise LustreError(f"'{tok}' (character {at}) is outside FRET's Lustre subset")
        if tok in _KEYWORDS or not (tok[0].isalpha() or tok[0] == "_"):
            raise LustreError(f"unexpected {tok!r} at character {at}")
        if self.peek() == "(":  # (a function the glossary declares)
            self.take("(")
            args = [self.expr()]
            while self.peek() == ",":
                self.take(",")
                args.append(self.expr())
            self.take(")")
            return self.build.call(tok, args), False
        return self.build.var(tok), self.is_boolean(tok)
