"""FRET's boolean streams monotone in their own previous value, read as past-time formulas.

A FRET Internal variable (or Mode) whose definition ``D`` reads itself only as
``preBool(b, s)``, each occurrence syntactically positive, is monotone in its previous value:
``s_t = Q_t | (P_t & s_(t-1))``, the recursion of the past-time *since* (Havelund & Rosu,
TACAS 2002), so ``s = P S psi``: :func:`since_expansion` builds it as the AST call
:data:`SINCE`. A boolean stream that is not monotone but reads only booleans and comparisons
is one bit of state: :func:`stream_expansion` builds it as ``STREAM_PREFIX + name`` with
arguments ``(P, Q)`` (:func:`stream_name` reads the name back). The derivation (Lustre's
semantics, Shannon's expansion, the first instant) and what stays a stream with state:
ARCHITECTURE.md ("FRET's streams as past-time formulas").
"""

from __future__ import annotations

from typing import Any

from fretc.fretish import ast as A

__all__ = ["SINCE", "since_expansion", "reads_itself_monotonically", "STREAM_PREFIX",
           "stream_name", "reads_itself_as_bit", "stream_expansion"]

#: the AST call name of the past-time since ``SINCE(a, c)`` = ``a S c`` (module docstring):
#: no FRETish or Lustre text can produce it (``$`` starts no name of either)
SINCE = "$since"

#: the AST call name of a boolean stream of booleans read by its state bit, followed by the
#: stream's name (module docstring); ``$`` starts no FRETish or Lustre name
STREAM_PREFIX = "$stream "

#: the operators through which an occurrence keeps its polarity
_KEEP = frozenset({"&", "|"})


def reads_itself_monotonically(e: A.Expr, name: str) -> bool:
    """Whether the definition ``e`` of the boolean stream ``name`` reads ``name`` at least
    once, each time as ``preBool(b, name)`` with ``b`` a literal, at a syntactically
    positive place (module docstring: Lustre's semantics makes ``e`` then a monotone
    function of ``name``'s previous value). Iterative (definitions nest up to
    :data:`fretc.fretish.limits.MAX_EXPR_DEPTH` levels)."""
    found = False
    stack: list[tuple[A.Expr, bool]] = [(e, True)]
    while stack:
        x, positive = stack.pop()
        if _occurrence(x, name):
            if not positive:
                return False
            found = True
        elif isinstance(x, A.Unary) and x.op == "!":
            stack.append((x.operand, not positive))
        elif isinstance(x, A.Binary) and x.op in _KEEP:
            stack += [(x.left, positive), (x.right, positive)]
        elif isinstance(x, A.Binary) and x.op == "->":
            if _mentions(x.left, name):
                return False
            stack.append((x.right, positive))
        elif isinstance(x, A.Call) and x.name == "ite" and len(x.args) == 3:
            if _mentions(x.args[0], name):
                return False
            stack += [(x.args[1], positive), (x.args[2], positive)]
        elif _mentions(x, name):  # (anywhere else: xor, <->, a comparison, a call ...)
            return False
    return found


def since_expansion(e: A.Expr, name: str) -> A.Expr:
    """``SINCE(P, psi)`` (:data:`SINCE`), the past-time formula the definition ``e`` of the
    boolean stream ``name`` is when :func:`reads_itself_monotonically` holds (module
    docstring: ``P`` = ``e`` with each ``preBool(b, name)`` true, ``Q`` with each false,
    ``psi`` = ``Q`` when every ``b`` is false, else ``Q | (FTP & D0)``, ``D0`` with each
    occurrence its own ``b``). ``e`` may read other definitions, already expanded."""
    def put(value: bool | None) -> A.Expr:
        return _replaced(e, name, value)

    q = put(False)
    firsts = {_first(x, name) for x in A.walk(e)} - {None}
    psi = q if firsts == {False} else A.Binary("|", q, A.Binary("&", A.Var("FTP"), put(None)))
    return A.Call(SINCE, (put(True), psi))


def stream_name(e: A.Expr) -> str | None:
    """The stream's name when ``e`` is a call made by :func:`stream_expansion` (two
    arguments, ``P`` and ``Q``), else None."""
    if isinstance(e, A.Call) and e.name.startswith(STREAM_PREFIX) and len(e.args) == 2:
        return e.name[len(STREAM_PREFIX):]
    return None


#: the boolean operators a stream of booleans is written with (Lustre's and FRETish's)
_BOOLEAN_OPS = frozenset({"!", "&", "|", "->", "xor", "<->"})


def reads_itself_as_bit(e: A.Expr, name: str, is_boolean: Any) -> bool:
    """Whether the definition ``e`` of the boolean stream ``name`` reads ``name`` at least
    once, each time as ``preBool(b, name)`` (``b`` a literal), and reads only booleans:
    boolean variables (``is_boolean(v)``, ``name`` included), literals, the boolean
    operators, ``ite``, ``preBool`` with a literal first value, and comparisons of the
    tick's values (no ``pre`` in them: each an atom, as every comparison is to the game;
    module docstring: one state bit then computes it over the atoms). Iterative."""
    found = False
    stack = [e]
    while stack:
        x = stack.pop()
        if _occurrence(x, name):
            found = True
        elif isinstance(x, A.Var):
            if x.name == name or not (x.name == "FTP" or is_boolean(x.name)):
                return False
        elif isinstance(x, A.Unary) and x.op in _BOOLEAN_OPS:
            stack.append(x.operand)
        elif isinstance(x, A.Binary) and x.op in _BOOLEAN_OPS:
            stack += [x.left, x.right]
        elif isinstance(x, A.Call) and x.name == "ite" and len(x.args) == 3:
            stack += list(x.args)
        elif (isinstance(x, A.Call) and x.name == "preBool" and len(x.args) == 2
              and isinstance(x.args[0], A.BoolLit)):
            if _mentions(x.args[1], name):  # (s two ticks ago, or a formula of it: no bit)
                return False
            stack.append(x.args[1])
        elif isinstance(x, A.Binary) and x.op in A.COMPARISON_OPS:
            if not _present_comparison(x, name):
                return False
        elif not isinstance(x, A.BoolLit):
            return False
    return found


