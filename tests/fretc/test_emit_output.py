"""``fretc FILE --emit monitor -o``: a file for one input, a directory for several; empty
input is an error; skipped requirements are listed on stderr."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_empty_input_is_an_error_and_creates_nothing(tmp_path):
    (tmp_path / "empty.fret").write_text("# only a comment\n")
    out = tmp_path / "empty_mon.py"
    res = _run(tmp_path / "empty.fret", "--emit", "monitor", "-o", out)
    assert res.exit_code == 2 and "no requirements" in res.output
    assert not out.exists()


def test_two_inputs_with_a_py_output_are_an_error(tmp_path):
    out = tmp_path / "two.py"
    res = _run(ROOT / "requirements/r1.fret", ROOT / "requirements/safe_ros.fret",
               "--emit", "monitor", "-o", out)
    assert res.exit_code == 2 and "give a directory" in res.output
    assert not out.exists()


def test_two_inputs_write_a_directory_and_one_input_a_file(tmp_path):
    res = _run(ROOT / "requirements/r1.fret", ROOT / "requirements/safe_ros.fret",
               "--emit", "monitor", "-o", tmp_path / "mons")
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "mons").iterdir()) == [
        "r1_monitors.py", "safe_ros_monitors.py"]
    res = _run(ROOT / "requirements/r1.fret", "--emit", "monitor", "-o", tmp_path / "r1")
    assert res.exit_code == 0 and (tmp_path / "r1").is_file()


def test_skipped_requirements_are_listed_on_stderr(tmp_path):
    (tmp_path / "p.fret").write_text(
        "P0: the sw shall always satisfy q\n"
        "P1: whenever p the sw shall immediately satisfy persists(3, q)\n")
    res = _run(tmp_path / "p.fret", "--emit", "monitor", "-o", tmp_path / "p_mon.py")
    assert res.exit_code == 0, res.output
    assert "skipped P1" in res.output and "P0" not in res.output.replace("p_monitors", "")
