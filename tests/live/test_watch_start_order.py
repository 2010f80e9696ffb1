"""`fretc watch` started before the robot's nodes, as a monitor usually is: a bound topic
advertised after `--wait` joins the run when it comes (its requirements are judged, never
`error` for a late node), `--until-idle` counts from the first message, not from the
connection, and a topic no node ever advertises makes only its requirements `error`, at the
end, naming it."""

import time

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds (Cyclone DDS) is not installed: "
                    "pip install 'fretc[watch]'")
pytest.importorskip("zenoh", reason="eclipse-zenoh is not installed: pip install 'fretc[watch]'")

from _bus import T0, bus_server, bus_url, float64_cdr, watch_while, write_watch_files  # noqa: E402

pytestmark = pytest.mark.watch


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
@pytest.mark.tor("TOR-WCH-001")
def test_nodes_that_start_after_the_watch_join_the_run(transport, tmp_path, dds_xml):
    """/a's node starts 3 s after the watch (whose --wait is 1 s) and /b's 1 s later; /a goes
    negative at its message 20: RA is violated there, RB (over /b) satisfied, RG (over a
    /ghost no node advertises) is `error` naming it; --until-idle 2 ends the run 2 s after
    the last message (the nodes are silent before they start: no end before them)."""
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n"
                             "RB: the robot shall always satisfy b_ok\n"
                             "RG: the robot shall always satisfy g_ok\n",
                             'a_ok = "/a.data > 0"\nb_ok = "/b.data > 0"\n'
                             'g_ok = "/ghost.data > 0"\n')
    url = bus_url(transport)
    got = {}

    def publish():
        time.sleep(3.0)  # the watch has waited for its topics, and gone on
        server = bus_server(url, dds_xml, ("/a",))
        got["server"] = server
        server.wait_subscribed(["/a"], timeout=30)
        for k in range(40):
            if k == 10:
                server.channel("/b", "cdr", "std_msgs/msg/Float64", "ros2msg",
                               b"float64 data")
                server.wait_subscribed(["/b"], timeout=30)
            server.log("/a", float64_cdr(-1.0 if k >= 20 else 1.0), T0 + k * 100_000_000)
            if k >= 10:
                server.log("/b", float64_cdr(1.0), T0 + k * 100_000_000 + 1)
            time.sleep(0.02)
        # the nodes stay up, silent: --until-idle ends the run

    t0 = time.monotonic()
    res, log = watch_while(publish, url, fret, dds_xml, "--until-idle", "2", wait=1,
                           duration=60, grace=30)
    took = time.monotonic() - t0
    got["server"].stop()
    by = {v["requirement"]: v for v in log["verdicts"]}
    assert by["RA"]["verdict"] == "violated", by["RA"]
    assert by["RA"]["first_violation"]["tick_time_ns"] - T0 in range(2_000_000_000,
                                                                      2_100_000_001)
    assert by["RB"]["verdict"] == "satisfied", by["RB"]
    assert by["RG"]["verdict"] == "error" and "/ghost was not advertised" in by["RG"]["error"]
    assert "not_advertised" in {p["kind"] for p in log["problems"]}
    assert res.exit_code == 2, res.output  # (RG could not be judged)
    assert took < 30, took  # ended by --until-idle, not by the duration
    assert log["messages"]["/a"] == 40 and log["messages"]["/b"] == 30


def test_a_publisher_silent_until_its_first_message_gets_no_transport_hint(tmp_path, dds_xml):
    """/a's writer is discovered at once but sends its first message 4 s later (a node that
    starts up slowly), past the 3 s after which the DDS client looks for silent publishers:
    nothing points to a transport (nothing was sent, so nothing was lost), and /a is
    judged."""
    from fretc.live.dds.client import SILENT_SECONDS

    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n",
                             'a_ok = "/a.data > 0"\n')
    url = bus_url("dds")
    server = bus_server(url, dds_xml, ("/a",))

    def publish():
        server.wait_subscribed(["/a"], timeout=30)
        time.sleep(SILENT_SECONDS + 1.0)
        for k in range(20):
            server.log("/a", float64_cdr(1.0), T0 + k * 100_000_000)
            time.sleep(0.02)
        time.sleep(0.3)
        server.stop()

    res, log = watch_while(publish, url, fret, dds_xml)
    (v,) = log["verdicts"]
    assert v["verdict"] == "satisfied", v
    assert not [p for p in log.get("problems", []) if "FASTDDS" in p.get("detail", "")]
    assert res.exit_code == 0, res.output
