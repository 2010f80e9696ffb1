"""Logs written by the Foxglove SDK itself (its MCAP writer, a ``json`` channel with a JSON
schema and a ``protobuf`` channel of ``foxglove.Log``) audit like any log: the verdicts and
first violations equal an independent recomputation from the raw messages (the ``mcap``
reader with Python's ``json`` and mcap-protobuf-support's decoder)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

foxglove = pytest.importorskip("foxglove")

from _logs import audit_written  # noqa: E402

S = 1_000_000_000
TICK = S // 10
ERROR_AT = 7  # the /log message of this index is an ERROR, superseded 1 ms later


def _write(path: Path) -> Path:
    from foxglove.channels import LogChannel
    from foxglove.messages import Log, LogLevel

    ctx = foxglove.Context()
    w = foxglove.open_mcap(str(path), context=ctx)
    state = foxglove.Channel("/state", message_encoding="json", context=ctx, schema={
        "type": "object", "properties": {"speed": {"type": "number"},
                                         "mode": {"type": "string"}}})
    log = LogChannel("/log", context=ctx)
    for i in range(20):
        state.log({"speed": 0.1 * i, "mode": "auto" if i < 12 else "manual"},
                  log_time=S + i * TICK)
        level = LogLevel.Error if i == ERROR_AT else LogLevel.Info
        log.log(Log(level=level, message=f"step {i}"), log_time=S + i * TICK + 1_000)
        log.log(Log(level=LogLevel.Info, message="ok"), log_time=S + i * TICK + 2_000)
    w.close()
    return path


def _raw(path: Path):
    """(state times, speeds, modes), (log times, levels) read without fretc."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    st, lg = [], []
    with open(path, "rb") as f:
        for _s, _ch, m in make_reader(f).iter_messages(topics=["/state"]):
            d = json.loads(m.data)
            st.append((m.log_time, d["speed"], d["mode"]))
    with open(path, "rb") as f:
        for _s, _c, m, d in make_reader(f, decoder_factories=[DecoderFactory()]) \
                .iter_decoded_messages(topics=["/log"]):
            lg.append((m.log_time, d.level))
    return st, lg


def test_an_sdk_log_audits_as_recomputed_from_its_raw_messages(tmp_path):
    log = _write(tmp_path / "sdk.mcap")
    la = audit_written(tmp_path, "f", 
                                      "@tick_period 100 ms\n"
                                      "S1: the robot shall always satisfy speed < 1.5\n"
                                      "S2: the robot shall always satisfy manual -> speed > 1\n"
                                      "E1: the robot shall never satisfy error_logged\n",
                                      
                                      '[tick]\nperiod = "100 ms"\n[variables]\nspeed = "/state.speed"\n'
                                      'manual = \'/state.mode = "manual"\'\n'
                                      'error_logged = "any_of_messages(/log.level >= ERROR)"\n', str(log))
    got = {v.requirement: v for v in la.verdicts}
    st, lg = _raw(log)
    # independent: ticks on the multiples of 100 ms from the first at or after the first
    # message; sample and hold of /state
    times = np.array([t for t, _s, _m in st])
    speed = np.array([s for _t, s, _m in st])
    t0 = -(-int(times[0]) // TICK) * TICK
    ticks = t0 + TICK * np.arange((times[-1] - t0) // TICK + 1)
    held = np.searchsorted(times, ticks, side="right") - 1
    bad = np.flatnonzero(speed[held] >= 1.5)
    assert got["S1"].verdict == "violated"
    assert got["S1"].first_violation.at.time_ns == int(ticks[bad[0]])
    manual = np.array([m == "manual" for _t, _s, m in st])[held]
    assert got["S2"].verdict == ("violated" if (manual & ~(speed[held] > 1)).any()
                                 else "satisfied")
    # E1's own clock runs on /log (each verdict stands alone): the ERROR is folded into
    # the first of its ticks at or after it
    err = min(t for t, level in lg if level >= 4)
    l0 = -(-lg[0][0] // TICK) * TICK
    log_ticks = l0 + TICK * np.arange((lg[-1][0] - l0) // TICK + 2)
    assert got["E1"].verdict == "violated"
    assert got["E1"].first_violation.at.time_ns == int(
        log_ticks[np.searchsorted(log_ticks, err)])
