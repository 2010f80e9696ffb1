"""The simulator's fault model (sim/faults.py): each fault kind, injected into a short run,
shows in the recorded /scan, /cmd_vel or Safety System messages exactly in its window, and
the run before the window is the run without the fault, message for message (the same
seed); the faults are in the recording's metadata; the default recordings are unchanged;
the command line pairs its options; a space searches the faults (sim/spaces/sensor_faults.toml)
and falsify and estimate pass them to the simulator.

The recordings are read back with ``mcap`` and ``rosbags``' ROS 2 store, never through the
simulator's internals; sector membership is computed from each message's own
``angle_min``/``angle_increment`` (REP 103), invalid ranges are NaN (REP 117)."""

from __future__ import annotations

import io
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_typestore

from fretc.sim.__main__ import main as sim_main
from fretc.sim.faults import FAULT_KINDS, Fault, faults_from_options
from fretc.sim.run import record_scenario
from fretc.sim.scenarios import SCENARIOS
from fretc.sim.space import SpaceError, apply, load_space

ROOT = Path(__file__).resolve().parents[2]
BINDINGS = ROOT / "requirements" / "safe_ros.bindings.toml"
pytestmark = pytest.mark.xdist_group("sim")

#: a short run: the mission starts at 1 s, its time limit at 2.5 s, 2 s of linger
BASE = replace(SCENARIOS["nominal"], max_time=2.5)
#: the fault's window (s): scans at 1.5 .. 2.1 s, proposals at 1.55 .. 2.15 s
START, DURATION = 1.5, 0.7
END = START + DURATION
TS = get_typestore(Stores.ROS2_HUMBLE)
TYPES = {"/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
         "/cmd_vel_filtered": "geometry_msgs/msg/Twist",
         "/gwendolen_control": "std_msgs/msg/Bool"}


class Rec:
    """One recording: every message as (topic, t s from the run's start, bytes), its
    metadata records."""

    def __init__(self, data: bytes):
        self.data = data
        reader = make_reader(io.BytesIO(data))
        rows = [(c.topic, m.log_time, m.data) for _s, c, m in reader.iter_messages(
            log_time_order=False)]
        t0 = min(t for _tp, t, _d in rows)  # the latched /map at the run's start
        self.t0 = t0
        self.rows = [(tp, round((t - t0) / 1e9, 6), d) for tp, t, d in rows]
        self.metadata = {m.name: dict(m.metadata)
                         for m in make_reader(io.BytesIO(data)).iter_metadata()}

    def before(self, t: float) -> list:
        return [r for r in self.rows if r[1] < t - 1e-9]

    def msgs(self, topic: str, lo: float = -math.inf, hi: float = math.inf) -> list:
        """(t s, decoded message) of ``topic`` with ``lo <= t < hi``."""
        return [(t, TS.deserialize_cdr(d, TYPES[topic])) for tp, t, d in self.rows
                if tp == topic and lo - 1e-9 <= t < hi - 1e-9]


def _run(sc=BASE, seed: int = 1, shield=None) -> Rec:
    out = io.BytesIO()
    record_scenario(sc, seed, out, shield=shield)
    return Rec(out.getvalue())


def _faulty(fault: Fault, seed: int = 1, shield=None) -> Rec:
    return _run(replace(BASE, faults=(fault,)), seed, shield)


@pytest.fixture(scope="module")
def base() -> Rec:
    return _run()


def _stamp_s(rec: Rec, msg) -> float:
    ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
    return round((ns - rec.t0) / 1e9, 6)


def _sector(msg, lo: float, hi: float) -> np.ndarray:
    n = len(msg.ranges)
    ang = np.degrees(msg.angle_min + np.arange(n) * msg.angle_increment)
    ang = (ang + 180.0) % 360.0 - 180.0
    return (ang >= lo - 1e-4) & (ang <= hi + 1e-4)  # (float32 angles; a beam is 0.5 deg)


def _same_before(base: Rec, got: Rec) -> None:
    assert got.before(START) == base.before(START)
    assert len(got.before(START)) > 100


def _scans_in_window(rec: Rec) -> list:
    got = rec.msgs("/scan", START, END)
    assert [t for t, _ in got] == [1.5, 1.6, 1.7, 1.8, 1.9, 2.0, 2.1]
    return got


def _scan_at(rec: Rec, t: float):
    (m,) = [m for tt, m in rec.msgs("/scan") if abs(tt - t) < 1e-9]
    return np.asarray(m.ranges), m


