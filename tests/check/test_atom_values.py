"""Numbers for comparisons of several variables (:mod:`fretc.check.atom_values`): whenever
z3 gives a tick's numbers, the audit's own evaluator reads every comparison with the truth
value the abstraction's letter asked; requirements over arithmetic (the case studies'
``yout = timeStep * 0.5 * (xin + xinpv) + ypv``) get tests for every obligation."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.testing.generate import generate
from fretc.check.atom_values import concrete_rows, free_atoms
from fretc.compiler import ir
from fretc.compiler.build import compile_entries
from fretc.compiler.evaluate import ft_at
from fretc.compiler.printers import to_smv
from fretc.fretish.files import load_requirements

_VARS = ("a", "b", "c")
_terms = st.recursive(
    st.one_of(st.sampled_from(_VARS).map(ir.var),
              st.sampled_from(["0", "1", "2", "0.5", "-3", "10"]).map(ir.num)),
    lambda inner: st.builds(ir.arith, st.sampled_from(["+", "-", "*", "/"]), inner, inner),
    max_leaves=5)
_cmps = st.builds(ir.cmp, st.sampled_from(["=", "!=", "<", "<=", ">", ">="]), _terms, _terms)


def _holds(atom, row) -> bool | None:
    """The comparison at one tick by the reference evaluator."""
    return ft_at(atom, [row], 0)


@settings(max_examples=150, deadline=None)
@given(st.lists(_cmps, min_size=1, max_size=3), st.data())
def test_numbers_give_the_letters_truth(atoms, data):
    free = free_atoms(atoms)
    letter = {k: data.draw(st.booleans(), label=k) for k in sorted(free)}
    row = {v: 0.0 for v in _VARS}
    got = concrete_rows([row], [letter], free)[0]
    if got == row and not all(_holds(free[k], row) is v for k, v in letter.items()):
        return  # z3 found no numbers (unsat or beyond its limit): the row is unchanged
    for key, want in letter.items():
        assert _holds(free[key], got) is want, (to_smv(free[key]), want, got)


def test_one_variable_comparisons_join_the_query():
    """``a > 3`` (the abstraction's) and ``a = b`` (free) share ``a``: z3 keeps both."""
    gt, eq = ir.cmp(">", ir.var("a"), ir.num("3")), ir.cmp("=", ir.var("a"), ir.var("b"))
    free = free_atoms([ir.and_(gt, eq)])
    assert set(free) == {to_smv(gt), to_smv(eq)}
    got = concrete_rows([{"a": 0.0, "b": 0.0}], [{to_smv(gt): True, to_smv(eq): False}], free)
    assert got[0]["a"] > 3 and got[0]["a"] != got[0]["b"]


def test_arithmetic_requirement_gets_every_test(tmp_path):
    """Every obligation of a requirement on an arithmetic identity is met by a confirmed
    test (each number 0 used to make the identity true whatever the model asked)."""
    p = tmp_path / "tustin.fret"
    p.write_text("T: Tustin shall always satisfy normal => "
                 "yout = timeStep * 0.5 * (xin + xinpv) + ypv\n"
                 "P: when in hdg Autopilot shall always satisfy "
                 "(Psi - (cmd - zero)) / (cmd - zero) <= 0.1\n")
    gen = generate(compile_entries(load_requirements([p])), fork=False)
    assert not gen.unknown, gen.unknown
    met = {(r, o) for t in gen.tests for r, o, _ in t.covers}
    assert ("T", "response:normal+") in met and ("P", "timing:immediately") in met
