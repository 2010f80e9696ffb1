"""``fretc shield --emit c``: the shield in C99, with the rules of ``--emit c``'s monitors:
standard headers only, no allocation, no recursion, constant time and memory per step.

Files ``<name>_shield.h`` and ``<name>_shield.c`` (prefix ``P`` = the name), and
``<name>_shield_run.c``, a program that runs the shield over a CSV of inputs and proposals
(its comment gives the format):

* ``P_shield_inputs`` / ``P_shield_outputs``: one field per FRET variable a requirement reads
  (``bool``, or ``double`` for one compared with numbers); a declared variable no
  requirement reads has no field (the caller passes such an output on unchanged); ``P_shield_state``: the monitors' state bits and the correction's scratch;
* ``P_shield_init(s)``; ``P_shield_step(s, inputs, proposed, corrected)``: the rule of
  :mod:`fretc.shield.machine` (as :class:`fretc.shield.runtime.ShieldRuntime`, compared on
  random runs in the tests); returns 1 when the proposal was changed (``s->reasons``: bit
  ``r`` set when ``P_SHIELD_REQUIREMENT_IDS[r]`` forced it), 0 when not, -1 when an input or
  a proposed number is NaN (no decision: ``corrected`` and the state untouched).

A comparison of several variables (:mod:`fretc.shield.predicates`) is computed in doubles
as the Python runtime computes it (:func:`c_term`); when an override changes an atom of an
output cluster, the cluster's variables take the numbers recorded for the new valuation (a
table searched linearly: constant time and memory). Each machine whose variables fit in 64
bits keeps a memo of its decisions in the state (:data:`MEMO_SLOTS` direct-mapped slots:
correction, reasons, next state), as the Python form caches its corrections: a tick met
before costs a lookup, a miss what the step costs without it.
"""

from __future__ import annotations

import keyword
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fretc.compiler.c_step import c_string
from fretc.shield.build import Shield
from fretc.shield.emit_python import tables

__all__ = ["render_c", "c_name", "c_names", "c_term"]

_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Bool _Complex _Imaginary bool true false "
    "NULL".split())
#: object-like macros a field of the same name would expand: those of the headers the C form
#: includes (C99's <math.h>, <stdio.h>, <stdlib.h>, <string.h>, <stdint.h>, <stdbool.h>,
#: <stddef.h>, and <errno.h>, which they may include) and the generated files' own
_C_MACROS = frozenset(
    "NAN INFINITY HUGE_VAL HUGE_VALF HUGE_VALL FP_NAN FP_INFINITE FP_ZERO FP_SUBNORMAL "
    "FP_NORMAL FP_ILOGB0 FP_ILOGBNAN FP_FAST_FMA FP_FAST_FMAF FP_FAST_FMAL MATH_ERRNO "
    "MATH_ERREXCEPT math_errhandling EOF BUFSIZ FILENAME_MAX FOPEN_MAX L_tmpnam TMP_MAX "
    "SEEK_SET SEEK_CUR SEEK_END stdin stdout stderr EXIT_SUCCESS EXIT_FAILURE RAND_MAX "
    "MB_CUR_MAX errno EDOM ERANGE EILSEQ SIZE_MAX PTRDIFF_MIN PTRDIFF_MAX SIG_ATOMIC_MIN "
    "SIG_ATOMIC_MAX WCHAR_MIN WCHAR_MAX WINT_MIN WINT_MAX INTMAX_MIN INTMAX_MAX UINTMAX_MAX "
    "INTPTR_MIN INTPTR_MAX UINTPTR_MAX __bool_true_false_are_defined "
    "INF_COST MAX_ATOMS LINE_MAX_BYTES MAX_COLUMNS".split())
#: macro families: <stdint.h>'s limits (INT8_MIN ... UINT_FAST64_MAX), the generated
#: files' per-machine and per-shield ones (M0_NIN, SAFE_ROS_SHIELD_...), and the names C
#: reserves (``_`` then a capital, or ``__``)
_C_RESERVED = re.compile(r"U?INT(_LEAST|_FAST)?\d+_(MIN|MAX)|U?INT\d+_C|INTMAX_C|UINTMAX_C"
                         r"|M\d+_[A-Z_]+|[A-Z0-9_]*_SHIELD_[A-Z_]+|FRETC_SHIELD_\w*|_[A-Z_]\w*")
_C_OPS = {"<": "<", "<=": "<=", ">": ">", ">=": ">=", "=": "==", "!=": "!="}


