"""The formula IR: one tree type for future-time LTL (ft, ft_inf), past-time LTL (pt) and the
arithmetic terms inside comparisons. Every printer, evaluator and code generator reads it;
nothing re-parses printed text (../shared/DESIGN.md, "One IR, many back ends").

Design notes: ARCHITECTURE.md, `compiler/ir.py`."""

from __future__ import annotations

from collections.abc import Container, Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fretc.fretish.ast import Probability


class Node:
    """One IR node; see the module docstring for ``op``. ``lo``/``hi`` are tick bounds of
    ``F G O H`` (``None`` = unbounded)."""

    __slots__ = ("op", "args", "name", "lo", "hi", "_hash", "text", "ztext", "stext")

    def __init__(self, op: str, args: tuple[Node, ...] = (), name: str | None = None,
                 lo: int | None = None, hi: int | None = None):
        # plain attribute stores, same shape as common.errors' __init__s (kept: a __slots__
        # class's fields)
        self.op = op
        self.args = args
        self.name = name
        self.lo = lo
        self.hi = hi
        self._hash: int | None = None  # computed on first use (most nodes are never hashed)
        # memo slots of compiler.printers (the FRET/SMV text with FTP printed as FTP, and as
        # (Z FALSE); the Spot text): a node's text is built once per node, however often a
        # formula shares it
        self.text: str | None = None
        self.ztext: str | None = None
        self.stext: str | None = None  # and the Spot text (compiler.printers.to_spot)

    def __hash__(self) -> int:
        h = self._hash
        if h is None:
            h = self._hash = hash((self.op, self.args, self.name, self.lo, self.hi))
        return h

    def __eq__(self, other) -> bool:
        if self is other:
            return True
        return (isinstance(other, Node) and self.op == other.op and self.name == other.name
                and self.lo == other.lo and self.hi == other.hi
                and (self._hash is None or other._hash is None or self._hash == other._hash)
                and self.args == other.args)

    def __repr__(self) -> str:
        """A short structural form for debugging (``Node<& 2 args>``, ``Node<ap p>``);
        :func:`fretc.compiler.printers.to_smv` prints a formula."""
        head = " ".join(str(x) for x in (self.op, self.name) if x is not None)
        bounds = f"[{self.lo},{self.hi}]" if self.hi is not None else ""
        args = f" {len(self.args)} args" if self.args else ""
        return f"Node<{head}{bounds}{args}>"

    @property
    def bounded(self) -> bool:
        """True for ``F G O H`` with a ``[lo, hi]`` window."""
        return self.hi is not None



def name_of(n: Node) -> str:
    """``n.name`` of a node whose op names something (``ap``, ``var``, ``num``, ``cmp``,
    ``arith``, ``fn``, ``call``, ``P``). Raises ``ValueError`` for a node without a name."""
    name = n.name
    if name is None:
        raise ValueError(f"IR node {n.op!r} has no name")
    return name


def window(n: Node) -> tuple[int, int]:
    """``(lo, hi)`` of a bounded ``F G O H`` node (:attr:`Node.bounded`). Raises
    ``ValueError`` for an unbounded one."""
    lo, hi = n.lo, n.hi
    if lo is None or hi is None:
        raise ValueError(f"IR node {n.op!r} has no [lo, hi] window")
    return lo, hi

#: while not None, the list :func:`and_`, :func:`or_` and :func:`S` append each pair of
#: formulas they compared and found different (``a & a = a``, ``a | a = a``, FRET's since
#: identity): :mod:`fretc.compiler.instantiate` records a template's comparisons with
#: :class:`recording_comparisons` to redo them on a requirement's atoms
_compared: list | None = None


class recording_comparisons:
    """Context manager: the list of ``(x, y)`` pairs of formulas the simplifying
    constructors compared and found different inside (see ``_compared``); not reentrant,
    single thread (the compiler's)."""

    def __enter__(self) -> list:
        global _compared
        if _compared is not None:
            raise RuntimeError("recording_comparisons is not reentrant")
        _compared = []
        return _compared

    def __exit__(self, *exc) -> None:
        global _compared
        _compared = None


