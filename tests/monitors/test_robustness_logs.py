"""The robustness of R4 and R5 in the audit of the shipped runs equals an independent
computation from the raw messages (sim.logs.read_log decodes them; the tick grid, sample and
hold and the margins are computed here in plain Python: on the multiples of 100 ms from the
first at or after the first message of the requirement's own topic, each tick holding the
newest message at or before it)."""

from __future__ import annotations

import bisect
from pathlib import Path

import pytest

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.sim.logs import read_log

ROOT = Path(__file__).resolve().parents[2]
PERIOD_NS = 100_000_000
LOGS = ["nominal.mcap", "sif_disabled.mcap", "unmapped_obstacles.mcap", "stop_delay.mcap"]


@pytest.fixture(scope="module")
def plan():
    return load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))


def _held(messages, value):
    """[(tick time, value of the newest message at or before it)] on the 100 ms grid (the
    multiples of 100 ms) from the first message to the last."""
    times = [t for t, _p, _m in messages]
    out, g = [], -(-times[0] // PERIOD_NS) * PERIOD_NS
    while g <= times[-1]:
        k = bisect.bisect_right(times, g) - 1
        out.append((g, value(messages[k][2])))
        g += PERIOD_NS
    return out


def _least(margins):
    """(least margin, first tick index where it occurs)."""
    least = min(margins)
    return least, margins.index(least)


def _robustness(la, rid):
    v = next(v for v in la.verdicts if v.requirement == rid)
    return v.verdict, v.robustness, v.robustness_at.tick, v.robustness_at.time_ns


@pytest.mark.parametrize("name", LOGS)
def test_r4_r5_robustness_from_raw_messages(plan, name):
    path = ROOT / "traces" / name
    log = read_log(path)
    la = audit_log(plan, str(path))
    # R4: linear_speed <= 0.5 & angular_speed <= 0.5, both from /cmd_vel_filtered
    r4 = _held(log.messages["/cmd_vel_filtered"],
               lambda m: min(0.5 - abs(m.linear.x), 0.5 - abs(m.angular.z)))
    value, tick = _least([m for _t, m in r4])
    verdict, rob, rtick, rtime = _robustness(la, "R4")
    assert (rob, rtick, rtime) == (value, tick, r4[tick][0])
    assert verdict == ("violated" if value < 0 else "satisfied")
    # R5: clearance > 0 from /ground_truth/clearance
    r5 = _held(log.messages["/ground_truth/clearance"], lambda m: m.data)
    value, tick = _least([m for _t, m in r5])
    verdict, rob, rtick, rtime = _robustness(la, "R5")
    assert (rob, rtick, rtime) == (value, tick, r5[tick][0])
    assert verdict == ("violated" if value <= 0 else "satisfied")


def test_sif_disabled_r5_is_the_depth_of_the_contact(plan):
    """The robot drives into the drum: R5's robustness is the (negative) clearance, and the
    audit JSON carries it with the tick."""
    la = audit_log(plan, str(ROOT / "traces" / "sif_disabled.mcap"))
    v = next(v for v in la.verdicts if v.requirement == "R5")
    assert v.verdict == "violated" and -0.01 < v.robustness < 0
    js = v.to_json(la.start_time_ns)["robustness"]
    assert js["value"] == v.robustness and js["tick"] == v.robustness_at.tick
    r2 = next(v for v in la.verdicts if v.requirement == "R2")
    assert r2.verdict == "violated" and r2.to_json(None)["robustness"]["value"] == "-inf"
