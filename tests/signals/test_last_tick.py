"""The last tick of a period clock (docs/guide/ticks.md, "The tick grid"): the first multiple
of the period at or after the last message of the requirement's topics, as the first tick is
the first multiple at or after their first message. So every message of a requirement's
topics is held by some tick (or counted as unsampled): the last message is judged, and a
topic with one message off the grid has one tick. One rule for the audit (the block
sampler), the tick-by-tick clock of the watch and of ``--write-csv``, and so the C runner
over that CSV; each checked here against the rule restated, on synthetic logs, hypothesis's
message times, the shipped runs and the tests' fixtures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _logs import MS, float64, twist_stamped, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main
from fretc.logs import open_log
from fretc.signals import sample, sample_groups
from fretc.signals.bindings.files import load_bindings
from fretc.signals.blocks import sample_blocks

ROOT = Path(__file__).resolve().parents[2]
F64 = "std_msgs/msg/Float64"


def _plan(folder: Path, fret: str, bindings: str):
    (folder / "u.fret").write_text(fret)
    (folder / "u.bindings.toml").write_text(bindings)
    return load_plan(AuditConfig(requirements=(str(folder / "u.fret"),)))


def _verdict(folder: Path, fret: str, bindings: str, log: Path):
    return audit_log(_plan(folder, fret, bindings), str(log)).verdicts[0]


BIND = '[tick]\nperiod = "100 ms"\n[variables]\nx = "/x.data"\ncode = "/err.data"\n'


def test_the_last_message_off_the_grid_is_judged(tmp_path):
    # 10 Hz stamped 50 ms off the grid, the last message (8.95 s) out of bounds: the grid
    # used to end at 8.9 s, the message never sampled nor counted as unsampled
    log = write_mcap(tmp_path / "x.mcap", [("/x", F64, 50 * MS + k * 100 * MS,
                                            float64(10.0 if k == 89 else 0.0))
                                           for k in range(90)])
    v = _verdict(tmp_path, "U: the robot shall always satisfy x < 5\n", BIND, log)
    assert v.verdict == "violated", v
    assert v.last_tick_ns == 9_000 * MS and v.ticks_evaluated == 90
    assert v.first_violation.at.time_ns == 9_000 * MS


def test_an_event_after_the_last_grid_tick_of_another_topic_is_judged(tmp_path):
    # /x on the grid to 9.0 s, the one failsafe event (code 5) at 9.03 s
    msgs = [("/x", F64, k * 100 * MS, float64(0.0)) for k in range(91)]
    msgs += [("/err", F64, 0, float64(0.0)), ("/err", F64, 9_030 * MS, float64(5.0))]
    log = write_mcap(tmp_path / "e.mcap", sorted(msgs, key=lambda m: m[2]))
    v = _verdict(tmp_path, "U: the robot shall never satisfy code = 5 & x < 1\n", BIND, log)
    assert v.verdict == "violated", v
    assert v.last_tick_ns == 9_100 * MS


def test_one_message_off_the_grid_is_one_tick(tmp_path):
    # an ArduPilot ERR record once at 41.000001 s: one tick at 41.1 s, which holds it
    log = write_mcap(tmp_path / "one.mcap", [("/err", F64, 41_000_001_000, float64(5.0))])
    v = _verdict(tmp_path, "U: the robot shall never satisfy code = 5\n", BIND, log)
    assert v.verdict == "violated", v
    assert v.ticks_evaluated == 1 and v.first_tick_ns == v.last_tick_ns == 41_100 * MS


def _rule(times: list[list[int]], period: int) -> list[int]:
    """The ticks of a clock over topics with these message times (each non-empty), restated
    from docs/guide/ticks.md: multiples of ``period`` from the first at or after the first
    message to the first at or after the last; evaluated from the first at or after every
    topic's first message."""
    first = min(t[0] for t in times)
    last = max(t[-1] for t in times)
    ready = max(t[0] for t in times)
    up = lambda t: -(-t // period) * period  # noqa: E731
    return [t for t in range(up(first), up(last) + 1, period) if t >= ready]


def _three_samplers(log: Path, bindings_path: Path, names: list[str], topics: frozenset):
    """The tick times of one clock by the block sampler, sample_groups and sample."""
    b = load_bindings(str(bindings_path))
    gs = sample_blocks(open_log(log), b, {0: (names, topics)})
    blocks = np.concatenate([blk.times for _k, blk in gs] or [np.zeros(0, np.int64)])
    groups = [t.time for _k, t in sample_groups(open_log(log), b, {0: (names, topics)})]
    one = [t.time for t in sample(open_log(log), b)]
    return blocks.tolist(), groups, one


_times = st.lists(st.integers(0, 3_000), min_size=1, max_size=25, unique=True).map(sorted)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=_times, b=_times, period=st.sampled_from([1, 7, 100, 250, 1000]),
       agg=st.booleans())