TRUE = Node("true")
FALSE = Node("false")
LAST = Node("LAST")
FTP = Node("FTP")


def const(value: bool) -> Node:
    """TRUE or FALSE."""
    return TRUE if value else FALSE


def ap(name: str) -> Node:
    """A boolean variable."""
    return Node("ap", name=name)


# --------------------------------------------------------------------------- boolean
def not_(a: Node) -> Node:
    """Negation; folds constants and double negation."""
    if a is TRUE or a.op == "true":
        return FALSE
    if a.op == "false":
        return TRUE
    if a.op == "!":
        return a.args[0]
    return Node("!", (a,))


# the dual of or_ below, same shape (kept: constants and operator swapped)
def and_(a: Node, b: Node) -> Node:
    """Conjunction; folds constants and ``a & a``."""
    if a.op == "false" or b.op == "false":
        return FALSE
    if a.op == "true":
        return b
    if b.op == "true":
        return a
    if a == b:
        return a
    if _compared is not None:
        _compared.append((a, b))
    return Node("&", (a, b))


# the dual of and_ above, same shape (kept: constants and operator swapped)
def or_(a: Node, b: Node) -> Node:
    """Disjunction; folds constants and ``a | a``."""
    if a.op == "true" or b.op == "true":
        return TRUE
    if a.op == "false":
        return b
    if b.op == "false":
        return a
    if a == b:
        return a
    if _compared is not None:
        _compared.append((a, b))
    return Node("|", (a, b))


def and_all(*xs: Node) -> Node:
    """Conjunction of any number of formulas (TRUE for none)."""
    out = TRUE
    for x in xs:
        out = and_(out, x)
    return out


def or_all(*xs: Node) -> Node:
    """Disjunction of any number of formulas (FALSE for none)."""
    out = FALSE
    for x in xs:
        out = or_(out, x)
    return out


def implies(a: Node, b: Node) -> Node:
    """Implication; folds constants."""
    if a.op == "false" or b.op == "true":
        return TRUE
    if a.op == "true":
        return b
    if b.op == "false":
        return not_(a)
    return Node("->", (a, b))


def xor(a: Node, b: Node) -> Node:
    """Exclusive or."""
    return Node("xor", (a, b))


def iff(a: Node, b: Node) -> Node:
    """Equivalence."""
    return Node("<->", (a, b))


# --------------------------------------------------------------------------- future time
def X(a: Node) -> Node:
    """Next. ``X TRUE = TRUE`` and ``X FALSE = FALSE`` hold on infinite words and on FRET's
    finite-trace model (a finite trace continues in an absorbing state)."""
    if a.op in ("true", "false"):
        return a
    return Node("X", (a,))


def F(a: Node, lo: int | None = None, hi: int | None = None) -> Node:
    """Eventually; bounded ``F[lo,hi]`` when ``hi`` is given (an empty window is FALSE)."""
    if hi is not None:
        lo = lo or 0
        if hi < lo or a.op == "false":
            return FALSE
        if a.op == "true":
            return TRUE
        if hi == 0:
            return a
        return Node("F", (a,), lo=lo, hi=hi)
    if a.op in ("true", "false"):
        return a
    return Node("F", (a,))


def G(a: Node, lo: int | None = None, hi: int | None = None) -> Node:
    """Globally; bounded ``G[lo,hi]`` when ``hi`` is given (an empty window is TRUE)."""
    if hi is not None:
        lo = lo or 0
        if hi < lo or a.op == "true":
            return TRUE
        if hi == 0 and lo == 0:
            return a
        return Node("G", (a,), lo=lo, hi=hi)
    if a.op in ("true", "false"):
        return a
    return Node("G", (a,))


