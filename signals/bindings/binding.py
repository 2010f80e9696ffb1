"""One FRET variable bound to an expression: :class:`Binding` and how it is made
(:func:`compile_expression`, :func:`parse_inline` for ``--bind NAME=EXPR``), evaluated (one
tick, or all ticks at once with numpy) and explained (:func:`operand_signals`)."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fretc.common.problems import BindingError, SignalError
from fretc.signals.bindings.compile import EvalError, EvalState, compile_node
from fretc.signals.bindings.expression import (GEOMETRY_CALLS, TF_TOPICS, geometry_tf, BinOp, Const, Expr, ExprLocation, Field, FuncCall, Ref,
                         UnaryOp, check, check_aggregate, check_size, substitute, unparse, walk)
from fretc.signals.bindings.extract import Valid, normalize_scalar
from fretc.signals.bindings.parse_cache import kept_parses
from fretc.signals.bindings.operations import Ops
from fretc.signals.bindings.windowing import WindowSpec, check_window

__all__ = ["VARNAME", "Binding", "compile_expression", "compile_kept", "parse_inline",
           "operand_signals", "fold", "EMPTY_FOLD"]

#: A FRET variable name as a binding key: an identifier, or the text of a quoted FRETish
#: variable (``"wind speed"``: a TOML quoted key ``"wind speed" = "..."``, or
#: ``--bind '"wind speed"=...'``): no quotes, no control characters, not blank at either end.
VARNAME = re.compile(r"(?=\S)[^\"\x00-\x1f\x7f]*(?<=\S)\Z")


@dataclass(eq=False)
class Binding:
    """One FRET variable bound to an expression.

    Attributes:
        name: the FRET variable.
        expr: the expression text.
        source: binding file path, or ``"<--bind NAME>"``.
        line, col: where the expression text starts in ``source`` (1-based; None unknown).
        ast: the expression tree, references to other variables substituted.
        topics: topics the expression reads (fields and ``age``).
        fields: the field references, in order of appearance.
        constants: the values of its named constants (``POWER_SUPPLY_STATUS_CHARGING``),
            filled in by :func:`fretc.signals.bindings.check_types` from a log's schemas.
        uses_tf: whether it reads ``tf()`` (every message of /tf and /tf_static).
        aggregate: how the values of the messages of its one topic since the previous tick
            are folded (``"any"``, ``"all"``, ``"count"``, ``"min"``, ``"max"``: written
            ``any_of_messages(EXPR)`` etc.), or None: the held message's value (sample and
            hold). Then :meth:`evaluate` gives EXPR on the held message, and the clocks fold
            (:func:`fold`).
        window: a window function over the messages of its one topic
            (``mean(/battery.current, 2s)``: :mod:`fretc.signals.bindings.windowing`), or
            None. Then :meth:`evaluate` gives the aggregated expression on the held message,
            and the clocks keep the window (:class:`fretc.signals.windows.SlidingWindow`).
        parts: for a window with parts (``waiting(/arm)``), one compiled binding per field
            each message contributes (:attr:`WindowSpec.parts`).
        tick_window: ``count_ticks(COND, 1min)``, the ticks of the clock in a window where
            COND held, or None. Then :meth:`evaluate` gives COND at the tick, and the
            samplings count (:mod:`fretc.signals.tick_windows`).
    """

    name: str
    expr: str
    source: str
    line: int | None
    col: int | None
    ast: Expr
    topics: frozenset[str]
    fields: tuple[Field, ...]
    _exact: bool = True
    constants: dict[str, Any] = field(default_factory=dict, repr=False)
    uses_tf: bool = False
    _scalar: Callable[[EvalState], Any] | None = field(default=None, repr=False)
    _vector: Callable[[Any], Any] | None = field(default=None, repr=False)
    aggregate: str | None = None
    window: WindowSpec | None = None
    parts: tuple = ()
    tick_window: WindowSpec | None = None

    def location(self) -> ExprLocation:
        """Where the expression is, for error messages."""
        return ExprLocation(self.source, self.name, self.line, self.col, self._exact)

    def _fail(self, exc: EvalError, context: str) -> SignalError:
        err = self.location().error(f"{exc.message}{context}", exc.node.col)
        return SignalError(str(err), variable=self.name)

    def evaluate(self, state: EvalState, context: str = "") -> bool | float:
        """Value at one tick: Python bool or float.

        Args:
            state: held messages, their times, and the tick time.
            context: appended to error messages (e.g. " at log time ...").

        Raises:
            SignalError: a missing field, index out of range, or a value that is an array;
                the message names the binding file:line:col and the variable.
        """
        try:
            v = self._scalar(state)  # type: ignore[misc]
        except EvalError as exc:
            raise self._fail(exc, context) from None
        t = type(v)
        if t is bool or t is float:  # the fast path: most values are
            return v
        v = normalize_scalar(v)  # ints and numpy scalars (results of array operations)
        if type(v) is bool or type(v) is float:
            return v
        if isinstance(v, Valid):
            raise self._fail(EvalError(self.ast, f"value is an array of {v.data.shape[-1]} "
                                       "items; reduce it with min/max/any/all/count"), context)
        raise self._fail(EvalError(self.ast, f"value {v!r} is not a boolean or a number"),
                         context)

    def raw(self, state: EvalState) -> Any:
        """Value at one tick as read, arrays included (``goal_waiting``'s status arrays):
        no check that it is a boolean or a number.

        Raises:
            SignalError: a missing field or an index out of range, as :meth:`evaluate`.
        """
        try:
            return self._scalar(state)  # type: ignore[misc]
        except EvalError as exc:
            raise self._fail(exc, "") from None

    def evaluate_columns(self, columns: Any) -> np.ndarray:
        """Values at all ticks (vectorized): 1-D bool or float64 array.

        Args:
            columns: an object with ``n`` (number of ticks), ``field(topic, path, node)`` →
                per-tick values (1-D array, or :class:`Valid` of 2-D) and ``age(topic)`` →
                seconds (1-D); see :mod:`fretc.signals.arrays`.

        Raises:
            SignalError: as :meth:`evaluate`.
        """
        try:
            v = self._vector(columns)  # type: ignore[misc]
        except EvalError as exc:
            raise self._fail(exc, "") from None
        if isinstance(v, Valid):
            raise self._fail(EvalError(self.ast, "value is an array; reduce it with "
                                       "min/max/any/all/count"), "")
        if not isinstance(v, np.ndarray):
            v = np.full(columns.n, v)
        if v.dtype == np.bool_:
            return v
        if v.dtype.kind in "iuf":
            return v.astype(np.float64, copy=False)
        raise self._fail(EvalError(self.ast, f"values of type {v.dtype} are not booleans or "
                                   "numbers"), "")


def compile_expression(name: str, expr: str, *, source: str = "<expression>",
                       line: int | None = None, col: int | None = None, exact: bool = True,
                       refs: dict[str, Binding] | None = None, nan: str = "unread",
                       inf: str = "unread", path_vars: dict | None = None,
                       parsed: tuple[Expr, frozenset[str]] | None = None) -> Binding:
    """Parse, check and compile one binding expression.

    Args:
        name: the FRET variable (an identifier, or the text of a quoted FRETish variable).
        expr: the expression text.
        source, line, col: where ``expr`` starts, for error messages (``exact`` False when
            columns inside the expression cannot be mapped to the file, e.g. escapes).
        refs: the other variables a bare name in ``expr`` may refer to (already compiled);
            their expressions are substituted.
        nan: the binding file's ``[tick] nan``: ``"unread"`` (a comparison with NaN is NaN,
            logic three-valued) or ``"false"`` (IEEE 754); :mod:`fretc.signals.bindings.operations`.
        inf: the binding file's ``[tick] inf``: ``"unread"`` (±inf read from a log field is
            NaN, but for REP 117 fields) or ``"value"``.
        path_vars: the binding file's ``[path_variables]`` (FoxQL's ``$name`` in filters and
            slices): name -> bool, int, float or string.
        parsed: what :func:`fretc.signals.bindings.parse.parse_expression` returned for
            ``expr`` and ``path_vars``, when the caller has it (a binding file parses each
            expression once, to order the variables by their references).

    Raises:
        BindingError: bad name, syntax error, unknown function, wrong arity, a bare topic
            used as a value; names source:line:col and the variable.
    """
    where = ExprLocation(source, name, line, col, exact)
    if not VARNAME.match(name):
        raise where.error(f"variable name {name!r} is not an identifier nor the text of a "
                          "quoted FRETish variable")
    if parsed is None:
        from fretc.signals.bindings.parse import parse_expression  # lazy: Lark (start-up)

        parsed = parse_expression(expr, where, path_vars)
    node, topics = parsed
    if any(isinstance(n, Ref) for n in walk(node)):
        trees = {n: b.ast for n, b in (refs or {}).items()}
        node = substitute(node, trees, where, name)
        check_size(node, where, "the expression with its references substituted")
        found: set[str] = set()
        check(node, where, found)
        topics = frozenset(found)
    fields = tuple(n for n in walk(node) if isinstance(n, Field) and (n.path or n.filters))
    extractors: dict[Field, Callable[[Any], Any]] = {}
    constants: dict[str, Any] = {}
    unread, inf_unread = nan != "false", inf != "value"
    aggregate = check_aggregate(node, where)
    body = node.args[0] if aggregate is not None else node  # type: ignore[attr-defined]
    windowed = check_window(node, where)
    window, tick_window = None, None
    parts: tuple[Binding, ...] = ()
    if windowed is not None and windowed[0].func == "count_ticks":
        (tick_window, body), windowed = windowed, None
        if aggregate is not None:  # count_ticks(called(/arm), 1min): the fold's argument
            body = body.args[0]  # type: ignore[attr-defined]
    if windowed is not None:
        window, body = windowed
        parts = tuple(compile_expression(f"{name}__part{i}", unparse(p), source=source,
                                         line=line, col=col, exact=False)
                      for i, p in enumerate(window.parts))
        fields += tuple(f for p in parts for f in p.fields)
    scalar = compile_node(body, Ops(False, unread, inf_unread), extractors, constants)
    vector = compile_node(body, Ops(True, unread, inf_unread), extractors, constants)
    uses_tf = any(isinstance(n, FuncCall) and (n.func == "tf" or n.func in GEOMETRY_CALLS
                                                and geometry_tf(n)) for n in walk(node))
    if uses_tf:  # tf() reads whole messages of both topics: decoders must keep transforms
        fields += tuple(Field(1, t, ("transforms",)) for t in TF_TOPICS)
    return Binding(name, expr, source, line, col, node, topics, fields, exact, constants,
                   uses_tf, scalar, vector, aggregate, window, parts, tick_window)


def parse_inline(spec: str, refs: dict[str, Binding] | None = None) -> Binding:
    """One inline binding ``NAME=EXPR`` (CLI ``--bind``); source is ``"<--bind NAME>"``.

    Raises:
        BindingError: no ``=``, bad name, or a bad expression (column counted in ``spec``).
    """
    name, sep, expr = spec.partition("=")
    name = name.strip()
    if len(name) >= 2 and name[0] == name[-1] == '"':
        name = name[1:-1]  # a quoted FRETish variable: --bind '"wind speed"=...'
    if not sep or not name:
        raise BindingError(f"<--bind {spec}>", "expected NAME=EXPRESSION")
    col = spec.index("=") + 2
    return compile_expression(name, expr, source=f"<--bind {name}>", line=1, col=col,
                              refs=refs)


_COMPARISONS = ("<", "<=", ">", ">=", "=", "!=")


def compile_kept(name: str, expr: str, source: str) -> Binding:
    """:func:`compile_expression` of ``expr`` (no path variables), its parse kept between
    runs as a binding file's are (:mod:`fretc.signals.bindings.parse_cache`: Lark is not
    loaded for an unchanged expression). Raises what :func:`compile_expression` raises."""
    parsed = kept_parses(f"{source}#{name}", {name: (expr, None, None, True)}, None)
    return compile_expression(name, expr, source=source, parsed=parsed[name])


def _operands(node: Expr, found: list[Expr]) -> None:
    """The non-constant operands of the comparisons ``node`` is made of (through
    ``& | -> !``), in order."""
    if isinstance(node, UnaryOp) and node.op == "!":
        _operands(node.arg, found)
    elif isinstance(node, BinOp) and node.op in ("&", "|", "->"):
        _operands(node.left, found)
        _operands(node.right, found)
    elif isinstance(node, BinOp) and node.op in _COMPARISONS:
        found.extend(side for side in (node.left, node.right) if not isinstance(side, Const))


def operand_signals(binding: Binding, limit: int = 4) -> list[tuple[str, Binding]]:
    """The numbers behind a boolean binding: the non-constant operands of the comparisons it
    is made of (through ``& | -> !``), as ``(label, Binding)`` pairs; e.g. ``too_close =
    "min(/scan.ranges) < 0.9"`` gives ``("too_close: min(/scan.ranges)", ...)``. At most
    ``limit`` of them; evidence shows them next to the boolean."""
    found: list[Expr] = []
    _operands(binding.ast, found)
    texts: dict[str, str] = {}  # operand's variable -> its text
    for i, side in enumerate(found):
        text = unparse(side)
        if text.startswith("(") and text.endswith(")"):
            text = text[1:-1]
        if text in texts.values() or len(texts) >= limit:
            continue
        texts[f"{binding.name}__operand{i}"] = text

    parsed = kept_parses(f"{binding.source}#{binding.name}",
                         {n: (t, binding.line, binding.col, False) for n, t in texts.items()},
                         None)
    return [(f"{binding.name}: {text}",
             compile_expression(name, text, source=binding.source, line=binding.line,
                                col=binding.col, exact=False, parsed=parsed[name]))
            for name, text in texts.items()]


#: The value of an aggregation over no message since the previous tick (None: the held
#: message's value, as without aggregation).
EMPTY_FOLD = {"any": False, "all": True, "count": 0.0, "min": None, "max": None}


def fold(aggregate: str, values: list) -> bool | float:
    """The values (bool/float, NaN unknown) of the messages since the previous tick folded
    by ``aggregate`` (docs/bindings.md, "Events between ticks"): ``any`` true when one is
    true, else NaN when one is NaN, else false; ``all`` the dual; ``count`` the number of
    true ones (NaN when one is NaN); ``min``/``max`` (NaN when one is NaN). ``values`` is
    not empty (:data:`EMPTY_FOLD` says what no message gives)."""
    unknown = any(v != v for v in values)
    if aggregate == "any":
        if any(v == v and v for v in values):
            return True
        return float("nan") if unknown else False
    if aggregate == "all":
        if any(v == v and not v for v in values):
            return False
        return float("nan") if unknown else True
    if aggregate == "count":
        return float("nan") if unknown else float(sum(1 for v in values if v))
    if unknown:
        return float("nan")
    nums = [float(v) for v in values]
    return min(nums) if aggregate == "min" else max(nums)