def c_name(variable: str) -> str:
    """A FRET variable as a C identifier: itself, with ``_`` after it when it is a C (or
    Python) keyword, a macro of the headers the C form includes or of its own files
    (``NAN``, ``errno``, ``EOF``, ``MAX_ATOMS``: a field of that name would be expanded) or a
    name C reserves; a name that is no identifier (FRET's dotted ``ROS.ok``, a quoted
    ``"load%"``) with ``_`` for each other character (``v_`` before a digit). Two names
    may give one: :func:`c_names` makes them unique."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", variable):
        variable = re.sub(r"[^A-Za-z0-9_]", "_", variable)
        if not variable or variable[0].isdigit():
            variable = "v_" + variable
    reserved = (variable in _C_KEYWORDS or variable in _C_MACROS or keyword.iskeyword(variable)
                or _C_RESERVED.fullmatch(variable) is not None)
    return variable + "_" if reserved else variable


def c_names(variables: Sequence[str]) -> dict[str, str]:
    """Each of ``variables`` (distinct FRET names) -> its C field name, unique among them:
    :func:`c_name`, with ``_2``, ``_3``, ... after a name another variable already has
    (the names that are C identifiers as they are keep them; the others are taken in the
    order given)."""
    out: dict[str, str] = {}
    used: set[str] = set()
    for v in sorted(variables, key=lambda v: c_name(v) != v):  # (stable: given order)
        name, k = c_name(v), 1
        while name in used:
            k += 1
            name = f"{c_name(v)}_{k}"
        out[v] = name
        used.add(name)
    return {v: out[v] for v in variables}


def _double(x: float) -> str:
    """A double as a C expression of the same value: a literal that reads back to it, or
    ``<math.h>``'s ``INFINITY``, ``(-INFINITY)``, ``NAN`` (a constant such as ``1e309`` is
    infinite in doubles; ``repr`` writes no C for it)."""
    x = float(x)
    if math.isnan(x):
        return "NAN"
    if math.isinf(x):
        return "INFINITY" if x > 0 else "(-INFINITY)"
    text = repr(x)
    return text if any(ch in text for ch in ".en") else text + ".0"


def c_term(t: tuple[Any, ...], struct: str, names: dict[str, str] | None = None) -> str:
    """A comparison of several variables or one of its terms
    (:func:`fretc.shield.runtime.term_value`) as a C expression over the fields of
    ``struct`` (a pointer), with the runtime's double arithmetic (``min``/``max`` as
    Python's, IEEE division); ``names`` the fields' names (:func:`c_names`; default
    :func:`c_name`)."""
    op = t[0]
    if op == "var":
        return f"{struct}->{names[t[1]] if names is not None else c_name(t[1])}"
    if op == "num":
        return _double(t[1])
    if op == "cmp":
        return f"({c_term(t[2], struct, names)} {_C_OPS[t[1]]} {c_term(t[3], struct, names)})"
    if op == "neg":
        return f"(-{c_term(t[1], struct, names)})"
    if op == "fn":
        a = c_term(t[2], struct, names)
        if t[1].startswith("abs"):
            return f"fabs({a})"
        b = c_term(t[3], struct, names)
        rel = "<" if t[1].startswith("min") else ">"
        return f"(({b}) {rel} ({a}) ? ({b}) : ({a}))"
    return f"({c_term(t[1], struct, names)} {op} {c_term(t[2], struct, names)})"


def _comment(text: str) -> str:
    """A C comment's text: :func:`fretc.common.textsafe.c_comment`, the one C comment escape
    (printable ASCII, no ``*/``, no trigraph)."""
    from fretc.common.textsafe import c_comment

    return c_comment(text)


@dataclass
class _CMachine:
    """One machine's tables as the templates read them."""

    k: int
    t: dict[str, Any]
    first_req: int
    numeric_outputs: list[tuple[str, list[tuple[str, str]], list[int]]]
    groups: list[dict[str, Any]]
    #: output clusters (:mod:`fretc.shield.predicates`): atoms, variables, rows (key, values)
    clusters: list[dict[str, Any]]
    #: per output atom, the indices (in the outputs struct's order) of the variables it reads
    atom_vars: list[list[int]]
    #: the index of the machine's first assumption in the state's ``broken``
    first_assumption: int = 0

    @property
    def n_in(self) -> int:
        """Input atoms."""
        return len(self.t["inputs"])

    @property
    def n_out(self) -> int:
        """Output atoms."""
        return len(self.t["outputs"])

    @property
    def n_bits(self) -> int:
        """State bits (at least one: C has no empty arrays)."""
        return max(1, len(self.t["init"]))

    @property
    def n_vars(self) -> int:
        """Variables of the node table."""
        return self.n_in + self.n_out + len(self.t["init"])

    @property
    def memo(self) -> bool:
        """Whether the machine keeps a memo of its corrections (:data:`MEMO_SLOTS` slots,
        keyed by the node table's variables packed in 64 bits: only when they fit)."""
        return 0 < self.n_vars <= 64


