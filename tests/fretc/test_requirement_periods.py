"""Durations in time units count ticks of the bindings' period in ``fretc check``, ``fretc
shield`` and ``fretc testgen``, as in ``fretc audit``, never as ticks.

The units case: ``safe_ros.fret`` without its ``@tick_period``, shielded with ``-b
requirements/safe_ros.bindings.toml`` (100 ms): ``--explain`` read R2's "within 1 second" as
1 tick and R6's "within 500 milliseconds" as 500 ticks (50 s of blind driving), exit 0, no
warning. Now 10 and 5 ticks; without any period an input error naming it (exit 2); a binding
file beside the requirements gives it as the audit's discovery finds it; a FRET export takes
it from ``-b``; a declared period that differs from the bindings' is refused.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

from _fret_export import fret_export

REPO = Path(__file__).resolve().parents[2]
REQS = REPO / "requirements"
BINDINGS = REQS / "safe_ros.bindings.toml"
IO = ["--inputs", "too_close,scan_stale,clearance", "--outputs",
      "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed"]


def _run(*args: str):
    return CliRunner().invoke(main, list(args))


def _no_period(folder: Path, name: str = "sr.fret") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text("".join(line for line in (REQS / "safe_ros.fret").read_text(
        encoding="utf-8").splitlines(keepends=True) if "@tick_period" not in line),
        encoding="utf-8")
    return path


def test_the_issue_units_case_gives_r2_10_ticks_and_r6_5_ticks(tmp_path):
    f = _no_period(tmp_path)
    got = _run("shield", str(f), "-b", str(BINDINGS), *IO, "--explain")
    assert got.exit_code == 0, got.output
    assert "R2: stopped may wait up to 10 ticks (1 s) after too_close becomes true" in got.output
    assert "R6: stop_requested may wait up to 5 ticks (0.5 s)" in got.output, got.output


def test_no_period_known_is_an_input_error_naming_it(tmp_path):
    f = _no_period(tmp_path / "alone")
    for cmd in (["shield", str(f), *IO], ["check", str(f)],
                ["testgen", str(f), "-o", str(tmp_path / "tests")]):
        got = _run(*cmd)
        assert got.exit_code == 2, (cmd, got.output)
        assert f"{f}:5: R2: '1 second' is a duration in time units and no tick period is " \
               "known" in got.output, (cmd, got.output)
        assert "R6: '500 milliseconds'" in got.output and "@tick_period 100 ms" in got.output
    # a duration in ticks needs no period
    ticks = tmp_path / "ticks.fret"
    ticks.write_text("R1: upon a c shall within 3 ticks satisfy o\n", encoding="utf-8")
    got = _run("shield", str(ticks), "--inputs", "a", "--outputs", "o", "--explain")
    assert got.exit_code == 0 and "o may wait up to 3 ticks after a" in got.output, got.output


def test_a_binding_file_beside_the_requirements_gives_the_period(tmp_path):
    f = _no_period(tmp_path / "beside", "safe_ros.fret")
    shutil.copy(BINDINGS, f.with_name("safe_ros.bindings.toml"))
    got = _run("shield", str(f), *IO, "--explain")
    assert got.exit_code == 0, got.output
    assert "may wait up to 10 ticks (1 s)" in got.output and "5 ticks (0.5 s)" in got.output


def test_check_takes_b_and_decides_as_with_the_declared_period(tmp_path):
    """``fretc check -b`` reads the durations with the bindings' period: its report is the
    report of the same file with ``@tick_period 100 ms`` (10 ticks: with the 1 tick FRET
    reads, R2's bound is another requirement)."""
    f = _no_period(tmp_path / "c")
    args = ["--inputs", "too_close,scan_stale,clearance", "--outputs",
            "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed", "--json"]
    got = _run("check", str(f), "-b", str(BINDINGS), *args)
    declared = tmp_path / "d" / "sr.fret"
    declared.parent.mkdir()
    declared.write_text((REQS / "safe_ros.fret").read_text(encoding="utf-8"), encoding="utf-8")
    want = _run("check", str(declared), *args)
    assert got.exit_code == want.exit_code and got.exit_code in (0, 1), got.output
    a, b = _no_lines(json.loads(got.output)), _no_lines(json.loads(want.output))
    assert json.dumps(a).replace(str(f), "F") == json.dumps(b).replace(str(declared), "F")


def _no_lines(doc):
    """``doc`` without its line numbers (the file without ``@tick_period`` is a line
    shorter)."""
    if isinstance(doc, dict):
        return {k: _no_lines(v) for k, v in doc.items() if k != "line"}
    if isinstance(doc, list):
        return [_no_lines(v) for v in doc]
    return doc


def test_a_fret_export_takes_the_period_of_b(tmp_path):
    export = tmp_path / "r2.json"
    export.write_text(json.dumps({"requirements": [
        {"reqid": "R2", "fulltext": "upon too_close agilex_agent shall within 1 second "
                                    "satisfy stopped"}]}), encoding="utf-8")
    got = _run("shield", str(export), "-b", str(BINDINGS), "--inputs", "too_close",
               "--outputs", "stopped", "--explain")
    assert got.exit_code == 0 and "may wait up to 10 ticks (1 s)" in got.output, got.output
    got = _run("shield", str(export), "--inputs", "too_close", "--outputs", "stopped")
    assert got.exit_code == 2 and "'1 second' is a duration in time units" in got.output


def test_a_declared_period_other_than_the_bindings_is_refused(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text("@tick_period 50 ms\nR2: upon too_close a shall within 1 second satisfy "
                 "stopped\n", encoding="utf-8")
    got = _run("shield", str(f), "-b", str(BINDINGS), "--inputs", "too_close", "--outputs",
               "stopped")
    assert got.exit_code == 2 and "declares a tick period of 50 ms but the bindings" \
        in got.output, got.output


def test_explain_says_1_tick(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text("R1: upon a c shall within 1 tick satisfy o\n", encoding="utf-8")
    got = _run("shield", str(f), "--inputs", "a", "--outputs", "o", "--explain")
    assert got.exit_code == 0 and "R1: o may wait up to 1 tick after a becomes true" \
        in got.output, got.output


def test_testgen_writes_the_bindings_period(tmp_path):
    f = _no_period(tmp_path / "t")
    reqs = f.with_name("r2.fret")
    reqs.write_text(f.read_text(encoding="utf-8").split("R3:")[0], encoding="utf-8")
    out = tmp_path / "tests"
    got = _run("testgen", str(reqs), "-b", str(BINDINGS), "-o", str(out))
    assert got.exit_code in (0, 1, 3), got.output
    text = (out / "tests.json").read_text(encoding="utf-8")
    assert json.loads(text)["tests"] and "within 10 ticks" in text, text[:2000]
    assert "within 1 ticks" not in text and "within 1 tick " not in text


def _two_components(tmp_path: Path) -> str:
    """A FRET export of two components: ``ctrl``'s pair conflicts, ``mon`` counts seconds."""
    return fret_export(tmp_path / "p.json", {
        "C1": "whenever a ctrl shall immediately satisfy o",
        "C2": "whenever a ctrl shall immediately satisfy !o",
        "M1": "upon b mon shall within 2 seconds satisfy w"},
        [("ctrl", "a", "Input"), ("ctrl", "o", "Output"), ("mon", "b", "Input"),
         ("mon", "w", "Output")])


def test_a_component_with_no_period_is_not_checked_and_the_others_are(tmp_path):
    """A FRET project: the component whose durations have no period is 'not checked' (its
    row says why, the error on stderr), the others are checked, and the run exits with the
    worst of them (1), not as an input error (2); alone (``--component``) it stays 2."""
    export, out = _two_components(tmp_path), tmp_path / "check.json"
    got = CliRunner().invoke(main, ["check", export, "--no-redundancy", "-o", str(out)])
    assert got.exit_code == 1, got.output
    rows = {r["component"]: r for r in json.loads(out.read_text())["fret_components"]}
    assert rows["ctrl"]["realizability"] == "unrealizable"
    assert rows["mon"]["realizability"] == "not checked"
    assert "M1: '2 seconds' is a duration in time units and no tick period is known" in \
        rows["mon"]["reason"]
    assert "error: " in got.output and "M1: '2 seconds'" in got.output
    given = _run("check", export, "--no-redundancy", "--tick-period", "1s", "--json")
    rows = {r["component"]: r for r in json.loads(given.output)["fret_components"]}
    assert rows["mon"]["realizability"] == "realizable", rows["mon"]
    alone = _run("check", export, "--component", "mon")
    assert alone.exit_code == 2 and "no tick period is known" in alone.output
