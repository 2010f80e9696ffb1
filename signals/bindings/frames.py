"""Robot state that is not one field: the transform between two frames from ``/tf`` and
``/tf_static`` (:class:`TfBuffer`, for ``tf(parent, child).x``) and a joint's item of
``sensor_msgs/JointState``'s parallel arrays (:func:`pick_joint`, for
``joint(/joint_states.position, "name")``).

TF (REP 105; tf2's tree): every ``geometry_msgs/TransformStamped`` of a ``tf2_msgs/TFMessage``
is an edge from ``header.frame_id`` (parent) to ``child_frame_id``; a frame has one
parent, a later transform of the same child replaces the earlier one (as tf2 does). Edges of
``/tf_static`` are held forever. Semantics are sample-and-hold, like every binding: at a
tick each edge is its newest transform at or before the tick, with no interpolation (tf2
interpolates between stamps; a binding does not). Frame names are compared without a
leading ``/`` (tf2 drops it).
"""

from __future__ import annotations

import math
from typing import Any

from fretc.common.textsafe import visible
from fretc.common.units import NS_PER_S

__all__ = ["LookupFailed", "TfBuffer", "pick_joint", "compose", "invert", "yaw_of",
           "frame_name", "FRAME_FIELDS", "Transform"]

#: The fields whose strings are TF frame names (std_msgs/Header's ``frame_id``,
#: geometry_msgs/TransformStamped's ``child_frame_id``): an entity keyed by one is a frame
#: and its key is read as :func:`frame_name` gives it.
FRAME_FIELDS = frozenset({"frame_id", "child_frame_id"})


def frame_name(name: str) -> str:
    """A TF frame name as fretc compares frames: without its leading ``/``. tf2 stores the
    frames of every transform it is given without a leading slash (ROS 2 geometry2,
    ``BufferCore::setTransformImpl``: ``stripSlash(frame_id)``, ``stripSlash(child_frame_id)``;
    a lookup naming a frame with one is an invalid argument), so ``/car`` and ``car`` are one
    frame. fretc strips every leading ``/`` (``//car`` too, where tf2 strips one: no frame
    of a recorded tree starts with two), in :class:`TfBuffer` and in the keys of entities
    that are frames (:data:`FRAME_FIELDS`), so that one frame is one entity, named once."""
    return name.lstrip("/")

#: A transform: (translation (x, y, z) in m, rotation as a unit quaternion (x, y, z, w)).
Transform = tuple[tuple[float, float, float], tuple[float, float, float, float]]
_IDENTITY: Transform = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


class LookupFailed(Exception):
    """Frames that do not connect at the tick, or a joint missing from the message held."""


