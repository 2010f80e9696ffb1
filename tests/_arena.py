"""Logs of entities carried one per message, alternating (tests/audit/test_entities_held.py,
tests/live/test_watch_entities.py): two 1:10 cars in a motion-capture arena, each car's pose
a transform of ``/tf`` in a message of its own, and the binding files that read them."""

from __future__ import annotations

from pathlib import Path

from _logs import ROS2, S, T, header, write_mcap

MS = S // 1000
#: ego's y at each of its messages (every 50 ms, 25 ms after the other car's): out of the
#: lane (below -1.0) from message 30 to 35, down to -1.14 m
EGO_Y = [0.1 - 0.03 * k if k < 30 else (-1.14 if k < 36 else 0.0) for k in range(60)]
OTHER_Y = [0.5] * 60


def _transform(t: int, child: str, y: float):
    TS, Tr = T(ROS2, "geometry_msgs/msg/TransformStamped"), T(ROS2, "geometry_msgs/msg/Transform")
    V, Q = T(ROS2, "geometry_msgs/msg/Vector3"), T(ROS2, "geometry_msgs/msg/Quaternion")
    return TS(header=header(t, frame="map"), child_frame_id=child,
              transform=Tr(translation=V(x=1.0, y=float(y), z=0.0),
                           rotation=Q(x=0.0, y=0.0, z=0.0, w=1.0)))


def arena_log(path: Path, ego=EGO_Y, other=OTHER_Y, ego_stops: int | None = None,
              static: bool = False) -> Path:
    """``/tf``: the other car's transform at 0, 50, 100, ... ms, the ego car's at 25, 75,
    ... ms (from 1 s), one transform a message, the other car's last; ``ego_stops``: the ego
    car's messages end after that many; ``static``: a ``/tf_static`` message first (the
    arena's camera in ``map``)."""
    TF = T(ROS2, "tf2_msgs/msg/TFMessage")
    msgs = []
    if static:
        msgs.append(("/tf_static", "tf2_msgs/msg/TFMessage", S, TF(transforms=[
            _transform(S, "mocap_camera", 0.0)])))
    for k in range(len(other)):
        t = S + k * 50 * MS
        msgs.append(("/tf", "tf2_msgs/msg/TFMessage", t, TF(transforms=[
            _transform(t, "car_other", other[k])])))
        if ego_stops is None or k < ego_stops:
            msgs.append(("/tf", "tf2_msgs/msg/TFMessage", t + 25 * MS, TF(transforms=[
                _transform(t + 25 * MS, "car_ego", ego[k])])))
    t = S + len(other) * 50 * MS  # (the run ends on the other car's message)
    msgs.append(("/tf", "tf2_msgs/msg/TFMessage", t, TF(transforms=[
        _transform(t, "car_other", other[-1])])))
    msgs.sort(key=lambda m: m[2])
    return write_mcap(path, msgs)


C1 = "C1: in present mode the car shall always satisfy car_y > -1.0 & car_y < 0.85\n"

FILTER = '''[tick]
period = "100 ms"
[entities]
car = "/tf.transforms[:].child_frame_id"
[variables]
car_y = 'max(/tf.transforms[:]{child_frame_id==$car}.transform.translation.y)'
present = 'count(/tf.transforms[:]{child_frame_id==$car}.transform.translation.y > -100) = 1'
'''
HELD = FILTER.replace('car = "/tf.transforms[:].child_frame_id"',
                      'car = { key = "/tf.transforms[:].child_frame_id", hold = "entity" }')
TF = '''[tick]
period = "100 ms"
[entities]
car = "/tf.transforms[:].child_frame_id"
[variables]
car_y = 'tf("map", $car).y'
present = 'tf("map", $car).age < 0.5'
'''
