"""``fretc shield-replay`` over damaged recordings (../shared/DESIGN.md, "Damage is a gap"):
the intact span is replayed and written, the damage is named (log time, what the reader
said), and the audit of the shielded run is partial there.

Metamorphic: the replay of a damaged copy of a shipped trace equals the replay of the intact
trace truncated at the damage's log time (the shield's messages and the recorded messages of
the span); the shielded run's verdicts never claim more than the intact replay's (never
``satisfied`` where the intact replay is ``violated``); nothing is left half-written when
the replay exits 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st


from _replay import REPO, TRACE, copy_mcap, docs_shield, rosbag2_copy, run

REQS = ["-r", str(REPO / "requirements" / "safe_ros.fret"), "-r",
        str(REPO / "requirements" / "shield" / "release.fret")]
SHIELD_TOPICS = ("/cmd_vel_filtered", "/gwendolen_control")


@pytest.fixture(scope="module")
def shield_dir(tmp_path_factory) -> Path:
    """The docs' simulator shield (R2..R6 and the release), Python form."""
    return docs_shield(tmp_path_factory.mktemp("shield"))


@pytest.fixture(scope="module")
def intact(shield_dir, tmp_path_factory) -> dict:
    """The replay of the intact trace: its JSON run."""
    tmp = tmp_path_factory.mktemp("intact")
    got = run("shield-replay", str(shield_dir), str(TRACE), "-o", str(tmp / "out"), *REQS,
              "--json", str(tmp / "r.json"))
    assert got.exit_code == 1, got.output
    return json.loads((tmp / "r.json").read_text())["runs"][0]


