"""`fretc watch --publish-diagnostics`: the verdicts come back on /diagnostics as
diagnostic_msgs/DiagnosticArray over the transport watched, read here by subscribers that are
not fretc's (DDS: the test's own IDL types; Zenoh: the key expression and rosbags' decoder):
the last array names each requirement `fretc: <id>` with the level and verdict of
`fretc audit` of the same log. Everything on 127.0.0.1, multicast off."""

import json
import time
from dataclasses import dataclass

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                    "pip install 'fretc[watch]'")
pytest.importorskip("zenoh", reason="eclipse-zenoh is not installed: pip install 'fretc[watch]'")

from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import byte, int32, sequence, uint32  # noqa: E402

from fretc.live.dds.idl_types import open_participant  # noqa: E402

from _bus import REQS, ROOT, audit_json, bus_url, replay, watch_process  # noqa: E402

pytestmark = pytest.mark.watch

TRACE = ROOT / "traces" / "stop_delay.mcap"
LEVEL = {"satisfied": 0, "vacuous": 0, "violated": 2, "error": 2, "unknown": 3}


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec_: int32
    nanosec_: uint32


@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp_: Time_
    frame_id_: str


@dataclass
class KeyValue_(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    key_: str
    value_: str


@dataclass
class DiagnosticStatus_(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    level_: byte
    name_: str
    message_: str
    hardware_id_: str
    values_: sequence[KeyValue_]


@dataclass
class DiagnosticArray_(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    header_: Header_
    status_: sequence[DiagnosticStatus_]


def _run(url: str, dds_xml: str, tmp_path) -> tuple[int, dict]:
    """Replay the trace on ``url`` and watch it with --publish-diagnostics, each in its own
    process; (watch exit code, watch JSON)."""
    rep = replay(TRACE, url, dds_xml, quiet=True)
    out = tmp_path / "w.json"
    try:
        res = watch_process(url, ["-r", REQS], out, dds_xml, "--publish-diagnostics")
        rep.wait(30)
    finally:
        rep.kill()
    assert out.exists(), res.stderr
    return res.returncode, json.loads(out.read_text())


def _audit(tmp_path) -> dict[str, str]:
    _code, doc = audit_json(TRACE, tmp_path / "a.json")
    return {v["requirement"]: v["verdict"] for log in doc["logs"] for v in log["verdicts"]}


def _check(last: list[tuple[str, int, dict]], audit: dict[str, str]) -> None:
    assert [name for name, _l, _v in last] == [f"fretc: {r}" for r in audit]
    for (name, level, values), (_rid, verdict) in zip(last, audit.items()):
        assert values["verdict"] == verdict, name
        assert level == LEVEL[verdict], name
        assert values["text"]
        assert (values["first_violation_s"] != "") == (verdict == "violated")


def test_diagnostics_over_dds_read_back_with_own_idl_types(tmp_path, dds_xml):
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    url = bus_url("dds")
    dp = open_participant(int(url[len("dds://"):]), dds_xml)  # configured as the watch's own
    reader = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray_),
                        qos=Qos(Policy.Reliability.Reliable(max_blocking_time=10**8),
                                Policy.History.KeepAll))
    code, _doc = _run(url, dds_xml, tmp_path)
    time.sleep(0.5)
    arrays = [a for a in reader.take(10_000) if a.sample_info.valid_data]
    assert len(arrays) >= 2  # while watching, and the final verdicts
    last = [(s.name_, s.level_, {kv.key_: kv.value_ for kv in s.values_})
            for s in arrays[-1].status_]
    _check(last, _audit(tmp_path))
    assert code == 1  # R2 is violated on this trace


def test_diagnostics_over_zenoh_read_back_by_key_expression(tmp_path):
    import zenoh
    from rosbags.typesys import Stores, get_typestore

    url = bus_url("zenoh")
    port = int(url.rsplit(":", 1)[1])
    got: list[tuple[str, bytes]] = []
    cfg = zenoh.Config()
    cfg.insert_json5("mode", '"peer"')
    cfg.insert_json5("scouting/multicast/enabled", "false")
    cfg.insert_json5("connect/endpoints", f'["tcp/127.0.0.1:{port}"]')
    store = get_typestore(Stores.ROS2_HUMBLE)
    holder = {}

    def listen():  # the replay's router is up once it listens; retry until connected
        session = zenoh.open(cfg)
        session.declare_subscriber("0/diagnostics/**",
                                   lambda s: got.append((str(s.key_expr),
                                                         s.payload.to_bytes())))
        holder["s"] = session

    import threading

    t = threading.Timer(1.0, listen)
    t.start()
    try:
        code, _doc = _run(url, "", tmp_path)
    finally:
        t.join()
        time.sleep(0.3)
        holder["s"].close()
    rihs = store.hash_rihs01("diagnostic_msgs/msg/DiagnosticArray")
    assert got and {k for k, _p in got} == {
        f"0/diagnostics/diagnostic_msgs::msg::dds_::DiagnosticArray_/{rihs}"}
    arr = store.deserialize_cdr(got[-1][1], "diagnostic_msgs/msg/DiagnosticArray")
    last = [(s.name, s.level, {kv.key: kv.value for kv in s.values}) for s in arr.status]
    _check(last, _audit(tmp_path))
    assert code == 1
