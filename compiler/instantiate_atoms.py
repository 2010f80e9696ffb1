"""A requirement's atoms converted for :mod:`fretc.compiler.instantiate`, as
:mod:`fretc.compiler.semantics` converts them, with the work kept to the atoms.

An expression without temporal functions or FTP means the same in ft, ft_inf and pt and is
converted once (:class:`PlainExpander`, which also collects its variables); the others are
converted per formula, a temporal function's expansion built once and shared by ft's derived
atom and pt (:class:`SharingExpander`). The leaves of names and literals
(:func:`name_node`) and the ``Left``/``Right`` endpoints of a scope whose mode is a name
(:func:`named_endpoints`) are made once per name. None of these caches holds a
requirement's expression or text.
"""

from __future__ import annotations

from fretc.fretish import ast as A
from fretc.fretish.fret_since import stream_name

from fretc.compiler import ir
from fretc.compiler.expressions import _TIME_NAMES, Expander
from fretc.compiler.ir import FALSE, FTP, LAST, Node
from fretc.compiler.scope_timing import fn_right, pt_endpoints

__all__ = ["PlainExpander", "SharingExpander", "Timed", "TIMED", "has_future_function",
           "is_shared_leaf", "name_node", "named_endpoints", "variables_into"]

class Timed(Exception):
    """Raised by :class:`PlainExpander` at the first temporal function or FTP."""


TIMED = object()  # an expression with temporal functions or FTP (converted per formula)


class PlainExpander(Expander):
    """:class:`~fretc.compiler.expressions.Expander` for ft (``FTP``, ``LAST``) that converts an
    expression *without* temporal functions or FTP - which then means the same in ft,
    ft_inf and pt (:mod:`fretc.compiler.semantics` converts it once) - and collects its
    variables on the way: ``names`` holds the ``ap``/``var`` names in the order the
    conversion creates them, which is the pre-order of the IR it returns (children are
    converted left to right, nothing converted is dropped: ``!!a`` folds to ``a``, which
    keeps ``a``'s names), i.e. :func:`fretc.compiler.ir.variables` of the result. At a temporal
    function or FTP it raises :class:`Timed` (the caller converts per formula), so one
    walk replaces :func:`~fretc.compiler.expressions.mentions_time`'s scan and the conversion."""

    def __init__(self):
        super().__init__("ft", FTP, LAST)
        self.names: dict = {}

    # The common shapes (names, comparisons, and/or/implies/xor/iff, negation, literals,
    # arithmetic) are dispatched on the AST node's exact type (saved as t: mypy does not
    # narrow e through t, hence the type: ignore comments) and build the nodes
    # Expander builds for them, in the same order (children left to right); any other
    # shape, or an error, is Expander's own code.
    def bool(self, e: A.Expr) -> Node:
        """``e`` as a boolean IR formula, as :meth:`fretc.compiler.expressions.Expander.bool` builds it
        for an expression without temporal functions."""
        t = type(e)
        if t is _Var:
            return self._name(e.name, "ap")  # type: ignore[union-attr]  # e's type is t
        if t is _Binary:
            op = e.op  # type: ignore[union-attr]  # e's type is t
            if op in _COMPARISON_OPS:  # Expander: ir.cmp, no derived atom (no preReal here)
                return Node("cmp", (self.term(e.left), self.term(e.right)), name=op)  # type: ignore[union-attr]  # e's type is t
            if op in _BOOL_OPS:  # Expander: Node(op) for & | ->, ir.xor, ir.iff
                return Node(op, (self.bool(e.left), self.bool(e.right)))  # type: ignore[union-attr]  # e's type is t
        elif t is _Unary and e.op == "!":  # type: ignore[union-attr]  # e's type is t
            return ir.not_(self.bool(e.operand))  # type: ignore[union-attr]  # e's type is t
        return Expander.bool(self, e)

    def _name(self, name: str, op: str) -> Node:
        """The leaf ``op`` (``ap`` or ``var``) of variable ``name``, recorded in
        :attr:`names`; FTP raises :class:`Timed`."""
        if name == "FTP":
            raise Timed
        self.names[name] = None
        return name_node(op, name)

    def _atom(self, node: Node) -> Node:
        return node  # no preInt/preReal here (they raise Timed): never a derived atom

    def _bool_call(self, e: A.Call) -> Node:
        if e.name in _TIME_NAMES or stream_name(e) is not None:  # (a stream: fret_since)
            raise Timed
        return Expander._bool_call(self, e)

    def term(self, e: A.Expr) -> Node:
        """``e`` as a numeric IR term, as :meth:`fretc.compiler.expressions.Expander.term` builds it."""
        t = type(e)
        if t is _Var:
            return self._name(e.name, "var")  # type: ignore[union-attr]  # e's type is t
        if t is _NumLit:
            return name_node("num", e.text)  # type: ignore[union-attr]  # ir.num
        if t is _Binary and e.op in _ARITH_OPS:  # type: ignore[union-attr]  # ir.arith
            return Node("arith", (self.term(e.left), self.term(e.right)), name=e.op)  # type: ignore[union-attr]  # e's type is t
        if isinstance(e, A.Call) and e.name in _TIME_NAMES:
            raise Timed  # preInt, preReal
        return Expander.term(self, e)