def U(a: Node, b: Node) -> Node:
    """Until; ``TRUE U b`` is ``F b``."""
    if b.op in ("true", "false"):
        return b
    if a.op == "false":
        return b
    if a.op == "true":
        return F(b)
    return Node("U", (a, b))


def V(a: Node, b: Node) -> Node:
    """Release: ``b`` holds up to and including the first point where ``a`` holds, or
    forever."""
    if b.op in ("true", "false"):
        return b
    if a.op == "true":
        return b
    if a.op == "false":
        return G(b)
    return Node("V", (a, b))


# --------------------------------------------------------------------------- past time
def Y(a: Node) -> Node:
    """Previous (strong): false at position 0."""
    return Node("Y", (a,))


def Z(a: Node) -> Node:
    """Weak previous: true at position 0 (``Z FALSE`` marks the first position)."""
    return Node("Z", (a,))


def O(a: Node, lo: int | None = None, hi: int | None = None) -> Node:
    """Once; bounded ``O[lo,hi]`` (``O[=n]`` is ``O[n,n]``) when ``hi`` is given."""
    if hi is not None:
        lo = lo or 0
        if hi < lo or a.op == "false":
            return FALSE
        if hi == 0:
            return a
        return Node("O", (a,), lo=lo, hi=hi)
    if a.op == "false":
        return a
    if a.op == "FTP" or a.op == "true":
        return TRUE
    return Node("O", (a,))


def H(a: Node, lo: int | None = None, hi: int | None = None) -> Node:
    """Historically; bounded ``H[lo,hi]`` when ``hi`` is given (empty window: TRUE).
    ``H[l,h] p`` at i: p at every j in [i-h, i-l] with j >= 0 (FRET/SALT convention)."""
    if hi is not None:
        lo = lo or 0
        if hi < lo or a.op == "true":
            return TRUE
        if hi == 0:
            return a
        return Node("H", (a,), lo=lo, hi=hi)
    if a.op == "true":
        return a
    return Node("H", (a,))


def S(a: Node, b: Node) -> Node:
    """Since. Simplifies FRET's identities ``a S (a & FTP) = H a`` and ``a S FTP`` forms."""
    if b.op == "false":
        return FALSE
    if b.op == "&" and b.args[1].op == "FTP":
        if b.args[0] == a:
            return H(a)
        if _compared is not None:
            _compared.append((b.args[0], a))
    if b.op == "&" and b.args[0].op == "FTP":
        if b.args[1] == a:
            return H(a)
        if _compared is not None:
            _compared.append((b.args[1], a))
    if a.op == "true":
        return O(b)
    return Node("S", (a, b))


def T(a: Node, b: Node) -> Node:
    """Trigger, the dual of since: ``a T b = !(!a S !b)``."""
    return Node("T", (a, b))


# --------------------------------------------------------------------------- terms
def stream(name: str, p: Node, q: Node) -> Node:
    """The boolean stream ``name`` by its state bit (module docstring's ``stream``): at each
    position ``p`` when the stream was true at the previous one, else ``q`` (``q`` at the
    first). A constant ``p`` and ``q`` that agree are that constant."""
    if p == q and p.op in ("true", "false"):
        return p
    return Node("stream", (p, q), name=name)


def var(name: str) -> Node:
    """A numeric variable (a term)."""
    return Node("var", name=name)


def num(text: str) -> Node:
    """A numeric literal, kept as written."""
    return Node("num", name=text)


def cmp(op: str, a: Node, b: Node) -> Node:
    """A comparison ``a op b`` of two terms (``op`` in ``= != < <= > >=``), kept as written
    (FRET prints ``(3 < 3)``; :func:`fold_constants` folds it for the analyses)."""
    return Node("cmp", (a, b), name=op)


