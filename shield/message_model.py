"""The message a group of outputs is: their bindings as terms over the message's fields, so
that every form of the shield decides values one message gives (KP-124).

Design notes: ARCHITECTURE.md, `shield/message_model.py`."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from fretc.shield.runtime_values import message_value, truth
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.expression import BinOp, Const, Expr, Field, FuncCall, UnaryOp
from fretc.signals.bindings.spec import Bindings

__all__ = ["NotModelled", "term_of", "model_of", "table_of", "writable", "group_atoms"]

_CMP = ("<", "<=", ">", ">=", "=", "!=")
_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "=": "=", "!=": "!="}


class NotModelled(Exception):
    """A binding no term of the model writes (module docstring): the message says which
    part."""


def term_of(e: Expr, slots: dict[tuple[str, tuple[str, ...]], int]) -> tuple[Any, ...]:
    """The binding ``e`` as a term of the model (module docstring), each field it reads
    given a slot in ``slots`` (field -> index, grown in first-read order).

    Raises:
        NotModelled: a part that is no such term."""
    if isinstance(e, Field):
        if not e.path or e.filters or not all(isinstance(p, str) for p in e.path):
            raise NotModelled(f"{e.text()}: only a field of attribute names")
        key = (e.topic, tuple(str(p) for p in e.path))
        return ("slot", slots.setdefault(key, len(slots)))
    if isinstance(e, Const):
        if isinstance(e.value, bool):
            return ("num", 1.0 if e.value else 0.0)
        if isinstance(e.value, float):
            return ("num", e.value)
        raise NotModelled(f"the constant {e.value!r}")
    if isinstance(e, UnaryOp):
        return ("not" if e.op == "!" else "neg", term_of(e.arg, slots))
    if isinstance(e, FuncCall):
        if e.func == "abs" and len(e.args) == 1:
            return ("fn", "abs", term_of(e.args[0], slots))
        if e.func in ("min", "max") and len(e.args) == 1 and isinstance(e.args[0], Field):
            return term_of(e.args[0], slots)  # (one element, as the inversion writes it)
        raise NotModelled(f"{e.func}()")
    if isinstance(e, BinOp):
        if e.op in _CMP:
            return _comparison(e, slots)
        a, b = term_of(e.left, slots), term_of(e.right, slots)
        if e.op == "&":
            return ("and", a, b)
        if e.op == "|":
            return ("or", a, b)
        if e.op == "->":
            return ("or", ("not", a), b)
        if e.op == "<->":
            return ("iff", a, b)
        raise NotModelled(f"the operator {e.op}")
    raise NotModelled(type(e).__name__)


def _comparison(e: BinOp, slots: dict[tuple[str, tuple[str, ...]], int]) -> tuple[Any, ...]:
    """A comparison: a boolean compared with ``true``/``false`` is itself or its negation
    (the binding language compares booleans so); else ``("cmp", op, a, b)``.

    Raises:
        NotModelled: a string, a named constant, ``age()``."""
    left, right, op = e.left, e.right, e.op
    if isinstance(left, Const) and isinstance(left.value, bool):
        left, right, op = right, left, _FLIP[op]
    if isinstance(right, Const) and isinstance(right.value, bool) and op in ("=", "!="):
        t = term_of(left, slots)
        return t if (op == "=") == right.value else ("not", t)
    for side in (left, right):
        if isinstance(side, FuncCall) and side.func == "age":
            raise NotModelled("age(): no field of the message")
    return ("cmp", op, term_of(left, slots), term_of(right, slots))


def writable(t: tuple[Any, ...]) -> bool:
    """Whether a number's term is a field, ``-x`` or ``abs(x)`` of a writable one."""
    if t[0] == "slot":
        return True
    if t[0] == "neg":
        return writable(t[1])
    return t[0] == "fn" and t[1] == "abs" and writable(t[2])


def _boolean(t: tuple[Any, ...]) -> bool:
    return t[0] in ("not", "and", "or", "iff", "cmp")


