"""Windows over time and services in ``fretc watch`` (docs/bindings.md): a log served live by
a foxglove-sdk server on 127.0.0.1 gives the same verdicts, first violations, warm-up and
robustness as its offline audit, for a 2-second mean, a count of messages per 10 s, a
percentile and ``waiting()`` of a service."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _logs import MS, S, boolean, float64, write_mcap  # noqa: E402
from _services import write_service_bag  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from test_watch import _key, _watch_trace  # noqa: E402

pytestmark = pytest.mark.watch


def _plan(tmp: Path, fret: str, bindings: str):
    (tmp / "w.fret").write_text(fret)
    (tmp / "w.bindings.toml").write_text(bindings)
    return load_plan(AuditConfig(requirements=(str(tmp / "w.fret"),)))


def test_window_requirements_watched_equal_their_audit(tmp_path):
    rng = np.random.default_rng(3)
    bt = np.sort(rng.integers(S, 30 * S, 600))
    et = np.sort(rng.integers(S, 30 * S, 12))
    msgs = [("/battery", "std_msgs/msg/Float64", int(t), float64(float(9 + rng.normal(0, 1))))
            for t in bt]
    msgs += [("/estop", "std_msgs/msg/Bool", int(t), boolean(True)) for t in et]
    log = write_mcap(tmp_path / "w.mcap", sorted(msgs, key=lambda m: (m[2], m[0])))
    plan = _plan(tmp_path, "@tick_period 100 ms\n"
                 "MEAN: the robot shall always satisfy mean_current < 9.6\n"
                 "PRESSES: the robot shall always satisfy presses <= 2\n"
                 "P90: the robot shall always satisfy p90 < 11\n",
                 '[tick]\nperiod = "100 ms"\n[variables]\n'
                 'mean_current = "mean(/battery.data, 2s)"\n'
                 'presses = "count(/estop.data, 10s)"\n'
                 'p90 = "percentile(/battery.data, 90, 5 s)"\n')
    w, la, done = _watch_trace(plan, log)
    ref = audit_log(plan, str(log))
    assert done["sent"] > 0 and la.error is None
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
    assert [v.robustness for v in la.verdicts] == [v.robustness for v in ref.verdicts]
    assert {v.verdict for v in ref.verdicts} >= {"violated"}  # the test decides something


def test_a_service_requirement_watched_equals_its_audit(tmp_path):
    events = [(S, 0, 1, 1, True), (S + 50 * MS, 3, 1, 1, True),
              (2 * S, 0, 2, 1, True), (2 * S + 300 * MS, 3, 2, 1, True)]
    log = write_service_bag(tmp_path, events)
    plan = _plan(tmp_path, "@tick_period 10 ms\n"
                 "ANSWERED: the arm_service shall always satisfy waiting_arm <= 0.1\n",
                 '[tick]\nperiod = "10 ms"\n[variables]\nwaiting_arm = "waiting(/arm)"\n')
    w, la, done = _watch_trace(plan, log)
    ref = audit_log(plan, str(log))
    assert ref.verdicts[0].verdict == "violated"
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]


def test_an_action_requirement_watched_equals_its_audit(tmp_path):
    from _services import write_action_bag

    status = [(S, [(1, 1)]), (S + 200 * MS, [(1, 2), (2, 1)]), (S + 400 * MS, [(1, 4), (2, 2)]),
              (2 * S, [(1, 4), (2, 6)])]
    log = write_action_bag(tmp_path, [(S + k * 100 * MS, 1, [k]) for k in range(12)], status)
    plan = _plan(tmp_path, "@tick_period 100 ms\n"
                 "RESULT: the fib_server shall always satisfy goal_wait <= 0.5\n",
                 '[tick]\nperiod = "100 ms"\n[variables]\ngoal_wait = "goal_waiting(/fib)"\n')
    w, la, done = _watch_trace(plan, log)
    ref = audit_log(plan, str(log))
    assert ref.verdicts[0].verdict == "violated"
    assert [_key(v) for v in la.verdicts] == [_key(v) for v in ref.verdicts]
