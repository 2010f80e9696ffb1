"""TF lookups (:class:`fretc.signals.bindings.frames.TfBuffer`) against homogeneous matrices
built with numpy from the same random tree (property-based), and paths as bindings print
them read back as the same field."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

import numpy as np
import pytest
from hypothesis import given, strategies as st

from fretc.signals.bindings.expression import ExprLocation, Field
from fretc.signals.bindings.parse import parse_expression
from fretc.signals.bindings.frames import LookupFailed, TfBuffer

unit = st.floats(-1, 1, allow_nan=False)
coord = st.floats(-50, 50, allow_nan=False)


def _matrix(t, q):
    x, y, z, w = np.array(q) / np.linalg.norm(q)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = r, t
    return m


def _msg(parent, child, t, q):
    v = NS(x=t[0], y=t[1], z=t[2])
    return NS(header=NS(frame_id=parent), child_frame_id=child,
              transform=NS(translation=v, rotation=NS(x=q[0], y=q[1], z=q[2], w=q[3])))


@given(st.lists(st.tuples(st.integers(0, 30), st.tuples(coord, coord, coord),
                          st.tuples(unit, unit, unit, unit)), min_size=1, max_size=7),
       st.data())
def test_lookup_equals_the_product_of_matrices(edges, data):
    """A random tree: frame i+1's parent is one of frames 0..i; any two frames connect."""
    buf, mats, parent_of = TfBuffer(), {}, {}
    for i, (p, t, q) in enumerate(edges):
        if sum(abs(c) for c in q) < 1e-3:
            q = (0.0, 0.0, 0.0, 1.0)
        parent, child = f"f{p % (i + 1)}", f"f{i + 1}"
        buf.add("/tf_static" if i % 2 else "/tf", NS(transforms=[_msg(parent, child, t, q)]),
                1000 * i)
        mats[child], parent_of[child] = _matrix(t, q), parent
    n = len(edges) + 1
    a = data.draw(st.integers(0, n - 1))
    b = data.draw(st.integers(0, n - 1))

    def to_root(f):
        m = np.eye(4)
        while f in parent_of:
            m = mats[f] @ m
            f = parent_of[f]
        return m
    want = np.linalg.inv(to_root(f"f{a}")) @ to_root(f"f{b}")
    for k, comp in enumerate("xyz"):
        got = buf.lookup(f"f{a}", f"/f{b}", comp, 10**6)
        assert got == pytest.approx(want[k, 3], abs=1e-6 * (1 + abs(want[k, 3])))
    yaw = buf.lookup(f"f{a}", f"f{b}", "yaw", 10**6)
    if abs(want[2, 0]) < 0.99:  # yaw is defined away from gimbal lock
        ref = math.atan2(want[1, 0], want[0, 0])
        assert math.remainder(yaw - ref, 2 * math.pi) == pytest.approx(0, abs=1e-6)


def test_frames_of_two_trees_do_not_connect():
    buf = TfBuffer()
    buf.add("/tf", NS(transforms=[_msg("a", "b", (1, 0, 0), (0, 0, 0, 1))]), 0)
    buf.add("/tf", NS(transforms=[_msg("c", "d", (1, 0, 0), (0, 0, 0, 1))]), 0)
    with pytest.raises(LookupFailed, match="frames 'a' and 'd' do not connect .* a, b, c, d"):
        buf.lookup("a", "d", "x", 0)
    assert buf.lookup("b", "b", "x", 0) == 0.0 and buf.lookup("b", "b", "age", 0) == 0.0


topics = st.text(st.characters(blacklist_categories=("Cs", "Cc")), min_size=1, max_size=20)
names = st.from_regex(r"[a-z][a-z0-9_]{0,8}", fullmatch=True)


@given(topics, st.lists(st.one_of(names, st.integers(-5, 5)), min_size=1, max_size=4)
       .filter(lambda p: isinstance(p[0], str)))
def test_a_field_as_printed_reads_back_as_the_same_field(topic, path):
    f = Field(1, topic, tuple(path))
    node, _ = parse_expression(f.text(), ExprLocation("t", None, None, None))
    assert isinstance(node, Field) and node.topic == topic and node.path == tuple(path)
