"""A comparison of constants (``3.0 >= 0``, as a FRET export's Internal constants make of
``level >= 0``) is its truth value for check and shield (:func:`fretc.compiler.ir.fold_constants`)
when exact and double arithmetic agree on it:
``fretc check`` abstracted it as a free proposition (``ctrl shall always satisfy 3.0 >= 0 &
ok`` was unrealizable, exit 1) and ``fretc shield`` ended with an internal error. One
they disagree on (``0.1 + 0.2 = 0.3``) is kept as written, so that the monitors, which
compute in doubles, keep their verdicts; the shield refuses it with the reason."""

from __future__ import annotations

from fractions import Fraction

from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli import main
from fretc.compiler import ir

OPS = ["=", "!=", "<", "<=", ">", ">="]
LITERALS = ["0", "3.0", "-2", "0.1", "0.2", "0.3", "1e-3", "2.5e2", "7"]


def _term(draw) -> tuple[ir.Node, Fraction, float]:
    a, b = draw(st.sampled_from(LITERALS)), draw(st.sampled_from(LITERALS))
    op = draw(st.sampled_from(["+", "-", "*", "/", None, "neg"]))
    if op is None:
        return ir.num(a), Fraction(a), float(a)
    if op == "neg":
        return ir.Node("neg", (ir.num(a),)), -Fraction(a), -float(a)
    if op == "/" and Fraction(b) == 0:
        b = "7"
    f = {"+": lambda x, y: x + y, "-": lambda x, y: x - y, "*": lambda x, y: x * y,
         "/": lambda x, y: x / y}[op]
    return ir.arith(op, ir.num(a), ir.num(b)), f(Fraction(a), Fraction(b)), f(float(a), float(b))


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_folded_exactly_when_reals_and_doubles_agree(data):
    (x, qx, dx), (y, qy, dy) = _term(data.draw), _term(data.draw)
    op = data.draw(st.sampled_from(OPS))
    cmp = {"=": lambda p, q: p == q, "!=": lambda p, q: p != q, "<": lambda p, q: p < q,
           "<=": lambda p, q: p <= q, ">": lambda p, q: p > q, ">=": lambda p, q: p >= q}[op]
    kept = ir.cmp(op, x, y)
    assert kept.op == "cmp"  # (the emitted formulas print it as FRET does)
    got = ir.fold_constants(ir.and_(ir.ap("p"), kept))
    if cmp(qx, qy) == cmp(dx, dy):
        assert got == (ir.ap("p") if cmp(qx, qy) else ir.FALSE)
    else:
        assert got == ir.and_(ir.ap("p"), kept)
    free = ir.cmp(op, ir.var("v"), y)  # (a variable: never folded)
    assert ir.fold_constants(free) is free


def test_check_and_shield_read_a_comparison_of_constants_as_its_truth(tmp_path):
    f = tmp_path / "c.fret"
    f.write_text("R2: ctrl shall always satisfy 3.0 >= 0 & ok\n", encoding="utf-8")
    got = CliRunner().invoke(main, ["check", str(f), "--outputs", "ok", "--no-progress"])
    assert got.exit_code == 0 and "R2: realizable" in got.output, got.output
    got = CliRunner().invoke(main, ["shield", str(f), "--outputs", "ok"])
    assert got.exit_code == 0, got.output
    f.write_text("R3: ctrl shall always satisfy 0.1 + 0.2 = 0.3 | ok\n", encoding="utf-8")
    got = CliRunner().invoke(main, ["shield", str(f), "--outputs", "ok"])
    assert got.exit_code == 2 and "comparison of constants ((0.1 + 0.2) = 0.3)" in got.output
