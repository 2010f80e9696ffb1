"""A ROS schema that spells a primitive another way the interface language allows is ROS's
layout (hostile round 9): ``uint8 level`` where diagnostic_msgs writes ``byte level`` (ROS 2:
rosidl_adapter maps ``byte`` to IDL ``octet``, ``char`` to ``uint8``, one unsigned byte each
on the wire); a real difference inside a sequence of messages is named by its field path.
"""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.logs import open_log
from fretc.logs.ros.known_types import ROS1_SAME, ROS2_SAME, layout_mismatch, same_spelling

HEADER = ("std_msgs/Header header\nDiagnosticStatus[] status\n" + "=" * 80
          + "\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n" + "=" * 80
          + "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n" + "=" * 80
          + "\nMSG: diagnostic_msgs/DiagnosticStatus\n{level} level\nstring name\nstring message\n"
          "string hardware_id\nKeyValue[] values\n" + "=" * 80
          + "\nMSG: diagnostic_msgs/KeyValue\nstring {key}\nstring value\n")


def _array_schema(level: str = "byte", key: str = "key") -> str:
    return HEADER.format(level=level, key=key)


def _diagnostics_log(tmp_path: Path, schema: str) -> Path:
    """Five DiagnosticArray messages on /diagnostics, each one status of level 2 with one
    key/value, under the ros2msg schema text ``schema``."""
    from _logs import ROS2, T, header, write_mcap

    def array(k: int):
        kv = T(ROS2, "diagnostic_msgs/msg/KeyValue")(key="k", value=str(k))
        status = T(ROS2, "diagnostic_msgs/msg/DiagnosticStatus")(
            level=2, name="motor", message="hot", hardware_id="m1", values=[kv])
        return T(ROS2, "diagnostic_msgs/msg/DiagnosticArray")(header=header(10**9 + k),
                                                             status=[status])

    name = "diagnostic_msgs/msg/DiagnosticArray"
    raw = {k: bytes(ROS2.serialize_cdr(array(k), name)) for k in range(5)}
    msgs = [("/diagnostics", name, 10**9 + k * 10**8, None) for k in range(5)]
    return write_mcap(tmp_path / "d.mcap", msgs, raw_override=raw,
                      schema_override={"/diagnostics": ("ros2msg", schema.encode())})


def _read(path: Path) -> tuple[list, list]:
    src = open_log(str(path))
    try:
        got = [m.data for m in src.messages(None)]
        return got, [(p.kind, p.detail) for p in src.problems]
    finally:
        src.close()


def test_byte_spelled_uint8_or_char_is_ros_own_diagnostic_status(tmp_path):
    """``byte level`` (ROS's own text), ``uint8 level`` and ``char level``: the same layout,
    the messages read, the level 2 in each; ``int8 level`` (signed) is not waived."""
    for spelling in ("byte", "uint8", "char"):
        got, problems = _read(_diagnostics_log(tmp_path, _array_schema(spelling)))
        assert problems == [], spelling
        assert len(got) == 5
        assert [int(s.level) for m in got for s in m.status] == [2] * 5, spelling
    got, problems = _read(_diagnostics_log(tmp_path, _array_schema("int8")))
    assert got == []
    assert problems and problems[0][0] == "unknown_schema"
    assert "status[].level is int8 where ROS has byte" in problems[0][1]


def test_a_difference_inside_a_sequence_of_messages_is_named_by_its_path(tmp_path):
    """A KeyValue's ``key`` renamed ``name`` two sequences down: the message names the field
    ``status[].values[]``'s first field (was "the layouts differ")."""
    got, problems = _read(_diagnostics_log(tmp_path, _array_schema(key="name")))
    assert got == []
    assert problems[0][0] == "unknown_schema"
    detail = problems[0][1]
    assert "field 1 of status[].values[] is 'name' where ROS has 'key'" in detail, detail
    assert "the layouts differ" not in detail


_BASES = ["bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "float64",
          "string"]


def _kinds(depth: int = 0):
    base = st.sampled_from(_BASES).map(lambda t: ("base", t))
    if depth >= 2:
        return base
    inner = _kinds(depth + 1)
    return st.one_of(
        base,
        st.lists(st.tuples(st.sampled_from("abc"), inner), min_size=1, max_size=3,
                 unique_by=lambda f: f[0]).map(lambda fs: ("msg", tuple(fs))),
        st.tuples(inner, st.integers(1, 3)).map(lambda t: ("array", t[0], t[1])),
        inner.map(lambda k: ("seq", k)))


@settings(max_examples=200)
@given(kind=_kinds(), same=st.sampled_from([ROS2_SAME, ROS1_SAME]))
def test_same_spelling_changes_no_layout_but_its_primitive_names(kind, same):
    """Property: the spelling rule is idempotent, keeps every field name, nesting and
    length, and two layouts equal under it differ only where each spells a primitive of one
    class (byte/char/uint8/octet in ROS 2; byte/int8, char/uint8 in ROS 1)."""
    lay = (("f", kind),)
    once = same_spelling(lay, same)
    assert same_spelling(once, same) == once
    assert str(once).count("'msg'") == str(lay).count("'msg'")
    assert str(once).count("'seq'") == str(lay).count("'seq'")
    signed = {k for k, v in same.items() if v == "int8"} | {"int8"}
    # signedness never waived: an int8 never equals a uint8 after the rule
    assert same_spelling((("f", ("base", "int8")),), same) != \
        same_spelling((("f", ("base", "uint8")),), same)
    for b in _BASES:
        if b not in same and b not in same.values() and b not in signed:
            assert same_spelling((("f", ("base", b)),), same) == (("f", ("base", b)),)


def test_a_real_difference_is_still_refused_for_each_distribution():
    """The rule waives spellings, never a layout: Twist with a float32 is still refused."""
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg("float32 x\nfloat64 y\nfloat64 z", "geometry_msgs/msg/Vector3"))
    assert "x is float32 where ROS has float64" in layout_mismatch(
        "ros2msg", store, "geometry_msgs/msg/Vector3")
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg("uint8 data", "std_msgs/msg/Byte"))
    assert layout_mismatch("ros2msg", store, "std_msgs/msg/Byte") is None
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg("int8 data", "std_msgs/msg/Byte"))
    assert layout_mismatch("ros1msg", store, "std_msgs/msg/Byte") is None  # (ROS 1 alias)
    assert layout_mismatch("ros2msg", store, "std_msgs/msg/Byte") is not None