def fold_constants(node: Node) -> Node:
    """``node`` with each comparison of two constant terms (numbers, ``-`` and ``+ - * /``
    of numbers) replaced by its truth value when exact arithmetic and double arithmetic
    (the monitors') agree on it, and the formula simplified by the constructors: ``3.0 >=
    0`` is TRUE; ``0.1 + 0.2 = 0.3``, true over the reals and false in doubles, is kept.
    For ``fretc check`` and ``fretc shield``, which would read such a comparison as a free
    proposition; the emitted formulas keep it as FRET prints it."""
    memo: dict[int, Node] = {}

    def go(n: Node) -> Node:
        got = memo.get(id(n))
        if got is not None:
            return got
        if n.op == "cmp":
            x, y = _constant(n.args[0]), _constant(n.args[1])
            out = n
            if x is not None and y is not None:
                exact = _CMP[n.name](x[0], y[0])  # type: ignore[index]
                if exact == _CMP[n.name](x[1], y[1]):  # type: ignore[index]
                    out = TRUE if exact else FALSE
        elif n.args and n.op not in ("arith", "neg", "fn", "ite"):
            args = tuple(go(a) for a in n.args)
            out = n if all(a is b for a, b in zip(args, n.args)) else rebuild(n, args)
        else:
            out = n
        memo[id(n)] = out
        return out
    return go(node)


_CMP = {"=": lambda x, y: x == y, "!=": lambda x, y: x != y, "<": lambda x, y: x < y,
        "<=": lambda x, y: x <= y, ">": lambda x, y: x > y, ">=": lambda x, y: x >= y}


def _constant(n: Node) -> tuple | None:
    """``(exact Fraction, double)`` of a constant term, None for another (a variable, a
    function, ``mod``/``^``, a division by 0, a literal that is no finite number)."""
    import math
    from fractions import Fraction

    if n.op == "num":
        try:
            q = Fraction(n.name)  # type: ignore[arg-type]
        except (ValueError, ZeroDivisionError, OverflowError):
            return None
        d = float(n.name)  # type: ignore[arg-type]
        return (q, d) if math.isfinite(d) else None
    if n.op == "neg":
        x = _constant(n.args[0])
        return None if x is None else (-x[0], -x[1])
    if n.op == "arith" and n.name in ("+", "-", "*", "/"):
        x, y = _constant(n.args[0]), _constant(n.args[1])
        if x is None or y is None or (n.name == "/" and y[0] == 0):
            return None
        ops = {"+": lambda p, q: p + q, "-": lambda p, q: p - q, "*": lambda p, q: p * q,
               "/": lambda p, q: p / q}[n.name]
        d = ops(x[1], y[1]) if not (n.name == "/" and y[1] == 0) else math.nan
        return (ops(x[0], y[0]), d) if math.isfinite(d) else None
    return None


def arith(op: str, a: Node, b: Node) -> Node:
    """Arithmetic ``a op b`` on two terms (``op`` in ``+ - * / mod ^``)."""
    return Node("arith", (a, b), name=op)


# --------------------------------------------------------------------------- queries
def walk(node: Node) -> Iterator[Node]:
    """Pre-order traversal (each distinct sub-node may be visited more than once)."""
    stack = [node]
    while stack:
        n = stack.pop()
        yield n
        stack.extend(reversed(n.args))


def variables(node: Node) -> list:
    """Names of boolean and numeric variables, in order of first appearance."""
    seen: dict[str | None, None] = {}
    for n in walk(node):
        if n.op in ("ap", "var") and n.name not in seen:
            seen[n.name] = None
    return list(seen)


def has_op(node: Node, ops: Container[str]) -> bool:
    """Does any sub-node of ``node`` have an ``op`` in ``ops``?"""
    return any(n.op in ops for n in walk(node))


