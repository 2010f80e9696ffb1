"""The robot: an AgileX Scout Mini as a velocity-controlled differential (skid-steer) base, its
wheel odometry, and a 2-D LiDAR like Safe-ROS's Velodyne projected to a ``LaserScan``.

Frames follow REP 105 (``map`` -> ``odom`` -> ``base_link``) and REP 103 (x forward, y left,
yaw counter-clockwise, SI units). The LiDAR sits at the ``base_link`` origin, so its scan is
published in ``base_link``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fretc.sim.world import World


def wrap_angle(a: float) -> float:
    """``a`` (rad) wrapped to ``[-pi, pi)``."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class ScoutMiniParams:
    """Geometry and limits of the Scout Mini.

    Footprint 0.42 m x 0.33 m (Safe-ROS ``costmap_common_params.yaml``:
    ``[[-0.21, -0.165], [-0.21, 0.165], [0.21, 0.165], [0.21, -0.165]]``); the base follows
    the commanded twist with the Safe-ROS DWA limits |v| <= 0.5 m/s, |w| <= 0.5 rad/s and
    accelerations of 0.5 m/s^2 and 0.5 rad/s^2. ``cmd_timeout`` s: the chassis drops a speed
    command older than its receive timeout and brakes to rest (the AgileX Scout Mini user
    manual, CAN protocol: commands every 20 ms, dropped after 500 ms), so a Safety System
    that goes silent (its node's restart) leaves the base at rest, not on its last command.
    """

    # dataclass fields, same shape as LidarParams' and sim.simulation.SimParams' (kept: parameter
    # defaults, no logic)
    half_length: float = 0.21
    half_width: float = 0.165
    max_v: float = 0.5
    max_w: float = 0.5
    acc_v: float = 0.5
    acc_w: float = 0.5
    cmd_timeout: float = 0.5

    @property
    def circumradius(self) -> float:
        """Distance (m) from ``base_link`` to a footprint corner."""
        return math.hypot(self.half_length, self.half_width)


@dataclass
class BaseState:
    """Ground-truth state: pose ``(x, y, yaw)`` in ``map`` (m, rad) and body twist ``v`` (m/s,
    along x of ``base_link``), ``w`` (rad/s, about z)."""

    x: float
    y: float
    yaw: float
    v: float = 0.0
    w: float = 0.0


class ScoutMini:
    """Velocity-controlled base with exact ground truth.

    :meth:`step` moves the base for ``dt`` s: the body twist approaches the commanded one
    (from ``/cmd_vel_filtered``) with the acceleration limits, saturated at the speed limits,
    and the pose follows the unicycle model exactly (constant twist over the step: arc of a
    circle).
    """

    def __init__(self, params: ScoutMiniParams, x: float, y: float, yaw: float):
        self.p = params
        self.state = BaseState(x, y, yaw)

    def step(self, cmd_v: float, cmd_w: float, dt: float) -> None:
        """Advance by ``dt`` s towards the commanded twist ``cmd_v`` m/s, ``cmd_w`` rad/s.

        A command beyond the speed limits (``+inf``, ``1e6``: the controller's faults of
        :mod:`fretc.sim.faults`) saturates at them; a NaN component, which no limit
        saturates, is ignored: the base keeps its current speed in it (a motor controller
        rejecting a malformed set-point keeps its last one)."""
        p, s = self.p, self.state
        if cmd_v != cmd_v:  # NaN
            cmd_v = s.v
        if cmd_w != cmd_w:
            cmd_w = s.w
        cmd_v = min(max(cmd_v, -p.max_v), p.max_v)
        cmd_w = min(max(cmd_w, -p.max_w), p.max_w)
        s.v += min(max(cmd_v - s.v, -p.acc_v * dt), p.acc_v * dt)
        s.w += min(max(cmd_w - s.w, -p.acc_w * dt), p.acc_w * dt)
        if abs(s.w) < 1e-9:
            s.x += s.v * dt * math.cos(s.yaw)
            s.y += s.v * dt * math.sin(s.yaw)
        else:
            r = s.v / s.w
            yaw1 = s.yaw + s.w * dt
            s.x += r * (math.sin(yaw1) - math.sin(s.yaw))
            s.y -= r * (math.cos(yaw1) - math.cos(s.yaw))
        s.yaw = wrap_angle(s.yaw + s.w * dt)

    def halt(self) -> None:
        """Zero the body twist at once (the base is blocked by a contact)."""
        self.state.v = 0.0
        self.state.w = 0.0


@dataclass(frozen=True)
class OdometryNoise:
    """Wheel-odometry error model: each odometry sample measures ``v*(1+e_v)`` and
    ``w*(1+k_w+e_w)`` with ``e_v ~ N(0, sigma_v)``, ``e_w ~ N(0, sigma_w)`` (relative errors)
    and a systematic skid-steer yaw-rate scale error ``k_w``. A base at rest measures exactly
    zero (encoders do not move)."""

    sigma_v: float = 0.02
    sigma_w: float = 0.04
    k_w: float = 0.03


