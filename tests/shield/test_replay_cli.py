"""``fretc shield-replay`` on the simulator's shipped recordings (``traces/``): a recorded
topic the shield publishes on (the hand-written SIF's ``/cmd_vel_filtered`` and
``/gwendolen_control``) kept unchanged under ``/recorded/...`` while the shield's messages
take the topic; bad inputs exit 2 naming where; a link planted at the output's name is
never written through."""

from __future__ import annotations

import json
from pathlib import Path

import pytest


from _replay import REPO, TRACE, copy_mcap, docs_shield, rosbag2_copy, run



@pytest.fixture(scope="module")
def shield_dir(tmp_path_factory) -> Path:
    """The docs' simulator shield (R2..R6 and the release), Python form."""
    return docs_shield(tmp_path_factory.mktemp("shield"))


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


def test_ticks_before_the_first_scan_are_decided_for_every_scan_and_say_so(shield_dir, tmp_path):
    from rosbags.typesys import Stores, get_typestore

    start = min(t for t, *_ in by_topic(TRACE)["/scan"])
    late = start + 1_000_000_000  # (the LiDAR's first scan a second after the rest)
    copy_mcap(TRACE, tmp_path / "late.mcap", lambda topic, t: topic != "/scan" or t >= late)
    got = run("shield-replay", str(shield_dir), str(tmp_path / "late.mcap"), "-o",
              str(tmp_path / "out"), "-r", str(REPO / "requirements" / "shield" /
                                                "release.fret"), "--json",
              str(tmp_path / "r.json"))
    assert got.exit_code in (0, 1), got.output
    doc = json.loads((tmp_path / "r.json").read_text())["runs"][0]
    faults = doc["input_faults"]
    # the first tick is the grid's first at or after the first message the shield reads
    # (a proposal on /cmd_vel, 50 ms in); every tick before the first scan is a fault
    first = -(-min(t for t, *_ in by_topic(TRACE)["/cmd_vel"]) // 100_000_000) * 100_000_000
    n = (late - first) // 100_000_000
    assert n == 9 and faults["ticks"] == n and faults["first_log_time"] == doc["first_tick"]
    assert doc["first_tick"] == first and start < first
    assert faults["last_log_time"] == late - 100_000_000 and "/scan" in faults["why"]
    assert (f"an input not read: decided for every value it could have had: {n} ticks"
            in got.output)
    store = get_typestore(Stores.ROS2_JAZZY)
    after = by_topic(tmp_path / "out" / "late.shielded.mcap")
    early = {topic: [store.deserialize_cdr(data, name) for t, data, name, _d in after[topic]
                     if t < late] for topic in ("/cmd_vel_filtered", "/gwendolen_control")}
    assert all(len(msgs) == n for msgs in early.values()), early
    # the unread scan is any scan: stale from the first tick on, so R6's stop request
    # comes within 500 ms (5 ticks) of every tick (the letter of R6: a request at least
    # once in every 6 ticks), and R3 zeroes the command with it
    requested = [m.data for m in early["/gwendolen_control"]]
    assert all(True in requested[k:k + 6] for k in range(len(requested) - 5)), requested
    for stop, cmd in zip(requested, early["/cmd_vel_filtered"]):
        assert not stop or cmd.linear.x == cmd.angular.z == 0, (requested, cmd)
    # from the first scan on, the shield decides as on the whole run
    assert doc["overrides"]["R9"]["ticks"] == 47


def test_a_rosbag2_folder_is_replayed_with_its_messages_kept(shield_dir, tmp_path):
    bag = tmp_path / "run_bag"
    rosbag2_copy(TRACE, bag)
    got = run("shield-replay", str(shield_dir), str(bag), "-o", str(tmp_path / "out"), "-r",
              str(REPO / "requirements" / "shield" / "release.fret"))
    assert got.exit_code in (0, 1), got.output
    before = by_topic(TRACE)
    after = by_topic(tmp_path / "out" / "run_bag.shielded.mcap")
    for topic, messages in before.items():
        kept = after["/recorded" + topic if topic in ("/cmd_vel_filtered",
                                                      "/gwendolen_control") else topic]
        assert [(t, d) for t, d, *_ in kept] == [(t, d) for t, d, *_ in messages], topic
    assert "R9: 47 ticks overridden" in got.output  # (as from the MCAP file itself)


def test_json_to_stdout_is_the_document_alone(shield_dir, tmp_path):
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "fretc", "shield-replay", str(shield_dir),
                           str(TRACE), "-o", str(tmp_path / "out"), "-r",
                           str(REPO / "requirements" / "shield" / "release.fret"), "--json",
                           "-"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)  # (the overrides and the audit's table on stderr)
    assert doc["runs"][0]["overrides"]["R9"]["ticks"] == 47
    assert "R9: 47 ticks overridden" in done.stderr


