"""Messages between ticks are never silently lost: every verdict counts, per bound topic, the
messages that no tick sampled (sample-and-hold keeps the newest), the same in the block
sampler of the audit and the tick-by-tick clock of the live watch, and equal to a count from
the log's own message times."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from _shared import SHARED, params  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TRACE = ROOT / "traces" / "stop_delay.mcap"
BASIS = SHARED / "data" / "foreign_logs" / "basis_pb" / "demo_81739.567984327.mcap"


def _expected(times: np.ndarray, ticks: np.ndarray) -> int:
    """Messages no tick holds, between the first and the last tick: per tick the newest
    message at or before it is held; the others of each window are not."""
    held = np.searchsorted(times, ticks, side="right") - 1
    return int(np.clip(np.diff(held) - 1, 0, None).sum())


def _audit(tmp_path: Path, fret: str, bindings: str, log: Path):
    (tmp_path / "u.fret").write_text(fret)
    (tmp_path / "u.bindings.toml").write_text(bindings)
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "u.fret"),)))
    return audit_log(plan, str(log))


def test_a_20_hz_topic_on_a_10_hz_clock_loses_every_other_message(tmp_path):
    from fretc.logs import open_log

    la = _audit(tmp_path, "@tick_period 100 ms\nU: the robot shall always satisfy far\n",
                '[tick]\nperiod = "100 ms"\n[variables]\n'
                'far = "/ground_truth/clearance.data > -1"\n', TRACE)
    v = la.verdicts[0]
    times = np.array([m.log_time for m in open_log(TRACE).messages({"/ground_truth/clearance"})])
    ticks = v.first_tick_ns + 100_000_000 * np.arange(v.ticks_evaluated)
    n = _expected(times, ticks)
    assert n > 800  # 1800 messages at 20 Hz, 900 ticks
    assert v.unsampled_messages == {"/ground_truth/clearance": n}


def test_the_watch_clock_counts_as_the_audit(tmp_path):
    from fretc.logs import open_log
    from fretc.signals import sample
    from fretc.signals.bindings.files import load_bindings

    (tmp_path / "b.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                     'far = "/ground_truth/clearance.data > -1"\n'
                                     'fast = "abs(/odom.twist.twist.linear.x) < 5"\n')
    b = load_bindings(str(tmp_path / "b.toml"))
    s = sample(open_log(TRACE), b)
    for _ in s:
        pass
    la = _audit(tmp_path, "@tick_period 100 ms\nU: the robot shall always satisfy far & fast\n",
                (tmp_path / "b.toml").read_text(), TRACE)
    assert s.unsampled == la.verdicts[0].unsampled_messages
    assert set(s.unsampled) == {"/ground_truth/clearance", "/odom"}


@pytest.mark.parametrize("log", params(lambda: [BASIS]))
def test_an_error_log_superseded_within_a_tick_is_counted(tmp_path, log):
    # the /log topic of the basis demo: an ERROR followed within milliseconds by other
    # messages; at 100 ms sample-and-hold no tick holds it, and the audit says how many
    # /log messages no tick sampled
    la = _audit(tmp_path, "@tick_period 100 ms\nE: the robot shall never satisfy error_logged\n",
                '[tick]\nperiod = "100 ms"\n[variables]\nerror_logged = "/log.level >= ERROR"\n',
                log)
    v = la.verdicts[0]
    assert v.unsampled_messages.get("/log", 0) > 0
