"""Generate the template table (:mod:`fretc.compiler.template_table`) from :mod:`fretc.compiler.semantics`.

    python -m fretc.compiler.make_table [--out DIR]

Design notes: ARCHITECTURE.md, `compiler/make_table.py`."""

from __future__ import annotations

import argparse
import json
import os
import re

from fretc.fretish import ast as A

from fretc.compiler import ir
from fretc.compiler.ir import LAST, Node
from fretc.compiler.printers import to_smv, to_spot
from fretc.compiler.semantics import construct
from fretc.compiler.template_table import (ALL_KEYS, ATOMS, BOUND0, MAX_OFFSET, MIN_OFFSET, TABLE_DIR,
                             file_name)

__all__ = ["SymbolicBound", "build_template", "unify", "write_table", "main"]

_SENTINEL = 1_000_000_000  # a symbolic n: far from 0 and from every other bound


class SymbolicBound(int):
    """The duration ``n`` (plus ``offset``) of a template: an ``int`` (the sentinel plus the
    offset) for the constructors' comparisons, printed as the format field of its offset.
    ``AssertionError`` for an offset outside ``MIN_OFFSET .. MAX_OFFSET``."""

    offset: int

    def __new__(cls, offset: int) -> SymbolicBound:
        if not MIN_OFFSET <= offset <= MAX_OFFSET:
            raise AssertionError(f"template bound n{offset:+d} out of range")
        self = super().__new__(cls, _SENTINEL + offset)
        self.offset = offset
        return self

    def __add__(self, k):
        if type(k) is int:
            return SymbolicBound(self.offset + k)
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, k):
        if type(k) is int:
            return SymbolicBound(self.offset - k)
        return NotImplemented

    def __format__(self, spec: str) -> str:
        return "{%d}" % (BOUND0 + self.offset - MIN_OFFSET)

    __str__ = __repr__ = lambda self: self.__format__("")


def _placeholder(field: int) -> Node:
    """An atom standing for format field ``field`` in every printed form."""
    node = Node("ap", name=f"\x00atom{field}")
    node.text = node.ztext = node.stext = "{%d}" % field
    return node


PLACEHOLDERS = tuple(_placeholder(i) for i in range(3 * ATOMS))
_FIELD_OF = {id(p): i for i, p in enumerate(PLACEHOLDERS)}


def build_template(scope: str, cond: str, timing: str, n: int | None) -> dict:
    """The table file's data (module docstring of :mod:`fretc.compiler.template_table`) of one
    key, built with placeholder atoms by :func:`fretc.compiler.semantics.construct` (``n``:
    ticks, or a :class:`SymbolicBound`)."""
    ph = PLACEHOLDERS
    sets = [(ph[k + 3], None if cond == "null" else ph[k + 1],
             ph[k + 2] if timing in A.STOP_TIMINGS else None)
            for k in range(0, 3 * ATOMS, ATOMS)]
    calls = iter(sets)  # construct converts the fields for ft, ft_inf, pt in order

    def mode(kind: str, last: Node):
        if scope == "null":
            return None
        return ph[2 * ATOMS] if kind == "pt" else ph[0] if last is LAST else ph[ATOMS]

    with ir.recording_comparisons() as compared:
        ft, ft_inf, pt, _, _ = construct(scope, cond, timing, n, mode,
                                         lambda x: next(calls))
    # each pair once (a shared sub-formula is compared again and again), as the
    # conditions on the atoms under which it would be equal
    conditions: dict = {}
    pairs = set()
    for x, y in compared:
        if (id(x), id(y)) in pairs:
            continue
        pairs.add((id(x), id(y)))
        conj: list = []
        if unify(x, y, conj):
            conditions.setdefault(json.dumps(conj), conj)
    return {"ft": _checked(to_smv(ft)), "ft_inf": _checked(to_smv(ft_inf)),
            "pt": _checked(to_smv(pt, "(Z FALSE)")), "ft_spot": _spot_or_none(ft),
            "ft_inf_spot": _spot_or_none(ft_inf), "fallback": list(conditions.values())}


