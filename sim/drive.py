"""The simulated Safe-ROS robot driven by a test trace (``python -m fretc.sim drive TRACE LOG
--bindings FILE``): the trace's *input* variables drive what the robot senses, the robot's
own SIF (:class:`fretc.sim.safety.SafetyAgent`), ``cmd_vel_interceptor`` and navigation
produce everything else, and the run is recorded as the simulator records (ROS 2 CDR MCAP,
:mod:`fretc.sim.recording`). It is the command ``FRETC_RUN_TRACE`` names for the pytest file
``fretc testgen --pytest`` writes, and the ``--command`` of ``fretc testrun``.

Design notes: ARCHITECTURE.md, `sim/drive.py`."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from fretc.common.outputs import open_output, output_folder
from fretc.signals.bindings.spec import Bindings
from fretc.testing.drive_plan import (DRIVEN_TOPICS, SCAN_MS, Classified, DriveError, classify,
                                      scan_plan)
from fretc.sim.recording import McapRecorder
from fretc.sim.scenarios import Scenario, get_scenario
from fretc.sim.simulation import RunResult, SimParams, Simulation

__all__ = ["LEAD_IN_S", "LEAD_OUT_S", "DriveError", "Classified", "TraceDrivenSimulation", "drive"]

#: seconds simulated before the trace's first tick
LEAD_IN_S = 3.0
#: seconds simulated after the trace's last tick, its inputs held
LEAD_OUT_S = 2.0


class _TraceLidar:
    """A LiDAR whose every beam reads ``value`` (set per scan by the simulation)."""

    def __init__(self, real):
        self.p = real.p
        self.value = 5.0

    def scan(self, world, x, y, yaw, t):
        """``n_beams`` ranges, all :attr:`value` (float32, as the real LiDAR's)."""
        return np.full(self.p.n_beams, self.value, dtype=np.float32)


class TraceDrivenSimulation(Simulation):
    """A :class:`Simulation` whose scans come from ``plan`` (:func:`scan_plan`): tick ``k``
    at sim time ``lead_ms + k * 100`` ms; the trace's last tick is ``last``, after which the
    run goes on ``out_ms`` with its inputs held."""

    def __init__(self, scenario: Scenario, plan: dict[int, float], last: int, lead_ms: int,
                 seed: int = 1, out_ms: int = 0):
        super().__init__(scenario, seed=seed, sim=SimParams(max_time=1e6, final_linger=0.0))
        self.plan = plan
        self.last = last
        self.end = last + out_ms // SCAN_MS
        self.lead_ms = lead_ms
        self.first = min(plan) if plan else 0
        self.trace_lidar = _TraceLidar(self.lidar)
        self.lidar = self.trace_lidar  # type: ignore[assignment]  # (a Lidar's interface)
        #: the last trace tick whose scan time the run reached (-1: none)
        self.reached = -1

    def _scan_10hz(self, rec, st, t_ms, t, s) -> None:
        k = (t_ms - self.lead_ms) // SCAN_MS
        if k >= self.end:
            st.end_ms = t_ms
        k = min(k, self.last)  # the lead-out: the last tick's inputs held
        self.reached = max(self.reached, k)
        if k < 0:  # the lead-in: as the first planned scan (silent after one before 0)
            p = self.first
            value = self.plan.get(p) if p >= 0 or k <= p else None
        else:
            value = self.plan.get(k)
        if value is None:
            return  # silent: no scan, the SIF hears nothing
        self.trace_lidar.value = value
        super()._scan_10hz(rec, st, t_ms, t, s)


def drive(rows: list[dict], bindings: Bindings, output: str | Path, *,
          scenario: str = "nominal", seed: int = 1, lead_in: float = LEAD_IN_S,
          lead_out: float = LEAD_OUT_S) -> tuple[Classified, RunResult]:
    """Drive the simulator with the trace ``rows`` (one mapping FRET variable -> value per
    tick) under ``bindings`` and record the run to ``output`` (MCAP, ROS 2).

    Raises:
        DriveError: the trace cannot drive the simulator (module docstring): no tick, no
            variable the driver drives, ``lead_in``/``lead_out`` not finite or negative; or
            the run ended (the mission over) before the trace's last tick was applied (the
            log is written, but it is not the trace's run).
        KeyError: an unknown scenario. OSError: ``output`` cannot be written."""
    for name, value in (("lead-in", lead_in), ("lead-out", lead_out)):
        if not math.isfinite(value) or value < 0:
            raise DriveError(f"--{name} {value!r}: seconds, finite and not negative")
    if not rows:
        raise DriveError("the trace has no ticks")
    roles = classify(list(rows[0]), bindings)
    if not roles.driven:
        raise DriveError("no variable of the trace is one the driver drives (the topics "
                         f"{', '.join(DRIVEN_TOPICS)}: in {bindings.source}, "
                         f"{', '.join(_drivable(bindings)) or 'none'}): the run would be the "
                         "robot alone, not the trace's")
    plan = scan_plan(rows, bindings, roles.driven)
    lead_ms = max(int(round(lead_in * 1000)), -min(plan) * SCAN_MS if plan else 0)
    lead_ms -= lead_ms % SCAN_MS
    sc = replace(get_scenario(scenario), max_time=None)
    sim = TraceDrivenSimulation(sc, plan, len(rows) - 1, lead_ms, seed,
                                int(round(lead_out * 1000)))
    output_folder(Path(output).parent)
    with open_output(output, "wb") as f:  # (never through a link planted there)
        rec = McapRecorder(f)
        result = sim.run(rec)
        rec.finish()
    if sim.reached < len(rows) - 1:
        Path(output).unlink(missing_ok=True)  # not the trace's run: never audited as one
        nxt = sim.reached + 1
        raise DriveError(f"the run ended at {result.duration:.1f} s of simulated time "
                         f"({result.outcome or 'its end'}) before the trace's tick {nxt} of "
                         f"{len(rows)} (due at {(lead_ms + nxt * SCAN_MS) / 1000:.1f} s): the "
                         "trace was not applied whole (a shorter --lead-in?)")
    return roles, result


def _drivable(bindings: Bindings) -> list[str]:
    """The variables of ``bindings`` the driver can drive (:func:`classify`'s ``driven``)."""
    return classify(list(bindings.variables), bindings).driven
