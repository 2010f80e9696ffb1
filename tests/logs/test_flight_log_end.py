"""The audit's ``end_time_ns`` of a flight log is the log's end, whichever topics the audit
reads, as on an MCAP (its summary's end): the last log time of a message of any topic
(``log_end`` of the PX4 ULog and ArduPilot DataFlash sources, known when the file is
opened), not the last message of the topics the requirements read."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

pytest.importorskip("pyulog")
pytest.importorskip("pymavlink")

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _dataflash import two_batteries  # noqa: E402
from _shared import SHARED, skip_without_shared  # noqa: E402
from _ulog import write_ulog  # noqa: E402
from fretc.audit import AuditConfig, audit_log, load_plan  # noqa: E402
from fretc.logs import open_log  # noqa: E402

FORMATS = {"sensor_gps": [("uint64_t", "timestamp"), ("float", "eph")],
           "vehicle_status": [("uint64_t", "timestamp"), ("uint8_t", "arming_state")]}


def _plan(tmp_path: Path, variable: str, expr: str, rule: str):
    (tmp_path / "r.fret").write_text(f"@tick_period 100 ms\nG: the drone shall always "
                                     f"satisfy {rule}\n", encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(
        f'[tick]\nperiod = "100 ms"\n[variables]\n{variable} = \'{expr}\'\n', encoding="utf-8")
    return load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))


def _ulog(tmp_path: Path) -> Path:
    """vehicle_status every 100 ms from 1 s to 5.9 s; sensor_gps 10 µs after each of the
    first 20 (its last at 2.90001 s)."""
    out = []
    for i in range(50):
        t = 1_000_000 + i * 100_000
        out.append(("vehicle_status", 0, [t, 2]))
        if i < 20:
            out.append(("sensor_gps", 0, [t + 10, 1.0]))
    return write_ulog(tmp_path / "f.ulg", FORMATS, [("vehicle_status", 0), ("sensor_gps", 0)],
                      out)


@pytest.mark.parametrize("expr, rule", [('"sensor_gps".eph', "eph < 5"),
                                        ('age("sensor_gps") > 0.5', "!eph")])
def test_a_px4_audit_reading_a_topic_that_stops_early_ends_at_the_log_end(tmp_path, expr,
                                                                           rule):
    log = _ulog(tmp_path)
    la = audit_log(_plan(tmp_path, "eph", expr, rule), str(log))
    assert la.verdicts[0].error is None
    assert la.end_time_ns == open_log(log).log_end == 5_900_000 * 1000
    assert la.to_json()["end_time_ns"] == 5_900_000 * 1000


def test_an_ardupilot_audit_reading_an_instance_that_stops_early_ends_at_the_log_end(
        tmp_path):
    log = two_batteries(tmp_path / "flight.bin")
    la = audit_log(_plan(tmp_path, "volt", '"BAT/1".Volt', "volt > 10"), str(log))
    assert la.verdicts[0].error is None and la.verdicts[0].verdict == "satisfied"
    assert la.end_time_ns == open_log(log).log_end == 5_900_000 * 1000


def test_the_shared_px4_sample_audited_on_vehicle_status_ends_at_the_log_end(tmp_path):
    """pyulog's sample flight: vehicle_status's last message is at 181.275 s, the log's last
    (of any topic) at 181.494 s; ``fretc audit --json`` says the latter."""
    skip_without_shared()
    log = SHARED / "data" / "foreign_logs" / "px4" / "sample.ulg"
    last_status = max(m.log_time for m in open_log(log).messages({"vehicle_status"}))
    (tmp_path / "r.fret").write_text("@tick_period 100 ms\nG: the drone shall always "
                                     "satisfy !failsafe\n", encoding="utf-8")
    (tmp_path / "r.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\nfailsafe = \'"vehicle_status".failsafe\'\n',
        encoding="utf-8")
    from click.testing import CliRunner

    from fretc.cli import main

    got = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), str(log),
                                    "--json", str(tmp_path / "a.json"), "--no-progress"])
    assert got.exit_code in (0, 3), got.output  # (the sample has logger dropouts: partial)
    end = json.loads((tmp_path / "a.json").read_text())["logs"][0]["end_time_ns"]
    assert end == open_log(log).log_end == 181_493_506_000 > last_status