def _qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def _rotate(q, v):
    x, y, z, _ = _qmul(_qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def compose(a: Transform, b: Transform) -> Transform:
    """``a ∘ b``: ``b`` expressed in ``a``'s parent frame (``a`` parent->mid, ``b``
    mid->child gives parent->child)."""
    t = _rotate(a[1], b[0])
    return ((a[0][0] + t[0], a[0][1] + t[1], a[0][2] + t[2]), _qmul(a[1], b[1]))


def invert(a: Transform) -> Transform:
    """The inverse transform (child->parent from parent->child)."""
    qi = (-a[1][0], -a[1][1], -a[1][2], a[1][3])
    t = _rotate(qi, a[0])
    return ((-t[0], -t[1], -t[2]), qi)


def yaw_of(q: tuple[float, float, float, float]) -> float:
    """Yaw (rad, about z, in (-pi, pi]) of a quaternion (x, y, z, w); REP 103's ZYX angles."""
    x, y, z, w = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class TfBuffer:
    """The newest transform of every edge of the TF tree seen so far (module docstring)."""

    def __init__(self) -> None:
        #: child frame -> (parent frame, transform parent->child, time (ns), static)
        self.edges: dict[str, tuple[str, Transform, int, bool]] = {}

    def add(self, topic: str, data: Any, t: int) -> None:
        """Add the transforms of one ``tf2_msgs/TFMessage`` of ``topic`` held from time ``t``
        (ns, the bindings' time base)."""
        static = topic == "/tf_static"
        for tr in getattr(data, "transforms", ()):
            parent = frame_name(str(tr.header.frame_id))
            child = frame_name(str(tr.child_frame_id))
            tl, r = tr.transform.translation, tr.transform.rotation
            norm = math.sqrt(r.x * r.x + r.y * r.y + r.z * r.z + r.w * r.w) or 1.0
            self.edges[child] = (parent, ((float(tl.x), float(tl.y), float(tl.z)),
                                          (r.x / norm, r.y / norm, r.z / norm, r.w / norm)),
                                 t, static)

    def _chain(self, frame: str) -> list[str]:
        """``frame`` and its ancestors up to the root of its tree."""
        out = [frame]
        while out[-1] in self.edges:
            parent = self.edges[out[-1]][0]
            if parent in out:  # a cycle: stop at it
                break
            out.append(parent)
        return out

    def _to_root(self, chain: list[str], upto: str) -> tuple[Transform, list[int]]:
        """The transform ``upto`` -> chain[0] and the times of the dynamic edges on it."""
        tr, times = _IDENTITY, []
        for frame in chain[:chain.index(upto)]:
            parent, edge, t, static = self.edges[frame]
            tr = compose(edge, tr)
            if not static:
                times.append(t)
        return tr, times

    def transform(self, parent: str, child: str) -> Transform:
        """``child``'s pose in ``parent``'s frame (the transform that moves a point given in
        ``child``'s frame into ``parent``'s) from the transforms held (identity for one frame).

        Raises:
            LookupFailed: the frames do not connect in the transforms held."""
        parent, child = frame_name(parent), frame_name(child)
        if parent == child:
            return _IDENTITY
        up_p, up_c = self._chain(parent), self._chain(child)
        common = next((f for f in up_c if f in up_p), None)
        if common is None:
            raise self._unconnected(parent, child)
        return compose(invert(self._to_root(up_p, common)[0]), self._to_root(up_c, common)[0])

    def _unconnected(self, parent: str, child: str) -> LookupFailed:
        known = sorted(set(self.edges) | {e[0] for e in self.edges.values()})
        return LookupFailed(
            f"frames {parent!r} and {child!r} do not connect in the transforms of /tf and "
            f"/tf_static held at this tick (frames: {', '.join(visible(k) for k in known) or 'none yet'})")

    def lookup(self, parent: str, child: str, component: str, now: int) -> float:
        """``component`` (x, y, z in m; yaw in rad; age in s) of ``child``'s pose in
        ``parent``'s frame at tick time ``now`` (ns); age is the largest time since a
        dynamic edge of the chain was last updated (0 when every edge is static).

        Raises:
            LookupFailed: the frames do not connect in the transforms held.
        """
        parent, child = frame_name(parent), frame_name(child)
        up_p, up_c = self._chain(parent), self._chain(child)
        common = next((f for f in up_c if f in up_p), None)
        if common is None:
            raise self._unconnected(parent, child)
        t_p, times_p = self._to_root(up_p, common)
        t_c, times_c = self._to_root(up_c, common)
        if component == "age":
            times = times_p + times_c
            return (now - min(times)) / NS_PER_S if times else 0.0
        tr = compose(invert(t_p), t_c)
        if component == "yaw":
            return yaw_of(tr[1])
        return tr[0]["xyz".index(component)]


def pick_joint(values: Any, names: Any, joint: str, text: str) -> float:
    """The item of ``values`` (an array beside a ``name`` array, as JointState's
    ``position``/``velocity``/``effort``) at the index of ``joint`` in ``names``.

    Raises:
        LookupFailed: ``joint`` is not in ``names``, or ``values`` is shorter than that
            index (JointState allows empty arrays).
    """
    names = [str(n) for n in names]
    try:
        i = names.index(joint)
    except ValueError:
        raise LookupFailed(f"joint({text}, {joint!r}): the message held has no joint "
                           f"{joint!r} (its joints: {', '.join(visible(x) for x in names) or 'none'})") from None
    data = getattr(values, "data", values)
    if i >= len(data):
        empty = " (JointState leaves an array empty when the driver does not measure it)" \
            if len(data) == 0 else ""
        raise LookupFailed(f"joint({text}, {joint!r}): {text} has {len(data)} items{empty}, "
                           f"fewer than the joint's index {i} in the name array (its joints: "
                           f"{', '.join(names)})")
    v = data[i]
    return bool(v) if isinstance(v, bool) else float(v)