def _machines(shield: Shield) -> list[_CMachine]:
    out, first, first_a = [], 0, 0
    fields = [v for v in shield.outputs if v in shield.read]  # (the outputs struct's)
    for k, t in enumerate(tables(shield)["machines"]):
        numeric = []
        clustered = {v for c in t["clusters"] for v in c["variables"]}
        for v in dict.fromkeys(s[0] for s in t["outputs"]):
            if v in clustered:
                continue
            idx = [j for j, s in enumerate(t["outputs"]) if s[0] == v]
            if t["outputs"][idx[0]][1] is not None:
                numeric.append((v, [(_C_OPS[t["outputs"][j][1]], _double(t["outputs"][j][2]))
                                    for j in idx], idx))
        groups = []
        names = [v for v, _s, _i in numeric]
        for g in t["groups"]:
            rows = []
            for key, nums in g["numbers"].items():
                rows.append((key, [_double(nums[v]) if v in nums else "NAN" for v in names]))
            groups.append({"atoms": g["atoms"], "rows": rows})
        clusters = [{"atoms": c["atoms"], "variables": c["variables"],
                     "rows": [(key, [_double(nums[v]) for v in c["variables"]])
                              for key, nums in c["numbers"].items()]}
                    for c in t["clusters"]]
        atom_vars = [sorted(fields.index(x) for x in (_term_variables(c) if op == "pred"
                                                      else {var}) if x in fields)
                     for var, op, c in t["outputs"]]
        out.append(_CMachine(k, t, first, numeric, groups, clusters, atom_vars, first_a))
        first += len(t["requirements"])
        first_a += len(t["assumptions"])
    return out


#: slots of a machine's correction memo (direct-mapped; a power of two): an override whose
#: inputs, proposal and state were met before copies the correction found then (the same
#: answer as computing it again: the correction is a function of these alone)
def _term_variables(t: tuple[Any, ...]) -> set[str]:
    """The variables a comparison of several variables reads (:func:`c_term`'s shape)."""
    if t[0] == "var":
        return {t[1]}
    return set().union(*(_term_variables(x) for x in t[1:] if isinstance(x, tuple)))


MEMO_SLOTS = 256


def render_c(shield: Shield, base: str) -> dict[str, str]:
    """``{file name: text}`` of the C form (module docstring); ``base`` the C prefix."""
    from fretc.compiler.codegen import _env  # lazy: Jinja2 only when C is written

    env = _env()
    env.filters["cstr"] = c_string
    env.filters["ccom"] = _comment
    names = c_names(list(dict.fromkeys([*shield.inputs, *shield.outputs])))
    env.filters["cname"] = names.__getitem__
    env.filters["double"] = _double
    env.filters["cterm"] = lambda t, struct: c_term(t, struct, names)
    t = tables(shield)
    machines = _machines(shield)
    # (the numbers the machines compare: a NaN there has no truth value, the runtime's
    # ValueError; a NaN elsewhere, a monitored requirement's, passes as in Python)
    compared: set[str] = set()
    for m in t["machines"]:
        for var, op, c in (*m["inputs"], *m["outputs"]):
            if op == "pred":
                compared |= _term_variables(c)
            elif op is not None:
                compared.add(var)
    outputs = [(v, v in shield.numbers) for v in shield.outputs if v in shield.read]
    ctx = {"p": base, "P": base.upper(), "shield": shield, "t": t, "machines": machines,
           "compared": compared,
           "inputs": [(v, v in shield.numbers) for v in shield.inputs if v in shield.read],
           "outputs": outputs,
           # the runner's CSV header (FRET names: any text, never a printf format)
           "header": "".join(["tick", *(f",{v}" for v, _n in outputs),
                              ",overridden,reasons,fault",
                              ",broken" if any(m["assumptions"] for m in t["machines"])
                              else "", "\n"]),
           "requirements": [r for m in t["machines"] for r in m["requirements"]],
           "assumptions": [a for m in t["machines"] for a in m["assumptions"]],
           "op_map": _C_OPS, "memo_slots": MEMO_SLOTS,
           "numeric": any(m.numeric_outputs for m in machines),
           "whole": any(v in m.t["integers"] for m in machines for v, _s, _i in m.numeric_outputs),
           "max_atoms": max([1] + [len(i) for m in machines for _v, _s, i in m.numeric_outputs])}
    return {f"{base}_shield.h": env.get_template("shield.h.j2").render(**ctx),
            f"{base}_shield.c": env.get_template("shield.c.j2").render(**ctx),
            f"{base}_shield_run.c": env.get_template("shield_runner.c.j2").render(**ctx)}
