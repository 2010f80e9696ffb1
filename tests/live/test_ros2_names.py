"""ROS 2's names on DDS and Zenoh (live/ros2_names.py) and the log-time merge of several
subscriptions (live/merge.py): no middleware needed."""

import time

import pytest

from fretc.live.events import EventQueue
from fretc.live.merge import MAX_HELD, MergeBuffer
from fretc.live.ros2_names import (attachment, attachment_time, dds_topic, dds_type,
                                   liveliness_token, parse_liveliness, parse_url, parse_zenoh_key,
                                   ros_topic_of_dds, ros_type, zenoh_key)


def test_urls():
    assert parse_url("dds://37").domain == 37
    assert parse_url("dds://").domain == 0
    z = parse_url("zenoh://127.0.0.1:7448?domain=5")
    assert (z.transport, z.host, z.port, z.domain, z.endpoint) == (
        "zenoh", "127.0.0.1", 7448, 5, "tcp/127.0.0.1:7448")
    assert parse_url("zenoh://robot").port == 7447
    for bad in ("dds://233", "dds://x", "zenoh://:7447", "ws://a:1"):
        with pytest.raises(ValueError):
            parse_url(bad)


def test_dds_names():
    assert dds_topic("/cmd_vel") == "rt/cmd_vel"
    assert ros_topic_of_dds("rt/ns/scan") == "/ns/scan"
    assert ros_topic_of_dds("rq/srvRequest") is None
    assert dds_type("geometry_msgs/msg/Twist") == "geometry_msgs::msg::dds_::Twist_"
    assert dds_type("std_msgs/Bool") == "std_msgs::msg::dds_::Bool_"
    assert ros_type("geometry_msgs::msg::dds_::Twist_") == "geometry_msgs/msg/Twist"


def test_zenoh_keys_and_tokens():
    key = zenoh_key(0, "/ns/scan", "sensor_msgs/msg/LaserScan", "RIHS01_ab")
    assert key == "0/ns/scan/sensor_msgs::msg::dds_::LaserScan_/RIHS01_ab"
    assert parse_zenoh_key(key) == (0, "/ns/scan", "sensor_msgs/msg/LaserScan", "RIHS01_ab")
    assert parse_zenoh_key("@ros2_lv/0/x") is None
    tok = liveliness_token(3, "zid", 11, "MP", "talker", "/ns/chatter", "std_msgs/msg/String",
                           "RIHS01_cd")
    parsed = parse_liveliness(tok)
    assert (parsed.domain, parsed.kind, parsed.topic, parsed.type) == (
        3, "MP", "/ns/chatter", "std_msgs/msg/String")
    assert parse_liveliness("@ros2_lv/0/zid/0/0/NN/%/%/talker") is None


def test_attachment_carries_the_source_timestamp():
    att = attachment(7, 1_700_000_000_123_456_789, bytes(16))
    assert len(att) == 33
    assert attachment_time(att) == 1_700_000_000_123_456_789
    assert attachment_time(None) is None and attachment_time(b"123") is None


def test_merge_releases_in_log_time_order_and_stays_bounded():
    q = EventQueue()
    m = MergeBuffer(q, hold=0.05).start()
    for t in (30, 10, 20):
        m.put("/a", t, b"x", 0)
    time.sleep(0.2)
    assert [q.get(timeout=1)[2] for _ in range(3)] == [10, 20, 30]
    m.stop()
    m2 = MergeBuffer(q, hold=60)  # never released by time: only by the bound
    for t in range(MAX_HELD + 5):
        m2.put("/a", t, b"", 0)
    assert q.qsize() == 5  # the oldest went on at once
    m2.stop()
    assert q.qsize() == MAX_HELD + 5
