"""``fretc shield`` enforces a requirement reading a FRET boolean stream of booleans that is
not monotone in its previous value (the toggle ``t := false -> (a xor pre t)``): the game
keeps the toggle's state bit (IR ``stream``, check/pt_monitor.py), and the Python runtime
and the C form, which execute the synthesized node tables, force ``o`` exactly at the ticks
where the toggle, as the audit computes it (compiler/stream_code.py), is true. A numeric
stream and a boolean stream reading a number are still refused, each with its reason."""

from __future__ import annotations

import csv
import io
import json
import random
import subprocess
import types
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.compiler.stream_code import stream_columns
from fretc.fretish.fret_streams import stream_system
from fretc.fretish.fret_variables import fret_variables
from fretc.shield.runtime import ShieldRuntime

from _c_monitors import build, needs_cc

TOGGLE = "false -> (a xor pre t)"
from _gen import fret_export, fret_var


def _export(tmp_path: Path, texts: list[str]) -> Path:
    return fret_export(tmp_path, texts, [fret_var("a", "Input"), fret_var("o", "Output"),
                                         fret_var("x", "Input", data_type="double"),
                                         fret_var("t", "Internal", TOGGLE),
                                         fret_var("m", "Internal", "false -> (a or pre m)"),
                                         fret_var("g", "Internal", "false -> ((x > pre x) xor pre g)"),
                                         fret_var("k", "Internal", "false -> ((x > 1.0) xor pre k)"),
                                         fret_var("h", "Internal", "x -> if a then x else pre h", "double")])


def _toggle(path: Path, a: list[bool]) -> list[bool]:
    """The toggle over ``a`` as the audit computes it (Lustre's semantics)."""
    variables = tuple(fret_variables(json.loads(path.read_text()), str(path)))
    system = stream_system(variables, ["t"])
    assert system is not None and system.inputs == ("a",)
    return stream_columns(system, {"a": np.array(a)}, len(a))["t"].tolist()


def _runs() -> list[list[bool]]:
    rng = random.Random(11)
    fixed = [False, True, False, False, True, True, False, True]
    return [fixed] + [[rng.random() < 0.5 for _ in range(40)] for _ in range(8)]


def test_the_shield_enforces_a_requirement_reading_a_toggle(tmp_path):
    path = _export(tmp_path, ["whenever t ctrl shall immediately satisfy o"])
    out = tmp_path / "out"
    got = CliRunner().invoke(main, ["shield", str(path), "--emit", "python", "--emit", "c",
                                    "-o", str(out)])
    assert got.exit_code == 0, got.output
    assert "enforces R1" in got.output and "stream variable" not in got.output
    module = types.ModuleType("shield_toggle")
    exec(compile((out / "p_shield.py").read_text(), "p_shield", "exec"), module.__dict__)
    rt = ShieldRuntime(module.TABLES)
    for a in _runs():
        t = _toggle(path, a)
        if len(a) == 8:  # (false at the first tick; flipped by each a after it)
            assert t == [False, True, True, True, False, True, True, False]
        for proposed in (False, True):
            rt.reset()
            for k, (ak, tk) in enumerate(zip(a, t)):
                d = rt.step({"a": ak, "x": 0.0}, {"o": proposed})
                want = True if tk else proposed
                assert bool(d.outputs["o"]) == want, (a, k, d)
                assert d.overridden == (want != proposed), (a, k, d)
    # the C form, built with the strict flags and sanitizers, decides alike
    needs_cc()
    exe = build(out, ["p_shield.c", "p_shield_run.c"], "run")
    for a in _runs():
        t = _toggle(path, a)
        for proposed in (False, True):
            text = "a,x,o\n" + "".join(f"{'true' if ak else 'false'},0.0,"
                                       f"{'true' if proposed else 'false'}\n" for ak in a)
            ran = subprocess.run([str(exe)], input=text, capture_output=True, text=True,
                                 timeout=60)
            assert ran.returncode == 0 and not ran.stderr, ran.stderr
            rows = list(csv.DictReader(io.StringIO(ran.stdout)))
            assert [r["o"] == "1" for r in rows] == [tk or proposed for tk in t], (a, rows)
            assert [r["overridden"] == "1" for r in rows] == [tk and not proposed for tk in t]


