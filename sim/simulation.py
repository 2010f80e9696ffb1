"""The simulation loop: world, robot, SRAS and Safety System on one fixed-step sim clock.

Clock: integer milliseconds from the start of the run, physics step 10 ms; the time written to
the log is ``EPOCH_NS + t`` (1_700_000_000 s, so stamps look like real ROS time). Within one
step the order is fixed:

Design notes: ARCHITECTURE.md, `sim/simulation.py`."""

from __future__ import annotations

import json
import math
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from fretc.sim.navigation import (INSPECTION_POINTS, ControllerParams, GlobalPlanner, LocalController,
                         Mission, PlannerParams)
from fretc.sim.faults import CMD_VALUES, SCAN_KINDS, Fault, fault_rng, in_sector
from fretc.sim.recording import Recorder
from fretc.sim.robot import (Lidar, LidarParams, OdometryNoise, ScoutMini, ScoutMiniParams,
                    WheelOdometry, min_valid_range, wrap_angle)
from fretc.sim.safety import CmdVelInterceptor, SafetyAgent, SafetyParams
from fretc.sim.scenarios import Scenario
from fretc.sim.world import OccupancyMap, World

#: Sim clock epoch (ns since the Unix epoch): 2023-11-14T22:13:20Z.
EPOCH_NS = 1_700_000_000 * 1_000_000_000
STEP_MS = 10


@dataclass(frozen=True)
class SimParams:
    """Run-level settings: ``mission_start`` s (first goal), ``max_time`` s (mission time
    limit), ``final_linger`` / ``contact_linger`` s of recording after the end,
    ``loc_sigma_xy`` m / ``loc_sigma_yaw`` rad (localization noise, per scan)."""

    # dataclass fields, same shape as sim.robot.ScoutMiniParams' (kept: parameter defaults, no
    # logic)
    mission_start: float = 1.0
    max_time: float = 110.0
    final_linger: float = 2.0
    contact_linger: float = 0.5
    loc_sigma_xy: float = 0.01
    loc_sigma_yaw: float = 0.005
    dwell: float = 1.0


@dataclass
class Trace:
    """What happened, sampled by the simulator for plots and summaries (not the log)."""

    t: list[float] = field(default_factory=list)            # s, 20 Hz
    x: list[float] = field(default_factory=list)            # m, ground truth
    y: list[float] = field(default_factory=list)
    yaw: list[float] = field(default_factory=list)
    v: list[float] = field(default_factory=list)            # m/s, ground truth
    clearance: list[float] = field(default_factory=list)    # m
    scan_t: list[float] = field(default_factory=list)       # s, 10 Hz
    scan_min: list[float] = field(default_factory=list)     # m, min valid range
    control: list[tuple[float, bool]] = field(default_factory=list)  # published Bools
    cmd_t: list[float] = field(default_factory=list)
    cmd_v: list[float] = field(default_factory=list)        # /cmd_vel_filtered linear.x
    cmd_w: list[float] = field(default_factory=list)


@dataclass
class RunResult:
    """Outcome of one run."""

    scenario: Scenario
    seed: int
    threshold: float
    duration: float                      # s of sim time (first to last message)
    counts: dict[str, int]               # messages per topic
    outcome: str                         # "completed", "aborted: ...", "contact"
    reached: list[tuple[int, float, float, float]]  # (goal index, t s, x m, y m) ground truth
    min_clearance: float
    contact: tuple[float, float, float] | None   # (t, x, y)
    sif_events: list
    trace: Trace
    world: World
    goals: list[tuple[float, float]]
    #: with a generated shield (:mod:`fretc.sim.shielded`): (t s, reasons, changed atoms) of
    #: each override, and its ticks
    overrides: list = field(default_factory=list)
    shield_ticks: int = 0
    #: the shield's assumptions of the environment that broke: (t s, ids) when first broken
    shield_broken: list = field(default_factory=list)


def _ns(t_ms: int) -> int:
    """Log time (ns) of sim time ``t_ms`` (ms)."""
    return EPOCH_NS + t_ms * 1_000_000


