"""``count_ticks(COND, 1e9 s)`` on a 10 s log: its window over the requirement's own ticks is
never complete, so no tick is evaluated; the error said "the log has no message on the bound
topics" (the log has 100 of them). It names the window, as a window over messages is named
(``tests/audit/test_windows_audit.py``)."""

from __future__ import annotations

from _logs import MS, S, audit_written, float64, write_mcap


def test_a_tick_window_that_never_fills_is_named(tmp_path):
    log = write_mcap(tmp_path / "w.mcap", [("/x", "std_msgs/msg/Float64", S + k * 100 * MS,
                                            float64(2.0)) for k in range(100)])
    la = audit_written(tmp_path, "w", "@tick_period 100 ms\n"
                                      "C: the robot shall always satisfy high < 10\n",
                                      '[tick]\nperiod = "100 ms"\n[variables]\n'
                                      'high = "count_ticks(/x.data > 1, 1e9 s)"\n', str(log))
    (v,) = la.verdicts
    assert v.verdict == "error", (v.verdict, v.error)
    assert "no message on the bound topics" not in v.error, v.error
    assert "high" in v.error and "count_ticks" in v.error and "never complete" in v.error, \
        v.error