def _checked(text: str) -> str:
    """``text``; ``AssertionError`` when it holds a brace of its own (not a field) or a
    bound that lost its offset."""
    own = re.sub(r"\{\d+\}", "", text)
    if "{" in own or "}" in own or str(_SENTINEL)[:6] in own:
        raise AssertionError(f"template text {text!r}")
    return text


def _spot_or_none(node: Node) -> str | None:
    try:
        return _checked(to_spot(node))
    except ValueError:
        return None


def _data(t: Node):
    """A template node as plain data: its field number for a placeholder, else ``[op,
    name, lo, hi, [args]]`` with a symbolic bound ``n + k`` as ``[k]``."""
    f = _FIELD_OF.get(id(t))
    if f is not None:
        return f
    return [t.op, t.name, _bound_data(t.lo), _bound_data(t.hi), [_data(a) for a in t.args]]


def _bound_data(b):
    return [b.offset] if type(b) is SymbolicBound else b


def unify(x: Node, y: Node, out: list) -> bool:
    """Could template nodes ``x`` and ``y`` be equal once the placeholders are replaced by
    atoms and the symbolic bounds by ``n`` plus their offsets? False: never; True: exactly
    when every condition appended to ``out`` holds: ``[0, f, g]`` atom ``f`` equals atom
    ``g``, ``[1, f, t]`` atom ``f`` equals template node ``t`` instantiated, ``[2, k, v]``
    ``n + k == v``."""
    if x is y:
        return True
    fx, fy = _FIELD_OF.get(id(x)), _FIELD_OF.get(id(y))
    if fx is not None and fy is not None:
        out.append([0, fx, fy])
        return True
    if fx is not None or fy is not None:
        out.append([1, fx, _data(y)] if fx is not None else [1, fy, _data(x)])
        return True
    if x.op != y.op or x.name != y.name or len(x.args) != len(y.args):
        return False
    for bx, by in ((x.lo, y.lo), (x.hi, y.hi)):
        sx, sy = type(bx) is SymbolicBound, type(by) is SymbolicBound
        if sx and sy:
            if bx.offset != by.offset:  # type: ignore[union-attr]  # sx and sy
                return False
        elif sx or sy:
            if (bx if sx else by) is None or (by if sx else bx) is None:
                return False
            out.append([2, bx.offset, by] if sx else [2, by.offset, bx])  # type: ignore[union-attr]
        elif bx != by:
            return False
    return all(unify(a, b, out) for a, b in zip(x.args, y.args))


def file_text(key: tuple) -> str:
    """The text of ``key``'s table file: one JSON object, keys sorted, one line per entry
    and per fallback conjunction (diffs stay readable)."""
    scope, cond, timing, nkey = key
    data = build_template(scope, cond, timing, SymbolicBound(0) if nkey == -1 else nkey)
    data["key"] = [scope, cond, timing, "n" if nkey == -1 else nkey]
    lines = []
    for name in sorted(data):
        value = data[name]
        if name == "fallback":
            rows = ",\n".join("  " + json.dumps(c, separators=(",", ":")) for c in value)
            text = "[\n" + rows + "\n ]" if value else "[]"
        else:
            text = json.dumps(value, separators=(",", ":"))
        lines.append(f" {json.dumps(name)}: {text}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


def write_table(folder: str) -> int:
    """Write the file of every key of :data:`~fretc.compiler.template_table.ALL_KEYS` into
    ``folder`` (created when missing); returns the number of files."""
    os.makedirs(folder, exist_ok=True)
    for key in ALL_KEYS:
        with open(os.path.join(folder, file_name(key)), "w", encoding="utf-8",
                  newline="\n") as fh:
            fh.write(file_text(key))
    return len(ALL_KEYS)


def main(argv: list[str] | None = None) -> None:
    """``python -m fretc.compiler.make_table [--out DIR]``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=TABLE_DIR, help="folder (default: %(default)s)")
    args = ap.parse_args(argv)
    print(f"{write_table(args.out)} template files written to {args.out}")


if __name__ == "__main__":
    main()