_REBUILD = {
    "!": lambda n, a: not_(a[0]), "&": lambda n, a: and_(*a), "|": lambda n, a: or_(*a),
    "->": lambda n, a: implies(*a), "X": lambda n, a: X(a[0]),
    "F": lambda n, a: F(a[0], n.lo, n.hi), "G": lambda n, a: G(a[0], n.lo, n.hi),
    "U": lambda n, a: U(*a), "V": lambda n, a: V(*a), "Y": lambda n, a: Y(a[0]),
    "Z": lambda n, a: Z(a[0]), "O": lambda n, a: O(a[0], n.lo, n.hi),
    "H": lambda n, a: H(a[0], n.lo, n.hi), "S": lambda n, a: S(*a),
}


def rebuild(n: Node, args: tuple[Node, ...]) -> Node:
    """``n`` with new children, simplified where a constructor applies."""
    f = _REBUILD.get(n.op)
    if f is not None:
        return f(n, args)
    return Node(n.op, args, n.name, n.lo, n.hi)


#: the probability bounds FRETish accepts (FRET 3.1 accepts ``!=`` too)
BOUND_OPS = (">=", ">", "<=", "<", "=", "!=")


class ProbabilityBound:
    """FRETish's probability field (``with probability OP p``) as the IR carries it beside the
    path formulas. FRET reads it per trigger (FRET 3.1's probabilistic templates,
    :mod:`fretc.compiler.pctl`): at each trigger of the requirement, the probability that
    the timing's obligation is met satisfies ``OP p``; never a statement about one run.

    ``op`` is one of :data:`BOUND_OPS`; ``p`` the bound as a float in [0, 1]; ``text`` the
    number as written (printed back unchanged). Immutable and hashable. :meth:`pctl`
    prints ``P<op><p> [ path ]`` around a path formula's text (PRISM's syntax; ``=`` and
    ``!=`` as FRET prints them, which PRISM has not). The parser
    (:mod:`fretc.fretish.parser`) has already refused a bound outside [0, 1]; ``ValueError``
    for another operator or value.
    """

    __slots__ = ("op", "p", "text")
    op: str
    p: float
    text: str

    def __init__(self, op: str, text: str):
        if op not in BOUND_OPS:
            raise ValueError(f"not a probability operator: {op!r}")
        p = float(text)
        if not 0.0 <= p <= 1.0:
            raise ValueError(f"probability {text} is outside [0, 1]")
        object.__setattr__(self, "op", op)
        object.__setattr__(self, "p", p)
        object.__setattr__(self, "text", text)

    def __setattr__(self, name, value):
        raise AttributeError("ProbabilityBound is immutable")

    def __eq__(self, other) -> bool:
        return (isinstance(other, ProbabilityBound) and self.op == other.op
                and self.p == other.p)

    def __hash__(self) -> int:
        return hash((self.op, self.p))

    def __repr__(self) -> str:
        return f"ProbabilityBound({self.op!r}, {self.text!r})"

    def __reduce__(self):
        return (ProbabilityBound, (self.op, self.text))

    def pctl(self, path: str) -> str:
        """``P<op><p> [ path ]``: the bound around the path formula's printed text."""
        return f"P{self.op}{self.text} [ {path} ]"

    @property
    def lower(self) -> bool:
        """A lower bound on the probability (``>=``, ``>``)."""
        return self.op in (">=", ">")

    def to_json(self) -> dict:
        """``{"op": ">=", "p": 0.95}`` (the audit JSON's ``bound``)."""
        return {"op": self.op, "p": self.p}

    def holds_at(self, rate: float) -> bool:
        """True when a probability ``rate`` satisfies the bound (``rate OP p``)."""
        return {">=": rate >= self.p, ">": rate > self.p, "<=": rate <= self.p,
                "<": rate < self.p, "=": rate == self.p, "!=": rate != self.p}[self.op]


def probability_bound(prob: Probability | None) -> ProbabilityBound | None:
    """The :class:`ProbabilityBound` of a parsed ``fretish.ast.Probability`` (None for
    None)."""
    return None if prob is None else ProbabilityBound(prob.op, prob.value)
