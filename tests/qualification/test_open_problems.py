"""The open known problems of src/fretc/qualification/known_problems.toml, each reproduced:
a strict ``xfail`` test that states the behaviour the problem breaks, so it fails (xfailed)
while the problem is open and passes - failing the run, strict - once it is fixed, when the
known problem's entry must get its ``fixed_in``. (KP-001's test is
tests/audit/test_streamed.py's, which asserts the fallback as designed.)"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _logs import MS, boolean, float64, write_mcap  # noqa: E402


@pytest.mark.xfail(strict=True, reason="KP-002 (open): an infinite input is named NaN")
def test_an_infinite_input_is_named_infinite_in_the_replay(tmp_path: Path):
    messages = []
    for i in range(8):
        t = 1_000 * MS + i * 100 * MS
        messages.append(("/x", "std_msgs/msg/Float64", t,
                         float64(float("inf") if i in (3, 4) else 1.0)))
        messages.append(("/o", "std_msgs/msg/Bool", t + 1, boolean(False)))
    write_mcap(tmp_path / "rec.mcap", messages)
    (tmp_path / "r.fret").write_text("S1: whenever x > 5 ctrl shall immediately satisfy o\n")
    (tmp_path / "r.toml").write_text('[tick]\nperiod = "100 ms"\n\n[variables]\n'
                                     'x = "/x.data"\no = "/o.data"\n')
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "r.toml"), "--inputs", "x", "--outputs",
                                    "o", "--emit", "python", "-o", str(tmp_path / "sh")])
    assert got.exit_code == 0, got.output
    got = CliRunner().invoke(main, ["shield-replay", str(tmp_path / "sh"),
                                    str(tmp_path / "rec.mcap"), "-o", str(tmp_path / "out"),
                                    "--json", str(tmp_path / "replay.json")])
    faults = json.loads((tmp_path / "replay.json").read_text())["runs"][0]["input_faults"]
    assert faults["ticks"] == 2  # the two infinite ticks, unread as the bindings say
    assert "NaN" not in faults["why"] and "inf" in faults["why"]


@pytest.mark.xfail(strict=True, reason="KP-003 (open): an unknown cell is called a NaN")
def test_an_unknown_cell_is_not_called_a_nan(tmp_path: Path):
    (tmp_path / "r.fret").write_text("R1: the sw shall always satisfy x <= 5\n")
    (tmp_path / "u.csv").write_text("x\n1\nunknown\n2\n")
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"),
                                    str(tmp_path / "u.csv"), "--json",
                                    str(tmp_path / "a.json"), "--no-progress"])
    assert got.exit_code == 3, got.output
    verdict = json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"][0]
    assert verdict["verdict"] == "unknown"
    assert "NaN" not in verdict["unknown_reason"]