def test_silence_drops_the_scans_of_its_window_only(base):
    got = _faulty(Fault("silence", START, DURATION))
    _same_before(base, got)
    assert got.msgs("/scan", START, END) == []
    assert len(base.msgs("/scan", START, END)) == 7
    times = [t for t, _ in got.msgs("/scan")]
    assert 1.4 in times and 2.2 in times


def test_silence_is_the_dropout():
    by_fault = _run(replace(BASE, faults=(Fault("silence", START, DURATION),)))
    by_dropout = _run(replace(BASE, dropout_start=START, dropout_duration=DURATION))
    assert by_fault.rows == by_dropout.rows
    assert "fretc.sim.faults" not in by_dropout.metadata


def test_all_nan_keeps_the_rate_and_invalidates_every_range(base):
    got = _faulty(Fault("all_nan", START, DURATION))
    _same_before(base, got)
    for _t, m in _scans_in_window(got):
        assert np.isnan(np.asarray(m.ranges)).all()
    for t in (1.4, 2.2):
        assert np.isfinite(_scan_at(got, t)[0]).sum() > 300


def test_sector_nan_invalidates_the_sector_only(base):
    got = _faulty(Fault("sector_nan", START, DURATION, sector=(-30.0, 30.0)))
    _same_before(base, got)
    for _t, m in _scans_in_window(got):
        r, sec = np.asarray(m.ranges), _sector(m, -30.0, 30.0)
        assert sec.sum() == 121  # -30..30 degrees at 0.5 degrees a beam
        assert np.isnan(r[sec]).all() and np.isfinite(r[~sec]).sum() > 300
    # the first scan of the window: the measurement outside the sector untouched
    r, m = _scan_at(got, START)
    r0, _ = _scan_at(base, START)
    sec = _sector(m, -30.0, 30.0)
    assert np.array_equal(r[~sec], r0[~sec], equal_nan=True)
    assert np.isfinite(r0[sec]).any()
    r_after, m_after = _scan_at(got, END)
    assert np.isfinite(r_after[_sector(m_after, -30.0, 30.0)]).any()


def test_a_sector_through_180_degrees_wraps():
    got = _faulty(Fault("sector_nan", START, DURATION, sector=(170.0, -170.0)))
    r, m = _scan_at(got, 1.7)
    behind = _sector(m, 170.0, 180.0) | _sector(m, -180.0, -170.0)
    assert behind.sum() == 41 and np.isnan(r[behind]).all()
    assert np.isfinite(r[~behind]).sum() > 300


def test_frozen_republishes_the_last_scan_with_fresh_stamps(base):
    got = _faulty(Fault("frozen", START, DURATION))
    _same_before(base, got)
    last, _ = _scan_at(got, 1.4)
    for t, m in _scans_in_window(got):
        assert np.array_equal(np.asarray(m.ranges), last, equal_nan=True)
        assert _stamp_s(got, m) == t
    after, m = _scan_at(got, END)
    assert not np.array_equal(after, last, equal_nan=True) and _stamp_s(got, m) == END


def test_stale_stamp_holds_the_header_stamp_with_fresh_ranges(base):
    got = _faulty(Fault("stale_stamp", START, DURATION))
    _same_before(base, got)
    window = _scans_in_window(got)
    assert {_stamp_s(got, m) for _t, m in window} == {START}
    assert np.array_equal(_scan_at(got, START)[0], _scan_at(base, START)[0], equal_nan=True)
    assert not np.array_equal(np.asarray(window[0][1].ranges), np.asarray(window[-1][1].ranges),
                              equal_nan=True)
    _r, m = _scan_at(got, END)
    assert _stamp_s(got, m) == END


def test_near_returns_add_a_few_short_beams_deterministically(base):
    fault = Fault("near_returns", START, DURATION)
    got = _faulty(fault)
    _same_before(base, got)
    near = np.float32(0.2)
    picked = []
    for _t, m in _scans_in_window(got):
        r = np.asarray(m.ranges)
        picked.append(tuple(np.flatnonzero(r == near)))
        assert len(picked[-1]) == 3
    assert len(set(picked)) > 1  # drawn per scan
    r, _ = _scan_at(got, START)
    r0, _ = _scan_at(base, START)
    differ = np.flatnonzero(~((r == r0) | (np.isnan(r) & np.isnan(r0))))
    assert tuple(differ) == picked[0]
    assert not (_scan_at(got, END)[0] == near).any()
    assert _faulty(fault).data == got.data
    # in a sector: the beams drawn there
    ahead = _faulty(Fault("near_returns", START, DURATION, sector=(-10.0, 10.0)))
    for _t, m in _scans_in_window(ahead):
        r = np.asarray(m.ranges)
        assert (r == near).sum() == 3 and (r[_sector(m, -10.0, 10.0)] == near).sum() == 3