@dataclass
class _RunState:
    """What one run carries from step to step: the trace, the SIF decisions waiting for
    their delay (``pending``: (due ms, stop)), the last min valid scan range, the contact,
    the run's end and outcome, the mission's dwell and goal state, the least clearance."""

    trace: Trace
    delay_ms: int
    max_ms: int
    start_ms: int = 0
    drop: tuple[int, int] | None = None
    pending: deque = field(default_factory=deque)
    interceptor_pending: deque = field(default_factory=deque)
    last_min: float = math.inf
    contact: tuple[float, float, float] | None = None
    blocked: bool = False
    end_ms: int | None = None
    outcome: str = ""
    dwell_until: int | None = None
    goal_active: bool = False
    min_clear: float = math.inf
    #: the silent LiDAR's windows (ms): the dropout's and the ``silence`` faults'
    silent: list[tuple[int, int]] = field(default_factory=list)
    #: the ranges of the last scan published without a scan fault (``frozen`` republishes them)
    last_good: np.ndarray | None = None
    #: per ``stale_stamp`` fault (its place in the scenario's list): the held header stamp (ns)
    stale: dict[int, int] = field(default_factory=dict)
    #: the Safety System's node is down (a ``safety_restart`` fault's window)
    safety_down: bool = False


class Simulation:
    """One run of a scenario. ``threshold`` m is the SIF's (Safe-ROS: 0.9 m); component
    parameters can be replaced for experiments. By default the SRAS's speed-limit zone is
    ``threshold + 0.05`` m, the agent's re-arm distance, so the robot is slow exactly while the
    SIF may be in its monitored release.

    Raises ``ValueError`` for a non-positive threshold."""

    def __init__(self, scenario: Scenario, seed: int = 1, threshold: float = 0.9,
                 omap: OccupancyMap | None = None, sim: SimParams = SimParams(),
                 # frozen dataclasses: one shared default instance is safe
                 robot: ScoutMiniParams = ScoutMiniParams(),  # noqa: B008
                 lidar: LidarParams = LidarParams(),  # noqa: B008
                 odom_noise: OdometryNoise = OdometryNoise(),  # noqa: B008
                 planner: PlannerParams = PlannerParams(),  # noqa: B008
                 controller: ControllerParams | None = None,
                 safety: SafetyParams | None = None, shield: Any = None):
        if not threshold > 0:
            raise ValueError("threshold must be > 0")
        self.scenario = scenario
        self.seed = int(seed)
        self.threshold = float(threshold)
        if scenario.max_time is not None:
            sim = replace(sim, max_time=float(scenario.max_time))
        if scenario.lidar_sigma is not None:
            lidar = replace(lidar, sigma=float(scenario.lidar_sigma))
        self.sim = sim
        self.omap = omap if omap is not None else OccupancyMap.load()
        self.world = World(self.omap, scenario.barrels, scenario.movers, scenario.removed)
        ss = np.random.SeedSequence(self.seed)
        g_odom, g_lidar, g_loc = (np.random.Generator(np.random.PCG64(s)) for s in ss.spawn(3))
        hx, hy, hyaw = scenario.home
        self.base = ScoutMini(robot, hx, hy, hyaw)
        self.odom = WheelOdometry(odom_noise, g_odom)
        self.lidar = Lidar(lidar, g_lidar)
        self.loc_rng = g_loc
        self.planner = GlobalPlanner(self.omap, planner)
        ctrl = controller or ControllerParams(slow_range=self.threshold + 0.05)
        self.controller = LocalController(ctrl)
        self.safety = SafetyAgent(safety or SafetyParams(
            threshold=self.threshold, enabled=scenario.sif_enabled, delay=scenario.stop_delay))
        self.interceptor = CmdVelInterceptor(faulty=scenario.interceptor_faulty)
        self.mission = Mission(INSPECTION_POINTS, (hx, hy), dwell=sim.dwell)
        #: a generated shield in place of the SIF and the interceptor (sim.shielded), or None
        self.shield = shield
        #: the scenario's fault injections (sim.faults); each near_returns fault's generator
        self.faults: tuple[Fault, ...] = tuple(scenario.faults)
        self._fault_rngs = {k: fault_rng(self.seed, k) for k, f in enumerate(self.faults)
                            if f.kind == "near_returns"}

    # ------------------------------------------------------------------ helpers
    def _loc_estimate(self):
        """AMCL-like estimate of map -> odom: true pose plus noise, composed with odom."""
        s = self.base.state
        ex = s.x + self.loc_rng.normal(0.0, self.sim.loc_sigma_xy)
        ey = s.y + self.loc_rng.normal(0.0, self.sim.loc_sigma_xy)
        eyaw = s.yaw + self.loc_rng.normal(0.0, self.sim.loc_sigma_yaw)
        o = self.odom
        tyaw = wrap_angle(eyaw - o.yaw)
        c, sn = math.cos(tyaw), math.sin(tyaw)
        tx = ex - (c * o.x - sn * o.y)
        ty = ey - (sn * o.x + c * o.y)
        return tx, ty, tyaw

    def _pose_estimate(self):
        tx, ty, tyaw = self.map_odom
        o = self.odom
        c, sn = math.cos(tyaw), math.sin(tyaw)
        return tx + c * o.x - sn * o.y, ty + sn * o.x + c * o.y, wrap_angle(tyaw + o.yaw)

    # ------------------------------------------------------------------ run
    def run(self, rec: Recorder) -> RunResult:
        """Simulate until the run ends, writing every message to ``rec`` (not finished here)."""
        sim = self.sim
        st = _RunState(trace=Trace(), delay_ms=int(round(self.safety.p.delay * 1000)),
                       max_ms=int(round(sim.max_time * 1000)))
        self.cmd_filtered = (0.0, 0.0)
        self.cmd_filtered_ms = 0  # (its log time: the chassis' receive timeout)
        self.map_odom = self._loc_estimate()
        st.start_ms = int(round(sim.mission_start * 1000))
        st.start_ms += (50 - st.start_ms % 100) % 100  # first SRAS tick at or after mission_start
        sc = self.scenario
        if sc.dropout_start is not None:
            st.drop = (int(round(sc.dropout_start * 1000)),
                       int(round((sc.dropout_start + sc.dropout_duration) * 1000)))
        st.silent = ([st.drop] if st.drop else []) + [
            flt.window_ms for flt in self.faults if flt.kind == "silence"]
        if self.faults and hasattr(rec, "metadata"):  # (a live server has no such place)
            rec.metadata("fretc.sim.faults", {
                "scenario": sc.name, "seed": str(self.seed),
                "faults": json.dumps([flt.describe() for flt in self.faults])})
        # start-up: the map (latched) and the agent's initial decision
        f, m = rec.factory, self.omap
        rec.write("/map", _ns(0), f.occupancy_grid(_ns(0), m.resolution, m.width, m.height,
                                                   m.origin_x, m.origin_y, m.grid))
        if self.shield is None:
            self._publish_control(rec, st, 0, False)
        else:
            self.shield.start(f)
        t_ms = 0
        while True:
            t = t_ms / 1000.0
            s = self.base.state
            if t_ms > 0:  # 1. physics
                self._physics(st, t_ms, t, s)
            if self.faults:  # the Safety System's node going down or coming back
                self._restart(rec, st, t_ms)
            # 2. delayed decisions
            while st.pending and st.pending[0][0] <= t_ms:
                self._publish_control(rec, st, t_ms, st.pending.popleft()[1])
            while st.interceptor_pending and st.interceptor_pending[0][0] <= t_ms:
                self._intercept_control(rec, st, t_ms, st.interceptor_pending.popleft()[1])
            if t_ms % 50 == 0 or (st.contact is not None and st.contact[0] == t):
                self._sample_20hz(rec, st, t_ms, t, s)
            if t_ms % 100 == 0 and not any(a <= t_ms < b for a, b in st.silent):
                self._scan_10hz(rec, st, t_ms, t, s)
            if t_ms % 100 == 0 and self.shield is not None and not st.safety_down:
                self._shield_tick(rec, st, t_ms)
            if t_ms % 100 == 50:
                self._publish_cmd(rec, st, t_ms, *self._sras(rec, st, t_ms, t, s))
            if st.end_ms is not None and t_ms >= st.end_ms:
                break
            t_ms += STEP_MS

        duration = t_ms / 1000.0
        return RunResult(
            scenario=sc, seed=self.seed, threshold=self.threshold, duration=duration,
            counts=dict(rec.counts), outcome=st.outcome, reached=list(self.mission.reached),
            min_clearance=st.min_clear, contact=st.contact, sif_events=list(self.safety.events),
            trace=st.trace, world=self.world, goals=self.mission.goals,
            overrides=list(self.shield.overrides) if self.shield is not None else [],
            shield_ticks=self.shield.ticks if self.shield is not None else 0,
            shield_broken=list(self.shield.broken) if self.shield is not None else [])

    def _restart(self, rec: Recorder, st: _RunState, t_ms: int) -> None:
        """A ``safety_restart`` fault (:mod:`fretc.sim.faults`): at the first step in its
        window the Safety System's node goes down (the SIF agent's pending decisions are lost;
        the shield hears and publishes nothing); at the first step after it the node comes
        back in its initial state: the shield reset, or a fresh SIF agent publishing its
        start-up ``false``."""
        down = any(flt.kind == "safety_restart" and flt.active(t_ms) for flt in self.faults)
        if down == st.safety_down:
            return
        st.safety_down = down
        if down:
            st.pending.clear()
            return
        if self.shield is not None:
            self.shield.restart()
            return
        events = self.safety.events
        self.safety = SafetyAgent(self.safety.p)
        self.safety.events = events
        self._publish_control(rec, st, t_ms, False)

    def _publish_control(self, rec: Recorder, st: _RunState, t_ms: int, stop) -> None:
        rec.write("/gwendolen_control", _ns(t_ms), rec.factory.bool(stop))
        st.trace.control.append((t_ms / 1000.0, bool(stop)))
        delay_ms = int(round(self.scenario.interceptor_delay * 1000))
        if delay_ms > 0:  # the interceptor fault: it acts on the message late
            st.interceptor_pending.append((t_ms + delay_ms, stop))
        else:
            self._intercept_control(rec, st, t_ms, stop)

    def _intercept_control(self, rec: Recorder, st: _RunState, t_ms: int, stop) -> None:
        out = self.interceptor.on_control(stop)
        if out is not None:
            self._publish_filtered(rec, st, t_ms, *out)

    def _publish_filtered(self, rec: Recorder, st: _RunState, t_ms: int, v: float,
                          w: float) -> None:
        self.cmd_filtered = (v, w)
        self.cmd_filtered_ms = t_ms
        rec.write("/cmd_vel_filtered", _ns(t_ms), rec.factory.twist(v, w))
        st.trace.cmd_t.append(t_ms / 1000.0)
        st.trace.cmd_v.append(v)
        st.trace.cmd_w.append(w)

    def _publish_cmd(self, rec: Recorder, st: _RunState, t_ms: int, v: float,
                     w: float) -> None:
        for flt in self.faults:  # the controller's faults: its proposal's linear.x
            if flt.kind in CMD_VALUES and flt.active(t_ms):
                v = CMD_VALUES[flt.kind]
        msg = rec.factory.twist(v, w)
        rec.write("/cmd_vel", _ns(t_ms), msg)
        if self.shield is not None:  # the proposal: the shield decides at its next tick
            if not st.safety_down:
                self.shield.hear("/cmd_vel", msg, _ns(t_ms))
            return
        self._publish_filtered(rec, st, t_ms, *self.interceptor.on_cmd_vel(v, w))

    def _shield_tick(self, rec: Recorder, st: _RunState, t_ms: int) -> None:
        """The generated shield's tick (:mod:`fretc.sim.shielded`), at the scan's log time."""
        for topic, msg in self.shield.tick(t_ms / 1000.0, _ns(t_ms)):
            if topic == "/cmd_vel_filtered":
                self._publish_filtered(rec, st, t_ms, float(msg.linear.x),
                                       float(msg.angular.z))
            else:
                rec.write(topic, _ns(t_ms), msg)
                if topic == "/gwendolen_control" and (
                        not st.trace.control or st.trace.control[-1][1] != bool(msg.data)):
                    st.trace.control.append((t_ms / 1000.0, bool(msg.data)))

    def _physics(self, st: _RunState, t_ms: int, t: float, s) -> None:
        """1. The base executes the last ``/cmd_vel_filtered`` (rest once it is older than
        the chassis' receive timeout, :class:`fretc.sim.robot.ScoutMiniParams`); the contact
        check (a contact blocks the base and ends the run ``contact_linger`` s later)."""
        base = self.base
        if not st.blocked:
            cmd = self.cmd_filtered
            if t_ms - self.cmd_filtered_ms > int(round(base.p.cmd_timeout * 1000)):
                cmd = (0.0, 0.0)
            base.step(*cmd, STEP_MS / 1000.0)
        self.odom.update(s.v, s.w, STEP_MS / 1000.0)
        if st.contact is None:
            lb = self.world.clearance_lower_bound(s.x, s.y, t, base.p.circumradius)
            if lb < 0.02:
                c = self.world.clearance(s.x, s.y, s.yaw, t, base.p.half_length,
                                         base.p.half_width)
                if c <= 0.0:
                    st.contact = (t, s.x, s.y)
                    st.blocked = True
                    base.halt()
                    st.outcome = "contact"
                    st.end_ms = t_ms + int(round(self.sim.contact_linger * 1000))
                    st.end_ms += (100 - st.end_ms % 100) % 100

    def _sample_20hz(self, rec: Recorder, st: _RunState, t_ms: int, t: float, s) -> None:
        """3. Every 50 ms (and at a contact): odometry, tf, ground truth."""
        f, o, trace = rec.factory, self.odom, st.trace
        if t_ms % 50 == 0:
            rec.write("/odom", _ns(t_ms), f.odometry(
                _ns(t_ms), o.x, o.y, o.yaw, o.v, o.w, _POSE_COV, _TWIST_COV))
            rec.write("/tf", _ns(t_ms), f.tf([f.transform(
                _ns(t_ms), "odom", "base_link", o.x, o.y, o.yaw)]))
        clr = self.world.clearance(s.x, s.y, s.yaw, t, self.base.p.half_length,
                                   self.base.p.half_width)
        st.min_clear = min(st.min_clear, clr)
        rec.write("/ground_truth/pose", _ns(t_ms),
                  f.pose_stamped(_ns(t_ms), "map", s.x, s.y, s.yaw, "/ground_truth/pose"))
        clearance = f.float64(clr)
        rec.write("/ground_truth/clearance", _ns(t_ms), clearance)
        if self.shield is not None and not st.safety_down:  # (a shield whose assumptions
            # read the ground truth)
            self.shield.hear("/ground_truth/clearance", clearance, _ns(t_ms))
        trace.t.append(t)
        trace.x.append(s.x)
        trace.y.append(s.y)
        trace.yaw.append(s.yaw)
        trace.v.append(s.v)
        trace.clearance.append(clr)

    def _scan_10hz(self, rec: Recorder, st: _RunState, t_ms: int, t: float, s) -> None:
        """4. Every 100 ms: ``/scan``, ``/tf`` map -> odom; the SIF reads the scan and may
        decide (published now, or ``stop_delay`` later); with a generated shield the shield
        hears the scan and there is no SIF."""
        f, lid = rec.factory, self.lidar.p
        ranges = self.lidar.scan(self.world, s.x, s.y, s.yaw, t)
        stamp_ns = _ns(t_ms)
        faulty = [(k, flt) for k, flt in enumerate(self.faults)
                  if flt.kind in SCAN_KINDS and flt.active(t_ms)]
        if not faulty:
            st.last_good = ranges
        for k, flt in faulty:
            ranges, stamp_ns = self._scan_fault(st, k, flt, ranges, t_ms, stamp_ns)
        scan = f.laser_scan(stamp_ns, "base_link", lid.angle_min, lid.angle_max,
                            lid.angle_increment, lid.scan_time, lid.range_min, lid.range_max,
                            ranges)
        rec.write("/scan", _ns(t_ms), scan)
        if self.shield is not None and not st.safety_down:
            self.shield.hear("/scan", scan, _ns(t_ms))
        self.map_odom = self._loc_estimate()
        rec.write("/tf", _ns(t_ms), f.tf([f.transform(_ns(t_ms), "map", "odom",
                                                      *self.map_odom)]))
        st.last_min = min_valid_range(ranges, lid.range_min, lid.range_max)
        st.trace.scan_t.append(t)
        st.trace.scan_min.append(st.last_min)
        if self.shield is not None or st.safety_down:  # (the shield is the Safety System:
            # no SIF beside it; a SIF agent that is down reads nothing)
            return
        decision = self.safety.on_scan(t, st.last_min, self.odom.v, self.odom.w)
        if decision is not None:
            if st.delay_ms > 0:
                st.pending.append((t_ms + st.delay_ms, decision))
            else:
                self._publish_control(rec, st, t_ms, decision)

    def _scan_fault(self, st: _RunState, k: int, flt: Fault, ranges: np.ndarray, t_ms: int,
                    stamp_ns: int) -> tuple[np.ndarray, int]:
        """The ranges (float32 ``(n_beams,)``, m) and header stamp (ns) the LiDAR driver
        publishes under the ``k``-th fault ``flt`` (a kind of :data:`fretc.sim.faults.SCAN_KINDS`),
        from the measured ``ranges`` and the scan's own stamp (REP 117: NaN is an invalid
        measurement; beam angles ``angle_min + i * angle_increment``, REP 103)."""
        lid = self.lidar.p
        kind = flt.kind
        if kind == "stale_stamp":
            return ranges, st.stale.setdefault(k, stamp_ns)
        if kind == "frozen":
            if st.last_good is None:  # (no scan before the window: the first one is held)
                st.last_good = ranges
            return st.last_good.copy(), stamp_ns
        out = ranges.copy()
        if kind == "all_nan":
            out[:] = np.nan
        elif kind == "sector_nan":
            assert flt.sector is not None
            out[in_sector(lid.angle_min, lid.angle_increment, lid.n_beams, flt.sector)] = np.nan
        else:  # near_returns
            beams = (np.flatnonzero(in_sector(lid.angle_min, lid.angle_increment, lid.n_beams,
                                              flt.sector))
                     if flt.sector is not None else np.arange(lid.n_beams))
            if beams.size:
                pick = self._fault_rngs[k].choice(beams, min(flt.near_count, beams.size),
                                                  replace=False)
                out[pick] = np.float32(flt.near_range)
        return out, stamp_ns

    def _command(self, st: _RunState, t: float) -> tuple[float, float]:
        ex, ey, eyaw = self._pose_estimate()
        return self.controller.compute(ex, ey, eyaw, self.odom.v, self.odom.w, st.last_min, t)

    def _sras(self, rec: Recorder, st: _RunState, t_ms: int, t: float,
              s) -> tuple[float, float]:
        """5. Every 100 ms, 50 ms after the scan: the SRAS's mission step; returns the
        ``/cmd_vel`` (v, w) to publish."""
        v = w = 0.0
        mis = self.mission
        if st.end_ms is None and t_ms >= st.start_ms:
            if not st.goal_active and st.dwell_until is None and not mis.done:
                st.goal_active = self._send_goal(rec, t_ms)
            elif st.goal_active:
                ex, ey, eyaw = self._pose_estimate()
                if self.controller.goal_reached(ex, ey):
                    mis.reached.append((mis.index, t, s.x, s.y))
                    st.goal_active = False
                    st.dwell_until = t_ms + int(round(mis.dwell * 1000))
                elif self.controller.stuck(t) or t_ms >= st.max_ms:
                    mis.aborted = True
                    mis.abort_reason = ("no progress" if t_ms < st.max_ms else "time limit")
                    st.outcome = f"aborted: {mis.abort_reason}"
                    st.goal_active = False
                    st.end_ms = t_ms + int(round(self.sim.final_linger * 1000))
                else:
                    v, w = self.controller.compute(ex, ey, eyaw, self.odom.v, self.odom.w,
                                                   st.last_min, t)
            if st.dwell_until is not None and t_ms >= st.dwell_until:
                st.dwell_until = None
                if mis.index + 1 >= len(mis.goals):
                    mis.done = True
                    st.outcome = "completed"
                    st.end_ms = t_ms + int(round(self.sim.final_linger * 1000))
                else:
                    mis.index += 1
                    st.goal_active = self._send_goal(rec, t_ms)
                    if st.goal_active:
                        v, w = self._command(st, t)
        elif st.end_ms is not None and st.contact is not None and st.goal_active:
            # after a contact nobody stops the robot: the SRAS keeps commanding
            v, w = self._command(st, t)
        return v, w

    def _send_goal(self, rec: Recorder, t_ms: int) -> bool:
        gx, gy = self.mission.current
        ns = _ns(t_ms)
        rec.write("/goal", ns, rec.factory.pose_stamped(ns, "map", gx, gy, 0.0, "/goal"))
        self.controller.set_goal(self.planner.plan((gx, gy)), t_ms / 1000.0)
        return True


#: Odometry covariances (row-major 6x6, x y z roll pitch yaw): planar pose and twist; the
#: unused dimensions get a large variance, as ROS drivers for planar bases do.
_POSE_COV = np.diag([1e-3, 1e-3, 1e6, 1e6, 1e6, 3e-3]).ravel()
_TWIST_COV = np.diag([4e-4, 1e-6, 1e6, 1e6, 1e6, 2e-3]).ravel()