def model_of(variables: list[str], passed: list[str], kinds: dict[str, str],
             bindings: Bindings,
             valuations: list[tuple[dict[str, bool], dict[Any, Any], dict[str, float]]],
             atom_specs: dict[str, tuple[str, str | None, Any]]
             ) -> tuple[dict[str, Any] | None, str]:
    """The model of a message group (module docstring) in the plan's terms, or None and why
    not: ``variables`` its outputs that requirements read (``kinds``: variable -> ``"b"`` or
    ``"n"``), ``passed`` the others bound to its topics, ``valuations`` the plan's (atom text
    -> value, the witness's fields, its numbers), ``atom_specs`` atom text -> ``(variable,
    op, constant)``. The witnesses are kept per valuation in the plan's order, as
    ``[(valuation, values per slot)]`` under ``"witnesses"``."""
    slots: dict[tuple[str, tuple[str, ...]], int] = {}
    reads: list[tuple[str, str, tuple[Any, ...]]] = []
    try:
        for v in [*variables, *passed]:
            t = term_of(bindings.variables[v].ast, slots)
            kind = kinds.get(v) or ("b" if _boolean(t) else "n")
            reads.append((v, kind, t))
    except NotModelled as exc:
        return None, f"{exc}"
    if all(kinds.get(v) != "n" for v in variables):
        return None, ""  # (booleans only: the decided atoms are the values, one message's)
    keys = list(slots)
    witnesses: list[tuple[dict[str, bool], list[Any]]] = []
    for vals, fields, nums in valuations:
        row: list[Any] = []
        for k in keys:
            x = fields.get(k, 0.0)
            if isinstance(x, list):
                x = x[0] if x else 0.0
            if isinstance(x, bool):
                x = 1.0 if x else 0.0
            if not isinstance(x, (int, float)):
                return None, f"the field {k[0]}.{'.'.join(k[1])} holds {x!r}"
            row.append(float(x))
        why = _agrees(reads, row, keys, vals, nums, atom_specs, bindings)
        if why:
            return None, why
        witnesses.append((vals, row))
    bools = {i for _v, k, t in reads if k == "b" and t[0] == "slot" for i in [t[1]]}
    model = {"slots": [(t, list(p)) for t, p in keys], "reads": reads,
             "passed": list(passed),
             "writes": [v for v, k, t in reads if k == "n" and v not in passed and writable(t)
                        and not _reads_bool_slot(t, bools)],
             "witnesses": witnesses}
    return model, ""


def _reads_bool_slot(t: tuple[Any, ...], bools: set[int]) -> bool:
    """Whether a number's term ends in a slot a boolean variable reads as a boolean."""
    while t[0] != "slot":
        t = t[1] if t[0] == "neg" else t[2]
    return t[1] in bools


def _agrees(reads: list[tuple[str, str, tuple[Any, ...]]], row: list[Any],
            keys: list[tuple[str, tuple[str, ...]]], vals: dict[str, bool],
            nums: dict[str, float], atom_specs: dict[str, tuple[str, str | None, Any]],
            bindings: Bindings) -> str:
    """Why the terms do not give the witness ``row`` its valuation, its numbers or the
    binding language's values ("" when they do)."""
    got = {v: (bool(message_value(t, row)) if k == "b" else float(message_value(t, row)))
           for v, k, t in reads}
    for text, want in vals.items():
        spec = atom_specs[text]
        if truth(spec, got[spec[0]]) != want:
            return f"its terms do not give {text} on the message solved for it"
    for v, x in nums.items():
        if v in got and got[v] != x:
            return f"its terms do not give {v} = {x!r} on the message solved for it"
    msgs: dict[str, Any] = {}
    for (topic, path), x in zip(keys, row):
        owner = msgs.setdefault(topic, SimpleNamespace())
        for name in path[:-1]:
            owner = owner.__dict__.setdefault(name, SimpleNamespace())
        setattr(owner, path[-1], x)
    st = EvalState()
    st.msgs, st.now, st.times = msgs, 0, {t: 0 for t in msgs}
    for v, _k, _t in reads:
        try:
            x = bindings.variables[v].evaluate(st)
        except Exception as exc:  # noqa: BLE001 - (the binding's reading of the witness)
            return f"{v}'s binding does not read the message solved ({exc})"
        if not (x == got[v] or (isinstance(x, bool) and bool(x) == got[v])):
            return f"its terms give {v} = {got[v]!r}, the binding {x!r}"
    return ""


def group_atoms(texts: list[str],
                valuations: list[tuple[dict[str, bool], Any, Any]]) -> list[int]:
    """A message group's output atoms, the machine's indices (``texts`` its output atoms'
    texts) of the atoms its ``valuations`` value, in order: the bits of a valuation key."""
    return sorted({j for vals, _f, _n in valuations for j, t in enumerate(texts) if t in vals})


def table_of(model: dict[str, Any], texts: list[str], atoms: list[int],
             specs: list[tuple[str, str | None, Any]], integers: list[str]) -> dict[str, Any]:
    """The model as the runtimes' tables hold it (module docstring): ``witness`` keyed by
    the valuation's bits over ``atoms`` (the machine's output atom indices of the group, in
    order; ``texts`` every output atom's text), ``check`` every atom of the machine reading
    one of the group's variables (``specs`` the machine's output atoms)."""
    witness = {}
    for vals, row in model["witnesses"]:
        key = sum(int(vals[texts[j]]) << i for i, j in enumerate(atoms))
        witness[key] = list(row)
    own = {v for v, _k, _t in model["reads"] if v not in model["passed"]}
    return {"atoms": list(atoms), "slots": [[t, list(p)] for t, p in model["slots"]],
            "reads": [[v, k, t] for v, k, t in model["reads"]],
            "passed": list(model["passed"]), "writes": list(model["writes"]),
            "witness": dict(sorted(witness.items())),
            "check": [j for j, s in enumerate(specs) if s[0] in own and s[1] != "pred"],
            "integers": [v for v in integers if v in own]}