@pytest.mark.parametrize("kind, value", [("cmd_nan", math.nan), ("cmd_inf", math.inf),
                                         ("cmd_huge", 1e6)])
def test_the_controllers_proposals_in_the_window(base, kind, value):
    got = _faulty(Fault(kind, START, DURATION))
    _same_before(base, got)
    window = got.msgs("/cmd_vel", START, END)
    assert [t for t, _ in window] == [1.55, 1.65, 1.75, 1.85, 1.95, 2.05, 2.15]
    for _t, m in window:
        x = m.linear.x
        assert (math.isnan(x) if math.isnan(value) else x == value)
    for _t, m in got.msgs("/cmd_vel", END) + got.msgs("/cmd_vel", 0.0, START):
        assert math.isfinite(m.linear.x) and abs(m.linear.x) <= 0.5
    # the interceptor forwards it; the base saturates (inf, 1e6) or ignores (NaN) it
    forwarded = [m.linear.x for _t, m in got.msgs("/cmd_vel_filtered", START, END)]
    assert forwarded and all(x == value or (math.isnan(x) and math.isnan(value))
                             for x in forwarded)
    poses = [TS.deserialize_cdr(d, "geometry_msgs/msg/PoseStamped").pose.position
             for tp, _t, d in got.rows if tp == "/ground_truth/pose"]
    assert all(math.isfinite(p.x) and math.isfinite(p.y) for p in poses)


def test_the_sifs_restart_is_silent_then_publishes_its_start_up_false(base):
    got = _faulty(Fault("safety_restart", START, DURATION))
    _same_before(base, got)
    assert got.msgs("/gwendolen_control", START, END) == []
    back = got.msgs("/gwendolen_control", END, END + 0.01)
    assert [(t, m.data) for t, m in back] == [(END, False)]
    assert base.msgs("/gwendolen_control", END, END + 0.01) == []


@pytest.fixture(scope="module")
def small_shield(tmp_path_factory):
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.shield.build import build_shield
    from fretc.shield.emit import write_forms
    from fretc.signals.bindings.files import load_bindings

    d = tmp_path_factory.mktemp("shield")
    (d / "r2.fret").write_text("R2: upon too_close agilex_agent shall within 1 second "
                               "satisfy stopped\n")
    shield = build_shield(compile_entries(load_requirements([d / "r2.fret"])), ["too_close"],
                          ["stopped"], bindings=load_bindings(BINDINGS), fork=False,
                          name="r2")
    write_forms(shield, ["python"], d / "out", bindings_file=str(BINDINGS))
    return d / "out"


def test_the_shields_restart_publishes_nothing_in_its_window(small_shield):
    from fretc.sim.run import shield_of

    plain = _run(shield=shield_of(f"shield:{small_shield}"))
    restarted = shield_of(f"shield:{small_shield}")
    got = _faulty(Fault("safety_restart", START, DURATION), shield=restarted)
    assert got.before(START) == plain.before(START)
    assert len(plain.msgs("/cmd_vel_filtered", START, END)) == 7
    assert got.msgs("/cmd_vel_filtered", START, END) == []
    assert [t for t, _ in got.msgs("/cmd_vel_filtered", END, END + 0.05)] == [2.2]
    # the shield's ticks before and after the crash are both counted
    assert restarted.ticks == len(got.msgs("/cmd_vel_filtered"))


def test_the_faults_are_in_the_recordings_metadata(base):
    faults = (Fault("sector_nan", START, DURATION, sector=(-30.0, 30.0)),
              Fault("cmd_huge", 1.0, 0.5))
    got = _run(replace(BASE, faults=faults), seed=7)
    meta = got.metadata["fretc.sim.faults"]
    assert meta["scenario"] == "nominal" and meta["seed"] == "7"
    assert json.loads(meta["faults"]) == [
        {"kind": "sector_nan", "start": 1.5, "duration": 0.7, "sector": [-30.0, 30.0]},
        {"kind": "cmd_huge", "start": 1.0, "duration": 0.5}]
    assert base.metadata == {}


def test_the_default_recording_is_the_shipped_one():
    out = io.BytesIO()
    record_scenario(SCENARIOS["lidar_dropout"], 1, out)
    assert out.getvalue() == (ROOT / "traces" / "lidar_dropout.mcap").read_bytes()


