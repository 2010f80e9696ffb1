"""``fretc shield --emit c``: the shield in C99, with the rules of ``--emit c``'s monitors:
standard headers only, no allocation, no recursion, constant time and memory per step.

Files ``<name>_shield.h`` and ``<name>_shield.c`` (prefix ``P`` = the name), and
``<name>_shield_run.c``, a program that runs the shield over a CSV of inputs and proposals
(its comment gives the format):

Design notes: ARCHITECTURE.md, `shield/emit_c.py`."""

from __future__ import annotations

import itertools
import keyword
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fretc.compiler.c_step import c_string
from fretc.shield.build import Shield
from fretc.shield.emit_python import tables
from fretc.shield.runtime import BELIEF_LIMIT, CASES_LIMIT
from fretc.shield.runtime_values import MESSAGE_ORDERS

__all__ = ["render_c", "c_name", "c_names", "c_term", "c_message"]

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


def c_term(t: tuple[Any, ...], struct: str, names: dict[str, str] | None = None,
           locals_: dict[str, str] | None = None) -> str:
    """A comparison of several variables or one of its terms
    (:func:`fretc.shield.runtime.term_value`) as a C expression over the fields of
    ``struct`` (a pointer), with the runtime's double arithmetic (``min``/``max`` as
    Python's, IEEE division); ``names`` the fields' names (:func:`c_names`; default
    :func:`c_name`); ``locals_`` variables read from a C variable instead (a bounded
    output's value ``x``)."""
    op = t[0]

    def sub(u: tuple[Any, ...]) -> str:
        return c_term(u, struct, names, locals_)

    if op == "var":
        if locals_ is not None and t[1] in locals_:
            return locals_[t[1]]
        return f"{struct}->{names[t[1]] if names is not None else c_name(t[1])}"
    if op == "num":
        return _double(t[1])
    if op == "cmp":
        return f"({sub(t[2])} {_C_OPS[t[1]]} {sub(t[3])})"
    if op == "neg":
        return f"(-{sub(t[1])})"
    if op == "fn":
        a = sub(t[2])
        if t[1].startswith("abs"):
            return f"fabs({a})"
        b = sub(t[3])
        rel = "<" if t[1].startswith("min") else ">"
        return f"(({b}) {rel} ({a}) ? ({b}) : ({a}))"
    return f"({sub(t[1])} {op} {sub(t[2])})"


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
    #: per input atom, the indices (in the inputs struct's order) of the compared numbers it
    #: reads: the atom is free (any value) when one of them is NaN
    in_vars: tuple[tuple[int, ...], ...] = ()
    #: the output variables the machine's atoms read, in the outputs struct's order
    out_vars: tuple[str, ...] = ()
    #: the fallback's value of each output atom (None: the shield has no fallback)
    fallback_atoms: tuple[int, ...] | None = None
    #: the message groups' models (:func:`_c_models`): their decided values made one message
    models: tuple[dict[str, Any], ...] = ()
    #: the outputs bounded by the inputs (:func:`_c_bounded`): each its atoms, as the
    #: runtime's :func:`fretc.shield.runtime_bounds.bounded_value` reads them
    bounded: tuple[dict[str, Any], ...] = ()
    #: per bound (output atom index) its C test and estimate (:func:`_c_bounded`)
    bound_fns: tuple[dict[str, Any], ...] = ()
    #: the twists (:func:`_c_twists`)
    twists: tuple[dict[str, Any], ...] = ()

    def bound_fn(self, j: int) -> dict[str, Any] | None:
        """The bound of output atom ``j`` (:attr:`bound_fns`), None when it is none."""
        return next((f for f in self.bound_fns if f["j"] == j), None)

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
    def n_free(self) -> int:
        """Input atoms that can be free (read a compared input number)."""
        return sum(1 for x in self.in_vars if x)

    @property
    def free_cap(self) -> int:
        """The most free input atoms a tick enumerates (:data:`C_FREE_LIMIT`)."""
        return min(self.n_free, C_FREE_LIMIT)

    @property
    def belief_cap(self) -> int:
        """The belief array's capacity: :data:`C_BELIEF_LIMIT`, or fewer when the state bits
        have fewer states (the belief can never hold more)."""
        return min(C_BELIEF_LIMIT, 1 << len(self.t["init"]))

    @property
    def case_cap(self) -> int:
        """The valuations of the free input atoms a tick keeps (at most
        :data:`C_CASES_LIMIT`)."""
        return min(1 << self.free_cap, C_CASES_LIMIT)

    @property
    def memo(self) -> bool:
        """Whether the machine keeps a memo of its corrections (:data:`MEMO_SLOTS` slots,
        keyed by the node table's variables packed in 64 bits: only when they fit)."""
        return 0 < self.n_vars <= 64


