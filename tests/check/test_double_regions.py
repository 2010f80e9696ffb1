"""The regions of one variable's comparisons in doubles
(:meth:`fretc.check.numeric_abstraction.NumericAbstraction.region` with ``doubles``, the
shield's game): exactly the truth values some double gives, each constant read as the
double nearest it, as the monitors and the shield's forms compute; against the truth values
of many doubles (the constants, their neighbours, random ones)."""

from __future__ import annotations

import math
from fractions import Fraction

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.check.numeric_abstraction import NumericAbstraction
from fretc.compiler import ir

OPS = ["<", "<=", ">", ">=", "=", "!="]
TEST = {"<": lambda v, c: v < c, "<=": lambda v, c: v <= c, ">": lambda v, c: v > c,
        ">=": lambda v, c: v >= c, "=": lambda v, c: v == c, "!=": lambda v, c: v != c}

#: constants: doubles, and decimal texts one ulp or less apart (two literals, one double)
constants = st.one_of(
    st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False).map(repr),
    st.sampled_from(["0.1", "0.10000000000000001", "1", "1.0000000000000002",
                     "1.0000000000000001", "0", "-0.0", "1e999", "-1e999", "2.5"]))


def _atom(op: str, text: str):
    return ir.cmp(op, ir.var("y"), ir.num(text))


def _holds(f, truth: dict) -> bool:
    """A propositional IR formula over comparison atoms under ``truth``."""
    if f.op == "true":
        return True
    if f.op == "false":
        return False
    if f.op == "!":
        return not _holds(f.args[0], truth)
    if f.op == "&":
        return all(_holds(a, truth) for a in f.args)
    if f.op == "|":
        return any(_holds(a, truth) for a in f.args)
    return truth[f]


def _truths(region, atoms) -> set[tuple[bool, ...]]:
    """The truth tuples a propositional disjunction of cubes over ``atoms`` allows (every
    tuple when TRUE)."""
    out = set()
    for k in range(2 ** len(atoms)):
        t = tuple(bool(k >> i & 1) for i in range(len(atoms)))
        if _holds(region, dict(zip(atoms, t))):
            out.add(t)
    return out


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(OPS), constants), min_size=1, max_size=4,
                unique=True),
       st.lists(st.floats(allow_nan=False), max_size=30))
def test_double_regions_are_the_truths_doubles_give(comparisons, samples):
    atoms = [_atom(op, c) for op, c in comparisons]
    if len(set(atoms)) < len(atoms):
        return
    phi = ir.and_all(*(ir.G(a) for a in atoms))
    numeric = NumericAbstraction.of([phi])
    allowed = _truths(numeric.region("y", doubles=True), atoms)
    consts = [float(Fraction(c)) if "e999" not in c else math.copysign(math.inf, float(c))
              for _op, c in comparisons]
    doubles = list(samples) + [math.inf, -math.inf, 0.0]
    for c in consts:
        doubles += [c, math.nextafter(c, math.inf), math.nextafter(c, -math.inf)]
    given_by_doubles = {tuple(TEST[op](v, c) for (op, _t), c in zip(comparisons, consts))
                        for v in doubles}
    # every double's truths are allowed; every allowed truth is some double's (the
    # regions' representatives are among the samples: the constants and their neighbours)
    assert given_by_doubles <= allowed, (comparisons, given_by_doubles - allowed)
    assert allowed <= given_by_doubles, (comparisons, allowed - given_by_doubles)


def test_two_literals_of_one_double_leave_no_value_between():
    atoms = [_atom(">", "0.1"), _atom("<", "0.10000000000000001")]
    numeric = NumericAbstraction.of([ir.G(ir.and_(*atoms))])
    assert (True, True) in _truths(numeric.region("y"), atoms)  # a real between them
    assert (True, True) not in _truths(numeric.region("y", doubles=True), atoms)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(OPS), st.one_of(
    st.integers(-6, 6).map(str), st.sampled_from(["0.5", "-1.5", "2.25", "1e999", "-1e999",
                                                  "3.0000000000000001"]))),
    min_size=1, max_size=4, unique=True))
def test_integer_regions_are_the_truths_whole_numbers_give(comparisons):
    """``integer``: the regions are exactly the truths of the whole numbers (as doubles, as
    the shield computes); ``y > 1 & y < 2`` has none."""
    atoms = [_atom(op, c) for op, c in comparisons]
    if len(set(atoms)) < len(atoms):
        return
    numeric = NumericAbstraction.of([ir.and_all(*(ir.G(a) for a in atoms))])
    allowed = _truths(numeric.region("y", doubles=True, integer=True), atoms)
    consts = [float(c) for _op, c in comparisons]
    # every region of whole numbers is met between -10 and 10 (the constants are within 7)
    given_by_integers = {tuple(TEST[op](float(v), c) for (op, _t), c in zip(comparisons, consts))
                         for v in range(-10, 11)}
    assert allowed == given_by_integers, (comparisons, allowed ^ given_by_integers)


def test_no_whole_number_lies_strictly_between_1_and_2():
    atoms = [_atom(">", "1"), _atom("<", "2")]
    numeric = NumericAbstraction.of([ir.G(ir.and_all(*atoms))])
    assert (True, True) in _truths(numeric.region("y", doubles=True), atoms)
    assert (True, True) not in _truths(numeric.region("y", doubles=True, integer=True), atoms)
    assert (True, True) not in _truths(numeric.regions(["y"], True, integers=["y"]), atoms)