class WheelOdometry:
    """Integrates the measured twist into the ``odom`` frame pose (starts at the origin,
    REP 105: continuous, drifting)."""

    def __init__(self, noise: OdometryNoise, rng: np.random.Generator):
        self.noise = noise
        self.rng = rng
        self.x = self.y = self.yaw = 0.0
        self.v = self.w = 0.0

    def update(self, v_true: float, w_true: float, dt: float) -> None:
        """Measure the true twist (m/s, rad/s) and integrate it over ``dt`` s (midpoint rule).
        Draws two normal variates per call (keeps the random stream aligned)."""
        e = self.rng.normal(0.0, 1.0, 2)
        self.v = v_true * (1.0 + self.noise.sigma_v * e[0])
        self.w = w_true * (1.0 + self.noise.k_w + self.noise.sigma_w * e[1])
        mid = self.yaw + 0.5 * self.w * dt
        self.x += self.v * dt * math.cos(mid)
        self.y += self.v * dt * math.sin(mid)
        self.yaw = wrap_angle(self.yaw + self.w * dt)


@dataclass(frozen=True)
class LidarParams:
    """2-D LiDAR like Safe-ROS's Velodyne projected by ``pointcloud_to_laserscan``: 360 deg
    with ``angle_increment = pi/360`` (0.0087 rad, that node's default), ``angle_min = -pi``,
    range 0.1-30 m, 10 Hz, Gaussian range noise ``sigma`` m, ranges reported in steps of
    ``resolution`` m (a VLP-16 reports distances in 2 mm units) and a per-beam probability
    ``p_invalid`` of an invalid return (published as NaN, REP 117)."""

    # dataclass fields, same shape as ScoutMiniParams' (kept: parameter defaults, no logic)
    n_beams: int = 720
    angle_min: float = -math.pi
    angle_increment: float = math.pi / 360.0
    range_min: float = 0.1
    range_max: float = 30.0
    sigma: float = 0.012
    resolution: float = 0.002
    p_invalid: float = 0.001
    scan_time: float = 0.1

    @property
    def angle_max(self) -> float:
        """Angle (rad) of the last beam: ``angle_min + (n_beams - 1) * angle_increment``."""
        return self.angle_min + (self.n_beams - 1) * self.angle_increment

    @property
    def angles(self) -> np.ndarray:
        """Beam angles (rad) in ``base_link``, float64 ``(n_beams,)``."""
        return self.angle_min + np.arange(self.n_beams) * self.angle_increment


class Lidar:
    """Ray-casts the physical world (map and unmapped objects) and encodes the result as
    ``sensor_msgs/LaserScan.ranges`` per REP 117: ``+inf`` when nothing is within
    ``range_max``, ``-inf`` for a return closer than ``range_min``, ``NaN`` for an invalid
    measurement."""

    def __init__(self, params: LidarParams, rng: np.random.Generator):
        self.p = params
        self.rng = rng

    def scan(self, world: World, x: float, y: float, yaw: float, t: float) -> np.ndarray:
        """One scan from pose ``(x, y, yaw)`` (m, rad, ``map`` frame) at sim time ``t`` s:
        float32 ``(n_beams,)`` ranges in m. Draws ``2 * n_beams`` variates per call."""
        p = self.p
        true = world.raycast(x, y, yaw + p.angles, t, p.range_max)
        noise = self.rng.normal(0.0, p.sigma, p.n_beams)
        invalid = self.rng.random(p.n_beams) < p.p_invalid
        with np.errstate(invalid="ignore"):
            r = true + noise
            if p.resolution > 0:
                r = np.round(r / p.resolution) * p.resolution
        r[np.isinf(true)] = np.inf
        r[np.isfinite(r) & (r > p.range_max)] = np.inf
        r[np.isfinite(r) & (r < p.range_min)] = -np.inf
        r[invalid] = np.nan
        return r.astype(np.float32)


def min_valid_range(ranges: np.ndarray, range_min: float, range_max: float) -> float:
    """The smallest *valid* range of a LaserScan (m): finite values within
    ``[range_min, range_max]``; ``-inf`` (REP 117: an object closer than ``range_min``) counts
    as ``range_min`` (the conservative reading); ``+inf`` and ``NaN`` are ignored. Returns
    ``inf`` if no value is valid."""
    r = np.asarray(ranges, dtype=np.float64)
    vals = r[np.isfinite(r) & (r >= range_min) & (r <= range_max)]
    m = float(vals.min()) if vals.size else math.inf
    if np.any(np.isneginf(r)):
        m = min(m, range_min)
    return m
