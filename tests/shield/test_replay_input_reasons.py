"""The reason ``fretc shield-replay`` gives for an input it could not read says what the
value was: a log field's +inf or -inf (unread by default, docs/bindings.md "NaN, ±inf") is
named ``+inf`` or ``-inf``, a NaN ``NaN`` (known problem KP-002); an expression that makes a
number of a log's ±inf says that it reads ±inf. The ticks are the same in every case."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

from _logs import MS, boolean, float64, write_mcap


def replay_faults(tmp_path: Path, bad: float, expr: str = "/x.data",
                  rule: str = "whenever x > 5 ctrl shall immediately satisfy o") -> dict:
    """The replay's ``input_faults`` over a recording of 8 ticks whose /x reads ``bad`` at
    ticks 3 and 4 (1.0 elsewhere), the shield of S1 (``rule``) with ``x = expr``."""
    messages = []
    for i in range(8):
        t = 1_000 * MS + i * 100 * MS
        messages.append(("/x", "std_msgs/msg/Float64", t, float64(bad if i in (3, 4) else 1.0)))
        messages.append(("/o", "std_msgs/msg/Bool", t + 1, boolean(False)))
    write_mcap(tmp_path / "rec.mcap", messages)
    (tmp_path / "r.fret").write_text(f"S1: {rule}\n")
    (tmp_path / "r.toml").write_text('[tick]\nperiod = "100 ms"\n\n[variables]\n'
                                     f'x = "{expr}"\no = "/o.data"\n')
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "r.toml"), "--inputs", "x", "--outputs",
                                    "o", "--emit", "python", "-o", str(tmp_path / "sh")])
    assert got.exit_code == 0, got.output
    got = CliRunner().invoke(main, ["shield-replay", str(tmp_path / "sh"),
                                    str(tmp_path / "rec.mcap"), "-o", str(tmp_path / "out"),
                                    "--json", str(tmp_path / "replay.json")])
    assert got.exit_code in (0, 1, 3, 6), got.output  # (6: every fault answered)
    return json.loads((tmp_path / "replay.json").read_text())["runs"][0]["input_faults"]


@pytest.mark.parametrize("bad, word", [(math.inf, "+inf"), (-math.inf, "-inf")])
def test_an_infinite_input_is_named_infinite_in_the_replay(tmp_path: Path, bad, word):
    faults = replay_faults(tmp_path, bad)
    assert faults["ticks"] == 2  # the two infinite ticks, unread as the bindings say
    assert faults["why"].startswith(f"input x is {word} (")
    assert "NaN" not in faults["why"] and '[tick] inf = "value"' in faults["why"]


def test_a_nan_input_is_still_named_nan(tmp_path: Path):
    faults = replay_faults(tmp_path, math.nan)
    assert faults["ticks"] == 2 and faults["why"] == "input x is NaN"


def test_an_expression_that_makes_a_number_of_an_infinite_field_says_it_reads_inf(
        tmp_path: Path):
    # 1 / inf would be 0: the log's inf is unread, so x is NaN, and the reason says why
    faults = replay_faults(tmp_path, math.inf, expr="1 / /x.data",
                           rule="whenever x > 0.5 ctrl shall immediately satisfy o")
    assert faults["ticks"] == 2
    assert faults["why"].startswith("input x reads ±inf (") and "NaN" not in faults["why"]
