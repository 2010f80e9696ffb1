"""TF frames as entities, named as tf2 names them (hostile round 9, E1): tf2 stores
every transform's frames without a leading ``/`` (ROS 2 geometry2,
``BufferCore::setTransformImpl``: ``stripSlash``), so ``/car`` and ``car`` are one frame.
fretc read them as two entities, ``car`` and ``/car``, both reading the one frame through
``tf()`` (the same verdict twice) or each only in its own messages through the filter (one
left ``unknown``). Now they are one entity, named ``car`` once, in the filter form and the
``tf()`` form alike, judged on every message of the frame whatever its spelling: the
verdicts are those of the same log with every name written ``car`` (metamorphic)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _arena import C1, FILTER, TF, _transform
from _logs import ROS2, S, T, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan

MS = S // 1000


def _log(path: Path, names: list[str], bad: int | None) -> Path:
    """One car's transforms every 50 ms (25 ms off the 100 ms ticks, so that every other
    one is held at a tick), its name spelled ``names[k]``, out of the lane at ``bad``."""
    TFM = T(ROS2, "tf2_msgs/msg/TFMessage")
    msgs = []
    for k, name in enumerate(names):
        t = S + k * 50 * MS + 25 * MS
        msgs.append(("/tf", "tf2_msgs/msg/TFMessage", t, TFM(transforms=[
            _transform(t, name, -2.0 if k == bad else 0.1)])))
    return write_mcap(path, msgs)


def _verdicts(tmp: Path, bindings: str, log: Path) -> dict:
    (tmp / "c.fret").write_text("@tick_period 100 ms\n" + C1)
    (tmp / "c.bindings.toml").write_text(bindings)
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp / "c.fret"),))), str(log))
    return {v.requirement: (v.verdict, v.error,
                            None if v.first_violation is None else v.first_violation.at.time_ns)
            for v in la.verdicts}


@pytest.mark.parametrize("form", ["filter", "tf"])
def test_slash_car_and_car_are_one_entity_named_car(tmp_path, form):
    """The smallest input: ``car`` and ``/car`` alternating, ``/car`` out of the lane at
    message 7 (held at the 400 ms tick). Before: entities ``car`` and ``/car``."""
    names = ["/car" if k % 2 else "car" for k in range(20)]
    got = _verdicts(tmp_path, FILTER if form == "filter" else TF,
                    _log(tmp_path / "a.mcap", names, bad=7))
    assert sorted(got) == ["C1", "C1[car=car]"], got
    assert got["C1[car=car]"][0] == "violated"
    assert got["C1[car=car]"][2] == S + 400 * MS
    assert got["C1"][0] == "violated"


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(slashes=st.lists(st.sampled_from(["", "/", "//"]), min_size=4, max_size=16),
       bad=st.none() | st.integers(0, 15), form=st.sampled_from(["filter", "tf"]))
def test_the_verdicts_do_not_depend_on_the_leading_slashes(tmp_path_factory, slashes, bad,
                                                           form):
    tmp = tmp_path_factory.mktemp("frames")
    binds = FILTER if form == "filter" else TF
    want = _verdicts(tmp, binds, _log(tmp / "plain.mcap", ["car"] * len(slashes), bad))
    got = _verdicts(tmp, binds, _log(tmp / "slashed.mcap", [s + "car" for s in slashes], bad))
    assert got == want


def test_frame_name_is_tf2s_stripped_name():
    from fretc.signals.bindings.frames import frame_name

    assert frame_name("/car") == frame_name("car") == "car"
    assert frame_name("map/car") == "map/car"  # (only the leading slash)
