"""The recorded scenarios. Each is a world (unmapped obstacles) plus fault injections.

Design notes: ARCHITECTURE.md, `sim/scenarios.py`."""

from __future__ import annotations

from dataclasses import dataclass, replace

from fretc.sim.faults import Fault
from fretc.sim.world import Barrel, MovingObstacle, RemovedObject

#: The mapped drum at (4.80, -3.55), 0.30 m across (measured on the map), and its twin.
DRUM_RADIUS = 0.15
MAPPED_DRUM_A = (4.80, -3.55)
MAPPED_DRUM_B = (4.80, -6.35)

_MOVED = (RemovedObject(*MAPPED_DRUM_A, 0.25, "drum A (moved)"),
          RemovedObject(*MAPPED_DRUM_B, 0.25, "drum B (moved)"))
_DRUMS = (Barrel(1.25, -0.60, DRUM_RADIUS, "drum A"),
          Barrel(-2.30, -2.20, DRUM_RADIUS, "drum B"))


@dataclass(frozen=True)
class Scenario:
    """A world and its fault injections.

    ``barrels``/``movers``/``removed``: unmapped objects (see :mod:`fretc.sim.world`);
    ``sif_enabled``: the SIF runs; ``interceptor_faulty``: the interceptor ignores stops;
    ``stop_delay`` s: delay of every ``/gwendolen_control`` decision; ``dropout_start`` /
    ``dropout_duration`` s: no scans in ``[start, start + duration)`` (sim time from the start
    of the run); ``home``: start and final pose ``(x, y, yaw)`` in m, rad;
    ``interceptor_delay`` s: the interceptor acts on each ``/gwendolen_control`` message that
    long after it arrives (until then it keeps forwarding ``/cmd_vel`` as before);
    ``lidar_sigma`` m: the LiDAR's range noise (None: :class:`fretc.sim.robot.LidarParams`'
    default); ``max_time`` s: the mission's time limit (None: :class:`fretc.sim.simulation.SimParams`'
    default). The defaults leave the shipped scenarios as recorded.

    ``faults``: further fault injections, each from its start for its duration
    (:class:`fretc.sim.faults.Fault`: a silent, invalid, frozen or stale LiDAR, spurious near
    returns, the controller's non-finite or huge proposals, the Safety System's restart);
    a scenario with faults writes them into its recording's metadata (``fretc.sim.faults``).
    A dropout (``dropout_start``) is the ``silence`` fault, kept as its own fields so that
    the shipped ``lidar_dropout`` recording stays as recorded.
    """

    name: str
    description: str
    barrels: tuple[Barrel, ...] = ()
    movers: tuple[MovingObstacle, ...] = ()
    removed: tuple[RemovedObject, ...] = ()
    sif_enabled: bool = True
    interceptor_faulty: bool = False
    stop_delay: float = 0.0
    dropout_start: float | None = None
    dropout_duration: float = 0.0
    home: tuple[float, float, float] = (-1.2, -0.8, 0.0)
    interceptor_delay: float = 0.0
    lidar_sigma: float | None = None
    max_time: float | None = None
    faults: tuple[Fault, ...] = ()


SCENARIOS: dict[str, Scenario] = {s.name: s for s in (
    Scenario("nominal", "The inspection mission in the mapped reactor room."),
    Scenario("unmapped_obstacles",
             "Drum A moved from its mapped place onto the route between points 1 and 2; "
             "drum B moved off the route.",
             barrels=_DRUMS, removed=_MOVED),
    Scenario("dynamic_obstacle",
             "A person crosses the route between points 1 and 2.",
             movers=(MovingObstacle(((1.6, 0.6), (1.6, -2.25), (-1.5, -2.25)), 0.5, 0.25,
                                    6.8, "person"),)),
    Scenario("sif_disabled",
             "The unmapped_obstacles world with the SIF switched off.",
             barrels=_DRUMS, removed=_MOVED, sif_enabled=False),
    Scenario("interceptor_fault",
             "The interceptor forwards /cmd_vel even while stop is requested.",
             interceptor_faulty=True),
    Scenario("stop_delay",
             "Every /gwendolen_control decision is published late.",
             stop_delay=2.0),
    Scenario("lidar_dropout",
             "No /scan for 3 s while the robot heads for the gap near point 3; the SIF has "
             "no fail-safe for stale scans.",
             dropout_start=27.0, dropout_duration=3.0),
)}


def get_scenario(name: str, stop_delay: float | None = None) -> Scenario:
    """The scenario called ``name``; ``stop_delay`` (s) overrides the delay of
    ``stop_delay``-type injections (it applies to the ``stop_delay`` scenario only).

    Raises ``KeyError`` (listing the known names) for an unknown scenario and ``ValueError``
    for a negative delay."""
    if name not in SCENARIOS:
        raise KeyError(f"unknown scenario {name!r}; known: {', '.join(SCENARIOS)}")
    sc = SCENARIOS[name]
    if stop_delay is not None:
        if stop_delay < 0:
            raise ValueError("stop_delay must be >= 0")
        if name == "stop_delay":
            sc = replace(sc, stop_delay=float(stop_delay))
    return sc
