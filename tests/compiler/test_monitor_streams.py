"""``fretc EXPORT --emit monitor`` of a FRET export whose requirements read Internal
variables defined as streams with state (their Lustre definitions read themselves through
``pre``: FRET's LMCPS ``psiAtZero`` and ``rollAtZero``): the monitor's inputs are the
variables the definitions read, it computes the streams tick by tick (its state kept between
steps), and it steps as the same requirement's monitor fed the streams' values as a plain
Python loop of the Lustre definitions computes them (written out here)."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from _monitor_helpers import autopilot_export, fret_export
from fretc.cli import main

LMCPS = Path(__file__).resolve().parents[3] / "shared/corpora/fret_projects/LMCPS/" \
    "LM_requirements.json"
PSI = "Psi -> if (hdg and not pre hdg) then Psi else pre psiAtZero"
ROLL = ("roll_angle -> if (autopilot_engaged and not hdg and not pre (autopilot_engaged and "
        "not hdg)) then roll_angle else pre rollAtZero")
INPUTS = [("Psi", "double"), ("hdg", "boolean"), ("autopilot_engaged", "boolean"),
          ("roll_angle", "double"), ("roll_cmd", "double")]
REQUIREMENTS = [
    ("R1", "Autopilot shall always satisfy Psi - psiAtZero <= 5"),
    ("R2", "while (autopilot_engaged & !hdg) Autopilot shall always satisfy (roll_angle - "
           "roll_cmd - rollAtZero)/(roll_cmd - rollAtZero) <= 0.1"),
    ("R3", "whenever hdg Autopilot shall within 2 ticks satisfy rollAtZero >= psiAtZero"),
]


def reference(rows: list[dict]) -> list[dict]:
    """``rows`` with psiAtZero and rollAtZero, by Lustre's semantics written out."""
    out: list[dict] = []
    for t, r in enumerate(rows):
        if t == 0:
            out.append(dict(r, psiAtZero=r["Psi"], rollAtZero=r["roll_angle"]))
            continue
        p, prev = out[-1], rows[t - 1]
        now = r["autopilot_engaged"] and not r["hdg"]
        was = prev["autopilot_engaged"] and not prev["hdg"]
        out.append(dict(r, psiAtZero=r["Psi"] if r["hdg"] and not prev["hdg"]
                        else p["psiAtZero"],
                        rollAtZero=r["roll_angle"] if now and not was else p["rollAtZero"]))
    return out


def _export(defined: bool) -> dict:
    return autopilot_export(defined, INPUTS, REQUIREMENTS, PSI, ROLL)


def _module(tmp: Path, doc: dict) -> dict:
    (tmp / "p.json").write_text(json.dumps(doc), encoding="utf-8")
    got = CliRunner().invoke(main, [str(tmp / "p.json"), "--emit", "monitor", "-o",
                                    str(tmp / "m.py")])
    assert got.exit_code == 0, got.output
    return runpy.run_path(str(tmp / "m.py"))


_NUM = st.sampled_from([-3.0, 0.0, 1.0, 2.5, 4.0, 9.0])
_ROW = st.fixed_dictionaries({"Psi": _NUM, "hdg": st.booleans(),
                              "autopilot_engaged": st.booleans(), "roll_angle": _NUM,
                              "roll_cmd": _NUM})


def test_the_inputs_are_what_the_definitions_read(tmp_path):
    mod = _module(tmp_path, _export(True))
    assert mod["MONITORS"]["R1"].VARIABLES == ("Psi", "hdg")
    assert sorted(mod["MONITORS"]["R3"].VARIABLES) == ["Psi", "autopilot_engaged", "hdg",
                                                       "roll_angle"]


@settings(max_examples=30, deadline=None)
@given(st.lists(_ROW, min_size=1, max_size=10), st.integers(0, 10))
def test_the_monitor_steps_as_the_streams_written_out(tmp_path_factory, rows, cut):
    tmp = tmp_path_factory.mktemp("m")
    computed = _module(tmp, _export(True))["MONITORS"]
    fed = _module(tmp, _export(False))["MONITORS"]
    want_rows = reference(rows)
    for rid, _text in REQUIREMENTS:
        m, w = computed[rid](), fed[rid]()
        got = [m.step(r) for r in rows[:cut]] + m.run(rows[cut:])
        assert got == w.run(want_rows), rid
        assert (m.status, m.status_tick, m.finish()) == (w.status, w.status_tick, w.finish())
        m.reset()  # a new run starts the streams again
        assert m.run(rows) == got


def test_the_lmcps_export(tmp_path):
    """FRET's LMCPS case study: every monitor module is written, psiAtZero and rollAtZero
    are inputs of none (the monitors of AP-010bv2, AP-010b, AP-004b compute them)."""
    if not LMCPS.is_file():
        pytest.skip("the LMCPS export (../shared/corpora/fret_projects/LMCPS) is absent")
    got = CliRunner().invoke(main, [str(LMCPS), "--emit", "monitor", "-o", str(tmp_path)])
    assert got.exit_code == 0, got.output
    monitors = {}
    for f in sorted(tmp_path.glob("*.py")):
        monitors.update(runpy.run_path(str(f))["MONITORS"])
    for rid in ("AP-010bv2", "AP-010b", "AP-004b"):
        assert not {"psiAtZero", "rollAtZero"} & set(monitors[rid].VARIABLES), rid
    assert "psiAtZero: FRET defines it (Internal) as" in got.stderr
    assert "that definition is a stream with state" in got.stderr


def test_the_notes_say_why_each_is_a_stream(tmp_path):
    doc = fret_export({"R1": "c shall always satisfy big"}, ("x", "Input", "boolean"),
                      ("a", "Internal", "boolean", "false -> pre b"),
                      ("b", "Internal", "boolean", "x and not a"),
                      ("big", "Internal", "boolean", "a or x"), component="c")
    (tmp_path / "p.json").write_text(json.dumps(doc), encoding="utf-8")
    got = CliRunner().invoke(main, [str(tmp_path / "p.json"), "--emit", "monitor", "-o",
                                    str(tmp_path / "m.py")])
    assert got.exit_code == 0, got.output
    assert runpy.run_path(str(tmp_path / "m.py"))["MONITORS"]["R1"].VARIABLES == ("x",)
    assert "big: FRET defines it (Internal) as a or x; that definition is a stream with " \
           "state (it reads a variable that reads itself through pre)" in got.stderr
    assert "a: FRET defines it (Internal) as false -> pre b; that definition is a stream " \
           "with state (it reads itself through pre)" in got.stderr
