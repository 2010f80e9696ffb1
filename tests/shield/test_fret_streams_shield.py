"""``fretc shield`` refuses a requirement reading a FRET stream variable (an Internal
variable whose Lustre definition reads itself through ``pre``), naming the stream and the
variables its definition reads: its machines step over one tick's inputs and outputs and
hold no stream's state. ``fretc testgen`` generates the tests and notes that a stream's
column is its own values, where the audit computes it."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main
from _gen import fret_export, fret_var


def _export(tmp_path: Path, texts: list[str]) -> Path:
    return fret_export(tmp_path, texts, [fret_var("b", "Input"), fret_var("o", "Output"),
                                         fret_var("latched", "Internal", "b -> (b xor pre latched)"),
                                         fret_var("x", "Input", data_type="double"),
                                         fret_var("g", "Internal", "b -> (b xor (pre g and x > pre x))")])


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