def _machines(shield: Shield, compared: set[str], cnames: dict[str, str]) -> list[_CMachine]:
    out, first, first_a = [], 0, 0
    fields = _output_fields(shield)  # (the outputs struct's)
    in_fields = [v for v in shield.inputs if v in shield.read]  # (the inputs struct's)
    numeric_in = [v for v in in_fields if v in shield.numbers and v in compared]
    for k, t in enumerate(tables(shield)["machines"]):
        numeric = []
        clustered = {v for c in t["clusters"] for v in c["variables"]}
        clustered |= {b["variable"] for b in t["bounds"]}  # (bounded: their own numbers)
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
            if g["atoms"]:  # (a group of bounded outputs alone has none: C has no empty arrays)
                groups.append({"atoms": g["atoms"], "rows": rows})
        clusters = [{"atoms": c["atoms"], "variables": c["variables"],
                     "rows": [(key, [_double(nums[v]) for v in c["variables"]])
                              for key, nums in c["numbers"].items()]}
                    for c in t["clusters"]]
        atom_vars = [sorted(fields.index(x) for x in (_term_variables(c) if op == "pred"
                                                      else {var}) if x in fields)
                     for var, op, c in t["outputs"]]
        in_vars = tuple(tuple(sorted(in_fields.index(x) for x in (
            _term_variables(c) if op == "pred" else {var} if op is not None else set())
            if x in numeric_in)) for var, op, c in t["inputs"])
        fns, bounded = _c_bounded(k, t, in_fields, numeric_in, cnames, shield)
        reads = {x for var, op, c in t["outputs"]
                 for x in (_term_variables(c) if op == "pred" else {var})}
        fb = shield.fallback
        out.append(_CMachine(k, t, first, numeric, groups, clusters, atom_vars, first_a,
                             in_vars, tuple(v for v in fields if v in reads),
                             tuple(int(b) for b in fb["atoms"][k]) if fb is not None
                             else None, _c_models(t), bounded, fns, _c_twists(k, t, fns)))
        first += len(t["requirements"])
        first_a += len(t["assumptions"])
    return out


def _key_max() -> int:
    """The position of the largest finite double in the doubles' order
    (:mod:`fretc.shield.runtime_bounds`)."""
    from fretc.shield.runtime_bounds import DOUBLE_MAX, _key

    return _key(DOUBLE_MAX)


def _output_fields(shield: Shield) -> list[str]:
    """The outputs struct's fields: the outputs a requirement reads, and those a twist
    scales."""
    twisted = {v for t in shield.twists for v in t}
    return [v for v in shield.outputs if v in shield.read or v in twisted]


def _c_bounded(k: int, t: dict[str, Any], in_fields: list[str], numeric_in: list[str],
               names: dict[str, str], shield: Shield
               ) -> tuple[tuple[dict[str, Any], ...], tuple[dict[str, Any], ...]]:
    """Machine ``k``'s bounds (table ``t``) as the template reads them: per bound its output
    atom ``j``, its test (the comparison as a C expression of ``x``, the output's value, and
    the inputs struct ``in``), its estimate, ``down`` and the inputs struct's indices of the
    numbers it reads (unread: its bound cannot be computed); per bounded output its field,
    its atoms in order (a constant's ``(j, op index, constant)``, a bound's ``(j, None,
    None)``) and the fallback's number (:func:`fretc.shield.runtime_bounds.bounded_value`)."""
    fns = []
    for b in t["bounds"]:
        j, v = b["atom"], b["variable"]
        term = t["outputs"][j][2]
        reads = sorted(in_fields.index(x) for x in _term_variables(term) - {v}
                       if x in numeric_in)
        fns.append({"j": j, "down": int(b["down"]), "reads": reads, "variable": v,
                    "test": c_term(term, "in", names, {v: "x"}),
                    "estimate": c_term(b["estimate"], "in", names)})
    fb = shield.fallback["outputs"] if shield.fallback is not None else {}
    bounded = []
    for v in dict.fromkeys(b["variable"] for b in t["bounds"]):
        atoms = []
        for j, (var, op, c) in enumerate(t["outputs"]):
            if var != v:
                continue
            atoms.append((j, None, None) if op == "pred" else
                         (j, ["<", "<=", ">", ">=", "=", "!="].index(op), _double(c)))
        bounded.append({"variable": v, "atoms": atoms,
                        "fallback": _double(float(fb.get(v, 0.0)))})
    return tuple(fns), tuple(bounded)


