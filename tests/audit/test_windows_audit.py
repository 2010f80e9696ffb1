"""Requirements on windows over time, audited (docs/bindings.md, "Windows over time"): the
verdicts and first violations of a 2-second mean, a count per minute and a percentile equal a
recomputation by pandas' rolling windows on the log's own messages; each requirement's
warm-up is its own window's (alone or in a set, the same verdicts); a window meeting a gap is
unknown there."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from _logs import MS, S, audit_written, boolean, float64, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan

FRET = ("@tick_period 100 ms\n"
        "MEAN: the robot shall always satisfy mean_current < 10\n"
        "PRESSES: the robot shall always satisfy presses <= 3\n"
        "P95: the robot shall always satisfy p95_period < 12\n")
BINDINGS = ('[tick]\nperiod = "100 ms"\n[variables]\n'
            'mean_current = "mean(/battery.data, 2s)"\n'
            'presses = "count(/estop.data, 1min)"\n'
            'p95_period = "percentile(/loop.data, 95, 10s)"\n')


def _audit(tmp: Path, fret: str, log: Path) -> dict:
    (tmp / "w.fret").write_text(fret)
    (tmp / "w.bindings.toml").write_text(BINDINGS)
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp / "w.fret"),))), str(log))
    return {v.requirement: v for v in la.verdicts}


def _first_violation(times, values, span_ns, threshold, op, first_msg):
    """pandas' recomputation: the first grid tick whose complete window breaks the bound."""
    for t, x in zip(times, values):
        if t - span_ns < first_msg:
            continue  # warm-up: the window is not complete
        if x != x:
            return None
        if not op(x, threshold):
            return int(t)
    return None


