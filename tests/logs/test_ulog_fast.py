"""The read of a sound ULog by one walk and numpy gathers (:mod:`fretc.logs.flight.ulog_fast`)
against the reference read (the framing walk of :mod:`fretc.logs.flight.ulog_framing` and pyulog's
read of every topic): on the real logs of ``../shared``, on a long log of copied flights and
on damaged copies (bytes changed, cut, zeroed, inserted), the fast read either gives what
the reference gives (every topic's rows, logged text, parameter changes, dropouts, the
framing) or declines (None), and it never declines a sound real log."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

pytest.importorskip("pyulog")

from _shared import SHARED, needs_shared  # noqa: E402
from fretc.logs.flight.ulog_fast import read_sound  # noqa: E402
from fretc.logs.flight.ulog_framing import ulog_framing  # noqa: E402

PX4 = SHARED / "data" / "foreign_logs" / "px4"
NAMES = ["sample.ulg", "sample_log_small.ulg", "sample_px4_events.ulg"]


def _reference(data: bytes):
    from pyulog import ULog

    with contextlib.redirect_stdout(io.StringIO()):
        return ULog(io.BytesIO(data), disable_str_exceptions=True), ulog_framing(data)


def _assert_same(got, data: bytes) -> None:
    ulog, framing = got
    want, want_framing = _reference(data)
    assert want_framing.damages == [] and not want_framing.appended
    assert dataclasses.asdict(framing) == dataclasses.asdict(want_framing)
    assert ulog.data_list == want.data_list  # pyulog's Data.__eq__: names, fields, arrays
    for attr in ("logged_messages", "logged_messages_tagged", "changed_parameters",
                 "dropouts", "start_timestamp", "last_timestamp", "msg_info_dict",
                 "msg_info_multiple_dict", "message_formats"):
        assert getattr(ulog, attr) == getattr(want, attr), attr


@needs_shared
@pytest.mark.parametrize("name", NAMES)
def test_a_sound_real_log_is_read_fast_as_pyulog_reads_it(name):
    data = (PX4 / name).read_bytes()
    got = read_sound(data)
    assert got is not None
    _assert_same(got, data)


@needs_shared
def test_copied_flights_with_a_dropout_and_logged_text_read_as_pyulog_reads_them(tmp_path):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    from bench_logs import long_ulog

    long_ulog(PX4 / "sample_px4_events.ulg", tmp_path / "long.ulg", 3)
    data = (tmp_path / "long.ulg").read_bytes()
    got = read_sound(data)
    assert got is not None and got[0].logged_messages
    _assert_same(got, data)


def _damage(data: bytes, kind: str, at: float, length: int, value: int) -> bytes:
    pos = 16 + int(at * (len(data) - 17))
    if kind == "flip":
        return data[:pos] + bytes([data[pos] ^ (value or 1)]) + data[pos + 1:]
    if kind == "cut":
        return data[:pos]
    if kind == "zero":
        return data[:pos] + bytes(min(length, len(data) - pos)) + data[pos + length:]
    return data[:pos] + bytes([value]) * length + data[pos:]  # bytes inserted


@needs_shared
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(["sample_log_small.ulg", "sample_px4_events.ulg"]),
       kind=st.sampled_from(["flip", "cut", "zero", "insert"]),
       at=st.floats(0, 1), length=st.integers(1, 300), value=st.integers(0, 255))
def test_a_damaged_copy_is_read_as_the_reference_reads_it_or_declined(
        name, kind, at, length, value):
    data = _damage((PX4 / name).read_bytes(), kind, at, length, value)
    got = read_sound(data)
    if got is not None:
        _assert_same(got, data)
    else:  # declined: the reference read reports what is wrong, or pyulog recovers
        pass


def test_bytes_that_are_no_ulog_are_declined():
    assert read_sound(b"") is None
    assert read_sound(b"ULog\x01\x12\x35" + bytes(9)) is None
    assert read_sound(b"not a ulog at all, not at all") is None
