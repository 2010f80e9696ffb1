"""``fretc shield`` refuses a requirement reading a FRET stream variable (an Internal
variable whose Lustre definition reads itself through ``pre``), naming the stream and the
variables its definition reads: its machines step over one tick's inputs and outputs and
hold no stream's state. ``fretc testgen`` generates the tests and notes that a stream's
column is its own values, where the audit computes it."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main


def _export(tmp_path: Path, texts: list[str]) -> Path:
    def var(name: str, kind: str, assignment: str = "", data_type: str = "boolean") -> dict:
        return {"project": "P", "component_name": "ctrl", "variable_name": name,
                "idType": kind, "dataType": data_type, "assignment": assignment}

    path = tmp_path / "p.json"
    path.write_text(json.dumps({"requirements": [
        {"reqid": f"R{k + 1}", "project": "P", "fulltext": t} for k, t in enumerate(texts)],
        "variables": [var("b", "Input"), var("o", "Output"),
                      var("latched", "Internal", "b -> (b xor pre latched)"),
                      var("x", "Input", data_type="double"),
                      var("g", "Internal", "b -> (b xor (pre g and x > pre x))")]}),
        encoding="utf-8")
    return path


def test_shield_refuses_a_stream_variable_by_name(tmp_path):
    """A boolean stream reading a previous number (``g``; ``latched``, reading booleans only, is
    enforced by its state bit: tests/shield/test_shield_stream_bits.py)."""
    path = _export(tmp_path, ["whenever g ctrl shall immediately satisfy o",
                              "whenever b ctrl shall immediately satisfy o"])
    got = CliRunner().invoke(main, ["shield", str(path), "-o", str(tmp_path / "out")])
    assert got.exit_code == 2, got.output
    assert "R1 reads the FRET stream variable g (its definition b -> (b xor (pre g and x > " \
           "pre x)) reads b, x now and through pre; a boolean stream reading a previous " \
           "number (pre of a number, or a numeric stream) holds what a real number decides" \
           in " ".join(got.output.split())
    assert "the shield does not compute" in got.output
    got = CliRunner().invoke(main, ["shield", str(path), "--exclude", "R1",
                                    "-o", str(tmp_path / "out")])
    assert got.exit_code == 0, got.output


def test_testgen_notes_a_stream_variable(tmp_path):
    path = _export(tmp_path, ["whenever latched ctrl shall immediately satisfy o"])
    got = CliRunner().invoke(main, ["testgen", str(path), "-o", str(tmp_path / "t")])
    assert got.exit_code == 0, got.output
    assert "note: latched (read by R1) is a FRET stream variable (its definition b -> (b " \
           "xor pre latched) reads b now and through pre): each test's column of it is " \
           "computed from the columns of those variables" in got.output
