"""A flight log's staleness requirement (``age()`` in the bindings) ticks to the log's end, as
on an MCAP (hostile round 9): a GPS that dies before the end of a flight is stale from ``age() >
limit`` on, not judged only up to its own last message. The log's end is the last log time
of a message of any topic (``log_end``, known when the file is opened), whichever topics the
requirement reads."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

pytest.importorskip("pyulog")
pytest.importorskip("pymavlink")

sys.path.insert(0, str(Path(__file__).parent))
from _dataflash import two_batteries  # noqa: E402
from _ulog import write_ulog  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.logs import open_log  # noqa: E402

MS, S = 1_000_000, 1_000_000_000
FRET = "@tick_period 100 ms\nG: the drone shall always satisfy !gps_stale\n"
FORMATS = {"sensor_gps": [("uint64_t", "timestamp"), ("float", "eph")],
           "vehicle_status": [("uint64_t", "timestamp"), ("uint8_t", "arming_state")]}


def _plan(tmp_path: Path, stale: str):
    (tmp_path / "r.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(
        f'[tick]\nperiod = "100 ms"\n[variables]\ngps_stale = \'{stale}\'\n', encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))


def _ulog(tmp_path: Path, gps_rows: int, rows: int = 50) -> Path:
    """vehicle_status every 100 ms from 1 s for ``rows`` messages; sensor_gps 10 µs after
    each of the first ``gps_rows``."""
    out = []
    for i in range(rows):
        t = 1_000_000 + i * 100_000
        out.append(("vehicle_status", 0, [t, 2]))
        if i < gps_rows:
            out.append(("sensor_gps", 0, [t + 10, 1.0]))
    return write_ulog(tmp_path / "f.ulg", FORMATS, [("vehicle_status", 0), ("sensor_gps", 0)],
                      out)


def _first_stale_tick(first_tick: int, last_gps: int, limit_ns: int) -> int:
    """The first 100 ms tick (of the grid from ``first_tick``) where the age of the GPS's
    last message (log time ``last_gps``) exceeds ``limit_ns``: computed here, not by fretc."""
    t = last_gps + limit_ns + 1
    return first_tick + max(0, math.ceil((t - first_tick) / (100 * MS))) * 100 * MS


@pytest.mark.parametrize("gps_rows", [20, 40])
@pytest.mark.tor("TOR-TCK-006")
def test_a_px4_gps_that_dies_before_the_end_of_the_flight_is_stale(tmp_path, gps_rows):
    log = _ulog(tmp_path, gps_rows)
    assert open_log(log).log_end == (1_000_000 + 49 * 100_000) * 1000  # vehicle_status's
    la = audit_log(_plan(tmp_path, 'age("sensor_gps") > 0.5'), str(log))
    v = la.verdicts[0]
    assert v.error is None
    last_gps = (1_000_000 + (gps_rows - 1) * 100_000 + 10) * 1000
    assert v.last_tick_ns == 59 * 100 * MS  # the log's end, not the GPS's last message
    assert v.verdict == "violated"
    assert v.first_violation.at.time_ns == _first_stale_tick(v.first_tick_ns, last_gps,
                                                              500 * MS)


def test_a_px4_gps_alive_to_the_end_is_never_stale(tmp_path):
    """The same flight with the GPS to its end: satisfied (the grid to the end changes no
    verdict of a topic that lives to it)."""
    la = audit_log(_plan(tmp_path, 'age("sensor_gps") > 0.5'), str(_ulog(tmp_path, 50)))
    v = la.verdicts[0]
    assert v.verdict == "satisfied"
    # (the grid tick at or after the GPS's last message, 5.90001 s: the log's end or later)
    assert v.last_tick_ns == 60 * 100 * MS


def test_a_px4_gps_that_dies_less_than_its_limit_before_the_end_is_not_stale(tmp_path):
    """Its last message at 5.40001 s, the log's end at 5.9 s: its age never exceeds
    0.5 s within the log, so satisfied (the grid does not run past the log's end)."""
    la = audit_log(_plan(tmp_path, 'age("sensor_gps") > 0.5'), str(_ulog(tmp_path, 45)))
    v = la.verdicts[0]
    assert v.verdict == "satisfied"
    assert v.last_tick_ns == 59 * 100 * MS


def test_an_ardupilot_battery_instance_that_stops_early_is_stale(tmp_path):
    """DataFlash: BAT instance 1 stops at 2.9 s, instance 0 goes on to 5.9 s; the log's end
    is the scan's latest TimeUS, and ``age("BAT/1")`` is stale from 3.5 s on."""
    log = two_batteries(tmp_path / "flight.bin")
    assert open_log(log).log_end == 5_900_000 * 1000
    la = audit_log(_plan(tmp_path, 'age("BAT/1") > 0.5'), str(log))
    v = la.verdicts[0]
    assert v.error is None
    assert v.verdict == "violated"
    assert v.last_tick_ns == 59 * 100 * MS
    assert v.first_violation.at.time_ns == _first_stale_tick(v.first_tick_ns,
                                                              2_900_010 * 1000, 500 * MS)
