"""DDS types as ROS 2 names them and as other programs do: fretc's members are named as
ROS 2's DDS IDL names them (``data_``, read by the test's own types in
tests/live/test_watch_middleware.py), and a watch's readers ignore member names in matching,
so a publisher whose types name members otherwise is read too."""

import json
import time
from dataclasses import dataclass

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                    "pip install 'fretc[watch]'")

from click.testing import CliRunner  # noqa: E402

from fretc.cli import main  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import float64  # noqa: E402
from _dds import fresh_domain  # noqa: E402

pytestmark = pytest.mark.watch


def test_a_publisher_naming_members_without_the_underscore_is_read(tmp_path, dds_xml):
    """ROS 2's DDS types (and fretc's) name members ``data_``; a plain Cyclone DDS program's
    ``Float64_`` names it ``data``. DDS refuses such a match without a word unless the
    reader ignores member names, which the watch's readers do: its ten 1.0 then five 0.0
    are read and the requirement is violated."""
    import gc
    import threading

    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic
    from fretc.live.dds.idl_types import open_participant

    @dataclass
    class Float64_(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
        data: float64

    (tmp_path / "w.fret").write_text(
        "@tick_period 100 ms\nRA: the robot shall always satisfy a_ok\n", encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\na_ok = "/a.data > 0"\n',
        encoding="utf-8")
    url = f"dds://{fresh_domain()}"
    dp = open_participant(int(url[len("dds://"):]), dds_xml)  # the watch's domain config
    writer = [DataWriter(dp, Topic(dp, "rt/a", Float64_), qos=Qos(
        Policy.Reliability.Reliable(max_blocking_time=10**9), Policy.History.KeepAll))]

    def publish():
        w = writer[0]
        deadline = time.monotonic() + 30
        while not w.get_matched_subscriptions() and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.3)
        for k in range(15):
            w.write(Float64_(data=1.0 if k < 10 else 0.0))
            time.sleep(0.1)
        w.wait_for_acks(5_000_000_000)
        writer.clear()
        del w
        gc.collect()  # the writer deleted: its publication leaves, the watch ends

    t = threading.Thread(target=publish, daemon=True)
    t.start()
    out = tmp_path / "w.json"
    res = CliRunner().invoke(main, ["watch", url, "-r", str(tmp_path / "w.fret"), "--no-live",
                                    "--json", str(out), "--duration", "30", "--wait", "10",
                                    "--restart-grace", "1", "--dds-config", dds_xml])
    t.join(20)
    assert out.exists(), (res.output, res.exception)
    log = json.loads(out.read_text())["logs"][0]
    assert log["messages"] == {"/a": 15}, res.output
    assert log["verdicts"][0]["verdict"] == "violated"
    assert res.exit_code == 1, res.output


def test_the_reader_takes_the_offered_reliability_and_durability():
    # a publication's QoS read from DCPSPublication is a cyclonedds Qos indexed by policy
    # (it has no attribute per policy): best effort and transient local as offered
    from cyclonedds.qos import Policy, Qos

    from fretc.live.dds.idl_types import reader_qos

    offered = Qos(Policy.Reliability.BestEffort, Policy.Durability.TransientLocal)
    got = [str(p) for p in reader_qos(offered, "/map")]
    assert "Policy.Reliability.BestEffort" in got and "Policy.Durability.TransientLocal" in got
    got = [str(p) for p in reader_qos(Qos(Policy.Durability.Volatile), "/scan")]
    assert any(p.startswith("Policy.Reliability.Reliable") for p in got)
    assert "Policy.Durability.Volatile" in got
    got = [str(p) for p in reader_qos(None, "/tf_static")]
    assert "Policy.Durability.TransientLocal" in got