_Var, _Binary, _Unary, _NumLit = A.Var, A.Binary, A.Unary, A.NumLit
_COMPARISON_OPS = frozenset(A.COMPARISON_OPS)
_BOOL_OPS = frozenset(A.BOOL_OPS)
_ARITH_OPS = frozenset(A.ARITH_OPS)

#: the leaf nodes of names and literals made so far: ``(op, name) -> Node`` for ``ap``,
#: ``var`` and ``num``; a node is immutable and its printed texts (memo slots of
#: compiler.printers) depend on its op and name only, so one node serves every
#: requirement that mentions the name. Emptied when it reaches _LEAVES_MAX entries.
_LEAVES: dict = {}
_LEAVES_MAX = 65536


#: (scope, mode name or None) -> (Left, Right, Right of ft_inf) of the temporal functions
#: for a scope whose mode is a plain name (or the null scope): made once per name, emptied
#: with _LEAVES
_ENDPOINTS: dict = {}


def named_endpoints(scope: str, m: Node | None) -> tuple:
    """``(Left, Right, Right_inf)``: :func:`~fretc.compiler.scope_timing.pt_endpoints`'s left of
    ``m``, :func:`~fretc.compiler.scope_timing.fn_right` of ``m`` with ``LAST`` and with FALSE;
    ``m`` is None or a leaf of :data:`_LEAVES` (a name), whose endpoints are functions of
    the scope and the name only: made once per pair (:data:`_ENDPOINTS`)."""
    key = (scope, None if m is None else m.name)
    ends = _ENDPOINTS.get(key)
    if ends is None:
        ends = _ENDPOINTS[key] = (pt_endpoints(scope, m)[0], fn_right(scope, m, LAST),
                                  fn_right(scope, m, FALSE))
    return ends


def is_shared_leaf(node: Node) -> bool:
    """Is ``node`` the shared ``ap`` leaf of its name (:func:`name_node`)?"""
    return node.op == "ap" and _LEAVES.get(("ap", node.name)) is node


def name_node(op: str, name: str) -> Node:
    """The leaf ``Node(op, name=name)`` (``ap``, ``var`` or ``num``), made once per
    ``(op, name)`` (:data:`_LEAVES`)."""
    key = (op, name)
    node = _LEAVES.get(key)
    if node is None:
        if len(_LEAVES) >= _LEAVES_MAX:
            _LEAVES.clear()
            _ENDPOINTS.clear()
        node = _LEAVES[key] = Node(op, name=name)
    return node


