"""Bindings a newcomer can write: slices with REP 117 filtering, references to
other variables (acyclic, checked), misspelt variables, unused bindings."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.files import parse_bindings
from fretc.common.problems import BindingError

from _logs import scan

ROOT = Path(__file__).resolve().parents[2]


def _value(expr, msg, name="x", refs=None):
    b = compile_expression(name, expr, refs=refs)
    st = EvalState()
    st.msgs["/scan"] = msg
    st.times["/scan"] = 0
    return b.evaluate(st)


def test_slices_of_laserscan_ranges_apply_rep_117_to_the_slice():
    """``min(/base_scan.ranges[40:50])`` was a syntax error."""
    ranges = [5.0, 0.05, float("nan"), 0.7, float("-inf"), 2.0, 40.0]  # min 0.1, max 10
    msg = scan(ranges)
    assert _value("min(/scan.ranges[1:4])", msg) == pytest.approx(0.7)  # 0.05 and nan invalid
    assert _value("min(/scan.ranges[3:5])", msg) == pytest.approx(0.1)  # -inf is range_min
    assert _value("len(/scan.ranges[5:])", msg) == 1.0  # 40.0 is out of range
    assert _value("max(/scan.ranges[:1])", msg) == pytest.approx(5.0)
    # no valid return, and 40.0 an invalid measurement (outside range_max): unknown, never
    # the clear path +inf; a beam of +inf alone (no return) is the clear +inf
    assert math.isnan(_value("min(/scan.ranges[6:7])", msg))
    assert math.isinf(_value("min(/scan.ranges[6:7])", scan([5.0, float("inf")][1:] * 7)))


def test_variables_can_refer_to_other_variables():
    b = parse_bindings('[tick]\nperiod = "100 ms"\n[variables]\n'
                       'near = "front < 0.5"\nfront = "min(/scan.ranges)"\n'
                       'alarm = "near & !quiet"\nquiet = "false"\n')
    assert b.variables["near"].topics == {"/scan"}
    st = EvalState()
    st.msgs["/scan"] = scan([0.3, 2.0])
    st.times["/scan"] = 0
    assert b.variables["near"].evaluate(st) is True
    assert b.variables["alarm"].evaluate(st) is True


def test_reference_cycles_and_unknown_names_are_errors():
    with pytest.raises(BindingError, match="cycle: a -> b -> a"):
        parse_bindings('[tick]\nperiod = "1 s"\n[variables]\na = "b & true"\nb = "!a"\n')
    with pytest.raises(BindingError, match="did you mean 'front'"):
        parse_bindings('[tick]\nperiod = "1 s"\n[variables]\nfront = "/s.x"\n'
                       'near = "frnt < 0.5"\n')


def test_misspelt_variable_gets_a_suggestion_and_unused_bindings_a_warning(tmp_path):
    (tmp_path / "m.fret").write_text("M1: the bot shall always satisfy clearnce > 0\n")
    (tmp_path / "m.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nclearance = "/ground_truth/clearance.data"\n')
    res = CliRunner().invoke(main, ["audit", "--no-progress", "-r", str(tmp_path / "m.fret"),
                                    str(ROOT / "traces" / "sif_disabled.mcap")])
    out = " ".join(res.output.split())
    assert res.exit_code == 2
    assert "did you mean 'clearance' for 'clearnce'?" in out
    assert "'clearance' is bound but no requirement uses it" in out