def _c_twists(k: int, t: dict[str, Any], fns: tuple[dict[str, Any], ...]
              ) -> tuple[dict[str, Any], ...]:
    """Machine ``k``'s twists (table ``t``) as the template reads them: the outputs, and the
    atoms reading them that a scaled value must keep (a constant's ``(j, variable index, C
    operator, constant)``, a bound's ``(j, variable index, None, None)``)."""
    bound = {f["j"] for f in fns}
    out = []
    for names in t["twists"]:
        atoms = []
        for j, (var, op, c) in enumerate(t["outputs"]):
            if var in names and op is not None:
                atoms.append((j, list(names).index(var), None, None) if j in bound else
                             (j, list(names).index(var), _C_OPS[op], _double(c)))
        out.append({"names": list(names), "atoms": atoms})
    return tuple(out)


def c_message(t: tuple[Any, ...], want: str = "n") -> str:
    """A message term (:mod:`fretc.shield.message_model`) as a C expression over the slots
    ``msg[]`` (doubles; a boolean field 0/1), as
    :func:`fretc.shield.runtime_values.message_value` computes it: ``want`` ``"b"`` an int
    (a number read as ``!= 0``), ``"n"`` a double (a boolean as 1.0 or 0.0)."""
    op = t[0]
    if op == "slot":
        text, kind = f"msg[{t[1]}]", "n"
    elif op == "num":
        text, kind = _double(t[1]), "n"
    elif op == "not":
        text, kind = f"(!{c_message(t[1], 'b')})", "b"
    elif op in ("and", "or", "iff"):
        sym = {"and": "&&", "or": "||", "iff": "=="}[op]
        text, kind = f"({c_message(t[1], 'b')} {sym} {c_message(t[2], 'b')})", "b"
    elif op == "cmp":
        text = f"({c_message(t[2], 'n')} {_C_OPS[t[1]]} {c_message(t[3], 'n')})"
        kind = "b"
    elif op == "neg":
        text, kind = f"(-{c_message(t[1], 'n')})", "n"
    else:  # ("fn", "abs", a)
        text, kind = f"fabs({c_message(t[2], 'n')})", "n"
    if want == "b" and kind == "n":
        return f"({text} != 0.0)"
    if want == "n" and kind == "b":
        return f"({text} ? 1.0 : 0.0)"
    return text


def _c_write(t: tuple[Any, ...]) -> list[str]:
    """The C statements that set the slot a number's term ``t`` reads so that ``t`` gives
    ``y`` (:func:`fretc.shield.runtime_values._message_write`), returning 0 when none can."""
    lines = []
    while t[0] != "slot":
        if t[0] == "neg":
            lines.append("y = -y;")
            t = t[1]
        else:
            lines += ["if (y < 0.0) {", "    return 0;", "}",
                      f"y = {c_message(t[2], 'n')} < 0.0 ? -y : y;"]
            t = t[2]
    return lines + [f"msg[{t[1]}] = y;"]


def _c_models(t: dict[str, Any]) -> tuple[dict[str, Any], ...]:
    """The models of machine table ``t``'s message groups as the C template reads them:
    the group's index, its atoms, witness rows, the decided variables (name, kind, read
    expression), the numbers written (index among them, C statements), the write orders
    tried after the first (:data:`fretc.shield.runtime_values.MESSAGE_ORDERS`), the atoms
    checked (atom index, variable index, op or None, constant) and the whole numbers."""
    out = []
    for gi, g in enumerate(t["groups"]):
        model = g.get("message")
        if not model:
            continue
        own = [(v, k, term) for v, k, term in model["reads"] if v not in model["passed"]]
        names = [v for v, _k, _t in own]
        terms = {v: term for v, _k, term in own}
        writes = [(names.index(v), _c_write(terms[v])) for v in model["writes"]]
        perms = (list(itertools.permutations(range(len(writes))))
                 if 0 < len(writes) <= MESSAGE_ORDERS else [])
        check = []
        for j in model["check"]:
            var, op, c = t["outputs"][j]
            check.append((j, names.index(var), None if op is None else
                          ["<", "<=", ">", ">=", "=", "!="].index(op), _double(c)
                          if op is not None else "0.0"))
        out.append({"i": gi, "atoms": model["atoms"],
                    "rows": [(key, [_double(x) for x in row])
                             for key, row in model["witness"].items()],
                    "nslots": max(1, len(model["slots"])),
                    "own": [(v, k, c_message(term, k)) for v, k, term in own],
                    "writes": writes, "perms": perms, "check": check,
                    "integers": [names.index(v) for v in model["integers"]]})
    return tuple(out)


