"""No output of a command is one of its inputs, for every command that writes files beside
audit, shield-replay, report and export (tested in test_outputs_replace_inputs.py): the
smallest input of each, an output named as an input (``fretc compile r.fret -o r.fret``), a
folder output that is the folder of inputs read, a symbolic link to an input. Each exits 2
naming the output and the input, and leaves every file as it was."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

FRET = "R: the robot shall always satisfy x > 0\n"
CSV = "time,x\n0,1\n1,2\n"
REFUSED = "an output never replaces an input"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _snapshot(folder: Path) -> dict:
    return {p.relative_to(folder): (p.read_bytes() if p.is_file() and not p.is_symlink()
                                    else None)
            for p in sorted(folder.rglob("*"))}


@pytest.fixture
def ws(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "reqs").mkdir()
    (tmp_path / "reqs" / "r.fret").write_text(FRET)
    (tmp_path / "r.fret").write_text(FRET)
    (tmp_path / "t.csv").write_text(CSV)
    (tmp_path / "link.out").symlink_to(tmp_path / "r.fret")
    return tmp_path


def _refused(ws, *args, output: str, input_: str):
    before = _snapshot(ws)
    got = _run(*args)
    assert got.exit_code == 2, got.output
    assert REFUSED in got.output and output in got.output and input_ in got.output, got.output
    assert "Traceback" not in got.output
    assert _snapshot(ws) == before


@pytest.mark.parametrize("args,output,input_", [
    (["compile", "r.fret", "--emit", "monitor", "-o", "r.fret"], "-o r.fret", "r.fret"),
    (["r.fret", "--emit", "psl", "-o", "link.out"], "-o link.out", "r.fret"),
    (["compile", "reqs", "--emit", "prism", "-o", "reqs/r.fret"], "-o reqs/r.fret",
     "reqs/r.fret"),
    (["compile", "reqs", "--emit", "c", "-o", "reqs"], "-o reqs", "the requirement folder"),
])
def test_compile(ws, args, output, input_):
    _refused(ws, *args, output=output, input_=input_)


@pytest.mark.parametrize("args,output,input_", [
    (["simulate", "r.fret", "t.csv", "--json", "t.csv"], "--json t.csv", "the trace"),
    (["simulate", "r.fret", "t.csv", "--json", "link.out"], "--json link.out", "r.fret"),
    (["simulate", "reqs", "t.csv", "-o", "reqs"], "-o reqs", "the requirement folder"),
])
def test_simulate(ws, args, output, input_):
    _refused(ws, *args, output=output, input_=input_)


def test_explain_into_the_folder_of_its_requirements(ws):
    _refused(ws, "explain", "reqs", "-o", "reqs", output="-o reqs",
             input_="the requirement folder reqs")


def test_distinguish_svg_over_a_requirement_file(ws):
    _refused(ws, "distinguish", "x > 0", "x > 1", "-r", "r.fret", "--svg", "link.out",
             output="--svg link.out", input_="r.fret")


@pytest.mark.parametrize("args,output,input_", [
    (["check", "r.fret", "-o", "r.fret"], "-o r.fret", "the requirement file r.fret"),
    (["check", "reqs", "--witness-dir", "reqs"], "--witness-dir reqs", "the requirement folder"),
])
def test_check(ws, args, output, input_):
    _refused(ws, *args, output=output, input_=input_)


def test_testgen_into_the_folder_of_its_requirements(ws):
    _refused(ws, "testgen", "reqs", "-o", "reqs", output="-o reqs",
             input_="the requirement folder reqs")


def test_testgen_naming_its_test_file_as_an_input(ws):
    (ws / "out").mkdir()
    (ws / "out" / "tests.json").symlink_to(ws / "r.fret")
    _refused(ws, "testgen", "r.fret", "-o", "out", output="out/tests.json",
             input_="the requirement file r.fret")


def test_testrun_outputs_naming_its_inputs(ws):
    got = _run("testgen", "r.fret", "-o", "tg")
    assert got.exit_code == 0, got.output
    for args, output, input_ in ((["--json", "tg/tests.json"], "--json tg/tests.json",
                                  "the tests' file"),
                                 (["--json", "tg/T01.csv"], "--json tg/T01.csv", "the trace"),
                                 (["--json", "r.fret"], "--json r.fret", "the requirement file"),
                                 (["--logs", "tg"], "--logs tg", "the test folder")):
        _refused(ws, "testrun", "tg", "--command", "true", *args, output=output, input_=input_)


@pytest.mark.parametrize("option", ["--json", "--record"])
def test_watch_outputs_naming_its_requirement_file(ws, option):
    """Refused before it connects (nothing listens on port 1)."""
    _refused(ws, "watch", "ws://127.0.0.1:1", "-r", "r.fret", "--connect-timeout", "1",
             option, "link.out", output=f"{option} link.out", input_="r.fret")


@pytest.mark.parametrize("command", ["estimate", "falsify"])
def test_estimate_and_falsify_output_folder_that_is_the_requirement_folder(ws, command):
    (ws / "space.toml").write_text("")
    _refused(ws, command, "-r", "reqs", "--space", "space.toml", "-o", "reqs",
             output="-o reqs", input_="the requirement folder reqs")


def test_shield_output_folder_that_is_the_requirement_folder(ws):
    (ws / "sh").mkdir()
    (ws / "sh" / "s.fret").write_text("S: the robot shall always satisfy obstacle => stop\n")
    args = ["shield", "sh", "--inputs", "obstacle", "--outputs", "stop", "--emit", "python"]
    _refused(ws, *args, "-o", "sh", output="-o sh", input_="the requirement folder sh")
    (ws / "a.fret").write_text("A: the environment shall always satisfy obstacle | !obstacle\n")
    (ws / "out").mkdir()
    (ws / "out" / "sh_shield.py").symlink_to(ws / "a.fret")
    _refused(ws, *args, "--assume", "a.fret", "-o", "out", output="out/sh_shield.py",
             input_="the assumption file (--assume) a.fret")


def test_outputs_apart_from_the_inputs_are_written(ws):
    """An output folder inside a folder of requirements is not one: its files are read, not
    its sub-folders."""
    got = _run("simulate", "reqs", "t.csv", "-o", "reqs/sim", "--json", "sim.json")
    assert got.exit_code == 0, got.output
    assert (ws / "reqs" / "sim" / "simulation.html").exists() and (ws / "sim.json").exists()
    got = _run("compile", "r.fret", "--emit", "monitor", "-o", "r.py")
    assert got.exit_code == 0, got.output
    assert (ws / "r.py").exists() and (ws / "r.fret").read_text() == FRET
