"""Types that are not in the log: a rosbag2 bag (sqlite3 and MCAP storage, written
here by rosbags) of a team's own message type with no stored definition audits with
``--msg-path`` and, without it, exits 2 with an error naming ``--msg-path``."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main

STATUS = ("std_msgs/Header header\nfloat64 battery_voltage\nuint8 STATE_OK=0\n"
          "uint8 STATE_FAULT=2\nuint8 state\nstring[] faults\n")
T0 = 1_700_000_000_000_000_000


def _msgs(tmp_path: Path) -> Path:
    d = tmp_path / "ws" / "src" / "my_robot_msgs" / "msg"
    d.mkdir(parents=True)
    (d / "Status.msg").write_text(STATUS)
    return tmp_path / "ws"


def _bag(tmp_path: Path, storage: str) -> Path:
    st = get_typestore(Stores.ROS2_HUMBLE)
    st.register(get_types_from_msg(STATUS, "my_robot_msgs/msg/Status"))
    Status = st.types["my_robot_msgs/msg/Status"]
    Header, Time = st.types["std_msgs/msg/Header"], st.types["builtin_interfaces/msg/Time"]
    path = tmp_path / f"bag_{storage}"
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=8, storage_plugin=plugin) as w:
        # no definition stored (msgdef ""), as rosbag2 bags of the Humble era
        c = w.add_connection("/status", "my_robot_msgs/msg/Status", msgdef="",
                             rihs01="RIHS01_" + "0" * 64)
        for i in range(30):
            t = T0 + i * 100_000_000
            m = Status(header=Header(stamp=Time(sec=t // 10**9, nanosec=t % 10**9),
                                     frame_id="base"),
                       battery_voltage=24.0 - i * 0.1, state=2 if i == 20 else 0, faults=[])
            w.write(c, t, st.serialize_cdr(m, "my_robot_msgs/msg/Status"))
    return path


def _reqs(tmp_path: Path) -> Path:
    d = tmp_path / "req"
    d.mkdir()
    (d / "c.fret").write_text("@tick_period 100 ms\nS1: the robot shall always satisfy "
                              "!faulted\nS2: the robot shall always satisfy volts > 20\n")
    (d / "c.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                       'faulted = "/status.state = STATE_FAULT"\n'
                                       'volts = "/status.battery_voltage"\n')
    return d


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_custom_type_audits_with_msg_path_and_names_it_without(tmp_path, storage):
    bag, msgs, reqs = _bag(tmp_path, storage), _msgs(tmp_path), _reqs(tmp_path)
    plan = load_plan(AuditConfig(requirements=(str(reqs),), msg_path=(str(msgs),)))
    v = {x.requirement: x for x in audit_log(plan, str(bag)).verdicts}
    assert v["S1"].verdict == "violated"
    assert v["S1"].first_violation.at.time_ns == T0 + 20 * 100_000_000  # state 2 at msg 20
    assert v["S2"].verdict == "satisfied"  # 24.0 down to 21.1 V
    res = CliRunner().invoke(main, ["audit", "-r", str(reqs), str(bag), "--no-progress"])
    assert res.exit_code == 2
    assert "--msg-path" in res.output and "my_robot_msgs/msg/Status" in res.output
    res = CliRunner().invoke(main, ["audit", "-r", str(reqs), str(bag), "--no-progress",
                                    "--msg-path", str(msgs)])
    assert res.exit_code == 1, res.output
    res = CliRunner().invoke(main, ["inspect", str(bag), "--msg-path", str(msgs)])
    assert res.exit_code == 0 and "30 messages" in res.output
    assert "STATE_FAULT = 2" in res.output


def test_a_bad_definition_in_msg_path_is_an_input_error_naming_the_file(tmp_path):
    bag = _bag(tmp_path, "sqlite3")
    _reqs(tmp_path)
    d = tmp_path / "bad" / "my_robot_msgs" / "msg"
    d.mkdir(parents=True)
    (d / "Status.msg").write_text("float64 = broken\n")
    res = CliRunner().invoke(main, ["inspect", str(bag), "--msg-path", str(tmp_path / "bad")])
    assert res.exit_code == 2
    assert "Status.msg" in res.output


def test_msg_path_in_the_bindings_file(tmp_path):
    bag, msgs, reqs = _bag(tmp_path, "sqlite3"), _msgs(tmp_path), _reqs(tmp_path)
    b = reqs / "c.bindings.toml"
    rel = Path("..") / msgs.name  # relative to the binding file's folder
    b.write_text(b.read_text() + f'[types]\nmsg_path = ["{rel.as_posix()}"]\n')
    res = CliRunner().invoke(main, ["audit", "-r", str(reqs), str(bag), "--no-progress"])
    assert res.exit_code == 1, res.output  # S1 violated: the type was read
    b.write_text(b.read_text().replace(f'["{rel.as_posix()}"]', "3"))
    res = CliRunner().invoke(main, ["audit", "-r", str(reqs), str(bag), "--no-progress"])
    assert res.exit_code == 2 and "msg_path" in res.output


def test_a_rosbridge_watch_reads_the_robots_own_types_with_msg_path(tmp_path):
    # rosbridge sends JSON and names the type; fretc builds CDR from the type's definition,
    # found in the --msg-path folders beside ROS 2's standard types
    from fretc.live.websocket.rosbridge import advertisement, json_to_cdr
    from fretc.logs import schema_decoder
    from fretc.logs.ros.msg_path import msg_path_typestore

    store = msg_path_typestore((str(_msgs(tmp_path)),))
    assert advertisement(1, "/status", "my_robot_msgs/msg/Status").encoding == "json"  # unknown
    adv = advertisement(1, "/status", "my_robot_msgs/msg/Status", store)
    assert (adv.encoding, adv.schema_encoding) == ("cdr", "ros2msg")
    raw = json_to_cdr("my_robot_msgs/msg/Status",
                      {"header": {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "base"},
                       "battery_voltage": 23.5, "state": 2, "faults": ["overheat"]}, store)
    msg = schema_decoder(adv.encoding, adv.schema_encoding, adv.schema_name, adv.schema)(raw)
    assert (msg.state, msg.battery_voltage, list(msg.faults)) == (2, 23.5, ["overheat"])


ARM_SRV = "float64 angle\n---\nbool success\nstring message\n"
DOCK_ACTION = "float64 x\n---\nbool docked\n---\nfloat64 distance\n"


def test_services_and_actions_from_srv_and_action_files(tmp_path):
    """A Humble-era bag that stores no definitions, with a team's own service's
    introspection events (``my_robot_msgs/srv/Arm_Event``) and action feedback
    (``my_robot_msgs/action/Dock_FeedbackMessage``): --msg-path reads ``srv/Arm.srv`` and
    ``action/Dock.action`` as rosidl generates their types; called()/answered() and the
    feedback's fields audit; without them the error names --msg-path."""
    from fretc.logs.ros.msg_path import msg_path_typestore

    ws = tmp_path / "ws" / "my_robot_msgs"
    (ws / "srv").mkdir(parents=True)
    (ws / "action").mkdir()
    (ws / "srv" / "Arm.srv").write_text(ARM_SRV)
    (ws / "action" / "Dock.action").write_text(DOCK_ACTION)
    st = msg_path_typestore((str(tmp_path / "ws"),))
    ev, fb = "my_robot_msgs/srv/msg/Arm_Event", "my_robot_msgs/action/Dock_FeedbackMessage"
    assert {ev, fb, "my_robot_msgs/srv/msg/Arm_Request",
            "my_robot_msgs/action/Dock_SendGoal_Request"} <= set(st.fielddefs)
    Ev, Info, Req, Res = (st.types[ev], st.types["service_msgs/msg/ServiceEventInfo"],
                          st.types["my_robot_msgs/srv/msg/Arm_Request"],
                          st.types["my_robot_msgs/srv/msg/Arm_Response"])
    Fb, Feedback, UUID = (st.types[fb], st.types["my_robot_msgs/action/Dock_Feedback"],
                          st.types["unique_identifier_msgs/msg/UUID"])
    Time = st.types["builtin_interfaces/msg/Time"]
    import numpy as np

    path = tmp_path / "bag"
    with Writer(path, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        ce = w.add_connection("/arm/_service_event", "my_robot_msgs/srv/Arm_Event", msgdef="",
                              rihs01="RIHS01_" + "0" * 64)
        cf = w.add_connection("/dock/_action/feedback",
                              "my_robot_msgs/action/Dock_FeedbackMessage", msgdef="",
                              rihs01="RIHS01_" + "0" * 64)
        for k in range(5):
            t = T0 + k * 1_000_000_000
            gid = np.arange(16, dtype=np.uint8)
            for kind, dt in ((1, 0), (2, 50_000_000 if k != 3 else 700_000_000)):
                e = Ev(info=Info(event_type=kind, stamp=Time(sec=0, nanosec=0), client_gid=gid,
                                 sequence_number=k),
                       request=[Req(angle=0.1 * k)] if kind == 1 else [],
                       response=[Res(success=True, message="")] if kind == 2 else [])
                w.write(ce, t + dt, st.serialize_cdr(e, ev))
            f = Fb(goal_id=UUID(uuid=gid), feedback=Feedback(distance=5.0 - k))
            w.write(cf, t + 10, st.serialize_cdr(f, fb))
    reqs = tmp_path / "req"
    reqs.mkdir()
    (reqs / "a.fret").write_text("@tick_period 100 ms\nA: the arm shall always satisfy "
                                 "wait <= 0.5\nD: the dock shall always satisfy dist > 0.5\n")
    (reqs / "a.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nwait = "waiting(/arm)"\n'
        'dist = "/dock/_action/feedback.feedback.distance"\n')
    plan = load_plan(AuditConfig(requirements=(str(reqs),), msg_path=(str(tmp_path / "ws"),)))
    v = {x.requirement: x for x in audit_log(plan, str(path)).verdicts}
    assert v["A"].verdict == "violated", v["A"].error  # call 3 waits 0.7 s
    assert v["D"].verdict == "satisfied", v["D"].error
    res = CliRunner().invoke(main, ["audit", "-r", str(reqs), str(path), "--no-progress"])
    assert res.exit_code == 2 and "--msg-path" in res.output and ".srv" in res.output
