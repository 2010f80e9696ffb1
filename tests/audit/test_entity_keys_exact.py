"""Entity keys are exact for every integer width and encoding (hostile round 9,
E3): ``uint64`` ids past 2**53 were read as float64, two tracks one double apart merged into
one entity and one's violation came out ``satisfied`` (exit 0). Here two tracks whose ids a
float64 merges (2**53 - 1 and 2**53 are distinct doubles, the control; 2**53 and 2**53 + 1,
2**64 - 2 and 2**64 - 1 are one double each) stay two entities, the second's violation
shows and ``fretc audit`` exits 1, in ROS 2 CDR, JSON, CBOR and protobuf MCAP."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st
from rosbags.typesys import get_types_from_msg

from _logs import ROS2, S, TRACK_BINDINGS, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "logs"))
import _encode  # noqa: E402  (the copies of a CDR MCAP in MCAP's other encodings)

BINDINGS = TRACK_BINDINGS
FRET = "@tick_period 100 ms\nT: in present mode the robot shall always satisfy dist > 0.5\n"
PAIRS = [(2**53 - 1, 2**53), (2**53, 2**53 + 1), (2**64 - 2, 2**64 - 1)]


def _types():
    for store in (ROS2, _encode._STORE):
        if "trk64/msg/Track" not in store.types:
            store.register(get_types_from_msg("uint64 id\nfloat64 distance", "trk64/msg/Track"))
            store.register(get_types_from_msg("trk64/Track[] tracks", "trk64/msg/TrackArray"))
    return ROS2.types["trk64/msg/Track"], ROS2.types["trk64/msg/TrackArray"]


def _log(tmp: Path, a: int, b: int, encoding: str, bad_at: int = 3) -> Path:
    """Tracks ``a`` (always 2.0 m away) and ``b`` (0.2 m at message ``bad_at``) in six
    messages, in ``encoding``."""
    Track, Arr = _types()
    msgs = [("/tracks", "trk64/msg/TrackArray", S + k * S // 10,
             Arr(tracks=[Track(id=a, distance=2.0),
                         Track(id=b, distance=0.2 if k == bad_at else 2.0)]))
            for k in range(6)]
    cdr = write_mcap(tmp / "t.mcap", msgs)
    return cdr if encoding == "cdr" else _encode.copy_as(cdr, tmp / f"t.{encoding}.mcap",
                                                          encoding)


def _files(tmp: Path) -> Path:
    (tmp / "t.fret").write_text(FRET)
    (tmp / "t.bindings.toml").write_text(BINDINGS)
    return tmp / "t.fret"


@pytest.mark.parametrize("encoding", ["cdr", "json", "cbor", "protobuf"])
@pytest.mark.parametrize("a,b", PAIRS, ids=["2^53-1", "2^53", "2^64-2"])
@pytest.mark.tor("TOR-BND-003")
def test_two_ids_a_double_merges_are_two_entities_and_the_violation_shows(
        tmp_path, encoding, a, b):
    fret = _files(tmp_path)
    log = _log(tmp_path, a, b, encoding)
    got = {v.requirement: v for v in
           audit_log(load_plan(AuditConfig(requirements=(str(fret),))), str(log)).verdicts}
    assert sorted(got) == sorted(["T", f"T[track={a}]", f"T[track={b}]"]), got
    assert got[f"T[track={a}]"].verdict == "satisfied"
    assert got[f"T[track={b}]"].verdict == "violated"
    assert got[f"T[track={b}]"].first_violation.at.time_ns == S + 3 * S // 10
    assert got["T"].verdict == "violated"


@pytest.mark.parametrize("encoding", ["cdr", "json"])
def test_the_audit_of_ids_past_2_53_exits_1_and_its_json_names_both(tmp_path, encoding):
    """The command's answer: exit 1 (it was 0), the audit JSON naming each id exactly."""
    a, b = 2**53, 2**53 + 1
    fret = _files(tmp_path)
    log = _log(tmp_path, a, b, encoding)
    res = CliRunner().invoke(main, ["audit", str(log), "-r", str(fret), "--json",
                                    str(tmp_path / "out.json")])
    assert res.exit_code == 1, res.output
    doc = json.loads((tmp_path / "out.json").read_text())
    verdicts = {v["requirement"]: v["verdict"]
                for log_ in doc["logs"] for v in log_["verdicts"]}
    assert verdicts[f"T[track={a}]"] == "satisfied"
    assert verdicts[f"T[track={b}]"] == "violated"


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**64 - 1), st.integers(0, 2**64 - 1))
@pytest.mark.tor("TOR-BND-003")
def test_the_exact_key_read_is_the_integer_written(a, b):
    """The key extractor and the filter on the entity's key read a uint64 (numpy array,
    numpy scalar, Python int) as the integer it is: two keys are one only when equal."""
    from types import SimpleNamespace

    from fretc.signals.bindings.expression import Field, Slice
    from fretc.signals.bindings.extract import entity_key, make_extractor

    arr = np.array([a, b], dtype=np.uint64)
    assert [entity_key(x) for x in arr] == [a, b]
    msg = SimpleNamespace(tracks=[SimpleNamespace(id=np.uint64(a)), SimpleNamespace(id=b)])
    key = make_extractor(Field(1, "/tracks", ("tracks", Slice(None, None), "id")), exact=True)
    assert key(msg) == [a, b]
    ids = make_extractor(Field(1, "/ids", ("ids",)), exact=True)
    assert ids(SimpleNamespace(ids=arr)) == [a, b]
    assert len({*key(msg)}) == (1 if a == b else 2)
