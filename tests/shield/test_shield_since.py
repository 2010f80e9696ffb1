"""``fretc shield`` enforces a requirement reading a FRET boolean stream monotone in its
previous value (the mode latch ``m := false -> (enter or (pre m and not exit))``): the game
reads its past-time formula ``P S psi`` (fretish/fret_since.py), and the runtime's outputs
follow the latch as the audit and the monitors compute it tick by tick
(compiler/stream_code.py). A numeric stream is still refused with its reason; a boolean one
not monotone in its previous value (reading booleans only) is enforced by its state bit."""

from __future__ import annotations

import json
import random
import types
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from fretc.cli import main
from fretc.compiler.stream_code import stream_columns
from fretc.fretish.fret_streams import stream_system
from fretc.fretish.fret_variables import fret_variables
from fretc.shield.runtime import ShieldRuntime

LATCH = "false -> (enter or (pre m and not exit))"
from _gen import fret_export, fret_var


def _export(tmp_path: Path, texts: list[str]) -> Path:
    return fret_export(tmp_path, texts, [fret_var("enter", "Input"), fret_var("exit", "Input"), fret_var("o", "Output"),
                                         fret_var("x", "Input", data_type="double"),
                                         fret_var("m", "Internal", LATCH),
                                         fret_var("t", "Internal", "false -> not pre t"),
                                         fret_var("h", "Internal", "x -> if enter then x else pre h", "double")])


def _latch(path: Path, ticks: list[tuple[bool, bool]]) -> list[bool]:
    """The latch over ``ticks`` as the audit computes it (Lustre's semantics)."""
    variables = tuple(fret_variables(json.loads(path.read_text()), str(path)))
    system = stream_system(variables, ["m"])
    assert system is not None and system.inputs == ("enter", "exit")
    cols = {"enter": np.array([e for e, _ in ticks]), "exit": np.array([x for _, x in ticks])}
    return stream_columns(system, cols, len(ticks))["m"].tolist()


def test_the_shield_enforces_a_requirement_reading_the_latch(tmp_path):
    path = _export(tmp_path, ["whenever m ctrl shall immediately satisfy o",
                              "whenever exit & !enter ctrl shall immediately satisfy !o"])
    got = CliRunner().invoke(main, ["shield", str(path), "--emit", "python",
                                    "-o", str(tmp_path / "out")])
    assert got.exit_code == 0, got.output
    assert "enforces R1, R2" in got.output and "stream variable" not in got.output
    module = types.ModuleType("shield_since")
    exec(compile((tmp_path / "out" / "p_shield.py").read_text(), "p_shield", "exec"),
         module.__dict__)
    rt = ShieldRuntime(module.TABLES)
    rng = random.Random(7)
    fixed = [(False, False), (True, False), (False, False), (False, True), (False, False),
             (True, True), (False, True), (True, False), (False, False), (False, False)]
    for ticks in [fixed] + [[(rng.random() < 0.3, rng.random() < 0.3) for _ in range(30)]
                            for _ in range(5)]:
        m = _latch(path, ticks)
        if ticks is fixed:  # (false at the first tick; set by enter, reset by exit alone)
            assert m == [False, True, True, False, False, True, False, True, True, True]
        for proposed in (False, True):
            rt.reset()
            for k, ((enter, ex), latched) in enumerate(zip(ticks, m)):
                d = rt.step({"enter": enter, "exit": ex}, {"o": proposed})
                reset = ex and not enter
                # (the latch forces o; a reset, where the latch is false, forbids it; the
                # shield changes the proposal only then)
                want = True if latched else (False if reset else proposed)
                assert bool(d.outputs["o"]) == want, (ticks, k, d)
                assert d.overridden == (want != proposed), (ticks, k, d)


def test_the_other_streams_are_refused_with_their_reason(tmp_path):
    """The toggle ``t`` reads booleans only: the shield enforces it by its state bit
    (tests/shield/test_shield_stream_bits.py); a numeric stream is refused."""
    path = _export(tmp_path, ["whenever t ctrl shall immediately satisfy o",
                              "whenever h > 2.0 ctrl shall immediately satisfy o"])
    got = CliRunner().invoke(main, ["shield", str(path), "--exclude", "R2"])
    assert got.exit_code == 0, got.output
    assert "enforces R1" in got.output and "stream variable" not in got.output
    got = CliRunner().invoke(main, ["shield", str(path), "--exclude", "R1"])
    assert got.exit_code == 2, got.output
    assert ("R2 reads the FRET stream variable h (its definition x -> if enter then x else "
            "pre h reads enter, x now and through pre; a numeric stream is a stored real "
            "number, a memory of a past value: no finite game holds it)"
            ) in " ".join(got.output.split())


def test_testgen_reads_the_latch_as_a_definition(tmp_path):
    """testgen's notes name the streams it gives values of their own
    (check.streams.streams_of_entry): the latch is none, the toggle still one. (Its
    obligations may end unknown, exit 3: Spot's traces read ft's derived past atom, the
    latch's since, as a free proposition, as for FRET's other past-time functions.)"""
    path = _export(tmp_path, ["whenever m ctrl shall immediately satisfy o",
                              "whenever t ctrl shall immediately satisfy o"])
    got = CliRunner().invoke(main, ["testgen", str(path), "-o", str(tmp_path / "tests")])
    assert got.exit_code in (0, 3), got.output
    assert "note: t (read by R2) is a FRET stream variable" in got.output
    assert "note: m (read by" not in got.output
