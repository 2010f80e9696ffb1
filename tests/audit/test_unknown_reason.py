"""The reason of an ``unknown`` verdict over a CSV trace names what its unknown ticks read:
``unknown`` cells are unknown values of their variable, never "comparisons with NaN" (known
problem KP-003); a NaN cell is a comparison with NaN; a trace with both says both."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main


def reason(tmp_path: Path, cells: list[str], rule: str = "x <= 5 & y <= 5") -> str:
    """The unknown reason of R1 (``always satisfy rule``) over a CSV of columns x and y,
    the rows ``cells`` (``"x,y"``)."""
    (tmp_path / "r.fret").write_text(f"R1: the sw shall always satisfy {rule}\n")
    (tmp_path / "u.csv").write_text("x,y\n" + "\n".join(cells) + "\n")
    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"),
                                    str(tmp_path / "u.csv"), "--json",
                                    str(tmp_path / "a.json"), "--no-progress"])
    assert got.exit_code == 3, got.output
    verdict = json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"][0]
    assert verdict["verdict"] == "unknown"
    return verdict["unknown_reason"]


def test_an_unknown_cell_is_not_called_a_nan(tmp_path: Path):
    got = reason(tmp_path, ["1,1", "unknown,1", "2,1"])
    assert got.startswith("1 of its 3 ticks are unknown (unknown values of x; the first at "
                          "tick 1,")
    assert "NaN" not in got


def test_unknown_cells_of_two_variables_name_both(tmp_path: Path):
    got = reason(tmp_path, ["1,unknown", "unknown,1", "2,1"])
    assert "2 of its 3 ticks are unknown (unknown values of x, y;" in got
    assert "NaN" not in got


def test_a_nan_cell_is_a_comparison_with_nan(tmp_path: Path):
    got = reason(tmp_path, ["1,1", "nan,1", "2,1"])
    assert "(comparisons with NaN; the first at tick 1," in got


def test_a_trace_with_both_names_both(tmp_path: Path):
    got = reason(tmp_path, ["1,1", "nan,1", "2,unknown"])
    assert "2 of its 3 ticks are unknown (unknown values of y, comparisons with NaN;" in got


@pytest.mark.parametrize("cells", [["1,1", "unknown,1", "nan,1"], ["nan,1", "unknown,1"]])
def test_a_nan_and_an_unknown_cell_of_one_variable_name_both(
        tmp_path: Path, cells):
    got = reason(tmp_path, cells)
    assert "unknown values of x, comparisons with NaN" in got