def _rolling(msg_t, msg_x, ticks, span_ns, how):
    rows = sorted([(t, 0, x) for t, x in zip(msg_t, msg_x)] + [(t, 1, math.nan) for t in ticks])
    df = pd.DataFrame(rows, columns=["t", "tick", "x"])
    df.index = pd.to_datetime(df["t"], unit="ns")
    r = df["x"].rolling(pd.Timedelta(span_ns, "ns"), closed="right", min_periods=0)
    return how(r)[df["tick"].to_numpy() == 1].to_numpy()


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1))
def test_window_verdicts_equal_a_pandas_recomputation(tmp_path_factory, seed):
    rng = np.random.default_rng(seed)
    tmp = tmp_path_factory.mktemp("wa")
    end = 150 * S
    bt = np.sort(rng.integers(0, end, 3000))  # irregular battery messages, ~20 Hz
    bx = np.round(9 + 1.5 * np.sin(bt / 7e9) + rng.normal(0, 1.0, len(bt)), 3)
    et = np.sort(rng.integers(0, end, 12))
    ex = rng.random(len(et)) < 0.7
    lt = np.arange(0, end, 10 * MS)
    lx = np.round(10 + rng.gamma(2.0, 0.6, len(lt)), 3)
    msgs = [("/battery", "std_msgs/msg/Float64", int(t), float64(float(x))) for t, x in zip(bt, bx)]
    msgs += [("/estop", "std_msgs/msg/Bool", int(t), boolean(bool(x))) for t, x in zip(et, ex)]
    msgs += [("/loop", "std_msgs/msg/Float64", int(t), float64(float(x))) for t, x in zip(lt, lx)]
    log = write_mcap(tmp / "w.mcap", sorted(msgs, key=lambda m: (m[2], m[0])))
    got = _audit(tmp, FRET, log)
    cases = {"MEAN": (bt, bx, 2 * S, lambda r: r.mean(), 10, lambda a, b: a < b),
             "PRESSES": (et, ex.astype(float), 60 * S, lambda r: r.sum(), 3,
                         lambda a, b: a <= b),
             "P95": (lt, lx, 10 * S, lambda r: r.quantile(0.95), 12, lambda a, b: a < b)}
    for req, (mt, mx, span, how, bound, op) in cases.items():
        # the grid: the first multiple at or after the first message to the first at or
        # after the last (docs/guide/ticks.md)
        ticks = np.arange((mt[0] + 100 * MS - 1) // (100 * MS) * (100 * MS),
                          -(-mt[-1] // (100 * MS)) * (100 * MS) + 1, 100 * MS)
        want = _first_violation(ticks, _rolling(mt, mx, ticks, span, how), span, bound, op,
                                int(mt[0]))
        v = got[req]
        assert v.verdict == ("violated" if want is not None else "satisfied"), (req, v.error)
        if want is not None:
            assert v.first_violation.at.time_ns == want, req
    for req in cases:  # each alone: its verdict does not depend on the others' windows
        alone = _audit(tmp, "@tick_period 100 ms\n" + next(
            line for line in FRET.splitlines() if line.startswith(req + ":")) + "\n", log)
        assert alone[req].verdict == got[req].verdict
        for attr in ("ticks_evaluated", "warmup_ticks", "first_tick_ns", "robustness"):
            assert getattr(alone[req], attr) == getattr(got[req], attr), (req, attr)
        # the warm-up is the requirement's own window: it starts at its first full span
        mt, span = cases[req][0], cases[req][2]
        assert got[req].first_tick_ns - span >= int(mt[0]) > got[req].first_tick_ns - span - 100 * MS, req


def test_a_window_meeting_a_gap_is_unknown_for_its_span(tmp_path):
    msgs = [("/battery", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0))
            for k in range(300)]
    msgs += [("/w", "std_msgs/msg/Float64", S + k * S // 10, float64(1.0)) for k in range(300)]
    log = write_mcap(tmp_path / "run.mcap", msgs, chunk_size=1024)
    with open(log, "rb") as f:
        summary = make_reader(f).get_summary()
    chunks = sorted((c for c in summary.chunk_indexes if {
        summary.channels[i].topic for i in c.message_index_offsets} == {"/battery"}),
        key=lambda c: c.message_start_time)
    bad = chunks[len(chunks) // 2]
    data = bytearray(log.read_bytes())
    data[bad.chunk_start_offset + bad.chunk_length // 2] ^= 0x20
    log.write_bytes(bytes(data))
    la = audit_written(tmp_path, "w", "@tick_period 100 ms\n"
                                      "W: the robot shall always satisfy mean_current < 10\n"
                                      "H: the robot shall always satisfy held < 10\n",
                                      
                                      '[tick]\nperiod = "100 ms"\n[variables]\nmean_current = "mean(/battery.data, 2s)"\n'
                                      'held = "/battery.data"\n', str(log))
    v = {x.requirement: x for x in la.verdicts}
    (g,) = la.gaps
    ticks = np.arange(S + 2 * S, S + 300 * S // 10, S // 10)  # the window's complete ticks
    want = int(np.count_nonzero((ticks >= g["start_ns"]) & (ticks - 2 * S < g["end_ns"])))
    assert v["W"].verdict == "unknown" and v["W"].unknown_ticks == want
    assert v["H"].unknown_ticks < want  # sample and hold is known from the next message


@pytest.mark.parametrize("name, expression", [
    ("mean_current", "mean(/x.data, 1e9 s)"), ("high", "count_ticks(/x.data > 1, 1e9 s)")])
def test_a_window_that_never_fills_is_named(tmp_path, name, expression):
    """``mean(x, 1e9 s)`` (a window over messages) and ``count_ticks(COND, 1e9 s)`` (over the
    requirement's own ticks) on a 10 s log: every tick is warm-up; the error said "the log
    has no message on the bound topics" (it has 100): it names the variable, the window and
    that it never completes."""
    log = write_mcap(tmp_path / "w.mcap", [("/x", "std_msgs/msg/Float64", S + k * 100 * MS,
                                            float64(2.0)) for k in range(100)])
    la = audit_written(tmp_path, "w", "@tick_period 100 ms\n"
                                      f"W: the robot shall always satisfy {name} < 10\n",
                                      '[tick]\nperiod = "100 ms"\n[variables]\n'
                                      f'{name} = "{expression}"\n', str(log))
    (v,) = la.verdicts
    assert v.verdict == "error" and "no message on the bound topics" not in v.error, v.error
    assert name in v.error and expression.split("(")[0] in v.error, v.error
    assert "never complete" in v.error, v.error