def by_topic(path: Path) -> dict[str, list]:
    """topic -> [(log time, bytes)] by the mcap library."""
    from mcap.reader import make_reader

    out: dict[str, list] = {}
    with open(path, "rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append((message.log_time, bytes(message.data)))
    return {k: sorted(v) for k, v in out.items()}


def truncated_copy(src: Path, dst: Path, end: int) -> None:
    """``src`` copied by the mcap library with only the messages of log time < ``end``."""
    copy_mcap(src, dst, lambda _topic, t: t < end)


def read_by_the_audit(path: Path) -> tuple[bool, bool]:
    """(whether the audit's reader finds the log damaged, whether it reads no message of
    /scan or none of /cmd_vel, which the shield reads, before the damage)."""
    from fretc.common.errors import FretcError
    from fretc.logs import open_log

    try:
        source = open_log(str(path))
    except FretcError:
        return True, True
    times = {"/scan": [], "/cmd_vel": []}
    for m in source.messages(set(times)):
        times[m.topic].append(m.log_time)
    end = source.intact_end
    return source.partial, any(not [t for t in ts if end is None or t < end]
                               for ts in times.values())


def _cut(at: int):
    return lambda data: data[:at]


def _zeroed(at: int, n: int = 64):
    return lambda data: data[:at] + bytes(n) + data[at + n:]


# the trace's first chunk holds bytes 38 .. 277,014 (0 .. 13.6 s), its second 303,420 ..
# 348,379 (13.6 .. 15.7 s), then the summary
DAMAGES = {
    "cut in the first chunk, early": _cut(40_000),
    "cut in the first chunk": _cut(150_000),
    "cut at the end of the first chunk": _cut(276_000),
    "cut between the chunks": _cut(290_000),
    "cut in the second chunk": _cut(320_000),
    "cut in the summary": _cut(352_000),
    "zeroed bytes in the first chunk": _zeroed(120_000),
    "zeroed bytes in the second chunk": _zeroed(330_000),
}


@pytest.mark.parametrize("damage", sorted(DAMAGES))
@pytest.mark.tor("TOR-SHD-007")
def test_a_damaged_recording_is_replayed_up_to_the_damage(shield_dir, intact, tmp_path,
                                                          damage):
    check_damaged(shield_dir, intact, tmp_path, DAMAGES[damage](TRACE.read_bytes()))


@pytest.mark.slow
@settings(max_examples=50)
@given(at=st.one_of(st.integers(9, TRACE.stat().st_size - 1),
                    st.integers(277_000, TRACE.stat().st_size - 1)),  # (the chunk after)
       zero=st.booleans(), n=st.integers(1, 4096))
def test_any_cut_or_zeroed_span_is_replayed_up_to_the_damage(shield_dir, intact, at, zero, n):
    import tempfile

    from hypothesis import event

    data = TRACE.read_bytes()
    bad = _zeroed(at, n)(data)[:len(data)] if zero else _cut(at)(data)
    with tempfile.TemporaryDirectory() as tmp:
        event(check_damaged(shield_dir, intact, Path(tmp), bad))


def check_damaged(shield_dir: Path, intact: dict, tmp_path: Path, data: bytes) -> str:
    """The replay of the damaged recording ``data``: exit 2 with nothing written when the
    audit's reader reads nothing before the damage; else the intact span replayed, equal
    to the replay of the intact trace truncated there, its audit partial and never more
    than the intact replay's."""
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(data)
    got = run("shield-replay", str(shield_dir), str(bad), "-o", str(tmp_path / "out"), *REQS,
              "--json", str(tmp_path / "r.json"))
    assert "Traceback" not in got.output and got.exception is None or \
        isinstance(got.exception, SystemExit), got.output
    partial, empty = read_by_the_audit(bad)
    if got.exit_code == 2:  # (nothing could be read: nothing written)
        assert "bad.mcap" in got.output and "damage" in got.output
        assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []
        assert empty, got.output
        return "nothing before the damage: exit 2"
    doc = json.loads((tmp_path / "r.json").read_text())["runs"][0]
    damaged = doc["damage"]
    if not partial:  # (bytes the reader does not check, or changed to what they were)
        assert damaged is None and doc["ticks"] == intact["ticks"]
        return "no damage found"
    assert damaged is not None, "the damage is said"
    end = damaged["damage_time_ns"]
    if end is None:  # (damage that loses no message: the summary; every message read)
        assert doc["written"] == intact["written"] and doc["ticks"] == intact["ticks"]
        assert got.exit_code in (1, 3)  # (never 0 over a damaged recording)
        assert "the recording is damaged" in got.output and damaged["problems"]
        return "damaged, no message lost: all replayed"
    assert "the recording is damaged" in got.output and str(end) in got.output
    assert damaged["problems"] and (doc["last_tick"] is None or doc["last_tick"] < end)
    # metamorphic: the intact trace truncated at the same log time, replayed
    truncated_copy(TRACE, tmp_path / "trunc.mcap", end)
    again = run("shield-replay", str(shield_dir), str(tmp_path / "trunc.mcap"), "-o",
                str(tmp_path / "t"), *REQS)
    assert again.exit_code in (0, 1, 3), again.output
    cut = by_topic(tmp_path / "out" / "bad.shielded.mcap")
    ref = by_topic(tmp_path / "t" / "trunc.shielded.mcap")
    assert set(cut) == set(ref)
    for topic in ref:
        assert cut[topic] == [m for m in ref[topic] if m[0] < end], topic
    for topic in SHIELD_TOPICS:  # (the intact span's ticks, every one published)
        assert len(cut[topic]) == doc["ticks"] > 0
    # the audit of the shielded run is partial at the damage, never more than the intact's
    audit = doc["audit"]
    assert audit["partial"] is True and audit["damage_time_ns"] == end
    full = {v["requirement"]: v["verdict"] for v in intact["audit"]["verdicts"]}
    for v in audit["verdicts"]:
        assert v["verdict"] in (full[v["requirement"]], "unknown"), (v, full)
        if full[v["requirement"]] == "violated":
            assert v["verdict"] != "satisfied"
    assert got.exit_code == (1 if any(v["verdict"] == "violated" for v in audit["verdicts"])
                             else 3)
    return "replayed up to the damage"


def test_a_recording_of_which_nothing_can_be_read_exits_2_and_writes_nothing(shield_dir,
                                                                            tmp_path):
    bad = tmp_path / "cut.mcap"
    bad.write_bytes(TRACE.read_bytes()[:20])
    got = run("shield-replay", str(shield_dir), str(bad), "-o", str(tmp_path / "out"), *REQS)
    assert got.exit_code == 2, got.output
    assert "cut.mcap" in got.output and "Traceback" not in got.output
    assert list((tmp_path / "out").iterdir()) == []


@pytest.mark.tor("TOR-SHD-007")
def test_the_shielded_recording_carries_the_damage_for_a_later_audit(shield_dir, tmp_path):
    """``fretc audit`` of the written shielded recording, alone, is partial at the damage
    too (the gap is carried in the file, as a watch's recording carries its own)."""
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(TRACE.read_bytes()[:150_000])
    got = run("shield-replay", str(shield_dir), str(bad), "-o", str(tmp_path / "out"), *REQS,
              "--json", str(tmp_path / "r.json"))
    assert got.exit_code in (1, 3), got.output
    end = json.loads((tmp_path / "r.json").read_text())["runs"][0]["damage"]["damage_time_ns"]
    bindings = str(next(shield_dir.glob("*.bindings.toml")))
    again = run("audit", *REQS, "-b", bindings, str(tmp_path / "out" / "bad.shielded.mcap"),
                "--no-progress", "--json", str(tmp_path / "a.json"))
    la = json.loads((tmp_path / "a.json").read_text())["logs"][0]
    assert la["partial"] is True and la["damage_time_ns"] == end, again.output
    assert all(v["verdict"] != "satisfied" or v["requirement"] != "R5"
               for v in la["verdicts"])  # (an invariant over a cut run is not satisfied)


@pytest.mark.parametrize("plugin", ["SQLITE3", "MCAP"])
def test_a_rosbag2_folder_whose_storage_is_cut_is_refused_as_the_audit_refuses_it(
        shield_dir, tmp_path, plugin):
    """rosbags opens no cut rosbag2 storage (sqlite3: "database disk image is malformed";
    MCAP: no end magic), so neither the audit nor the replay reads anything of it: exit 2,
    the folder and the reader's words named, nothing written."""
    from rosbags.rosbag2 import StoragePlugin

    bag = tmp_path / "run_bag"
    rosbag2_copy(TRACE, bag, storage_plugin=getattr(StoragePlugin, plugin))
    storage = next(p for p in bag.iterdir() if p.suffix in (".db3", ".mcap"))
    storage.write_bytes(storage.read_bytes()[: storage.stat().st_size // 2])
    bindings = str(next(shield_dir.glob("*.bindings.toml")))
    audited = run("audit", *REQS, "-b", bindings, str(bag), "--no-progress")
    got = run("shield-replay", str(shield_dir), str(bag), "-o", str(tmp_path / "out"), *REQS)
    assert audited.exit_code == got.exit_code == 2, (audited.output, got.output)
    assert "run_bag" in got.output and "cannot open rosbag2" in got.output
    assert "Traceback" not in got.output
    assert list((tmp_path / "out").iterdir()) == []


def test_a_cut_ros1_bag_is_replayed_up_to_the_damage_as_the_audit_reads_it(shield_dir,
                                                                          tmp_path):
    """A ROS 1 bag cut short (a crashed recording: no index) is read record by record, as
    the audit reads it: its intact span replayed, equal to the replay of the whole bag
    there (the shield's messages and the recorded ones, their ROS 1 channels)."""
    from mcap.reader import make_reader
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    bag = tmp_path / "run.bag"
    with Writer(bag) as w, open(REPO / "traces" / "nominal_ros1.mcap", "rb") as f:
        conns = {}
        for schema, channel, m in make_reader(f).iter_messages(log_time_order=True):
            pkg, name = schema.name.split("/")
            if f"{pkg}/msg/{name}" not in store.types:
                continue  # (/tf: a type Noetic's store lacks, which the shield does not read)
            if channel.topic not in conns:
                conns[channel.topic] = w.add_connection(channel.topic, f"{pkg}/msg/{name}",
                                                        typestore=store)
            w.write(conns[channel.topic], m.log_time, m.data)
    cut = tmp_path / "cut" / "run.bag"
    cut.parent.mkdir()
    cut.write_bytes(bag.read_bytes()[: bag.stat().st_size // 2])
    whole = run("shield-replay", str(shield_dir), str(bag), "-o", str(tmp_path / "whole"),
                *REQS)
    got = run("shield-replay", str(shield_dir), str(cut), "-o", str(tmp_path / "out"), *REQS,
              "--json", str(tmp_path / "r.json"))
    assert whole.exit_code in (0, 1) and got.exit_code in (1, 3), got.output
    doc = json.loads((tmp_path / "r.json").read_text())["runs"][0]
    end = doc["damage"]["damage_time_ns"]
    assert end is not None and "truncated" in got.output and "without the bag index" in got.output
    ref = by_topic(tmp_path / "whole" / "run.shielded.mcap")
    mine = by_topic(tmp_path / "out" / "run.shielded.mcap")
    assert set(mine) == set(ref)
    for topic in ref:
        assert mine[topic] == [m for m in ref[topic] if m[0] < end], topic
        assert mine[topic], topic  # (every topic has messages before the cut)
    assert doc["audit"]["partial"] is True and doc["audit"]["damage_time_ns"] == end


def test_damage_that_loses_no_message_is_named_and_never_exits_0(shield_dir, tmp_path):
    """Zeroed bytes in the summary (its CRC fails; every record is read without the index):
    the whole recording replayed, the damage named, exit 3 where the shielded run's audit
    alone would give 0 (as fretc audit of the recording gives 3)."""
    data = bytearray(TRACE.read_bytes())
    data[355_000:355_064] = bytes(64)
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    reqs = ["-r", str(REPO / "requirements" / "shield" / "release.fret")]
    got = run("shield-replay", str(shield_dir), str(bad), "-o", str(tmp_path / "out"), *reqs,
              "--json", str(tmp_path / "r.json"))
    assert got.exit_code == 3, got.output
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["exit_code"] == 3 and doc["runs"][0]["audit"]["partial"] is False
    damage = doc["runs"][0]["damage"]
    assert damage["damage_time_ns"] is None and "summary" in damage["problems"][0]
    assert "every message in it replayed" in got.output
    assert by_topic(tmp_path / "out" / "bad.shielded.mcap") == by_topic(
        run_whole(shield_dir, tmp_path, reqs))


def run_whole(shield_dir: Path, tmp_path: Path, reqs: list[str]) -> Path:
    """The intact trace's shielded recording, replayed into ``tmp_path / "whole"``."""
    got = run("shield-replay", str(shield_dir), str(TRACE), "-o", str(tmp_path / "whole"),
              *reqs)
    assert got.exit_code == 0, got.output
    return tmp_path / "whole" / "sif_disabled.shielded.mcap"


def test_a_watch_recording_s_gaps_are_carried_into_the_shielded_recording(shield_dir,
                                                                         tmp_path):
    """A recording of ``fretc watch --record`` carries the gaps in which the watch lost
    messages; the shielded recording carries them on, so its audit is partial as the
    recording's is."""
    from mcap.reader import make_reader

    from fretc.logs.base import Gap
    from fretc.logs.recorded_gaps import GAPS_METADATA, WATCH_LIBRARY, gaps_json, parse_gaps

    lost = [Gap(1_700_000_005_000_000_000, 1_700_000_006_000_000_000, frozenset({"/scan"}),
                "dropped")]
    watched = tmp_path / "watched.mcap"
    copy_mcap(TRACE, watched,  # (what the watch lost left out)
              lambda topic, t: not (topic == "/scan" and lost[0].start <= t <= lost[0].end),
              library=WATCH_LIBRARY, metadata={GAPS_METADATA: {"gaps": gaps_json(lost)}})
    got = run("shield-replay", str(shield_dir), str(watched), "-o", str(tmp_path / "out"),
              *REQS, "--json", str(tmp_path / "r.json"))
    assert got.exit_code in (1, 3), got.output
    with open(tmp_path / "out" / "watched.shielded.mcap", "rb") as f:
        carried = [parse_gaps(m.metadata["gaps"]) for m in make_reader(f).iter_metadata()
                   if m.name == GAPS_METADATA]
    assert carried == [lost]
    audit = json.loads((tmp_path / "r.json").read_text())["runs"][0]["audit"]
    assert audit["partial"] is True and audit["damage_time_ns"] == lost[0].start
