"""``tf()`` on a ROS 1 tf log with no /tf_static (the Husky bag of ros-planning/navigation,
recorded before tf2): the transform tree is read from /tf alone, and its values equal those
of the bag's own messages read with rosbags."""

from __future__ import annotations

import pytest

from _shared import SHARED, params  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402

BAG = SHARED / "data" / "foreign_logs" / "husky_ekf" / "gps_data.bag"


def _z_from_the_bag() -> set[float]:
    from rosbags.rosbag1 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    out = set()
    with Reader(BAG) as r:
        cs = [c for c in r.connections if c.topic == "/tf"]
        st = get_typestore(Stores.EMPTY)
        st.register(get_types_from_msg(cs[0].msgdef.data, cs[0].msgtype))
        for c, _t, raw in r.messages(connections=cs):
            for tr in st.deserialize_ros1(raw, c.msgtype).transforms:
                if (tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/")) == (
                        "base_footprint", "base_link"):
                    out.add(tr.transform.translation.z)
    return out


@pytest.mark.parametrize("bag", params(lambda: [BAG]))
def test_tf_reads_a_tree_on_tf_alone(tmp_path, bag):
    (z,) = _z_from_the_bag()
    (tmp_path / "t.fret").write_text("@tick_period 100 ms\n"
                                     "T1: the robot shall always satisfy height_as_logged\n"
                                     "T2: the robot shall always satisfy height_above\n")
    (tmp_path / "t.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\n'
        f'height_as_logged = \'abs(tf("base_footprint", "base_link").z - {z!r}) < 1e-9\'\n'
        f'height_above = \'tf("base_footprint", "base_link").z > {z!r} + 0.001\'\n')
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
    la = audit_log(plan, str(bag))
    v = {x.requirement: x for x in la.verdicts}
    assert v["T1"].verdict == "satisfied", v["T1"].error
    assert v["T2"].verdict == "violated"
    assert "/tf_static" not in la.missing_topics
