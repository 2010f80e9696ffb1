"""How a test trace drives the simulated Safe-ROS robot (``python -m fretc.sim drive``): which
of its variables can drive the robot (:func:`classify`, by the topics their bindings read) and
the range each trace tick's LiDAR scan reads (:func:`scan_plan`, by the same inversion of the
bindings as ``fretc testgen --bindings``, :mod:`fretc.testing.mcap_log`). The simulation that
applies the plan is :mod:`fretc.sim.drive`'s.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fretc.signals.bindings.spec import Bindings, make_bindings
from fretc.testing.mcap_log import EPOCH_NS, plan_messages, write_mcap

__all__ = ["DRIVEN_TOPICS", "SCAN_MS", "DriveError", "Classified", "classify", "scan_plan"]

#: topics the driver writes from a trace
DRIVEN_TOPICS = ("/scan",)
SCAN_MS = 100
_CLOCK = "fretc_drive_clock"


class DriveError(ValueError):
    """A trace the simulator cannot be driven by (the message says why)."""


@dataclass
class Classified:
    """The trace's variables by role (:func:`classify`): ``driven`` and ``system`` names,
    ``not_drivable`` name -> why."""

    driven: list[str]
    system: list[str]
    not_drivable: dict[str, str]


def classify(names: list[str], bindings: Bindings) -> Classified:
    """The role of each FRET variable of ``names`` under ``bindings`` (module docstring).

    Raises:
        DriveError: a variable without a binding."""
    out = Classified([], [], {})
    for n in names:
        b = bindings.variables.get(n)
        if b is None:
            raise DriveError(f"{n}: no binding in {bindings.source}")
        topics = set(b.topics)
        if topics and topics <= set(DRIVEN_TOPICS):
            out.driven.append(n)
        elif any(t.startswith("/ground_truth/") for t in topics):
            out.not_drivable[n] = ("the simulated world's ground truth "
                                   f"({', '.join(sorted(topics))}): it follows from where the "
                                   "robot drives")
        elif topics & set(DRIVEN_TOPICS):
            out.not_drivable[n] = (f"reads {', '.join(sorted(topics))}: a driven topic with "
                                   "the robot's own")
        else:
            out.system.append(n)
    return out


def scan_plan(rows: list[dict[str, Any]], bindings: Bindings, driven: list[str]
              ) -> dict[int, float]:
    """Trace tick (< 0: before the trace) -> the range every beam of that tick's scan reads;
    ticks absent have no scan. Ticks before the first planned one are not in the map.

    Raises:
        DriveError: the tick is not 100 ms, or the driven values cannot be written."""
    if bindings.tick.period_ns != SCAN_MS * 1_000_000:
        raise DriveError(f"{bindings.source}: the tick must be the LiDAR's 100 ms period")
    if not driven:
        return {k: 5.0 for k in range(len(rows))}
    driven_rows = [{n: r[n] for n in driven} for r in rows]
    # checked as testgen's logs are, read back; with a clock topic at every tick, so that the
    # log spans the trace even where /scan is silent at its start or end
    clock = make_bindings({_CLOCK: "/fretc_drive/clock.data"}, bindings.tick).variables
    check = replace(bindings, variables={**bindings.variables, **clock})
    with tempfile.TemporaryDirectory() as tmp:
        _, adjusted, why = write_mcap([{**r, _CLOCK: True} for r in driven_rows], check,
                                      Path(tmp) / "inputs.mcap")
    if why is not None:
        raise DriveError(f"the trace's inputs cannot be written as /scan messages: {why}")
    if adjusted:
        raise DriveError(f"the trace's inputs {', '.join(adjusted)} cannot be given together "
                         "by /scan messages")
    msgs, _ = plan_messages(driven_rows, bindings)
    period = bindings.tick.period_ns
    out = {}
    for t, topic, obj in msgs:
        if topic == "/scan":
            out[(t - EPOCH_NS) // period] = float(obj.get("ranges", [5.0])[0])
    return out