def test_command_line_options_pair_in_order():
    got = faults_from_options(("sector_nan", "cmd_nan"), (1.0, 5.0), (2.0,), ("-30:30",))
    assert got == (Fault("sector_nan", 1.0, 2.0, (-30.0, 30.0)), Fault("cmd_nan", 5.0, 2.0))
    with pytest.raises(ValueError, match="given 2 times for 3"):
        faults_from_options(("all_nan",) * 3, (1.0, 2.0), (1.0,))
    with pytest.raises(ValueError, match="needs --fault-duration"):
        faults_from_options(("all_nan",), (1.0,), ())
    with pytest.raises(ValueError, match="needs a sector"):
        faults_from_options(("sector_nan",), (1.0,), (1.0,))
    with pytest.raises(ValueError, match="need --fault KIND"):
        faults_from_options((), (1.0,), ())
    with pytest.raises(ValueError, match=r"\[-180, 180\]"):
        faults_from_options(("near_returns",), (1.0,), (1.0,), ("-200:0",))
    r = CliRunner().invoke(sim_main, ["record", "-o", "/dev/null", "--fault", "sector_nan",
                                      "--fault-start", "1", "--fault-duration", "1"])
    assert r.exit_code == 2 and "sector" in r.output
    r = CliRunner().invoke(sim_main, ["record", "-o", "/dev/null", "--fault", "bogus"])
    assert r.exit_code == 2 and "safety_restart" in r.output


# ----------------------------------------------------------------------------- spaces
def test_the_shipped_space_loads_every_kind():
    space = load_space(ROOT / "sim" / "spaces" / "sensor_faults.toml")
    assert space.names == ["fault_kind", "fault_start", "fault_duration", "fault_sector_low",
                           "fault_sector_high"]
    kind = space.distributions[0]
    assert kind.kind == "choice" and kind.values == tuple(float(i)
                                                          for i in range(len(FAULT_KINDS)))
    sc = apply(space.scenario, space.point([0.2, 0.5, 0.5, 0.0, 1.0]))
    assert sc.faults == (Fault("sector_nan", 20.0, 2.6, (-90.0, 90.0)),)