@pytest.mark.tor("TOR-TCK-002")
def test_every_sampler_ends_the_grid_at_or_after_the_last_message(tmp_path, a, b, period, agg):
    ms = [("/x", F64, t * MS, float64(t)) for t in a] + [("/y", F64, t * MS, float64(t))
                                                          for t in b]
    log = write_mcap(tmp_path / "h.mcap", sorted(ms, key=lambda m: m[2]))
    y = "any_of_messages(/y.data > 100)" if agg else "/y.data > 100"
    (tmp_path / "h.toml").write_text(f'[tick]\nperiod = "{period} ms"\n[variables]\n'
                                     f'x = "/x.data"\ny = "{y}"\n')
    expected = [t * MS for t in _rule([a, b], period)]
    got = _three_samplers(log, tmp_path / "h.toml", ["x", "y"], frozenset({"/x", "/y"}))
    assert got == (expected, expected, expected)
    assert expected[-1] >= max(a[-1], b[-1]) * MS


def test_csv_export_and_c_runner_judge_the_last_message(tmp_path):
    """``--write-csv`` writes the audit's ticks, the last one included, and the C runner
    over it gives the audit's verdict."""
    from _c_monitors import build, needs_cc

    log = write_mcap(tmp_path / "x.mcap", [("/x", F64, 50 * MS + k * 100 * MS,
                                            float64(10.0 if k == 89 else 0.0))
                                           for k in range(90)])
    _plan(tmp_path, "@tick_period 100 ms\nU: the robot shall always satisfy x < 5\n", BIND)
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "u.fret"), str(log),
                                    "--write-csv", str(tmp_path / "csv"), "--no-progress"])
    assert res.exit_code == 1, res.output
    rows = (tmp_path / "csv" / "x.csv").read_text().splitlines()
    assert rows[-1] == "9,10.0" and len(rows) == 3 + 90  # the mark, its clock, the header
    needs_cc()
    res = CliRunner().invoke(main, [str(tmp_path / "u.fret"), "--emit", "c", "-o",
                                    str(tmp_path / "c")])
    assert res.exit_code == 0, res.output
    exe = build(tmp_path / "c", sorted(p.name for p in (tmp_path / "c").glob("*.c")), "runner")
    import subprocess
    got = subprocess.run([str(exe), str(tmp_path / "csv" / "x.csv")], capture_output=True,
                         text=True)
    assert got.returncode == 1 and got.stdout.split("\t")[:2] == ["U", "violated"], got


def _fixture_logs() -> list[Path]:
    """The shipped runs and the MCAP fixtures of the tests."""
    logs = sorted((ROOT / "traces").glob("*.mcap"))
    logs += sorted((ROOT / "tests" / "fixtures").rglob("*.mcap"))
    return logs


