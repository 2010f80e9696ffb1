"""A sensor that dies while the run goes on, over DDS and Zenoh: its publisher leaves, so
nothing of it is sent any more. That is a silence, not a loss: the time since its last
message is known and grows (`age(/scan)`), so a staleness requirement is judged (violated
without the stop it asks for, satisfied with it, never unknown), while a requirement over the
values it last sent is unknown from where it left (never judged on stale values) with the
reason that its publisher left; the run is not partial, and the audit of the watch's
recording gives the same verdicts."""

import json
import time

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                    "pip install 'fretc[watch]'")
pytest.importorskip("zenoh", reason="eclipse-zenoh is not installed: pip install 'fretc[watch]'")

from _bus import T0, audit_json, bus_server, bus_url, float64_cdr, watch_while  # noqa: E402
from _gaps import left_for_good  # noqa: E402

pytestmark = pytest.mark.watch

BOOL = ("cdr", "std_msgs/msg/Bool", "ros2msg", b"bool data")
#: R6 of requirements/safe_ros.fret, and a requirement over the scan's values
FRET = ("@tick_period 100 ms\n"
        "R6: whenever scan_stale safety_system shall within 500 milliseconds satisfy "
        "stop_requested\n"
        "RV: the lidar shall always satisfy scan_ok\n")
BINDINGS = ('[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\n'
            'scan_stale = "age(/scan) > 0.3"\nstop_requested = "/gwendolen_control.data"\n'
            'scan_ok = "/scan.data > 0"\n')


def _bool(x: bool) -> bytes:
    return b"\x00\x01\x00\x00" + bytes([x])


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
@pytest.mark.parametrize("stop", [True, False], ids=["stop-requested", "no-stop"])
def test_a_lidar_that_dies_is_judged_by_its_age(transport, stop, tmp_path, dds_xml):
    """/scan every 100 ms for 3 s, then its publisher leaves; /gwendolen_control every 100 ms
    for 8 s, raising the stop request 200 ms after the last scan (``stop``) or never."""
    fret = tmp_path / "w.fret"
    fret.write_text(FRET, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    url = bus_url(transport)
    server = bus_server(url, dds_xml, ("/scan",))
    server.channel("/gwendolen_control", *BOOL)

    def publish():
        server.wait_subscribed(["/scan", "/gwendolen_control"], timeout=30)
        time.sleep(0.3)
        for k in range(80):
            if k < 30:
                server.log("/scan", float64_cdr(1.0), T0 + k * 100_000_000)
            if k == 30:
                server.unpublish("/scan")  # the LiDAR's node dies
            server.log("/gwendolen_control", _bool(stop and k >= 31),
                       T0 + k * 100_000_000 + 50_000_000)
            time.sleep(0.02)
        time.sleep(0.3)
        server.stop()

    rec = tmp_path / "rec.mcap"
    res, log = watch_while(publish, url, fret, dds_xml, "--record", str(rec))
    by = {v["requirement"]: v for v in log["verdicts"]}
    assert by["R6"]["verdict"] == ("satisfied" if stop else "violated"), by["R6"]
    if not stop:  # stale from 3.3 s on (age over 0.3 s), the request due within 0.5 s
        assert by["R6"]["first_violation"]["tick_time_ns"] - T0 in range(3_700_000_000,
                                                                         4_000_000_001)
    # the scan's value is not held over the silence: RV cannot be judged past it
    assert by["RV"]["verdict"] == "unknown", by["RV"]
    assert left_for_good(by["RV"]["unknown_reason"], "/scan"), by["RV"]["unknown_reason"]
    assert not log["partial"], log.get("problems")
    assert res.exit_code == (3 if stop else 1), res.output  # (3: RV unknown)
    # the audit of the recording judges as the watch did
    _code, doc = audit_json(rec, tmp_path / "a.json", ("-r", str(fret)))
    offline = {v["requirement"]: (v["verdict"], json.dumps(v.get("first_violation")))
               for v in doc["logs"][0]["verdicts"]}
    assert offline == {r: (v["verdict"], json.dumps(v.get("first_violation")))
                       for r, v in by.items()}
    assert not doc["logs"][0]["partial"]