def _present_comparison(x: A.Binary, name: str) -> bool:
    """Whether the comparison ``x`` reads this tick's values only (no ``pre``, not the
    stream ``name``): an atom of the tick, as the game and the monitors read every
    comparison, so a stream reading it is still one state bit over the atoms."""
    return not any((isinstance(y, A.Call) and y.name in ("preBool", "preInt", "preReal"))
                   or (isinstance(y, A.Var) and y.name == name) for y in A.walk(x))


def stream_expansion(e: A.Expr, name: str) -> A.Expr:
    """The call ``STREAM_PREFIX + name`` of ``(P, Q)`` (module docstring): ``P`` is ``e``
    with each ``preBool(b, name)`` read as ``true`` after the first instant and ``b`` at it
    (``!FTP | b``, folded), ``Q`` with it ``false`` after and ``b`` at it (``FTP & b``), for a
    definition :func:`reads_itself_as_bit` accepts (its other definitions expanded)."""
    def at(after: bool) -> Any:
        def occurrence(b: bool) -> A.Expr:
            if b == after:
                return A.BoolLit(b)
            return A.Unary("!", A.Var("FTP")) if after else A.Var("FTP")
        return occurrence

    return A.Call(STREAM_PREFIX + name, (_replaced_by(e, name, at(True)),
                                         _replaced_by(e, name, at(False))))


def _replaced_by(e: A.Expr, name: str, by: Any) -> A.Expr:
    """``e`` with each ``preBool(b, name)`` replaced by ``by(b)``, literals folded
    (:func:`_folded`)."""
    first = _first(e, name)
    if first is not None:
        return by(first)
    if not _mentions(e, name):
        return e
    if isinstance(e, A.Unary):
        return _folded(A.Unary(e.op, _replaced_by(e.operand, name, by)))
    if isinstance(e, A.Binary):
        return _folded(A.Binary(e.op, _replaced_by(e.left, name, by),
                                _replaced_by(e.right, name, by)))
    if isinstance(e, A.Call):
        return _folded(A.Call(e.name, tuple(_replaced_by(a, name, by) for a in e.args)))
    return e


def _first(x: A.Expr, name: str) -> bool | None:
    """``b`` when ``x`` is ``preBool(b, name)`` with ``b`` a literal, else None."""
    if (isinstance(x, A.Call) and x.name == "preBool" and len(x.args) == 2
            and isinstance(x.args[0], A.BoolLit) and isinstance(x.args[1], A.Var)
            and x.args[1].name == name):
        return x.args[0].value
    return None


def _occurrence(x: A.Expr, name: str) -> bool:
    """Whether ``x`` is ``preBool(b, name)`` with ``b`` a literal."""
    return _first(x, name) is not None


def _mentions(e: A.Expr, name: str) -> bool:
    return any(isinstance(x, A.Var) and x.name == name for x in A.walk(e))


def _replaced(e: A.Expr, name: str, value: bool | None) -> A.Expr:
    """``e`` with each ``preBool(b, name)`` replaced by the literal ``value`` (None: by its
    own ``b``), literals folded (:func:`_replaced_by`)."""
    return _replaced_by(e, name, lambda b: A.BoolLit(b if value is None else value))


def _folded(e: A.Expr) -> A.Expr:
    """``e`` (a node whose operands were just replaced) with a literal operand of ``!``,
    ``&``, ``|``, ``->`` or an ``ite`` branch folded away (Boolean algebra's identities:
    ``x & true`` is ``x``, ``x | true`` is ``true``, ...), so the formula reads as the
    definition did: ``(enter | !exit) S enter``, not ``(enter | (true & !exit)) S ...``."""
    lit = _literal
    if isinstance(e, A.Unary) and e.op == "!" and lit(e.operand) is not None:
        return A.BoolLit(not lit(e.operand))
    if isinstance(e, A.Binary) and e.op in ("&", "|", "->"):
        a, b = lit(e.left), lit(e.right)
        absorbing = e.op == "|"  # (the value that decides alone: true for |, false for &)
        if e.op == "->":
            if a is False or b is True:
                return A.BoolLit(True)
            return e.right if a is True else (A.Unary("!", e.left) if b is False else e)
        if a is not None:
            return A.BoolLit(absorbing) if a is absorbing else e.right
        if b is not None:
            return A.BoolLit(absorbing) if b is absorbing else e.left
    if isinstance(e, A.Call) and e.name == "ite" and len(e.args) == 3:
        c, x, y = e.args
        if x == y:
            return x
        if lit(c) is not None:
            return x if lit(c) else y
        if lit(x) is not None and lit(y) is not None:
            return x if lit(x) == lit(y) else c if lit(x) else A.Unary("!", c)
        if lit(x) is not None:  # ite(c, true, y) = c | y; ite(c, false, y) = !c & y
            return A.Binary("|", c, y) if lit(x) else A.Binary("&", A.Unary("!", c), y)
        if lit(y) is not None:  # ite(c, x, true) = !c | x; ite(c, x, false) = c & x
            return A.Binary("|", A.Unary("!", c), x) if lit(y) else A.Binary("&", c, x)
    return e


def _literal(e: A.Expr) -> bool | None:
    return e.value if isinstance(e, A.BoolLit) else None
