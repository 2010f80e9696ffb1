"""A FoxQL filter right after the topic (``/r{radiation_type==1}.range``) in ``fretc watch``:
the watch reads the topic for the stream and gives the audit's verdicts; a failing message is
not read by the stream's bindings (a large range on another radiation type violates
nothing)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from _logs import ROS2, S, T, header, write_mcap  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from test_watch import _watch_trace  # noqa: E402

pytestmark = pytest.mark.watch

BINDINGS = '''[tick]
period = "100 ms"
[variables]
ultra = '/r{radiation_type==0}.range'
ir = '/r{radiation_type==1}.range'
'''
FRET = ("U: the robot shall always satisfy ultra < 5\n"
        "I: the robot shall always satisfy ir < 5\n")
#: (radiation type, range) per message, every 100 ms: infrared exceeds 5 at message 7 only
ROWS = [(0, 1.0), (1, 2.0), (0, 3.0), (0, 9.0), (1, 1.0), (0, 2.0), (0, 9.0), (1, 6.0),
        (0, 1.0), (1, 1.0)]


def _log(tmp: Path) -> Path:
    Range = T(ROS2, "sensor_msgs/msg/Range")
    msgs = [("/r", "sensor_msgs/msg/Range", S + k * S // 10,
             Range(header=header(S + k * S // 10), radiation_type=kind, field_of_view=0.1,
                   min_range=0.0, max_range=10.0, range=r))
            for k, (kind, r) in enumerate(ROWS)]
    return write_mcap(tmp / "r.mcap", msgs)


def test_watch_reads_a_stream_as_the_audit(tmp_path):
    (tmp_path / "t.fret").write_text("@tick_period 100 ms\n" + FRET, encoding="utf-8")
    (tmp_path / "t.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "t.fret"),)))
    log = _log(tmp_path)
    w, la, done = _watch_trace(plan, log, rate=40.0)
    ref = audit_log(plan, str(log))
    assert done["sent"] == len(ROWS) and la.error is None
    assert w.needed == {"/r"}  # the stream's topic is what the watch subscribes to
    key = [(v.requirement, v.verdict, v.first_violation and v.first_violation.at.time_ns,
            v.ticks_evaluated, v.warmup_ticks) for v in la.verdicts]
    assert key == [(v.requirement, v.verdict, v.first_violation and v.first_violation.at.time_ns,
                    v.ticks_evaluated, v.warmup_ticks) for v in ref.verdicts]
    got = {v.requirement: v for v in la.verdicts}
    assert got["U"].first_violation.at.time_ns == S + 3 * S // 10
    assert got["I"].first_violation.at.time_ns == S + 7 * S // 10  # not at 3 nor 6
    # each clock runs from its stream's first message to its last: I 1.1 s .. 1.9 s, U
    # 1.0 s .. 1.8 s
    assert (got["I"].ticks_evaluated, got["U"].ticks_evaluated) == (9, 9)
