"""``fretc EXPORT --emit c`` of a FRET export whose requirements read Internal variables
defined as streams with state (FRET's LMCPS ``psiAtZero``, ``rollAtZero``: Lustre
definitions that read themselves through ``pre``): the C monitor's inputs are the variables
the definitions read, it computes the streams tick by tick in its state, and it steps (pt
verdict, LTL3 verdict and tick, finish, the audit's word) as the Python monitor of the same
requirements fed the streams as a plain Python loop of the Lustre definitions computes them
(tests/compiler/test_monitor_streams.py's reference); built with the strict flags and the
sanitizers (tests/_c_monitors.py)."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.compiler.c_codegen import c_units, emit_c
from fretc.compiler.codegen import build_monitor_module
from fretc.fretish.files import load_requirements
from fretc.fretish.fret_variables import fret_declarations

from _c_monitors import build, driver_source, needs_cc, run_driver, write
from _monitor_helpers import fret_export, load_source
from test_monitor_streams import LMCPS, _ROW, _export, reference


def _compiled(tmp: Path, defined: bool) -> list:
    (tmp / f"p{int(defined)}.json").write_text(json.dumps(_export(defined)), encoding="utf-8")
    entries = load_requirements([tmp / f"p{int(defined)}.json"])
    entries, _notes = fret_declarations(entries, streams=True)
    return compile_entries(entries)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    needs_cc()
    tmp = tmp_path_factory.mktemp("c")
    compiled = _compiled(tmp, True)
    files, skipped = emit_c(compiled)
    assert not skipped
    units = c_units(compiled)
    monitors = [m for u in units for m in u.monitors]
    write(files, tmp)
    (tmp / "driver.c").write_text(driver_source(units), encoding="utf-8")
    exe = build(tmp, [f for f in files if f.endswith(".c") and f != "runner.c"]
                + ["driver.c"], "driver")
    fed = load_source(build_monitor_module(_compiled(tmp, False), "fed").text)
    return exe, monitors, fed


def test_the_inputs_are_what_the_definitions_read(built):
    _exe, monitors, _fed = built
    names = {m.id: [x.raw_name for x in m.inputs] for m in monitors}
    assert sorted(names["R1"]) == ["Psi", "hdg"]
    assert not {"psiAtZero", "rollAtZero"} & {n for v in names.values() for n in v}


def _python(cls, trace: list[dict]) -> tuple[list, int]:
    m = cls()
    ticks = [(bool(m.step(s)), m.status, m.status_tick) for s in trace]
    return ticks, int(m.finish())


@pytest.mark.tor("TOR-GEN-003")
@settings(max_examples=40, deadline=None)
@given(st.lists(_ROW, min_size=1, max_size=12))
def test_the_c_monitor_steps_as_the_streams_written_out(built, rows):
    exe, monitors, fed = built
    jobs = [(k, m, rows) for k, m in enumerate(monitors)]
    for m, got in zip(monitors, run_driver(exe, jobs)):
        ticks, fin = _python(fed.MONITORS[m.id], reference(rows))
        # (a comparison reading NaN, x / 0 here, makes the C monitor's tick unread: it
        # stops there, where the Python monitor leaves NaN to its caller)
        u = got["unread"] if got["unread"] >= 0 else len(rows)
        assert got["ticks"][:u] == ticks[:u], m.id
        if got["unread"] < 0:
            assert got["finish"] == fin, m.id


@pytest.mark.tor("TOR-GEN-003")
def test_a_nan_input_of_a_stream_makes_its_tick_unread(built):
    exe, monitors, _fed = built
    row = {"Psi": 1.0, "hdg": False, "autopilot_engaged": False, "roll_angle": 0.0,
           "roll_cmd": 0.0}
    trace = [row, dict(row, Psi=math.nan), row]
    k = next(i for i, m in enumerate(monitors) if m.id == "R1")
    got = run_driver(exe, [(k, monitors[k], trace)])[0]
    assert got["unread"] == 1 and got["verdict"] == "unknown"


def test_the_lmcps_export(tmp_path):
    """FRET's LMCPS case study: ``--emit c`` exits 0, psiAtZero is an input of no monitor,
    and the C files (the CSV runner with them) build with the strict flags."""
    if not LMCPS.is_file():
        pytest.skip("the LMCPS export (../shared/corpora/fret_projects/LMCPS) is absent")
    needs_cc()
    got = CliRunner().invoke(main, [str(LMCPS), "--emit", "c", "-o", str(tmp_path)])
    assert got.exit_code == 0, got.output
    headers = "".join(p.read_text(encoding="utf-8") for p in tmp_path.glob("*.h"))
    assert "/* psiAtZero:" not in headers and "/* rollAtZero:" not in headers
    assert "_AP_010bv2_step" in headers
    # (not with -Werror: other LMCPS requirements' monitors have unused locals, a warning
    # that predates the streams)
    cc = needs_cc()
    sources = sorted(p.name for p in tmp_path.glob("*.c"))
    built = subprocess.run([cc, "-std=c99", "-Wall", "-o", "runner", *sources, "-lm"],
                           cwd=tmp_path, capture_output=True, text=True)
    assert built.returncode == 0, built.stderr[-4000:]
    assert not any(q in built.stderr for q in ("stream", "'q_", "\u2018q_"))
    assert subprocess.run([str(tmp_path / "runner")], capture_output=True).returncode != 0


#: boolean streams, nested pre, streams reading each other, / and mod (the C helpers)
MIXED = {
    "requirements": [
        {"reqid": "S1", "fulltext": "whenever seen c shall immediately satisfy half <= y + 3"},
        {"reqid": "S2", "fulltext": "c shall always satisfy big | d > 1"}],
    "variables": fret_export({}, ("x", "Input", "boolean"), ("y", "Input", "double"),
                             ("d", "Internal", "", "y -> pre (pre d) + 1.0"),
                             ("seen", "Internal", "boolean", "x -> (x or pre seen)"),
                             ("half", "Internal", "", "if seen then d / 2.0 else d mod 2.0"),
                             ("a", "Internal", "boolean", "false -> pre b"),
                             ("b", "Internal", "boolean", "x and not a"),
                             ("big", "Internal", "boolean", "a or y > 2.0"),
                             component="c")["variables"]}


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    needs_cc()
    tmp = tmp_path_factory.mktemp("mixed")
    (tmp / "m.json").write_text(json.dumps(MIXED), encoding="utf-8")
    entries, _notes = fret_declarations(load_requirements([tmp / "m.json"]), streams=True)
    compiled = compile_entries(entries)
    files, skipped = emit_c(compiled)
    assert not skipped
    units = c_units(compiled)
    write(files, tmp)
    (tmp / "driver.c").write_text(driver_source(units), encoding="utf-8")
    exe = build(tmp, [f for f in files if f.endswith(".c") and f != "runner.c"]
                + ["driver.c"], "driver")
    py = load_source(build_monitor_module(compiled, "mixed").text)
    return exe, [m for u in units for m in u.monitors], py


@pytest.mark.tor("TOR-GEN-003")
@settings(max_examples=40, deadline=None)
@given(st.lists(st.fixed_dictionaries({"x": st.booleans(), "y": st.sampled_from(
    [-2.0, 0.0, 1.5, 3.0, 7.0])}), min_size=1, max_size=12))
def test_the_c_monitor_steps_as_the_python_one(mixed, rows):
    """Boolean streams, nested ``pre``, streams reading each other, ``/`` and ``mod``: the
    C monitor and the Python one (itself against the reference loops:
    tests/compiler/test_stream_code.py) step alike."""
    exe, monitors, py = mixed
    assert sorted(x.raw_name for x in monitors[0].inputs) == ["x", "y"]
    for m, got in zip(monitors, run_driver(exe, [(k, m, rows)
                                                for k, m in enumerate(monitors)])):
        ticks, fin = _python(py.MONITORS[m.id], rows)
        u = got["unread"] if got["unread"] >= 0 else len(rows)
        assert got["ticks"][:u] == ticks[:u], m.id
        if got["unread"] < 0:
            assert got["finish"] == fin, m.id
