"""A lightweight, deterministic simulation of the Safe-ROS system (Benjumea, Farrell, Dennis,
FMAS 2025) that records MCAP logs for fretc to audit.

An AgileX Scout Mini inspects Safe-ROS's reactor room (the upstream occupancy map, shipped in
``sim/data`` under BSD-3-Clause, see ``sim/data/NOTICE``):

Design notes: ARCHITECTURE.md, `sim/__init__.py`."""

from fretc.sim.run import record
from fretc.sim.scenarios import SCENARIOS, Scenario, get_scenario

__all__ = ["record", "SCENARIOS", "Scenario", "get_scenario"]
