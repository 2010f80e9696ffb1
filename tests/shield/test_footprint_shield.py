"""The shipped footprint requirements (requirements/shield/footprint.fret: Nav2's stop
polygon and approach model, the footprint moved along the commanded arc, beside the
approach and slowdown bounds) are proved by ``fretc shield --prove``, and the shield's
Python form replayed over the simulator's unmapped-obstacles run keeps every one of them
where the recorded commands break them."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
FRET = REPO / "requirements" / "shield" / "footprint.fret"
BINDINGS = REPO / "requirements" / "shield" / "footprint.bindings.toml"
TRACE = REPO / "traces" / "unmapped_obstacles.mcap"


def test_the_footprint_shield_is_proved_and_keeps_its_requirements_on_a_recorded_run(
        tmp_path):
    run = CliRunner()
    got = run.invoke(main, ["shield", str(FRET), "-b", str(BINDINGS), "--prove", "--emit",
                            "python", "-o", str(tmp_path / "s")])
    assert got.exit_code == 0, got.output
    for rid in ("S2", "S3", "N1", "N2"):
        assert f"  {rid}: holds" in got.output
    recorded = run.invoke(main, ["audit", "-r", str(FRET), "-b", str(BINDINGS), str(TRACE),
                                 "--no-progress"])
    assert recorded.exit_code == 1, recorded.output  # the SRAS's own commands break them
    replay = run.invoke(main, ["shield-replay", str(tmp_path / "s"), str(TRACE), "-o",
                               str(tmp_path / "r"), "-r", str(FRET)])
    assert replay.exit_code == 0, replay.output
    assert "4 satisfied, 0 vacuous, 0 violated" in " ".join(replay.output.split())