class SharingExpander(Expander):
    """:class:`~fretc.compiler.expressions.Expander` whose temporal functions' expansions are
    shared, through ``memo``, by the expanders of one requirement: an expansion is built
    in a pt expander whatever the formula kind, from the call, ``Left``, ``Right`` and
    the endpoint-free flag only (:meth:`Expander._past_function`), so ft's derived
    ``past`` atom holds pt's expansion of the same call, and pt's derived ``future`` atom
    ft's. Keyed by the identities of the call and of the endpoints (alive while the
    requirement is instantiated); the nodes are equal to those built anew, and shared
    nodes are immutable."""

    def __init__(self, kind: str, left_pt: Node, right_ft: Node, memo: dict):
        super().__init__(kind, left_pt, right_ft)
        self.memo = memo

    # the common shapes as in PlainExpander (same nodes, same order; leaves shared)
    def bool(self, e: A.Expr) -> Node:
        """``e`` as a boolean IR formula whose name nodes are shared between the formulas of one
        requirement (:meth:`fretc.compiler.expressions.Expander.bool`'s result otherwise)."""
        t = type(e)
        if t is _Var:
            name = e.name  # type: ignore[union-attr]  # e's type is t
            return FTP if name == "FTP" else name_node("ap", name)
        if t is _Binary:
            op = e.op  # type: ignore[union-attr]  # e's type is t
            if op in _COMPARISON_OPS:
                return self._atom(Node("cmp", (self.term(e.left), self.term(e.right)),  # type: ignore[union-attr]  # e's type is t
                                       name=op))
            if op in _BOOL_OPS:
                return Node(op, (self.bool(e.left), self.bool(e.right)))  # type: ignore[union-attr]  # e's type is t
        elif t is _Unary and e.op == "!":  # type: ignore[union-attr]  # e's type is t
            return ir.not_(self.bool(e.operand))  # type: ignore[union-attr]  # e's type is t
        return Expander.bool(self, e)

    def term(self, e: A.Expr) -> Node:
        """``e`` as a numeric IR term with shared name nodes (see :meth:`bool`)."""
        t = type(e)
        if t is _Var:
            return name_node("var", e.name)  # type: ignore[union-attr]  # ir.var
        if t is _NumLit:
            return name_node("num", e.text)  # type: ignore[union-attr]  # ir.num
        if t is _Binary and e.op in _ARITH_OPS:  # type: ignore[union-attr]  # ir.arith
            return Node("arith", (self.term(e.left), self.term(e.right)), name=e.op)  # type: ignore[union-attr]  # e's type is t
        return Expander.term(self, e)

    def _past_function(self, e: A.Call) -> Node:
        return self._memoized(Expander._past_function, e)

    def _future_function(self, e: A.Call) -> Node:
        return self._memoized(Expander._future_function, e)

    def _memoized(self, expand, e: A.Call) -> Node:
        """``expand(self, e)`` once per call node, endpoints and freedom."""
        key = (expand, id(e), id(self.left_pt), id(self.right_ft), self.free)
        node = self.memo.get(key)
        if node is None:
            node = self.memo[key] = expand(self, e)
        return node


#: FRET's future-time functions (compiler.expressions' ``_FUTURE_FUNCS``, checked by
#: tests/compiler/test_instantiate.py)
_FUTURE_FUNCTIONS = frozenset(("persists", "occurs", "nextOcc"))


def has_future_function(e: A.Expr) -> bool:
    """Does ``e`` call a future-time function (``persists``, ``occurs``, ``nextOcc``)
    anywhere?"""
    for x in A.walk(e):
        if isinstance(x, A.Call) and x.name in _FUTURE_FUNCTIONS:
            return True
    return False


def variables_into(node: Node, seen: dict, done: set) -> None:
    """:func:`fretc.compiler.ir.variables` of ``node`` added to ``seen`` (a dict used as an
    ordered set), in the same order: pre-order, first appearance; a sub-formula met again
    (``done``: node identities) is skipped, its names are in ``seen`` already."""
    op = node.op
    if op == "ap" or op == "var":
        seen[node.name] = None
        return
    for a in node.args:
        if a.args:
            i = id(a)
            if i in done:
                continue
            done.add(i)
            variables_into(a, seen, done)
        elif a.op == "ap" or a.op == "var":
            seen[a.name] = None

