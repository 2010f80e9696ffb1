"""`fretc watch` over Zenoh beyond the replay round trip (tests/live/test_watch_middleware.py
has that): payloads that do not decode, a topic of another type than the bindings expect,
samples on wildcard key expressions, and zenoh-bridge-ros2dds's layout. Each test runs its
own Zenoh peer on 127.0.0.1 with a server written here; everything in one process."""

import time

import pytest

from _gaps import left_for_good  # noqa: E402

pytest.importorskip("zenoh", reason="eclipse-zenoh is not installed: pip install 'fretc[watch]'")

from _bus import T0, bus_server, bus_url, float64_cdr, watch_while, write_watch_files  # noqa: E402

pytestmark = pytest.mark.watch

#: one requirement over /a's std_msgs/Float64
RA = ("RA: the robot shall always satisfy a_ok\n", 'a_ok = "/a.data > 0"\n')


def test_a_truncated_zenoh_payload_is_undecodable_not_held_over(tmp_path):
    """A message that does not decode opens a gap: the run is partial (exit 3), never a
    clean pass; the watch ends by itself when the publisher leaves."""
    fret = write_watch_files(tmp_path, *RA)
    url = bus_url("zenoh")
    server = bus_server(url, "", ("/a",))

    def publish():
        server.wait_subscribed(timeout=30)
        for k in range(30):
            data = b"\x00\x01" if k == 15 else float64_cdr(1.0)
            server.log("/a", data, T0 + k * 50_000_000)
            time.sleep(0.005)
        time.sleep(0.5)
        server.stop()

    res, log = watch_while(publish, url, fret, duration=60, wait=None, grace=0.5, join=10)
    kinds = {p["kind"] for p in log["problems"]}
    assert "undecodable" in kinds, res.output
    assert res.exit_code == 3, res.output


def test_a_topic_of_another_type_than_the_bindings_expect_is_not_read(tmp_path):
    """/a is bound as std_msgs/Bool ([types]) but carries Float64: reported, its
    requirement is error (exit 2), never judged from a misread value."""
    fret = write_watch_files(tmp_path, *RA, '[types]\n"/a" = "std_msgs/msg/Bool"\n')
    url = bus_url("zenoh")
    server = bus_server(url, "", ("/a",))

    def publish():
        server.wait_subscribed(timeout=30)
        for k in range(10):
            server.log("/a", float64_cdr(1.0), T0 + k * 50_000_000)
        time.sleep(0.3)
        server.stop()

    res, log = watch_while(publish, url, fret, duration=20, wait=5, grace=0.5, join=10)
    (v,) = log["verdicts"]
    assert v["verdict"] == "error"
    assert "std_msgs/msg/Bool" in v["error"] and "/a" in v["error"], v["error"]
    assert res.exit_code == 2, res.output


@pytest.mark.parametrize("wildcard", ["0/a/**", "**", "0/a/*/*"])
def test_samples_on_wildcard_keys_are_messages_of_the_topic_they_reach(tmp_path, wildcard):
    """Zenoh delivers a put on ``0/a/**``, ``**`` or ``0/a/*/*`` to the subscriber of /a
    (its key expression intersects theirs): those are messages of /a, typed by /a's
    liveliness token, and the violating value among them is found (was: ignored, satisfied,
    exit 0)."""
    import json

    from fretc.live.ros2_names import attachment

    fret = write_watch_files(tmp_path, *RA)
    url = bus_url("zenoh")
    server = bus_server(url, "", ("/a",))

    def publish():
        server.wait_subscribed(timeout=30)
        for k in range(20):  # rmw_zenoh's attachment gives each its log time, 50 ms apart
            value = -1.0 if 8 <= k < 12 else 1.0  # 200 ms: over a tick
            server.session.put(wildcard, float64_cdr(value),
                               attachment=attachment(k + 1, T0 + k * 50_000_000, bytes(16)))
            time.sleep(0.005)
        time.sleep(0.5)
        server.stop()

    res, log = watch_while(publish, url, fret, wait=None, grace=0.5, join=10)
    (v,) = log["verdicts"]
    assert v["verdict"] == "violated", (v, res.output)
    assert res.exit_code == 1, res.output
    # they reach the subscriber of /clock too (the watch's time source): not clock messages,
    # and not untyped messages of /clock either (they are /a's)
    assert not [p for p in log["problems"] if "/clock" in json.dumps(p)], log["problems"]
    assert log["messages"].get("/a") == 20, log["messages"]


def test_zenoh_bridge_ros2dds_layout(tmp_path):
    """``zenoh://HOST:PORT?layout=bridge``: topics on zenoh-bridge-ros2dds's key expressions
    (``a``, no domain, type or hash) with its liveliness tokens (``@ros2_lv/<zid>/MP/a/
    std_msgs§msg§Float64/:::``); the type comes from the token, the log time is the arrival
    (the bridge forwards no source timestamp); a violating value is seen, and ``/b``'s
    publisher leaving while ``/a`` goes on makes the requirement reading it unknown."""
    from fretc.live.ros2_names import bridge_liveliness

    assert bridge_liveliness("z1", "ns/a", "std_msgs/msg/Float64") == \
        "@ros2_lv/z1/MP/ns§a/std_msgs§msg§Float64/:::"
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n"
                             "RB: the robot shall always satisfy b_ok\n",
                             'a_ok = "/a.data > 0"\nb_ok = "/b.data > 0"\n')
    url = bus_url("zenoh") + "?layout=bridge"
    server = bus_server(url, "", ("/a", "/b"))
    f64 = float64_cdr

    def publish():
        server.wait_subscribed(["/a", "/b"], timeout=30)
        time.sleep(0.3)
        for k in range(30):
            server.log("/a", f64(-1.0 if 20 <= k < 25 else 1.0), 0)  # 250 ms: ticks see it
            if k < 10:
                server.log("/b", f64(1.0), 0)
            if k == 10:
                server.unpublish("/b")
            time.sleep(0.05)
        time.sleep(0.3)
        server.stop()

    res, log = watch_while(publish, url, fret)
    by = {v["requirement"]: v for v in log["verdicts"]}
    assert log["messages"] == {"/a": 30, "/b": 10}
    assert by["RA"]["verdict"] == "violated"
    assert by["RB"]["verdict"] == "unknown" and left_for_good(by["RB"]["unknown_reason"], "/b")
    assert abs(log["start_time_ns"] - time.time_ns()) < 120 * 10**9  # dated on arrival
    assert res.exit_code == 1, res.output