def test_a_stream_reading_a_comparison_of_the_tick_is_enforced_by_its_bit(tmp_path):
    """``k := false -> ((x > 1.0) xor pre k)``: the comparison is an atom of the tick, so
    ``k`` is one state bit over it; the shield's runtime forces ``o`` exactly where ``k``,
    as the audit computes it from ``x``, is true."""
    path = _export(tmp_path, ["whenever k ctrl shall immediately satisfy o"])
    out = tmp_path / "out"
    got = CliRunner().invoke(main, ["shield", str(path), "--emit", "python", "-o", str(out)])
    assert got.exit_code == 0, got.output
    module = types.ModuleType("shield_k")
    exec(compile((out / "p_shield.py").read_text(), "p_shield", "exec"), module.__dict__)
    rt = ShieldRuntime(module.TABLES)
    variables = tuple(fret_variables(json.loads(path.read_text()), str(path)))
    system = stream_system(variables, ["k"])
    assert system is not None and system.inputs == ("x",)
    rng = random.Random(5)
    for _ in range(6):
        x = [rng.choice([0.0, 0.5, 1.0, 1.5, 3.0]) for _ in range(30)]
        k = stream_columns(system, {"x": np.array(x)}, len(x))["k"].tolist()
        assert any(k) and not all(k)
        rt.reset()
        for xk, kk in zip(x, k):
            d = rt.step({"a": False, "x": xk}, {"o": False})
            assert bool(d.outputs["o"]) == kk and d.overridden == kk, (x, k, d)


def test_a_numeric_stream_and_a_boolean_one_reading_a_number_are_still_refused(tmp_path):
    path = _export(tmp_path, ["whenever h > 2.0 ctrl shall immediately satisfy o",
                              "whenever g ctrl shall immediately satisfy o"])
    got = CliRunner().invoke(main, ["shield", str(path), "--exclude", "R2"])
    assert got.exit_code == 2, got.output
    assert ("R1 reads the FRET stream variable h (its definition x -> if a then x else "
            "pre h reads a, x now and through pre; a numeric stream is a stored real "
            "number, a memory of a past value: no finite game holds it)"
            ) in " ".join(got.output.split())
    got = CliRunner().invoke(main, ["shield", str(path), "--exclude", "R1"])
    assert got.exit_code == 2, got.output
    assert ("R2 reads the FRET stream variable g (its definition false -> ((x > pre x) xor "
            "pre g) reads x now and through pre; a boolean stream reading a previous number "
            "(pre of a number, or a numeric stream) holds what a real number decides, not a "
            "machine of boolean state bits over the tick's atoms)"
            ) in " ".join(got.output.split())


@pytest.mark.parametrize("text", ["whenever t ctrl shall immediately satisfy o",
                                  "whenever m ctrl shall immediately satisfy o",
                                  "upon occurred(2, a) ctrl shall immediately satisfy o",
                                  "upon persisted(2, a) ctrl shall immediately satisfy o"])
def test_the_proof_reads_past_atoms_by_their_expansion(tmp_path, text):
    """``--prove`` reads the requirement's ft_inf formula with Spot, where the toggle, a
    latch (a since) and ``occurred`` are derived past atoms: given to Spot over temporal
    testers (check/past_testers.py), the closed loop is proved (before: the toggle
    ``unknown``; the latch, ``occurred`` and ``persisted`` a false violation, Spot reading
    the atom as a free proposition: ``cycle{!a & !o & "persisted(2,a)"}``);
    ``--explain`` does not read the liberties of a response over the past."""
    path = _export(tmp_path, [text])
    got = CliRunner().invoke(main, ["shield", str(path), "--prove", "--explain"])
    out = " ".join(got.output.split())
    assert got.exit_code == 0 and "R1: holds" in out, out
    assert "violated" not in out and "unknown" not in out
    assert "R1: enforced as it reads (a condition or response reading the past" in out


def test_the_gwendolen_form_steps_the_toggles_bit_as_the_python_form(tmp_path):
    """The Gwendolen form's Java machine (javac) against the Python form, tick by tick:
    decided atoms, next state (the toggle's bit among it) and broken flag equal; its
    properties file says why it does not state R1 (the stream is the shield's state)."""
    from test_gwendolen import java_steps, python_steps

    path = _export(tmp_path, ["whenever t ctrl shall immediately satisfy o"])
    out = tmp_path / "g"
    got = CliRunner().invoke(main, ["shield", str(path), "--emit", "python", "--emit",
                                    "gwendolen", "--name", "safe_ros", "-o", str(out)])
    assert got.exit_code == 0, got.output
    assert "not stated: t is a FRET stream read by its state bit" in \
        (out / "safe_ros.psl").read_text(encoding="utf-8")
    runs = [[({"a": ak, "x": 0.0}, {"o": proposed}) for ak in a]
            for a in _runs() for proposed in (False, True)]
    lines, want = python_steps(out, runs)
    got_lines = java_steps(out, lines, tmp_path)
    assert got_lines == want
    assert any(w.split()[1] != "0" * len(w.split()[1]) for w in want)  # (the bit was set)
