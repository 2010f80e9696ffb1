"""rosbag2 recordings of ROS 2 services (Jazzy's service introspection): the events of a
service ``/arm`` (``std_srvs/srv/SetBool``) on its topic ``/arm/_service_event``, type
``std_srvs/srv/SetBool_Event`` (``info``: ``service_msgs/msg/ServiceEventInfo`` with
``event_type`` REQUEST_SENT 0, REQUEST_RECEIVED 1, RESPONSE_SENT 2, RESPONSE_RECEIVED 3,
``client_gid``, ``sequence_number``; ``request`` and ``response``: sequences of at most one),
written with rosbags' rosbag2 writer (MCAP storage, as Jazzy records by default)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

EVENT = "std_srvs/srv/SetBool_Event"
_MANGLED = "std_srvs/srv/msg/SetBool_Event"


def _store():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    types.update(get_types_from_msg("bool data", "std_srvs/srv/SetBool_Request"))
    types.update(get_types_from_msg("bool success\nstring message",
                                    "std_srvs/srv/SetBool_Response"))
    types.update(get_types_from_msg(
        "service_msgs/msg/ServiceEventInfo info\n"
        "std_srvs/srv/SetBool_Request[<=1] request\n"
        "std_srvs/srv/SetBool_Response[<=1] response", EVENT))
    # rosbags files a name under /srv/ as pkg/srv/msg/Name: the names Jazzy records instead
    store.register(types)  # rosbags files them as std_srvs/srv/msg/...: same CDR
    return store


_SEP = "=" * 80 + "\n"
#: The definition Jazzy's rosbag2 stores for the event type (ros2msg, dependencies after it)
MSGDEF = ("service_msgs/ServiceEventInfo info\nSetBool_Request[<=1] request\n"
          "SetBool_Response[<=1] response\n" + _SEP + "MSG: service_msgs/ServiceEventInfo\n"
          "uint8 REQUEST_SENT = 0\nuint8 REQUEST_RECEIVED = 1\nuint8 RESPONSE_SENT = 2\n"
          "uint8 RESPONSE_RECEIVED = 3\nuint8 event_type\nbuiltin_interfaces/Time stamp\n"
          "char[16] client_gid\nint64 sequence_number\n" + _SEP
          + "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n" + _SEP
          + "MSG: std_srvs/SetBool_Request\nbool data\n" + _SEP
          + "MSG: std_srvs/SetBool_Response\nbool success\nstring message\n")


def write_service_bag(folder: Path, events: list[tuple[int, int, int, int, bool]],
                      extra: list[tuple[int, float]] = ()) -> Path:
    """A rosbag2 (MCAP storage) of ``/arm/_service_event`` events ``(log time ns, event_type,
    client (its gid's last byte), sequence_number, success)`` and ``/tick`` Float64 messages
    ``(log time ns, value)``; returns the ``.mcap`` file."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = _store()
    T = store.types
    bag = folder / "svc_bag"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/arm/_service_event", EVENT, msgdef=MSGDEF,
                                rihs01="RIHS01_" + "0" * 64)
        tick = w.add_connection("/tick", "std_msgs/msg/Float64", typestore=store)
        rows = [(t, 0, e) for t, *e in events] + [(t, 1, (x,)) for t, x in extra]
        for t, kind, e in sorted(rows, key=lambda r: (r[0], r[1])):
            if kind == 1:
                w.write(tick, t, store.serialize_cdr(T["std_msgs/msg/Float64"](data=e[0]),
                                                     "std_msgs/msg/Float64"))
                continue
            etype, client, seq, ok = e
            gid = np.zeros(16, np.uint8)
            gid[0], gid[15] = 1, client
            info = T["service_msgs/msg/ServiceEventInfo"](
                event_type=etype, stamp=T["builtin_interfaces/msg/Time"](
                    sec=t // 10**9, nanosec=t % 10**9), client_gid=gid, sequence_number=seq)
            req = [T["std_srvs/srv/msg/SetBool_Request"](data=True)] if etype <= 1 else []
            res = ([T["std_srvs/srv/msg/SetBool_Response"](success=ok, message="")]
                   if etype >= 2 else [])
            msg = T[_MANGLED](info=info, request=req, response=res)
            w.write(conn, t, store.serialize_cdr(msg, _MANGLED))
    return next(bag.glob("*.mcap"))


#: Kilted's action topics: the feedback of ``example_interfaces/action/Fibonacci`` as rosbag2
#: stores its definition (package-relative names), and the goals' status array
FEEDBACK = "example_interfaces/action/Fibonacci_FeedbackMessage"
FEEDBACK_DEF = ("unique_identifier_msgs/UUID goal_id\nFibonacci_Feedback feedback\n" + _SEP
                + "MSG: unique_identifier_msgs/UUID\nuint8[16] uuid\n" + _SEP
                + "MSG: example_interfaces/Fibonacci_Feedback\nint32[] sequence\n")


def write_action_bag(folder: Path, feedback: list[tuple[int, int, list[int]]],
                     status: list[tuple[int, list[tuple[int, int]]]]) -> Path:
    """A rosbag2 (MCAP storage) of ``/fib/_action/feedback`` messages ``(log time ns, goal
    (its uuid's first byte), sequence)`` and ``/fib/_action/status`` arrays ``(log time ns,
    [(goal, status)])`` (action_msgs/msg/GoalStatus: SUCCEEDED 4, ABORTED 6); returns the
    ``.mcap`` file."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg("int32[] sequence",
                                      "example_interfaces/msg/Fibonacci_Feedback"))
    store.register(get_types_from_msg("unique_identifier_msgs/UUID goal_id\n"
                                      "example_interfaces/msg/Fibonacci_Feedback feedback",
                                      "example_interfaces/msg/Fibonacci_FeedbackMessage"))
    T = store.types

    def uuid(goal: int):
        u = np.zeros(16, np.uint8)
        u[0] = goal
        return T["unique_identifier_msgs/msg/UUID"](uuid=u)

    bag = folder / "action_bag"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        fb = w.add_connection("/fib/_action/feedback", FEEDBACK, msgdef=FEEDBACK_DEF,
                              rihs01="RIHS01_" + "0" * 64)
        st = w.add_connection("/fib/_action/status", "action_msgs/msg/GoalStatusArray",
                              typestore=store)
        rows = [(t, 0, (g, seq)) for t, g, seq in feedback] + [(t, 1, s) for t, s in status]
        for t, kind, data in sorted(rows, key=lambda r: (r[0], r[1])):
            if kind == 0:
                msg = T["example_interfaces/msg/Fibonacci_FeedbackMessage"](
                    goal_id=uuid(data[0]), feedback=T["example_interfaces/msg/Fibonacci_Feedback"](
                        sequence=np.array(data[1], np.int32)))
                w.write(fb, t, store.serialize_cdr(
                    msg, "example_interfaces/msg/Fibonacci_FeedbackMessage"))
                continue
            arr = T["action_msgs/msg/GoalStatusArray"](status_list=[
                T["action_msgs/msg/GoalStatus"](goal_info=T["action_msgs/msg/GoalInfo"](
                    goal_id=uuid(g), stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)),
                    status=s) for g, s in data])
            w.write(st, t, store.serialize_cdr(arr, "action_msgs/msg/GoalStatusArray"))
    return next(bag.glob("*.mcap"))