#: slots of a machine's correction memo (direct-mapped; a power of two): an override whose
#: inputs, proposal and state were met before copies the correction found then (the same
#: answer as computing it again: the correction is a function of these alone)
def _term_variables(t: tuple[Any, ...]) -> set[str]:
    """The variables a comparison of several variables reads (:func:`c_term`'s shape)."""
    if t[0] == "var":
        return {t[1]}
    return set().union(*(_term_variables(x) for x in t[1:] if isinstance(x, tuple)))


MEMO_SLOTS = 256

#: the most states a machine's belief holds in C: the Python form's
#: :data:`fretc.shield.runtime.BELIEF_LIMIT`, so that both forms lose a machine's state at
#: the same tick
C_BELIEF_LIMIT = BELIEF_LIMIT
#: the most cases (a valuation of the free input atoms, then a state of the belief) a machine
#: decides one tick for: the Python form's :data:`fretc.shield.runtime.CASES_LIMIT`
C_CASES_LIMIT = CASES_LIMIT
#: the most input atoms a tick's unread numbers may leave free in one machine: their 2^k
#: valuations are each tried against ``env_ok`` (65,536 BDD walks at most); a machine whose
#: inputs can leave more free is lost at a tick that does (the Python form, which has no such
#: bound, may still decide it when few of those valuations are real)
C_FREE_LIMIT = 16


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
    # (the numbers the machines compare: a NaN there has no truth value, the runtime's
    # ValueError; a NaN elsewhere, a monitored requirement's, passes as in Python)
    compared: set[str] = set()
    for m in t["machines"]:
        for var, op, c in (*m["inputs"], *m["outputs"]):
            if op == "pred":
                compared |= _term_variables(c)
            elif op is not None:
                compared.add(var)
    twisted = {v for t in shield.twists for v in t}
    compared |= twisted  # (a twist's proposal is checked: a NaN or infinite one replaced)
    machines = _machines(shield, compared, names)
    outputs = [(v, v in shield.numbers or v in twisted) for v in _output_fields(shield)]
    # (the outputs of one message: a proposal one of them cannot be read replaces them all,
    # as the Python form's _replaced)
    mates = [[(v, v in shield.numbers or v in twisted)
              for v in dict.fromkeys([*(m["outputs"][j][0] for j in g["atoms"]),
                                      *g.get("decides", ())])]
             for m in t["machines"] for g in m["groups"]]
    ctx = {"p": base, "P": base.upper(), "shield": shield, "t": t, "machines": machines,
           "compared": compared, "mates": [g for g in mates if len(g) > 1],
           "inputs": [(v, v in shield.numbers) for v in shield.inputs if v in shield.read],
           "outputs": outputs,
           # the runner's CSV header (FRET names: any text, never a printf format)
           "header": "".join(["tick", *(f",{v}" for v, _n in outputs),
                              ",overridden,reasons,fault",
                              ",broken" if any(m["assumptions"] for m in t["machines"])
                              else "", "\n"]),
           "requirements": [r for m in t["machines"] for r in m["requirements"]],
           "assumptions": [a for m in t["machines"] for a in m["assumptions"]],
           "op_map": _C_OPS, "memo_slots": MEMO_SLOTS, "belief_limit": C_BELIEF_LIMIT,
           "cases_limit": C_CASES_LIMIT, "free_limit": C_FREE_LIMIT,
           "numeric": any(m.numeric_outputs for m in machines),
           "bounds": any(m.bound_fns for m in machines),
           "key_max": _key_max(), "double_max": _double(1.7976931348623157e308),
           "twist_count": sum(len(m.twists) for m in machines),
           "whole": any(v in m.t["integers"] for m in machines for v, _s, _i in m.numeric_outputs),
           "max_atoms": max([1] + [len(i) for m in machines for _v, _s, i in m.numeric_outputs])}
    return {f"{base}_shield.h": env.get_template("shield.h.j2").render(**ctx),
            f"{base}_shield.c": env.get_template("shield.c.j2").render(**ctx),
            f"{base}_shield_run.c": env.get_template("shield_runner.c.j2").render(**ctx)}
