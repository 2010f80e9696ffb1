"""A lightweight, deterministic simulation of the Safe-ROS system (Benjumea, Farrell, Dennis,
FMAS 2025) that records MCAP logs for fretc to audit.

An AgileX Scout Mini inspects Safe-ROS's reactor room (the upstream occupancy map, shipped in
``sim/data`` under BSD-3-Clause, see ``sim/data/NOTICE``):

* :mod:`fretc.sim.world` — the static map (``/map``), the physical room with unmapped and moving
  objects, exact LiDAR ray casting and ground-truth footprint clearance;
* :mod:`fretc.sim.robot` — the velocity-controlled base, wheel odometry with noise, the 2-D LiDAR
  (REP 117 encoding of out-of-range returns);
* :mod:`fretc.sim.navigation` — the SRAS: global planner on the inflated static map, local
  controller publishing ``/cmd_vel`` at 10 Hz, the inspection mission;
* :mod:`fretc.sim.safety` — the Safety System: the Gwendolen agent's SIF (with the monitored-release
  recovery that lets the nominal mission continue past a stop) and the ``cmd_vel_interceptor``;
* :mod:`fretc.sim.scenarios` — nominal, unmapped_obstacles, dynamic_obstacle, sif_disabled,
  interceptor_fault, stop_delay, lidar_dropout;
* :mod:`fretc.sim.faults` — faults injected into any scenario from any start for any duration:
  a silent, invalid (all or a sector NaN), frozen or stale-stamped LiDAR, spurious near
  returns, the controller's NaN/+inf/huge ``/cmd_vel``, the Safety System's restart;
* :mod:`fretc.sim.simulation` — the fixed-step sim clock and the order of events;
* :mod:`fretc.sim.recording` — ROS 1/ROS 2 messages (``rosbags``) written with ``mcap``;
* :mod:`fretc.sim.logs` — reading runs back and a reference evaluation of requirements R1-R6;
* :mod:`fretc.sim.plot` — a PNG of a run.

Command line: ``python -m fretc.sim record --scenario nominal --seed 1 -o traces/nominal.mcap
[--ros1] [--png traces/nominal.png] [--threshold 0.9] [--stop-delay 2.0]``
``[--fault KIND --fault-start S --fault-duration S [--fault-sector LO:HI]]...``.
"""

from fretc.sim.run import record
from fretc.sim.scenarios import SCENARIOS, Scenario, get_scenario

__all__ = ["record", "SCENARIOS", "Scenario", "get_scenario"]
