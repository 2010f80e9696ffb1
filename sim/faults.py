"""The simulator's fault model: sensor, controller and Safety System faults injected from any
start time for any duration, in any scenario (:attr:`fretc.sim.scenarios.Scenario.faults`,
``python -m fretc.sim record --fault KIND --fault-start S --fault-duration S``, the
``fault_*`` parameters of a space, ``bench/shield_scenarios.py --fault``).

A fault is active at the sim times ``t`` with ``start <= t < start + duration`` (s from the
start of the run, on the simulator's 1 ms grid); outside every window the run is the run
without the fault, message for message. Kinds: ``silence``, ``all_nan``, ``sector_nan``,
``frozen``, ``stale_stamp``, ``near_returns``, ``cmd_nan``, ``cmd_inf``, ``cmd_huge``,
``safety_restart``; what each shows in the recorded messages, and how the run stays
deterministic (same seed, same faults: byte-identical MCAP): ARCHITECTURE.md ("The
simulator's faults").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["FAULT_KINDS", "SCAN_KINDS", "CMD_KINDS", "Fault", "parse_sector", "CMD_VALUES",
           "in_sector"]

#: the fault kinds, in the order of their index (a space's ``fault_kind`` parameter)
FAULT_KINDS: tuple[str, ...] = ("silence", "all_nan", "sector_nan", "frozen", "stale_stamp",
                                "near_returns", "cmd_nan", "cmd_inf", "cmd_huge",
                                "safety_restart")
#: the kinds that change the published ``/scan`` messages (silence drops them)
SCAN_KINDS = ("all_nan", "sector_nan", "frozen", "stale_stamp", "near_returns")
#: the controller's ``/cmd_vel`` faults and the ``linear.x`` (m/s) each proposes
CMD_VALUES: dict[str, float] = {"cmd_nan": math.nan, "cmd_inf": math.inf, "cmd_huge": 1e6}
CMD_KINDS = tuple(CMD_VALUES)
#: the kinds that read ``sector``
SECTOR_KINDS = ("sector_nan", "near_returns")


@dataclass(frozen=True)
class Fault:
    """One fault injection (module docstring).

    ``kind`` in :data:`FAULT_KINDS`; ``start`` s of sim time from the start of the run,
    ``duration`` s (the window ``[start, start + duration)``); ``sector`` ``(low, high)`` in
    degrees (REP 103: counter-clockwise from straight ahead, each in ``[-180, 180]``; ``low >
    high`` wraps through 180, so ``(170, -170)`` is the 20 degrees behind) for
    ``sector_nan`` (required) and ``near_returns`` (optional: the whole scan); ``near_range``
    m and ``near_count`` beams of ``near_returns``.

    Raises ``ValueError`` for an unknown kind, a negative or non-finite start or duration,
    a sector out of ``[-180, 180]``, a ``sector_nan`` without a sector, a ``near_range``
    that is not a finite positive number or a ``near_count`` below 1."""

    kind: str
    start: float
    duration: float
    sector: tuple[float, float] | None = None
    near_range: float = 0.2
    near_count: int = 3

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise ValueError(f"unknown fault kind {self.kind!r}; known: "
                             f"{', '.join(FAULT_KINDS)}")
        for name, v in (("start", self.start), ("duration", self.duration)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"the fault's {name} must be a finite number of seconds "
                                 f">= 0, not {v!r}")
        if self.sector is not None:
            lo, hi = self.sector
            if not all(math.isfinite(x) and -180.0 <= x <= 180.0 for x in (lo, hi)):
                raise ValueError(f"the fault's sector ({lo:g}, {hi:g}) must lie in "
                                 "[-180, 180] degrees")
        elif self.kind == "sector_nan":
            raise ValueError("a sector_nan fault needs a sector (LO:HI degrees)")
        if not (math.isfinite(self.near_range) and self.near_range > 0):
            raise ValueError("near_range must be a finite number of metres > 0")
        if self.near_count < 1:
            raise ValueError("near_count must be at least 1 beam")

    @property
    def window_ms(self) -> tuple[int, int]:
        """The window ``[start, end)`` in integer ms of sim time."""
        return (int(round(self.start * 1000)),
                int(round((self.start + self.duration) * 1000)))

    def active(self, t_ms: int) -> bool:
        """Whether the fault is active at sim time ``t_ms`` (ms)."""
        a, b = self.window_ms
        return a <= t_ms < b

    def describe(self) -> dict:
        """The fault as plain data (the recording's metadata, JSON)."""
        d: dict = {"kind": self.kind, "start": self.start, "duration": self.duration}
        if self.sector is not None:
            d["sector"] = list(self.sector)
        if self.kind == "near_returns":
            d["near_range"] = self.near_range
            d["near_count"] = self.near_count
        return d


def parse_sector(text: str) -> tuple[float, float]:
    """``"LO:HI"`` (degrees) as ``(lo, hi)``.

    Raises ``ValueError`` when it is not two numbers separated by ``:``."""
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise ValueError(f"a sector is LO:HI in degrees (e.g. -30:30), not {text!r}") from None
    return lo, hi


def in_sector(angle_min: float, angle_increment: float, n: int,
              sector: tuple[float, float]) -> np.ndarray:
    """A boolean mask ``(n,)`` of the beams whose angle (``angle_min + i * angle_increment``
    rad, wrapped to ``[-180, 180)`` degrees; REP 103) lies in ``sector`` (degrees, both ends
    included; ``low > high`` wraps through 180). An end is met within 1e-4 degrees, so a
    consumer computing the angles from the message's float32 ``angle_min`` and
    ``angle_increment`` finds the same beams (float32 rounding moves them ~1e-5 degrees;
    a beam is 0.5 degrees)."""
    ang = np.degrees(angle_min + np.arange(n) * angle_increment)
    ang = (ang + 180.0) % 360.0 - 180.0
    lo, hi = sector
    eps = 1e-4
    if lo <= hi:
        return (ang >= lo - eps) & (ang <= hi + eps)
    return (ang >= lo - eps) | (ang <= hi + eps)


def fault_rng(seed: int, index: int) -> np.random.Generator:
    """The generator of the ``index``-th fault of a run with ``seed`` (module docstring)."""
    return np.random.Generator(np.random.PCG64(
        np.random.SeedSequence(int(seed), spawn_key=(3, int(index)))))


def faults_from_options(kinds: tuple[str, ...] | list[str], starts: tuple[float, ...] | list[float],
                        durations: tuple[float, ...] | list[float],
                        sectors: tuple[str, ...] | list[str] = ()) -> tuple[Fault, ...]:
    """The faults of the command line's repeated ``--fault KIND``, ``--fault-start S``,
    ``--fault-duration S`` and ``--fault-sector LO:HI`` (degrees), paired in order: each of
    the others given once (for every fault) or once per ``--fault``; a sector given once
    goes to each fault that reads one (:data:`SECTOR_KINDS`).

    Raises ``ValueError`` for a start, duration or sector without a ``--fault``, a count
    that is neither 1 nor the number of faults, a missing start or duration, or a fault
    :class:`Fault` refuses."""
    n = len(kinds)
    if not n:
        if starts or durations or sectors:
            raise ValueError("--fault-start, --fault-duration and --fault-sector need --fault "
                             "KIND")
        return ()

    def each(name: str, values, required: bool) -> list:
        if not values:
            if required:
                raise ValueError(f"--fault needs {name}")
            return [None] * n
        if len(values) == 1:
            return list(values) * n
        if len(values) != n:
            raise ValueError(f"{name} is given {len(values)} times for {n} --fault: give it "
                             "once (for every fault) or once per --fault")
        return list(values)

    st = each("--fault-start", starts, True)
    du = each("--fault-duration", durations, True)
    se = each("--fault-sector", sectors, False)
    return tuple(Fault(k, float(a), float(d),
                       parse_sector(s) if s is not None and k in SECTOR_KINDS else None)
                 for k, a, d, s in zip(kinds, st, du, se))