@pytest.mark.parametrize("log", _fixture_logs(), ids=lambda p: p.name)
@pytest.mark.tor("TOR-TCK-002", "TOR-WCH-001")
def test_audit_watch_clock_and_csv_share_the_last_tick(tmp_path, log):
    """Metamorphic: on every shipped run, each Safe-ROS requirement's clock in the audit
    has the ticks of the watch's tick-by-tick clock on the same messages; the last tick is
    at or after the last message of the clock's topics and less than a period after it, or,
    for a clock reading age() (R6), at or after the log's end (its last message, of any
    topic) and less than a period after that: a topic silent to the end is stale there."""
    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))
    la = audit_log(plan, str(log))
    b = plan.bindings
    period = b.tick.period_ns
    src = open_log(str(log))
    for r, v in zip(plan.requirements, la.verdicts):
        if v.verdict == "error" or not v.ticks_evaluated:
            continue
        topics = frozenset(t for n in r.variables for t in b.variables[n].topics)
        ticks = [t.time for _k, t in sample_groups(open_log(str(log)), b,
                                                   {0: (list(r.variables), topics)})]
        assert (ticks[0], ticks[-1], len(ticks)) == (v.first_tick_ns, v.last_tick_ns,
                                                    v.ticks_evaluated), r.id
        last = max(m.log_time for m in src.messages(set(topics)))
        if any("age(" in b.variables[n].expr for n in r.variables):
            last = max(m.log_time for m in open_log(str(log)).messages())
        assert 0 <= v.last_tick_ns - last < period, r.id



@pytest.mark.tor("TOR-TCK-006")
def test_a_topic_silent_to_the_end_of_the_log_is_stale_there(tmp_path):
    """/scan stops at 2.9 s of a 10 s log (/other goes on): a requirement over age(/scan)
    alone ticks to the log's end and is violated from 3.3 s (age over 0.3 s); it was
    satisfied, its clock ending at /scan's last message. A requirement over /scan's values
    alone still ends there (the values are held only while the topic publishes)."""
    msgs = [("/other", F64, k * 100 * MS + MS, float64(1.0)) for k in range(100)]
    msgs += [("/scan", F64, k * 100 * MS, float64(1.0)) for k in range(30)]
    log = write_mcap(tmp_path / "s.mcap", sorted(msgs, key=lambda m: m[2]))
    _plan(tmp_path, "@tick_period 100 ms\nS: the lidar shall always satisfy !stale\n"
          "V: the lidar shall always satisfy scan_ok\n",
          '[tick]\nperiod = "100 ms"\n[variables]\nstale = "age(/scan) > 0.3"\n'
          'scan_ok = "/scan.data > 0"\n')
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "u.fret"),)))
    by = {v.requirement: v for v in audit_log(plan, str(log)).verdicts}
    assert by["S"].verdict == "violated" and by["S"].first_violation.at.tick == 33, by["S"]
    assert by["S"].last_tick_ns == 10_000 * MS  # the grid tick at or after the log's end (9.901 s)
    assert by["V"].verdict == "satisfied" and by["V"].last_tick_ns == 2_900 * MS


@pytest.mark.tor("TOR-TCK-006")
def test_age_on_header_stamps_ticks_to_the_last_stamp_not_the_log_end(tmp_path):
    """The log's end is a log time: a clock on header stamps (here a simulation's clock from
    0, logged at wall-clock times) ticks to its topics' last stamp, whatever the log's end
    on the other clock; taking it there would make billions of ticks."""
    wall = 1_700_000_000 * 10**9
    msgs = [("/scan", "geometry_msgs/msg/TwistStamped", wall + k * 100 * MS,
             twist_stamped(k * 100 * MS, x=1.0)) for k in range(30)]
    log = write_mcap(tmp_path / "sim.mcap", msgs)
    v = _verdict(tmp_path, "@tick_period 100 ms\nS: the lidar shall always satisfy !stale\n",
                 '[tick]\nperiod = "100 ms"\ntime = "header"\n[variables]\n'
                 'stale = "age(/scan) > 0.3"\n', log)
    assert v.verdict == "satisfied" and v.last_tick_ns == 2_900 * MS, v
