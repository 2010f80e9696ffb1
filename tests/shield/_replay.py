"""What the shield-replay tests share: the CLI runner and the docs' simulator shield
(R2..R6 and the release of ``requirements/shield/release.fret``, Python form) built into a
folder."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
TRACE = REPO / "traces" / "sif_disabled.mcap"


def run(*args: str):
    """``fretc ARGS`` in process (click's result: ``exit_code``, ``output``)."""
    return CliRunner().invoke(main, list(args))


def docs_shield(out: Path) -> Path:
    """``out`` after ``fretc shield`` wrote the docs' simulator shield (Python form) into it."""
    got = run("shield", str(REPO / "requirements" / "safe_ros.fret"),
              str(REPO / "requirements" / "shield" / "release.fret"), "-b",
              str(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml"),
              "--inputs", "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind",
              "--outputs", "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,"
              "linear_velocity", "--emit", "python", "-o", str(out))
    assert got.exit_code == 0, got.output
    return out
