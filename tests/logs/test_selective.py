"""Selective decoding (logs/ros/selective.py) against rosbags' full decode: identical values.

* every field (outside arrays of messages) of every message of every shipped trace and both
  real logs, decoded selectively, equals the full decode;
* the ticks of the Safe-ROS and real-log bindings equal with and without the fast path;
* hypothesis: random values of a type built to stress the CDR alignment rules (empty
  sequences before 8-byte fields, strings of every length mod 4, nested arrays) in CDR and
  ROS 1, random subsets of fields;
* malformed payloads fall back to rosbags, so the error is rosbags'.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from fretc.logs.ros import selective
from fretc.audit import AuditConfig, load_plan
from fretc.common.problems import SignalError
from fretc.signals import sample
from fretc.logs import open_log

from _shared import SHARED as _SHARED, needs_shared

ROOT = Path(__file__).resolve().parents[2]
SHARED = _SHARED / "data" / "logs"
TRACES = sorted((ROOT / "traces").glob("*.mcap"))
#: the real logs of ../shared, skipped without it
REAL = [pytest.param(p, marks=needs_shared, id=p.name)
        for p in (SHARED / "cmd_vel_scaled.mcap", SHARED / "stage_mapping1.bag")]


def leaves(obj, prefix=()):
    """Paths of every field of a rosbags message outside arrays of messages."""
    out = []
    for name in obj.__dataclass_fields__:
        if name == "__msgtype__":
            continue
        v = getattr(obj, name)
        if hasattr(v, "__dataclass_fields__"):
            out += leaves(v, prefix + (name,))
        elif isinstance(v, list) and v and hasattr(v[0], "__dataclass_fields__"):
            continue
        else:
            out.append(prefix + (name,))
    return out


def get(obj, path):
    for p in path:
        obj = getattr(obj, p)
    return obj


def same(a, b) -> bool:
    if isinstance(a, np.ndarray):
        return (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape
                and np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    if isinstance(a, float) and a != a:
        return isinstance(b, float) and b != b
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("path", TRACES + REAL, ids=lambda p: p.name)
@pytest.mark.tor("TOR-LOG-001")
def test_every_field_of_every_log_equals_the_full_decode(path):
    full = list(open_log(path).messages())
    wanted = {}
    for m in full:
        wanted.setdefault(m.topic, {selective.HEADER_STAMP}).update(leaves(m.data))
    before = dict(selective.stats)
    src = open_log(path)
    src._wanted_fields = {t: frozenset(p) for t, p in wanted.items()}
    fast = list(src.messages())
    assert selective.stats["fast_types"] > before["fast_types"]  # the fast path ran
    assert selective.stats["fallback_messages"] == before["fallback_messages"]
    assert len(fast) == len(full)
    for a, b in zip(full, fast):
        assert (a.topic, a.log_time, a.publish_time, a.header_stamp) == \
               (b.topic, b.log_time, b.publish_time, b.header_stamp)
        assert type(b.data) is not type(a.data)  # the fast path's objects
        assert type(b.data).__name__ == type(a.data).__name__
        for p in wanted[a.topic] - {selective.HEADER_STAMP}:
            assert same(get(a.data, p), get(b.data, p)), (path.name, a.topic, p)


def _ticks(path, plan, fast: bool, monkeypatch):
    if not fast:
        monkeypatch.setattr(selective, "selective_decoder", lambda *a, **k: None)
    try:
        return [(t.index, t.time, t.values, t.log_times) for t in sample(open_log(path),
                                                                         plan.bindings)]
    except SignalError as exc:  # must be the same error on both paths
        return str(exc)
    finally:
        monkeypatch.undo()


def _nan_eq(x, y):
    return x == y or (x != x and y != y)


@pytest.mark.parametrize("path,req,time_base", [
    (p, ROOT / "requirements", None) for p in TRACES[:3]] + [
    (TRACES[3], ROOT / "requirements", "header")] + [
    pytest.param(SHARED / log, ROOT / "requirements/real_logs" / (log.split(".")[0] + ".fret"),
                 time_base, marks=needs_shared)
    for log, time_base in (("cmd_vel_scaled.mcap", None), ("cmd_vel_scaled.mcap", "header"),
                           ("stage_mapping1.bag", None))],
    ids=lambda p: getattr(p, "name", str(p)))
def test_ticks_equal_with_and_without_the_fast_path(path, req, time_base, monkeypatch):
    plan = load_plan(AuditConfig(requirements=(str(req),), time_base=time_base))
    a = _ticks(path, plan, True, monkeypatch)
    b = _ticks(path, plan, False, monkeypatch)
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
        return
    assert len(a) == len(b) > 0
    for x, y in zip(a, b):
        assert x[:2] == y[:2] and x[3] == y[3]
        assert x[2].keys() == y[2].keys()
        assert all(_nan_eq(x[2][k], y[2][k]) for k in x[2])


# --------------------------------------------------------------------------- alignment stress
STRESS = """
string a
float64[] b
uint8 c
float64 d
int16[3] e
string[] f
fretc_test/msg/Inner[] g
bool h
float32[] i
fretc_test/msg/Inner[2] j
uint64 k
string l
int8[] m
fretc_test/msg/Inner n
================================================================================
MSG: fretc_test/msg/Inner
uint8 x
float64 y
string s
"""


def _store():
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(STRESS, "fretc_test/msg/Stress"))
    return store


STORE = _store()
Stress = STORE.types["fretc_test/msg/Stress"]
Inner = STORE.types["fretc_test/msg/Inner"]
text = st.text(alphabet=st.characters(codec="utf-8", exclude_characters="\x00"), max_size=7)
f64 = st.floats(allow_nan=False, width=64)
inner = st.builds(Inner, x=st.integers(0, 255), y=f64, s=text)
stress = st.builds(
    Stress, a=text,
    b=st.lists(f64, max_size=3).map(lambda v: np.array(v, dtype=np.float64)),
    c=st.integers(0, 255), d=f64,
    e=st.lists(st.integers(-2**15, 2**15 - 1), min_size=3, max_size=3).map(
        lambda v: np.array(v, dtype=np.int16)),
    f=st.lists(text, max_size=3), g=st.lists(inner, max_size=3), h=st.booleans(),
    i=st.lists(st.floats(width=32, allow_nan=False), max_size=3).map(
        lambda v: np.array(v, dtype=np.float32)),
    j=st.lists(inner, min_size=2, max_size=2), k=st.integers(0, 2**64 - 1), l=text,
    m=st.lists(st.integers(-128, 127), max_size=5).map(lambda v: np.array(v, dtype=np.int8)),
    n=inner)
LEAVES = [("a",), ("b",), ("c",), ("d",), ("e",), ("f",), ("h",), ("i",), ("k",), ("l",),
          ("m",), ("n", "x"), ("n", "y"), ("n", "s")]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(msg=stress, pick=st.lists(st.sampled_from(LEAVES), unique=True),
       ros1=st.booleans())
def test_alignment_rules_on_random_messages(msg, pick, ros1):
    typename = "fretc_test/msg/Stress"
    if ros1:
        raw = STORE.serialize_ros1(msg, typename)
        full = lambda r: STORE.deserialize_ros1(r, typename)  # noqa: E731
    else:
        raw = STORE.serialize_cdr(msg, typename)
        full = lambda r: STORE.deserialize_cdr(r, typename)  # noqa: E731
    dec = selective.selective_decoder(STORE, typename, "ros1" if ros1 else "cdr", pick, full)
    assert dec is not None
    got = dec.fast(bytes(raw))  # the fast path itself, no fallback
    want = full(bytes(raw))
    for p in pick:
        assert same(get(want, p), get(got, p)), p


def test_not_covered_falls_back_to_the_full_decoder():
    typename = "fretc_test/msg/Stress"
    full = lambda r: STORE.deserialize_cdr(r, typename)  # noqa: E731
    # a field inside a sequence of messages, a whole nested message, an unknown field
    for paths in ([("g", 0, "x")], [("n",)], [("nope",)]):
        assert selective.selective_decoder(STORE, typename, "cdr", paths, full) is None


def test_malformed_payload_gives_rosbags_error():
    from rosbags.serde import SerdeError

    typename = "fretc_test/msg/Stress"
    msg = Stress(a="x", b=np.zeros(2), c=1, d=2.0, e=np.zeros(3, np.int16), f=[], g=[],
                 h=True, i=np.zeros(0, np.float32), j=[Inner(1, 2.0, ""), Inner(1, 2.0, "")],
                 k=3, l="", m=np.zeros(0, np.int8), n=Inner(1, 1.0, "z"))
    raw = bytes(STORE.serialize_cdr(msg, typename))
    full = lambda r: STORE.deserialize_cdr(r, typename)  # noqa: E731
    dec = selective.selective_decoder(STORE, typename, "cdr", [("d",)], full)
    assert dec(raw).d == 2.0
    for bad in (raw[:-9], raw + b"\0" * 8):
        with pytest.raises(SerdeError):
            dec(bad)
        with pytest.raises(Exception):
            dec.fast(bad)
