"""PX4 multi-instance uORB topics as entities of one kind (hostile round 9): ``sensor_gps`` (instance
0) and ``sensor_gps/1`` are topics of their own, and ``sensor_gps/*`` holds every instance's
messages with its ``multi_id`` (ULog's instance number), the key of one value per message of an
``[entities]`` kind (docs/bindings.md, "One message, one entity")."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("pyulog")

sys.path.insert(0, str(Path(__file__).parent))
from _ulog import write_ulog  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.logs import open_log  # noqa: E402
from fretc.logs.schema import log_schemas  # noqa: E402

MS = 1_000_000
FORMATS = {"sensor_gps": [("uint64_t", "timestamp"), ("float", "eph")]}
FRET = "@tick_period 100 ms\nG: the drone shall always satisfy eph_ok\n"


def _two_gps(tmp_path: Path, bad_from: int = 15) -> Path:
    """Two GPS instances every 100 ms from 1 s, 30 messages each; instance 1 (10 µs after
    instance 0) reads eph 9 m from its message ``bad_from`` on, else 2 m; instance 0 1 m."""
    rows = []
    for i in range(30):
        t = 1_000_000 + i * 100_000
        rows.append(("sensor_gps", 0, [t, 1.0]))
        rows.append(("sensor_gps", 1, [t + 10, 9.0 if i >= bad_from else 2.0]))
    return write_ulog(tmp_path / "f.ulg", FORMATS, [("sensor_gps", 0), ("sensor_gps", 1)],
                      rows)


def _plan(tmp_path: Path, bindings: str):
    (tmp_path / "r.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(bindings, encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))


PER_INSTANCE = """[tick]
period = "100 ms"
[entities]
gps = '"sensor_gps/*".multi_id'
[variables]
eph_ok = '"sensor_gps/*"{multi_id==$gps}.eph < 5'
"""


def test_each_gps_instance_is_an_entity_of_one_kind(tmp_path):
    log = _two_gps(tmp_path)
    src = open_log(log)
    assert src.topics()["sensor_gps/*"] == "px4_msgs/msg/SensorGpsInstances"
    assert dict(log_schemas(src)["sensor_gps/*"].fields())["multi_id"].name == "uint8"
    la = audit_log(_plan(tmp_path, PER_INSTANCE), str(log))
    v = {x.requirement: x for x in la.verdicts}
    assert set(v) == {"G", "G[gps=0]", "G[gps=1]"}
    assert v["G[gps=0]"].verdict == "satisfied"
    assert v["G[gps=1]"].verdict == "violated"
    assert v["G"].verdict == "violated"
    # instance 1's first bad message at 2.50001 s: the first 100 ms tick at or after it
    bad = (1_000_000 + 15 * 100_000 + 10) * 1000
    first = v["G[gps=1]"].first_tick_ns
    assert v["G[gps=1]"].first_violation.at.time_ns == \
        first + math.ceil((bad - first) / (100 * MS)) * 100 * MS
    assert la.problems == []


def test_an_instance_entity_equals_its_own_topic_audited_alone(tmp_path):
    """Metamorphic: ``G[gps=1]`` over ``sensor_gps/*`` is the verdict of the plain topic
    ``sensor_gps/1`` read alone (verdict, first violation, ticks)."""
    log = _two_gps(tmp_path, bad_from=7)
    per = {x.requirement: x for x in audit_log(_plan(tmp_path, PER_INSTANCE),
                                               str(log)).verdicts}
    for k, topic in ((0, "sensor_gps"), (1, "sensor_gps/1")):
        alone = audit_log(_plan(tmp_path, f'[tick]\nperiod = "100 ms"\n[variables]\n'
                                f'eph_ok = \'"{topic}".eph < 5\'\n'), str(log)).verdicts[0]
        e = per[f"G[gps={k}]"]
        assert (e.verdict, e.ticks_evaluated, e.first_tick_ns, e.last_tick_ns) == \
            (alone.verdict, alone.ticks_evaluated, alone.first_tick_ns, alone.last_tick_ns)
        assert (e.first_violation.at.time_ns if e.first_violation else None) == \
            (alone.first_violation.at.time_ns if alone.first_violation else None)


@settings(max_examples=25)
@given(counts=st.lists(st.integers(0, 6), min_size=1, max_size=3),
       seed=st.integers(0, 10**6))
def test_the_instances_topic_is_every_instance_s_messages(tmp_path_factory, counts, seed):
    """Property: ``sensor_gps/*`` delivers exactly the messages of ``sensor_gps`` and each
    ``sensor_gps/k``, in log time, each with its multi_id k; a log of one instance has it."""
    import random

    rnd = random.Random(seed)
    rows = []
    for k, n in enumerate(counts):
        for i in range(n):
            rows.append((1_000_000 + rnd.randrange(10**6), k, float(i)))
    rows.sort()
    if not rows:
        return
    instances = [("sensor_gps", k) for k in range(len(counts))]
    path = write_ulog(tmp_path_factory.mktemp("inst") / "f.ulg", FORMATS, instances,
                      [("sensor_gps", k, [t, x]) for t, k, x in rows])
    src = open_log(path)
    plain = {}
    for m in src.messages({t for t in src.topics() if not t.endswith("/*")}):
        k = 0 if m.topic == "sensor_gps" else int(m.topic.rsplit("/", 1)[1])
        plain.setdefault(k, []).append((m.log_time, m.data.eph))
    every = {}
    times = []
    for m in src.messages({"sensor_gps/*"}):
        every.setdefault(m.data.multi_id, []).append((m.log_time, m.data.eph))
        times.append(m.log_time)
    assert every == plain
    assert times == sorted(times)
