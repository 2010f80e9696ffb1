"""FRET's array elements (``yout(3)`` in FRET's Lockheed Martin case study, MATLAB's
indexing from Simulink: the first element is 1) audited against a binding of the array: the
element ``r(k)`` of ``r = "/scan.ranges"`` is ``/scan.ranges[k-1]``, the same value at every
tick as a binding of that item written by hand; a binding of the element itself wins."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

LOG = str(Path(__file__).resolve().parents[2] / "traces" / "dynamic_obstacle.mcap")


def _audit(tmp_path: Path, variables: str) -> tuple[str, dict]:
    (tmp_path / "r.fret").write_text(
        "R1: ctrl shall always satisfy r(1) = beam0\n"
        "R2: ctrl shall always satisfy r(1) != beam0\n"
        "R3: ctrl shall always satisfy r(3) > 1.2\n"
        "R4: ctrl shall always satisfy beam2 > 1.2\n", encoding="utf-8")
    (tmp_path / "b.toml").write_text('[tick]\nperiod = "100 ms"\n\n[variables]\n' + variables,
                                     encoding="utf-8")
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "b.toml"), LOG, "--no-progress", "--json",
                                    str(tmp_path / "a.json")])
    doc = json.loads((tmp_path / "a.json").read_text(encoding="utf-8"))
    return got.output, {v["requirement"]: v for v in doc["logs"][0]["verdicts"]}


def test_an_element_is_the_array_item_counted_from_one(tmp_path):
    out, got = _audit(tmp_path, 'r = "/scan.ranges"\nbeam0 = "/scan.ranges[0]"\n'
                                'beam2 = "/scan.ranges[2]"\n')
    assert got["R1"]["verdict"] == "satisfied", out
    assert got["R2"]["verdict"] == "violated"
    assert got["R2"]["first_violation"]["tick"] == 0
    assert got["R3"]["verdict"] == got["R4"]["verdict"] == "violated"
    assert got["R3"]["first_violation"]["tick"] == got["R4"]["first_violation"]["tick"]
    assert "'r' is bound but no requirement uses it" not in out
    assert "r(3): the element 3 of r (FRET counts from 1), bound to /scan.ranges[2]" in out


def test_a_binding_of_the_element_itself_wins(tmp_path):
    out, got = _audit(tmp_path, 'r = "/scan.ranges"\nbeam0 = "/scan.ranges[0]"\n'
                                'beam2 = "/scan.ranges[2]"\n"r(1)" = "/scan.ranges[1]"\n')
    assert got["R1"]["verdict"] == "violated", out  # (r(1) is beam 1 here, not beam 0)
    assert "the element 1 of r" not in out and "the element 3 of r" in out
