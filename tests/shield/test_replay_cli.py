"""``fretc shield-replay`` on the simulator's shipped recordings (``traces/``): a recorded
topic the shield publishes on (the hand-written SIF's ``/cmd_vel_filtered`` and
``/gwendolen_control``) kept unchanged under ``/recorded/...`` while the shield's messages
take the topic; bad inputs exit 2 naming where; a link planted at the output's name is
never written through."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

REPO = Path(__file__).resolve().parents[2]
TRACE = REPO / "traces" / "sif_disabled.mcap"


def run(*args: str):
    return CliRunner().invoke(main, list(args))


@pytest.fixture(scope="module")
def shield_dir(tmp_path_factory) -> Path:
    """The docs' simulator shield (R2..R6 and the release), Python form."""
    out = tmp_path_factory.mktemp("shield")
    got = run("shield", str(REPO / "requirements" / "safe_ros.fret"),
              str(REPO / "requirements" / "shield" / "release.fret"), "-b",
              str(REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml"),
              "--inputs", "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind",
              "--outputs", "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,"
              "linear_velocity", "--emit", "python", "-o", str(out))
    assert got.exit_code == 0, got.output
    return out


def by_topic(path: Path) -> dict[str, list]:
    """topic -> [(log time, bytes, schema name, schema data)] by the mcap library."""
    from mcap.reader import make_reader

    out: dict[str, list] = {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append(
                (message.log_time, bytes(message.data), schema.name, bytes(schema.data)))
    return out


def test_recorded_outputs_are_kept_under_recorded_and_the_shield_takes_their_topics(
        shield_dir, tmp_path):
    got = run("shield-replay", str(shield_dir), str(TRACE), "-o", str(tmp_path / "out"),
              "-r", str(REPO / "requirements" / "safe_ros.fret"), "-r",
              str(REPO / "requirements" / "shield" / "release.fret"),
              "--json", str(tmp_path / "r.json"))
    assert got.exit_code == 1, got.output  # (R5, the plant's, is as recorded: violated)
    doc = json.loads((tmp_path / "r.json").read_text())["runs"][0]
    before = by_topic(TRACE)
    after = by_topic(tmp_path / "out" / "sif_disabled.shielded.mcap")
    kept = {"/cmd_vel_filtered": "/recorded/cmd_vel_filtered",
            "/gwendolen_control": "/recorded/gwendolen_control"}
    assert doc["recorded_kept_as"] == kept
    for topic, messages in before.items():
        assert after[kept.get(topic, topic)] == messages, topic
    ticks = doc["ticks"]
    assert len(after["/cmd_vel_filtered"]) == len(after["/gwendolen_control"]) == ticks
    assert {t for t, *_ in after["/cmd_vel_filtered"]} == {
        doc["first_tick"] + k * 100_000_000 for k in range(ticks)}
    verdicts = {v["requirement"]: v["verdict"] for v in doc["audit"]["verdicts"]}
    assert verdicts["R2"] == verdicts["R9"] == verdicts["R11"] == "satisfied"
    assert verdicts["R5"] == "violated"
    assert doc["overrides"]["R9"]["ticks"] > 0
    assert "R2: 1 tick overridden" in got.output
    assert "R5" in got.output and "a replay does not move the robot" in got.output


def test_a_log_without_the_topics_the_shield_reads_is_an_input_error(shield_dir, tmp_path):
    got = run("shield-replay", str(shield_dir), str(REPO / "traces" / "nominal.csv"), "-o",
              str(tmp_path / "out"), "-r", str(REPO / "requirements" / "safe_ros.fret"))
    assert got.exit_code == 2, got.output
    assert "nominal.csv" in got.output and "/scan" in got.output
    assert "Traceback" not in got.output


def test_a_folder_that_is_no_shield_is_an_input_error(tmp_path):
    got = run("shield-replay", str(tmp_path), str(TRACE), "-o", str(tmp_path / "out"))
    assert got.exit_code == 2, got.output
    assert "*_shield.py" in got.output


def test_a_link_planted_at_the_output_is_not_written_through(shield_dir, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "victim"
    victim.write_text("keep")
    (out / "sif_disabled.shielded.mcap").symlink_to(victim)
    got = run("shield-replay", str(shield_dir), str(TRACE), "-o", str(out), "-r",
              str(REPO / "requirements" / "shield" / "release.fret"))
    assert got.exit_code == 0, got.output
    assert victim.read_text() == "keep"
    assert not (out / "sif_disabled.shielded.mcap").is_symlink()
