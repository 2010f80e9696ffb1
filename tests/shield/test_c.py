"""The C form of the shield against the Python one, on random requirement sets, runs and
proposals: the same corrected outputs, overrides and reasons at every tick; built with the
strict flags of ``--emit c`` and run under AddressSanitizer and UBSan."""

from __future__ import annotations

import csv
import io
import math
import subprocess
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings

from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import tables
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import ShieldRuntime

from _c_monitors import build, needs_cc, write
from _gen import INPUTS, OUTPUTS, build as build_shield, compile_text, requirement_sets, runs


def run_c(shield, rows: list[tuple[dict, dict]], folder: Path) -> list[dict]:
    """The C runner of ``shield`` (built with sanitizers) over ``rows``: per tick the
    corrected outputs, ``overridden`` and ``reasons``."""
    write(render_c(shield, "t"), folder)
    exe = build(folder, ["t_shield.c", "t_shield_run.c"], "run")
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(INPUTS + OUTPUTS)
    for ins, prop in rows:
        w.writerow([_cell(ins[v]) for v in INPUTS] + [_cell(prop[v]) for v in OUTPUTS])
    got = subprocess.run([str(exe)], input=text.getvalue(), capture_output=True, text=True,
                         timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    return list(csv.DictReader(io.StringIO(got.stdout)))


def _cell(x) -> str:
    return ("true" if x else "false") if isinstance(x, bool) else repr(float(x))


def _same(shield, rows, c_rows) -> None:
    rt = ShieldRuntime(tables(shield))
    for (ins, prop), c in zip(rows, c_rows, strict=True):
        d = rt.step(ins, prop)
        for v in OUTPUTS:
            if v not in shield.read:
                assert v not in c
                continue
            want, got = d.outputs[v], c[v]
            if isinstance(want, bool):
                assert got == str(int(want)), (v, d, c)
            else:
                assert float(got) == want or (math.isnan(want) and math.isnan(float(got))), \
                    (v, d, c)
        assert c["overridden"] == str(int(d.overridden)), (d, c)
        assert set(filter(None, c["reasons"].split("|"))) == set(d.reasons), (d, c)


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(text=requirement_sets(), rows=runs(length=60))
@pytest.mark.tor("TOR-SHD-004")
def test_c_and_python_shields_decide_alike(text, rows):
    needs_cc()
    with tempfile.TemporaryDirectory() as tmp:
        try:
            shield = build_shield(compile_text(text, Path(tmp)))
        except ShieldError:
            assume(False)
        _same(shield, rows, run_c(shield, rows, Path(tmp) / "c"))


def _runner(tmp_path: Path, response: str, name: str) -> Path:
    """The C runner (sanitizers on) of the shield of ``whenever a sw shall immediately
    satisfy RESPONSE``, built in ``tmp_path / name`` with the prefix ``name``."""
    shield = build_shield(compile_text(f"R1: whenever a sw shall immediately satisfy "
                                       f"{response}\n", tmp_path))
    write(render_c(shield, name), tmp_path / name)
    return build(tmp_path / name, [f"{name}_shield.c", f"{name}_shield_run.c"], "run")


def test_the_c_runner_refuses_a_nul_byte_and_names_the_line(tmp_path):
    needs_cc()
    exe = _runner(tmp_path, "x", "t")
    head = ",".join(INPUTS + OUTPUTS) + "\n"
    good = "true,false,false,false,false,0.0\n"
    got = subprocess.run([str(exe)], input=(head + good + "tr\0ue,false,false,false,false,0\n"
                                            + good).encode(), capture_output=True, timeout=60)
    assert got.returncode == 2 and b"line 3: a NUL byte" in got.stderr
    got = subprocess.run([str(exe)], input=(head + "true,false,false,maybe,false,0\n").encode(),
                         capture_output=True, timeout=60)
    assert got.returncode == 2 and b"line 2: x: not a boolean" in got.stderr
    exe = _runner(tmp_path, "v < 1", "u")
    got = subprocess.run([str(exe)], input=(head + "true,false,false,false,false,nan\n").encode(),
                         capture_output=True, timeout=60)
    # (a proposed NaN is replaced, never passed on: the row says so)
    row = list(csv.DictReader(io.StringIO(got.stdout.decode())))[0]
    assert got.returncode == 0 and row["fault"] == "proposal" and float(row["v"]) < 1, row


def test_the_c_runner_reads_true_and_false_in_any_case_as_the_audit_does(tmp_path):
    """``TRUE``/``False`` are booleans in a CSV trace fretc audit reads; the shield's runner
    refused them ("not a boolean"). The same rows in any case give the same corrections;
    a word that is neither is still refused, with its line."""
    needs_cc()
    exe = _runner(tmp_path, "x", "t")
    head = ",".join(INPUTS + OUTPUTS) + "\n"
    rows = ["true,false,false,false,false,0\n", "false,true,true,true,false,1\n",
            "true,true,false,false,true,0.5\n"]

    def run(text: str) -> subprocess.CompletedProcess:
        return subprocess.run([str(exe)], input=(head + text).encode(), capture_output=True,
                              timeout=60)

    lower = run("".join(rows))
    assert lower.returncode == 0 and b",1," in lower.stdout  # (the first row is corrected)
    for spell in (str.upper, str.title, lambda r: r.replace("true", "tRuE")):
        got = run("".join(spell(r) for r in rows))
        assert got.returncode == 0 and got.stdout == lower.stdout, got.stderr
    for word in ("tru", "truex", "yes", "TRUE1"):
        got = run(rows[0] + word + rows[1][len("false"):])
        assert got.returncode == 2 and b"line 3: a: not a boolean" in got.stderr, got.stderr


@pytest.mark.parametrize("prefer", [(), (("x", True),), (("x", False), ("y", True))])
def test_preferences_break_ties_alike_in_c_and_python(tmp_path, prefer):
    # x | y must hold: an unsafe proposal (both false) has two corrections of one change;
    # the preference picks one, the same in both forms
    shield = build_shield(compile_text("R1: whenever a sw shall immediately satisfy x | y\n",
                                       tmp_path), prefer=list(prefer))
    rows = [({"a": True, "b": False, "m": False}, {"x": False, "y": False, "v": 0.0})] * 3
    rt = ShieldRuntime(tables(shield))
    d = rt.step(*rows[0])
    if prefer and prefer[0] == ("x", True):
        assert d.outputs["x"] and not d.outputs["y"]
    if prefer and prefer[0] == ("x", False):
        assert d.outputs["y"] and not d.outputs["x"]
    if needs_cc():
        _same(shield, rows, run_c(shield, rows, tmp_path / "c"))


def test_a_shield_that_enforces_nothing_still_builds_and_runs(tmp_path):
    # every requirement over inputs only: no machine, no output field; the C form builds
    # with the strict flags and passes every tick
    needs_cc()
    shield = build_shield(compile_text("R1: the sw shall always satisfy a\n", tmp_path))
    assert not shield.machines and list(shield.monitored) == ["R1"]
    write(render_c(shield, "e"), tmp_path / "c")
    exe = build(tmp_path / "c", ["e_shield.c", "e_shield_run.c"], "run")
    got = subprocess.run([str(exe)], input=",".join(INPUTS + OUTPUTS) + "\n"
                         "true,false,false,false,false,0.0\n", capture_output=True, text=True,
                         timeout=60)
    assert got.returncode == 0 and got.stdout.splitlines() == [
        "tick,overridden,reasons,fault", "0,0,,"], got


def test_names_that_are_no_c_identifiers_build_and_decide_alike(tmp_path):
    """FRET's dotted names, quoted ones with ``*/``, ``%`` or a backslash, and two names that
    sanitize alike (``arm.stop``, ``arm_stop``): the C form builds with the strict flags
    (they were pasted in as fields and into the runner's printf), names each field after
    its FRET name, and decides as the Python form; the Python form imports (a backslash in
    its docstring was a SyntaxError)."""
    from fretc.shield.build import build_shield as build_one
    from fretc.shield.emit_python import load_shield, render_python

    needs_cc()
    compiled = compile_text('R1: whenever ROS.ok sw shall immediately satisfy arm.stop\n'
                            'R2: whenever "x*/y" sw shall immediately satisfy "load%"\n'
                            'R3: whenever "p\\N" sw shall immediately satisfy arm_stop\n',
                            tmp_path)
    ins, outs = ["ROS.ok", "x*/y", "p\\N"], ["arm.stop", "load%", "arm_stop"]
    shield = build_one(compiled, ins, outs, fork=False)
    files = render_c(shield, "n")
    assert "bool arm_stop;" in files["n_shield.h"]
    assert "bool arm_stop_2; /* FRET's arm.stop */" in files["n_shield.h"]
    write(files, tmp_path / "c")
    exe = build(tmp_path / "c", ["n_shield.c", "n_shield_run.c"], "run")
    py = load_shield(render_python(shield))()
    rows = [({v: bool(k >> i & 1) for i, v in enumerate(ins)},
             {v: bool(k >> (i + 3) & 1) for i, v in enumerate(outs)}) for k in range(64)]
    text = ",".join(ins + outs) + "\n" + "".join(
        ",".join(_cell(x) for x in [*a.values(), *p.values()]) + "\n" for a, p in rows)
    got = subprocess.run([str(exe)], input=text, capture_output=True, text=True, timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    c_rows = list(csv.DictReader(io.StringIO(got.stdout)))
    assert list(c_rows[0])[1:4] == outs
    for (a, p), c in zip(rows, c_rows, strict=True):
        d = py.step(a, p)
        assert {v: c[v] for v in outs} == {v: str(int(d.outputs[v])) for v in outs}, (a, p, c)
        assert c["overridden"] == str(int(d.overridden))


def test_a_nan_no_enforced_requirement_compares_passes_in_c_as_in_python(tmp_path):
    """``d`` is read only by R2, over inputs only (monitored): a NaN there is decided on, in
    the Python form and now in C (it returned -1, no decision); a NaN in ``v``, which R1
    compares, is a proposal the shield cannot read: replaced in both (by the fallback's
    value, v = 0, which R1 keeps), never passed on, never an exception."""
    from fretc.shield.build import build_shield as build_one
    from fretc.shield.emit_python import load_shield, render_python

    needs_cc()
    compiled = compile_text("R1: whenever a sw shall immediately satisfy v <= 0.5\n"
                            "R2: the sw shall always satisfy d > 0\n", tmp_path)
    shield = build_one(compiled, ["a", "d"], ["v"], fork=False)
    assert list(shield.monitored) == ["R2"]
    write(render_c(shield, "n"), tmp_path / "c")
    exe = build(tmp_path / "c", ["n_shield.c", "n_shield_run.c"], "run")
    py = load_shield(render_python(shield))()
    d = py.step({"a": True, "d": math.nan}, {"v": 0.9})
    got = subprocess.run([str(exe)], input="a,d,v\ntrue,nan,0.9\n", capture_output=True,
                         text=True, timeout=60)
    assert got.returncode == 0, got.stderr
    row = list(csv.DictReader(io.StringIO(got.stdout)))[0]
    assert float(row["v"]) == d.outputs["v"] == 0.5 and row["overridden"] == "1"
    d = load_shield(render_python(shield))().step({"a": True, "d": 1.0}, {"v": math.nan})
    assert d.overridden and d.fault == "proposal v is NaN" and d.outputs == {"v": 0.0}, d
    got = subprocess.run([str(exe)], input="a,d,v\ntrue,1.0,nan\n", capture_output=True,
                         text=True, timeout=60)
    row = list(csv.DictReader(io.StringIO(got.stdout)))[0]
    assert got.returncode == 0 and row["fault"] == "proposal" and float(row["v"]) == 0.0, row
