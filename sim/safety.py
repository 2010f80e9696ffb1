"""The Safety System: the Gwendolen agent's SIF and the ``cmd_vel_interceptor``.

SIF (Safe-ROS, FMAS 2025; property ``[] (B(agilex_agent,too_close) -> <> B(agilex_agent,
stopped))``): on every ``/scan`` the agent computes the minimum *valid* range (REP 117) and
publishes ``true`` on ``/gwendolen_control`` below ``threshold`` (0.9 m), ``false`` once clear,
on changes only; a state machine (``ARMED``, ``STOPPED``, ``MONITORED``: our design of the
recovery, which the paper leaves open) releases a stop for a slow monitored move above
``release_floor``. The interceptor (Safe-ROS ``cmd_vel_interceptor_node.py``) forwards each
``/cmd_vel`` to ``/cmd_vel_filtered``, or a zero Twist while a stop is requested. Fault
injections: ``enabled=False``, ``delay``, ``faulty=True``. The states, the release floor's
clearance and the faults in full: ARCHITECTURE.md ("The simulator's Safety System").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ARMED, STOPPED, MONITORED = "ARMED", "STOPPED", "MONITORED"


@dataclass(frozen=True)
class SafetyParams:
    """SIF settings (see the module docstring); distances in m, times in s, speeds in m/s
    and rad/s."""

    threshold: float = 0.9
    hysteresis: float = 0.05
    hold: float = 1.0
    stopped_eps: float = 0.01
    margin: float = 0.05
    release_floor: float = 0.45
    slow_speed: float = 0.1
    speed_tolerance: float = 0.02
    enabled: bool = True
    delay: float = 0.0


@dataclass
class SifEvent:
    """One decision of the agent: sim time ``t`` s of the decision, the published value,
    the state entered, the ``min_range`` m it was based on and why."""

    t: float
    stop: bool
    state: str
    min_range: float
    reason: str


class SafetyAgent:
    """The Gwendolen agent's SIF with the monitored-release recovery."""

    def __init__(self, params: SafetyParams = SafetyParams()):
        self.p = params
        self.state = ARMED
        self.release_range = math.inf
        self.was_clear = False
        self.rest_since: float | None = None
        self.events: list[SifEvent] = []

    @property
    def stop_requested(self) -> bool:
        """The agent's current decision (before any publication delay)."""
        return self.state == STOPPED

    def on_scan(self, t: float, min_range: float, v_odom: float, w_odom: float,
                ) -> bool | None:
        """Process one scan at sim time ``t`` s with its minimum valid range (m) and the
        latest odometry twist; returns the Bool to publish, or ``None``."""
        p = self.p
        if not p.enabled:
            return None
        at_rest = abs(v_odom) < p.stopped_eps and abs(w_odom) < p.stopped_eps
        clear = min_range >= p.threshold + p.hysteresis
        if self.state == ARMED:
            if min_range < p.threshold:
                return self._go(t, STOPPED, min_range, "too close")
        elif self.state == STOPPED:
            if clear:
                return self._go(t, ARMED, min_range, "clear")
            if at_rest:
                if self.rest_since is None:
                    self.rest_since = t
            else:
                self.rest_since = None
            if (self.rest_since is not None and t - self.rest_since >= p.hold - 1e-9
                    and min_range >= p.release_floor):
                self.release_range = min_range
                self.was_clear = min_range >= p.threshold
                return self._go(t, MONITORED, min_range, "monitored release")
        else:  # MONITORED
            if clear:
                self.state = ARMED
                self.events.append(SifEvent(t, False, ARMED, min_range, "re-armed"))
                return None
            if min_range >= p.threshold:
                self.was_clear = True
            if min_range < self.release_range - p.margin:
                return self._go(t, STOPPED, min_range, "approached during release")
            if self.was_clear and min_range < p.threshold:
                return self._go(t, STOPPED, min_range, "too close again")
            if abs(v_odom) > p.slow_speed + p.speed_tolerance:
                return self._go(t, STOPPED, min_range, "too fast during release")
        return None

    def _go(self, t, state, min_range, reason) -> bool:
        self.state = state
        self.rest_since = None
        stop = state == STOPPED
        self.events.append(SifEvent(t, stop, state, min_range, reason))
        return stop


class CmdVelInterceptor:
    """Safe-ROS's ``cmd_vel_interceptor`` (see the module docstring)."""

    def __init__(self, faulty: bool = False):
        self.faulty = faulty
        self.stop_requested = False

    def on_control(self, stop: bool) -> tuple[float, float] | None:
        """A ``/gwendolen_control`` message arrived; returns the Twist ``(v, w)`` to publish
        on ``/cmd_vel_filtered`` at once (a zero Twist on a stop request), or ``None``."""
        self.stop_requested = bool(stop)
        if stop and not self.faulty:
            return (0.0, 0.0)
        return None

    def on_cmd_vel(self, v: float, w: float) -> tuple[float, float]:
        """A ``/cmd_vel`` arrived; returns the Twist to forward on ``/cmd_vel_filtered``."""
        if self.stop_requested and not self.faulty:
            return (0.0, 0.0)
        return (v, w)