def test_the_same_replay_writes_the_same_bytes(shield_dir, tmp_path):
    for out in ("a", "b"):
        got = run("shield-replay", str(shield_dir), str(TRACE), "-o", str(tmp_path / out),
                  "-r", str(REPO / "requirements" / "shield" / "release.fret"))
        assert got.exit_code == 0, got.output
    assert (tmp_path / "a" / "sif_disabled.shielded.mcap").read_bytes() == \
        (tmp_path / "b" / "sif_disabled.shielded.mcap").read_bytes()


@pytest.mark.parametrize("edit, named", [
    (lambda t: t.replace('"/gwendolen_control" = "std_msgs/msg/Bool"',
                         '"/gwendolen_control" = "std_msgs/msg/Nope"'),
     "/gwendolen_control (std_msgs/msg/Nope)"),
    (lambda t: t.replace('time = "log"', 'time = "header"'), "time = 'header'"),
    (lambda t: t.replace('"/cmd_vel_filtered" = "/cmd_vel" }', '"/cmd_vel_filtered" = "/odom_cmd" }'),
     "no message of /odom_cmd"),
], ids=["unknown type", "header time base", "proposal topic not recorded"])
def test_a_binding_file_the_replay_cannot_take_is_an_input_error(shield_dir, tmp_path, edit,
                                                                 named):
    import shutil

    folder = tmp_path / "shield"
    shutil.copytree(shield_dir, folder)
    toml = next(folder.glob("*.bindings.toml"))
    toml.write_text(edit(toml.read_text()))
    got = run("shield-replay", str(folder), str(TRACE), "-o", str(tmp_path / "out"), "-r",
              str(REPO / "requirements" / "shield" / "release.fret"))
    assert got.exit_code == 2, got.output
    assert named in got.output and "Traceback" not in got.output


def test_the_recorded_run_violates_what_the_shielded_run_satisfies(shield_dir, tmp_path):
    """The page's claim: as recorded (the SIF switched off), R2 and R9 are violated on
    ``sif_disabled``; shielded, satisfied."""
    reqs = ["-r", str(REPO / "requirements" / "safe_ros.fret"), "-r",
            str(REPO / "requirements" / "shield" / "release.fret")]
    bindings = str(next(shield_dir.glob("*.bindings.toml")))
    got = run("audit", *reqs, "-b", bindings, str(TRACE), "--no-progress", "--json",
              str(tmp_path / "a.json"))
    assert got.exit_code == 1, got.output
    recorded = {v["requirement"]: v["verdict"]
                for v in json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"]}
    got = run("shield-replay", str(shield_dir), str(TRACE), "-o", str(tmp_path / "out"),
              *reqs, "--json", str(tmp_path / "r.json"))
    shielded = {v["requirement"]: v["verdict"] for v in json.loads(
        (tmp_path / "r.json").read_text())["runs"][0]["audit"]["verdicts"]}
    assert recorded["R2"] == recorded["R9"] == "violated"
    assert shielded["R2"] == shielded["R9"] == "satisfied"
    assert recorded["R5"] == shielded["R5"] == "violated"  # (the plant's: as recorded)


def test_an_output_topic_the_recording_lacks_without_a_proposal_is_an_input_error(tmp_path):
    """The Safety System round: an output topic without ``[shield] proposals`` or ``[shield] originates``
    proposed the default message at every tick, silently. The shipped trace holds
    ``/cmd_vel_filtered`` (the hand-written interceptor's): without the table it is its own
    proposal, and said; a topic it does not hold is refused, naming it and the tables."""
    import re

    src = (REPO / "requirements" / "shield" / "safe_ros_shield.bindings.toml").read_text()
    fret = [str(REPO / "requirements" / "safe_ros.fret"),
            str(REPO / "requirements" / "shield" / "release.fret")]
    io = ["--inputs", "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind",
          "--outputs", "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,"
          "linear_velocity"]
    no_table = re.sub(r'\nproposals = \{[^}]*\}\n', "\n", src)
    assert no_table != src
    for name, text, code, said in (
            ("own", no_table, (0, 1), "proposals of /cmd_vel_filtered: its recorded messages"),
            ("none", no_table.replace("/cmd_vel_filtered", "/cmd_vel_safe"), (2,),
             "no proposal for /cmd_vel_safe")):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "b.toml").write_text(text)
        got = run("shield", *fret, "-b", str(folder / "b.toml"), *io, "--emit", "python",
                  "-o", str(folder / "shield"))
        assert got.exit_code == 0, got.output
        got = run("shield-replay", str(folder / "shield"), str(TRACE), "-o",
                  str(folder / "out"))
        assert got.exit_code in code and said in got.output.replace("\n", " "), got.output
