"""The pt formula as the straight-line C99 code of one monitor tick (``fretc --emit c``).

The same scheme as the Python monitors' tick code (:mod:`fretc.compiler.pt_step`: Havelund &
Rosu, TACAS 2002), from the same formula IR: the sub-formulas in post-order, each a ``const``
local computed from this tick's inputs and the state's values of the previous tick, then the
next values stored into the state. Time and memory per tick are constant and known when the
code is generated: no allocation, no recursion, no loop, no floating point unless the formula
compares numbers.

Design notes: ARCHITECTURE.md, `compiler/c_step.py`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from fretc.compiler.ir import Node, name_of, window
from fretc.compiler.printers import to_smv
from fretc.compiler.pt_step import CodegenError, _future_error, opaque, post_order

__all__ = ["CField", "CStep", "HELPERS", "c_number", "c_string", "compile_c_nodes",
           "uint_type"]

_C_CMP = {"=": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">="}
_C_FORMS = {"!": "!{0}", "&": "({0} && {1})", "|": "({0} || {1})", "xor": "({0} != {1})",
            "->": "(!{0} || {1})", "<->": "({0} == {1})"}
_C_FN = {"absReal": "fabs", "absInt": "fabs", "minReal": "fretc_min", "minInt": "fretc_min",
         "maxReal": "fretc_max", "maxInt": "fretc_max"}
_C_ARITH_FN = {"/": "fretc_div", "mod": "fretc_mod", "^": "fretc_pow"}
_NUMERIC_OPS = ("var", "num", "arith", "neg", "fn", "pre")

#: The C helpers a generated file may need, by name (defined ``static`` before the monitors
#: when used; the Python monitors' ``_div``, ``_mod``, ``_pow`` and builtins ``min``, ``max``).
HELPERS = {
    "fretc_div": "static double fretc_div(double a, double b)\n"
                 "{\n    return b == 0.0 ? NAN : a / b;\n}\n",
    "fretc_mod": "static double fretc_mod(double a, double b)\n"
                 "{\n    return (b == 0.0 || isinf(a)) ? NAN : fmod(a, b);\n}\n",
    "fretc_pow": "static double fretc_pow(double a, double b)\n"
                 "{\n    double r;\n    if (a == 0.0 && b < 0.0)\n        return NAN;\n"
                 "    r = pow(a, b);\n"
                 "    /* an overflow of finite operands: NaN, as the Python monitors */\n"
                 "    return (isinf(r) && !isinf(a) && !isinf(b)) ? NAN : r;\n}\n",
    "fretc_min": "static double fretc_min(double a, double b)\n"
                 "{\n    return b < a ? b : a;\n}\n",
    "fretc_max": "static double fretc_max(double a, double b)\n"
                 "{\n    return b > a ? b : a;\n}\n",
}


@dataclass(frozen=True)
class CField:
    """One field of a monitor's state struct: C type, name, array length (0: a scalar),
    initial value (a C expression; arrays start all zero) and a comment."""

    ctype: str
    name: str
    length: int
    init: str
    comment: str

    @property
    def size(self) -> int:
        """Bytes of the field (``bool`` is one byte on every ABI fretc targets)."""
        return _SIZES[self.ctype] * max(self.length, 1)


_SIZES = {"bool": 1, "uint8_t": 1, "int8_t": 1, "uint16_t": 2, "int16_t": 2, "uint32_t": 4,
          "int32_t": 4, "uint64_t": 8, "int64_t": 8, "double": 8}


@dataclass
class CStep:
    """The C code of one tick: ``lines`` declare the locals (``const`` values of this tick)
    from the inputs ``in`` and the state ``s``; ``commits`` store the next state; ``fields``
    the state struct's fields it needs; ``inputs`` maps a FRET variable (or the printed form
    of an uninterpreted function) to (input field, ``"bool"`` or ``"double"``); ``nan_checks``
    the C expressions true when a comparison reads NaN this tick (an unread tick, as
    :mod:`fretc.monitors.nan` defines it); ``helpers`` the :data:`HELPERS` used."""

    lines: list[str] = field(default_factory=list)
    commits: list[str] = field(default_factory=list)
    fields: list[CField] = field(default_factory=list)
    inputs: dict[str, tuple[str, str]] = field(default_factory=dict)
    locals: dict[Node, str] = field(default_factory=dict)
    types: dict[Node, str] = field(default_factory=dict)
    nan_checks: list[str] = field(default_factory=list)
    helpers: set[str] = field(default_factory=set)
    bool_reads: set[str] = field(default_factory=set)
    uses_first: bool = False
    counter: int = 0

    def new(self, prefix: str = "n") -> str:
        """A fresh name (``n1``, ``c2``, ...)."""
        self.counter += 1
        return f"{prefix}{self.counter}"

    def local(self, ctype: str, expr: str, prefix: str = "n") -> str:
        """Declare ``const ctype name = expr;`` and return the name."""
        name = self.new(prefix)
        self.lines.append(f"const {ctype} {name} = {expr};")
        return name

    def add_field(self, ctype: str, init: str, comment: str, length: int = 0,
                  prefix: str = "x") -> str:
        """Reserve a state field; returns ``s->name``."""
        name = self.new(prefix)
        self.fields.append(CField(ctype, name, length, init, comment))
        return f"s->{name}"


def uint_type(max_value: int) -> str:
    """The smallest unsigned C type holding ``0 .. max_value``."""
    for bits in (8, 16, 32, 64):
        if max_value < (1 << bits):
            return f"uint{bits}_t"
    raise CodegenError(f"a bound of {max_value} ticks does not fit a 64-bit counter")


def compile_c_nodes(roots: list[Node], code: CStep) -> list[str]:
    """Emit the C code of ``roots`` (common sub-formulas shared) into ``code``; returns the
    C expressions (locals or literals) of their values. Raises :class:`CodegenError` for a
    future-time operator or function (:func:`fretc.compiler.pt_step.check_monitorable`)."""
    for n in post_order(roots, code.locals):
        code.locals[n] = _emit(n, code)
    return [code.locals[r] for r in roots]


def _ctype(n: Node, code: CStep) -> str:
    if n.op in _NUMERIC_OPS:
        return "double"
    if n.op == "ite":
        return code.types.get(n.args[1], "bool")
    if n.op == "call":
        return "bool"
    return "bool"


def _emit(n: Node, code: CStep) -> str:
    """The C expression of node ``n`` (its arguments done): a literal or a local."""
    # (an uninterpreted application is an input: its arguments have no code, post_order)
    a = [] if opaque(n) else [code.locals[x] for x in n.args]
    ctype = code.types[n] = _ctype(n, code)
    op = n.op
    if op in ("true", "false"):
        return op
    if op == "FTP":
        code.uses_first = True
        return "first"
    if op in ("ap", "var"):
        return _read(name_of(n), code, numeric=op == "var")
    if op == "num":
        return c_number(name_of(n))
    if (op == "fn" and n.name not in _C_FN) or op == "call":
        return _read(to_smv(n), code, numeric=op == "fn")
    if op == "past":
        code.types[n] = code.types[n.args[0]]
        return a[0]
    if op == "future":
        raise _future_error(n)
    expr = _expression(n, a, code)
    if expr is not None:
        return code.local(ctype, expr)
    return _temporal(n, a, code)


def _expression(n: Node, a: list[str], code: CStep) -> str | None:
    """A pure expression of this tick, or None."""
    op = n.op
    if op == "cmp":
        for x, arg in zip(a, n.args):
            if code.types[arg] == "double" and arg.op != "num":
                code.nan_checks.append(f"isnan({x})")
        return f"{a[0]} {_C_CMP[name_of(n)]} {a[1]}"
    if op == "arith":
        if n.name in ("+", "-", "*"):
            return f"{a[0]} {n.name} {a[1]}"
        code.helpers.add(_C_ARITH_FN[name_of(n)])
        return f"{_C_ARITH_FN[name_of(n)]}({a[0]}, {a[1]})"
    if op == "neg":
        return f"-{a[0]}"
    if op == "fn":
        _nan_arguments(n, a, code)
        if _C_FN[name_of(n)].startswith("fretc_"):
            code.helpers.add(_C_FN[name_of(n)])
        return f"{_C_FN[name_of(n)]}({', '.join(a)})"
    if op == "ite":
        _nan_arguments(n, a, code)
        return f"{a[0]} ? {a[1]} : {a[2]}"
    if op == "pre":
        _nan_arguments(n, a, code)
        prev = code.add_field("double", "0.0", f"previous value of {_text(n.args[1])}")
        code.uses_first = True
        code.commits.append(f"{prev} = {a[1]};")
        return f"first ? {a[0]} : {prev}"
    form = _C_FORMS.get(op)
    return None if form is None else form.format(*a)


def _nan_arguments(n: Node, a: list[str], code: CStep) -> None:
    """A numeric input given straight to a function (``minReal(x, y)``, ``preReal(0, x)``,
    ``ite``'s branches) that is NaN makes the tick unread, as the audit's NaN rule reads a
    variable argument of a call (:func:`fretc.monitors.nan.nan_ticks_of`), even where the
    function's value does not carry it (``max(0.0, NaN)`` is 0.0)."""
    for x, arg in zip(a, n.args):
        if arg.op == "var" and code.types.get(arg) == "double":
            code.nan_checks.append(f"isnan({x})")


def _temporal(n: Node, a: list[str], code: CStep) -> str:
    """Y, Z, O, H, S, T: state fields and the local of the value."""
    op, what = n.op, _text(n)
    if op in ("Y", "Z"):
        prev = code.add_field("bool", "false" if op == "Y" else "true", what)
        code.commits.append(f"{prev} = {a[0]};")
        return code.local("bool", prev)
    if op in ("O", "H") and n.hi is None:
        prev = code.add_field("bool", "false" if op == "O" else "true", what)
        out = code.local("bool", f"{a[0]} || {prev}" if op == "O" else f"{a[0]} && {prev}")
    elif op in ("O", "H"):
        out = _bounded(n, a[0], code)
    elif op in ("S", "T"):
        prev = code.add_field("bool", "false" if op == "S" else "true", what)
        out = code.local("bool", f"{a[1]} || ({a[0]} && {prev})" if op == "S"
                         else f"{a[1]} && ({a[0]} || {prev})")
    else:
        raise CodegenError(f"no monitor code for the future-time operator {op!r} in pt")
    if op not in ("O", "H") or n.hi is None:
        code.commits.append(f"{prev} = {out};")
    return out


def _bounded(n: Node, arg: str, code: CStep) -> str:
    """``O[lo,hi]`` / ``H[lo,hi]`` (module docstring): the local of its value."""
    (lo, hi), what = window(n), _text(n)
    bit = arg if n.op == "O" else f"!{arg}"
    if lo > 0:
        pos_t = uint_type(lo)
        ring = code.add_field("uint8_t", "", f"the last {lo} values of the argument of "
                              f"{what} (ring buffer of bits)", length=(lo + 7) // 8)
        pos = code.add_field(pos_t, "0", f"position in the ring buffer of {what}")
        p = code.local(pos_t, pos, "p")
        delayed = code.local("bool", f"(({ring}[{p} >> 3] >> ({p} & 7u)) & 1u) != 0", "d")
        now = code.local("bool", bit, "b")
        code.commits.append(
            f"{ring}[{p} >> 3] = (uint8_t)({now} ? ({ring}[{p} >> 3] | (1u << ({p} & 7u)))"
            f" : ({ring}[{p} >> 3] & ~(1u << ({p} & 7u))));")
        code.commits.append(f"{pos} = ({pos_t})({p} + 1u == {lo}u ? 0u : {p} + 1u);")
        bit, hi = delayed, hi - lo
    cnt_t = uint_type(hi + 1)
    prev = code.add_field(cnt_t, f"{hi + 1}u", f"ticks since the argument of {what} "
                          f"{'last held' if n.op == 'O' else 'last failed'}, capped at "
                          f"{hi + 1}", prefix="c")
    cnt = code.local(cnt_t, f"({cnt_t})({bit} ? 0u : ({prev} <= {hi}u ? {prev} + 1u : "
                     f"{hi + 1}u))", "c")
    code.commits.append(f"{prev} = {cnt};")
    return code.local("bool", f"{cnt} <= {hi}u" if n.op == "O" else f"{cnt} > {hi}u")


def _read(name: str, code: CStep, numeric: bool) -> str:
    """The local of input ``name`` (a boolean read of a numeric input is ``!= 0``, and
    NaN there is an unread tick: :mod:`fretc.monitors.nan`)."""
    got = code.inputs.get(name)
    if got is None:
        got = code.inputs[name] = (f"v{len(code.inputs)}", "double" if numeric else "bool")
    elif numeric and got[1] == "bool":
        got = code.inputs[name] = (got[0], "double")
    if numeric:
        return f"in->{got[0]}"
    code.bool_reads.add(got[0])
    return f"b_{got[0]}"


def c_number(text: str) -> str:
    """C text of a FRETish number literal as a double (``3`` -> ``3.0``, ``1e400`` ->
    ``HUGE_VAL``)."""
    value = float(text)
    if math.isinf(value):
        return "HUGE_VAL" if value > 0 else "(-HUGE_VAL)"
    out = repr(value)
    return out if value >= 0 else f"({out})"


#: C99 (5.2.4.1) promises string literals of this many bytes, after concatenation
C_STRING_MAX = 4095


def c_string(text: str) -> str:
    """A C string expression of ``text`` (UTF-8): a string literal, printable ASCII as is
    but ``\\``, ``"`` and ``?`` (trigraphs) escaped, every other byte in octal, split into
    adjacent literals of at most 200 bytes; past :data:`C_STRING_MAX` bytes (more than C99
    promises a literal, ``-pedantic`` refuses it) a compound literal of character
    constants, ``((const char[]){'a', ..., 0})``, of the same bytes."""
    data = text.encode("utf-8")
    if len(data) > C_STRING_MAX:
        chars = [f"'{chr(b)}'" if 32 <= b < 127 and chr(b) not in "\\'?" else f"'\\{b:03o}'"
                 for b in data] + ["0"]
        rows = [", ".join(chars[i:i + 16]) for i in range(0, len(chars), 16)]
        return "((const char[]){" + ", \\\n    ".join(rows) + "})"
    parts, cur = [], []
    for b in data:
        c = chr(b)
        if c in '\\"?':
            cur.append("\\" + c)
        elif 32 <= b < 127:
            cur.append(c)
        else:
            cur.append(f"\\{b:03o}")
        if len(cur) >= 200:
            parts.append('"' + "".join(cur) + '"')
            cur = []
    if cur or not parts:
        parts.append('"' + "".join(cur) + '"')
    return " ".join(parts)


def _text(n: Node) -> str:
    """A comment-safe FRET text of ``n`` (no ``*/``, at most 80 characters)."""
    t = "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in to_smv(n))
    t = t if len(t) <= 80 else t[:77] + "..."
    t = t.replace("*/", "* /").replace("/*", "/ *")
    while "??" in t:  # no trigraph
        t = t.replace("??", "? ?")
    return t
