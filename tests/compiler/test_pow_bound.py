"""``x ^ n`` with integer operands whose result is beyond a float (2**1024) is NaN at once, in
the generated monitors and the reference evaluator, as in the column engine (overflow is
NaN), never an exact big integer computed for minutes (found by bench/fuzz.py: ``y ^
1000000000000000000000000000000`` stepped with y = 2 hung the monitor)."""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

from fretc.compiler import codegen
from fretc.compiler.evaluate import _arith

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import fuzz  # noqa: E402


def test_generated_monitor_steps_a_huge_integer_power_at_once():
    c, rejected = fuzz.front("the sw shall always satisfy x + 2 * y ^ "
                             "1000000000000000000000000000000 <= z", "P")
    assert rejected is None
    ns: dict = {}
    exec(compile(codegen.render_module([c], "m", []), "m", "exec"), ns)
    m = ns["MONITORS"]["P"]()
    t0 = time.process_time()
    assert m.step({"x": 1, "y": 2, "z": 3}) is False  # NaN <= 3 is false
    assert time.process_time() - t0 < 1


def test_reference_evaluator_power_bound():
    t0 = time.process_time()
    assert math.isnan(_arith("^", 2, 10**30))
    assert time.process_time() - t0 < 1
    assert _arith("^", 2, 10) == 1024 and _arith("^", -3, 3) == -27
    assert _arith("^", 1, 10**30) == 1 and _arith("^", 2, 1023) == 2**1023