def test_a_space_snaps_the_kind_to_the_listed_ones(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('scenario = "nominal"\n[parameters]\n'
                 'fault_kind = {dist = "choice", values = ["all_nan", "near_returns"]}\n'
                 'fault_start = [1.0, 2.0]\nfault_duration = [0.5, 1.0]\n')
    space = load_space(p)
    kinds = {space.point([u, 0.5, 0.5])["fault_kind"] for u in np.linspace(0, 1, 41)}
    assert kinds == {1.0, 5.0}
    assert apply(space.scenario, space.point([0.9, 0.0, 1.0])).faults == (
        Fault("near_returns", 1.0, 1.0),)
    p.write_text('scenario = "nominal"\n[parameters]\nfault_kind = "frozen"\n'
                 'fault_start = {dist = "uniform", low = 1.0, high = 2.0, fault = 0.5}\n'
                 'fault_duration = [0.5, 1.0]\n')
    space = load_space(p)
    assert {space.point([u, 0.5, 0.5])["fault_kind"] for u in (0.0, 1.0)} == {3.0}
    happened = [space.at_latent([0.0, z, 0.0, 0.0]) for z in (-1.0, 1.0)]
    assert [("fault_start" in v) for v in happened] == [True, False]
    assert apply(space.scenario, happened[1]).faults == ()


@pytest.mark.parametrize("body, words", [
    ('fault_kind = "bogus"\nfault_start = [1, 2]\nfault_duration = [1, 2]',
     "unknown fault 'bogus'"),
    ('fault_kind = "all_nan"\nfault_start = [1, 2]', "fault_start needs fault_duration"),
    ('fault_kind = [0, 12]\nfault_start = [1, 2]\nfault_duration = [1, 2]', "from 0 to 9"),
    ('fault_kind = {dist = "choice", values = [1, 2.5]}\nfault_start = [1, 2]\n'
     'fault_duration = [1, 2]', "names, or whole indices"),
    ('fault_kind = {dist = "choice", values = [1, 2], fault = 0.5}\nfault_start = [1, 2]\n'
     'fault_duration = [1, 2]', "goes on fault_start"),
    ('fault_kind = "sector_nan"\nfault_start = [1, 2]\nfault_duration = [1, 2]\n'
     'fault_sector_low = [-200, 0]\nfault_sector_high = [0, 10]', "[-180, 180]"),
    ('fault_kind = "sector_nan"\nfault_start = [1, 2]\nfault_duration = [1, 2]\n'
     'fault_sector_low = [-20, 0]', "needs fault_sector_high"),
])
def test_bad_fault_parameters_name_file_and_line(tmp_path, body, words):
    p = tmp_path / "s.toml"
    p.write_text(f'scenario = "nominal"\n[parameters]\n{body}\n')
    with pytest.raises(SpaceError, match=r"s\.toml:\d+: ") as exc:
        load_space(p)
    assert words in str(exc.value)


SMALL_SPACE = """scenario = "nominal"
seed = 1
max_time = 2.5
[parameters]
fault_kind = {dist = "choice", values = ["all_nan", "cmd_huge"]}
fault_start = [1.2, 2.0]
fault_duration = [0.3, 0.6]
"""


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    from fretc.audit import AuditConfig, load_plan

    d = tmp_path_factory.mktemp("small")
    (d / "space.toml").write_text(SMALL_SPACE)
    (d / "r.fret").write_text("R5: the scout_mini shall always satisfy clearance > 0\n")
    plan = load_plan(AuditConfig(requirements=[str(d / "r.fret")], bindings=[str(BINDINGS)]))
    return d, load_space(d / "space.toml"), plan


def _spy(monkeypatch, module) -> list:
    seen: list = []
    real = module.record_scenario

    def spy(sc, *a, **k):
        seen.append(sc.faults)
        return real(sc, *a, **k)

    monkeypatch.setattr(module, "record_scenario", spy)
    return seen


def test_falsify_passes_the_fault_to_the_simulator(small, monkeypatch, tmp_path):
    import fretc.sim.falsify as falsify_mod

    _d, space, plan = small
    seen = _spy(monkeypatch, falsify_mod)
    search = falsify_mod.falsify(plan, space, 2, 1, tmp_path / "out")
    assert len(search.runs) == 2 and len(seen) == 2
    for run, faults in zip(search.runs, seen):
        p = run.parameters
        assert faults == (Fault(FAULT_KINDS[int(p["fault_kind"])], p["fault_start"],
                                p["fault_duration"]),)
        assert FAULT_KINDS[int(p["fault_kind"])] in ("all_nan", "cmd_huge")


def test_estimate_passes_the_fault_to_the_simulator(small, monkeypatch, tmp_path):
    import fretc.sim.estimate as estimate_mod

    _d, space, plan = small
    seen = _spy(monkeypatch, estimate_mod)
    result = estimate_mod.estimate(plan, space, 3, tmp_path / "out", budget=2)
    assert len(result.runs) == 2 and len(seen) == 2
    for run, faults in zip(result.runs, seen):
        p = run.parameters
        assert faults == (Fault(FAULT_KINDS[int(p["fault_kind"])], p["fault_start"],
                                p["fault_duration"]),)
        assert 1.2 <= p["fault_start"] <= 2.0 and 0.3 <= p["fault_duration"] <= 0.6


def _speeds(rec: Rec) -> dict[float, float]:
    """The base's ground-truth speed (m/s) between consecutive poses, by the first pose's
    time (s from the run's start, rounded to ms)."""
    TYPES.setdefault("/ground_truth/pose", "geometry_msgs/msg/PoseStamped")
    poses = rec.msgs("/ground_truth/pose")
    return {round(t0, 3): math.hypot(b.pose.position.x - a.pose.position.x,
                                     b.pose.position.y - a.pose.position.y) / (t1 - t0)
            for (t0, a), (t1, b) in zip(poses, poses[1:])}


def test_the_chassis_brakes_once_the_last_command_is_older_than_its_timeout(small_shield):
    """The shield's node restarting for 0.9 s from 1.5 s: the simulated base executed its
    last command through the whole silence (an estimate over sim/spaces/sensor_faults.toml
    found contacts with the shield: a restart of 4 s at 30.7 s, on the approach to P3). The
    Scout Mini's chassis drops a speed command older than 500 ms and brakes to rest (its
    user manual, CAN protocol): the base holds the last command (0.12 m/s) until it is 500 ms
    old, then brakes at its 0.5 m/s^2 and is at rest before the node is back, while the run
    without the restart speeds up."""
    from fretc.sim.run import shield_of

    plain = _speeds(_run(shield=shield_of(f"shield:{small_shield}")))
    got = _speeds(_faulty(Fault("safety_restart", 1.5, 0.9),
                          shield=shield_of(f"shield:{small_shield}")))
    held = got[1.5]
    assert held > 0.05 and all(got[t] == pytest.approx(held) for t in (1.6, 1.7, 1.8))
    assert got[2.0] < held and got[2.2] == 0.0 and got[2.35] == 0.0, got
    assert plain[2.2] > 0.3, plain
