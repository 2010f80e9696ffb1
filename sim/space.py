"""Scenario parameter spaces for falsification (``fretc falsify --space FILE.toml``): a base
scenario of :mod:`fretc.sim.scenarios`, the simulator's seed, and a range for each parameter the
search may change.

Design notes: ARCHITECTURE.md, `sim/space.py`."""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import NoReturn, TYPE_CHECKING

from fretc.common.errors import FretcError, Where

from fretc.sim.distributions import Distribution, DistributionError, parse_distribution
from fretc.sim.faults import FAULT_KINDS, Fault
from fretc.sim.scenarios import DRUM_RADIUS, SCENARIOS, Scenario
from fretc.sim.simulation import STEP_MS
from fretc.sim.world import Barrel

if TYPE_CHECKING:
    import numpy as np

__all__ = ["PARAMETERS", "Space", "SpaceError", "load_space", "apply"]

#: parameter -> (unit, what it changes)
PARAMETERS: dict[str, tuple[str, str]] = {
    "interceptor_delay": ("s", "the interceptor acts on each /gwendolen_control message this "
                               "late (the interceptor delay fault)"),
    "stop_delay": ("s", "every /gwendolen_control decision of the SIF is published this late"),
    "dropout_start": ("s", "no /scan from this sim time on (lidar dropout)"),
    "dropout_duration": ("s", "for this long (needs dropout_start)"),
    "obstacle_x": ("m", "an unmapped drum (r = 0.15 m) at x in the map frame (needs "
                        "obstacle_y)"),
    "obstacle_y": ("m", "... and at y (needs obstacle_x)"),
    "obstacle_speed": ("m/s", "the walking speed of the scenario's moving obstacles"),
    "obstacle_start": ("s", "the sim time the moving obstacles start walking"),
    "lidar_sigma": ("m", "the LiDAR's range noise (standard deviation)"),
    "fault_kind": ("index", "the fault injected: its index in sim.faults.FAULT_KINDS (a name "
                            "or a choice of names in the file; needs fault_start)"),
    "fault_start": ("s", "the fault starts at this sim time (needs fault_kind and "
                         "fault_duration)"),
    "fault_duration": ("s", "... and lasts this long (needs fault_start)"),
    "fault_sector_low": ("deg", "the sector faults' beams from this angle (REP 103: 0 ahead, "
                                "counter-clockwise; needs fault_sector_high)"),
    "fault_sector_high": ("deg", "... to this one (low > high wraps through 180)"),
}

#: the sector of a sector fault whose space gives none (degrees): the 90 degrees ahead
DEFAULT_SECTOR = (-45.0, 45.0)
#: the fault parameters, each needing ``fault_start``; the sector's bounds each other
_FAULT_KEYS = ("fault_kind", "fault_duration", "fault_sector_low", "fault_sector_high")
_SIGNED = ("obstacle_x", "obstacle_y", "fault_sector_low", "fault_sector_high")

#: The largest magnitude of a range's bound, in the parameter's unit: far past any map
#: (metres) or run (seconds), and small enough that squares and sums stay finite.
MAX_MAGNITUDE = 1e9

_NEEDS = {"obstacle_x": "obstacle_y", "obstacle_y": "obstacle_x",
          "dropout_duration": "dropout_start"}


class SpaceError(FretcError):
    """A space file fretc cannot use (its message names ``file:line``)."""


@dataclass(frozen=True)
class Space:
    """A parameter space: ``scenario`` (the base :class:`~fretc.sim.scenarios.Scenario`), the
    simulator's ``seed``, and ``parameters``: ``(name, low, high)`` in file order;
    ``distributions``: one :class:`~fretc.sim.distributions.Distribution` per parameter, same
    order (a plain range is uniform on it)."""

    path: str
    scenario: Scenario
    seed: int
    parameters: tuple[tuple[str, float, float], ...]
    distributions: tuple[Distribution, ...] = ()
    #: the Safety System of every run: ``None`` the hand-written SIF and interceptor,
    #: ``"shield:DIR"`` a generated shield (``fretc falsify --safety``, :mod:`fretc.sim.run`)
    safety: str | None = None

    @property
    def latent_dims(self) -> int:
        """The number of latent standard normal coordinates of one run
        (:mod:`fretc.sim.distributions`)."""
        return sum(d.latent_dims for d in self.distributions)

    def at_latent(self, z: Sequence[float] | np.ndarray) -> dict[str, float]:
        """The parameter values at latent coordinates ``z`` (``latent_dims`` floats); a
        fault that does not happen is left out (the scenario's own value)."""
        out, i = {}, 0
        for d in self.distributions:
            v = d.value(z[i:i + d.latent_dims])
            i += d.latent_dims
            if v is not None:
                out[d.name] = v
        return out

    def check_sampling(self) -> None:
        """Raise :class:`SpaceError` (``file:line``) when a parameter's distribution is
        degenerate for sampling (a plain range ``[x, x]``: one value)."""
        for d in self.distributions:
            if not d.low < d.high and d.kind == "uniform":
                try:
                    text = Path(self.path).read_text(encoding="utf-8")
                except OSError:
                    text = ""
                line = _line_of(text, d.name)
                raise SpaceError(f"{self.path}:{line}: {d.name}: the range [{d.low:g}, "
                                 f"{d.high:g}] is a single value: a degenerate distribution "
                                 "for sampling (widen it, or fix the value in the scenario)",
                                 where=Where(self.path, line))

    @property
    def names(self) -> list[str]:
        """The parameter names, in file order."""
        return [p[0] for p in self.parameters]

    def point(self, unit: list[float]) -> dict[str, float]:
        """The parameter values of a point of the unit cube (one coordinate in ``[0, 1]``
        per parameter, clipped), rounded to 1 ms / 1 mm / 1e-6; ``fault_kind`` (a category)
        snapped to the nearest kind index its distribution allows (a choice's values, or
        the integers of its range)."""
        out = {}
        dists = {d.name: d for d in self.distributions}
        for (name, lo, hi), u in zip(self.parameters, unit):
            u = min(max(float(u), 0.0), 1.0)
            out[name] = round(lo + u * (hi - lo), 6)
            if name == "fault_kind":
                d = dists.get(name)
                allowed = (d.values if d is not None and d.kind == "choice" and d.values
                           else tuple(float(i) for i in range(math.ceil(lo),
                                                               math.floor(hi) + 1)))
                out[name] = min(allowed, key=lambda v: (abs(v - out[name]), v))
        return out


def _toml_type(value: object) -> str:
    """A decoded TOML value's type, in words."""
    return {dict: "table", list: "array", bool: "boolean", int: "integer",
            float: "float", str: "string"}.get(type(value), type(value).__name__)


def _line_of(text: str, key: str) -> int | None:
    for i, line in enumerate(text.splitlines(), 1):
        if re.match(rf"\s*{re.escape(key)}\s*=", line):
            return i
    return None


def load_space(path: str | Path) -> Space:
    """Read a space file.

    Raises:
        SpaceError: unreadable or invalid TOML, an unknown scenario or parameter, a range
            that is not ``[low, high]`` of finite numbers with ``low <= high``, a parameter
            without its partner (``obstacle_x`` without ``obstacle_y``), or one the base
            scenario cannot take; the message names ``file:line``.
    """
    p = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
        doc = tomllib.loads(text)
    except OSError as exc:
        raise SpaceError(f"{p}: cannot read the space file: {exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        m = re.search(r"line (\d+), column (\d+)", str(exc))
        where = f"{p}:{m.group(1)}:{m.group(2)}" if m else p
        raise SpaceError(f"{where}: not a TOML file: {exc}",
                         where=Where(p, int(m.group(1)), int(m.group(2))) if m else None) from None

    def fail(key: str, msg: str) -> NoReturn:
        line = _line_of(text, key)
        raise SpaceError(f"{p}:{line}: {msg}" if line else f"{p}: {msg}",
                         where=Where(p, line))

    unknown = sorted(set(doc) - {"scenario", "seed", "max_time", "parameters"})
    if unknown:
        fail(unknown[0], f"unknown key {unknown[0]!r}; known: scenario, seed, max_time, "
                         "[parameters]")
    name = doc.get("scenario")
    if not isinstance(name, str) or name not in SCENARIOS:
        shown = repr(name) if isinstance(name, str) else f"a TOML {_toml_type(name)}"
        fail("scenario", f"scenario {shown} is not one of {', '.join(SCENARIOS)}")
    sc = SCENARIOS[name]
    seed = doc.get("seed", 1)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**32:
        fail("seed", "seed must be an integer in [0, 2^32 - 1] (the simulator's generator "
                     "takes 32 bits)")
    if "max_time" in doc:
        mt = doc["max_time"]
        tick = STEP_MS / 1000
        if (not isinstance(mt, (int, float)) or isinstance(mt, bool) or not math.isfinite(mt)
                or not mt >= tick):
            fail("max_time", f"max_time must be a finite number of seconds, at least one "
                             f"simulator step ({tick:g} s)")
        sc = replace(sc, max_time=float(mt))
    params = doc.get("parameters")
    if not isinstance(params, dict) or not params:
        fail("[parameters]", "the space needs a [parameters] table with at least one "
                             "parameter")
    out, dists = [], []
    for key, rng in params.items():
        rng, dist = _parameter(key, rng, params, sc, name, fail)
        out.append((key, float(rng[0]), float(rng[1])))
        dists.append(dist or Distribution(key, "uniform", float(rng[0]), float(rng[1])))
    return Space(p, sc, seed, tuple(out), tuple(dists))


def _parameter(key: str, rng, params: dict, sc: Scenario, name: str, fail):
    """``([low, high], distribution or None)`` of one ``[parameters]`` entry (a range or a
    distribution table), checked as :func:`load_space` documents (``fail(key, msg)``
    raises)."""
    if key not in PARAMETERS:
        fail(key, f"unknown parameter {key!r}; known: {', '.join(PARAMETERS)}")
    if key == "fault_kind":
        rng, fixed = _fault_kind(rng, fail)
        if fixed is not None:
            _fault_needs(key, params, fail)
            return rng, fixed
    if isinstance(rng, dict):
        try:
            dist = parse_distribution(key, rng, key not in ("obstacle_x", "obstacle_y"),
                                      lambda msg: _raise(msg))
        except DistributionError as exc:
            fail(key, str(exc))
        if dist.fault is not None and key in ("obstacle_x", "obstacle_y"):
            fail(key, f"{key}: a fault share is not supported for the obstacle's "
                      "position (it needs its partner); use dropout or a delay")
        if dist.fault is not None and key in _FAULT_KEYS:
            fail(key, f"{key}: a fault share goes on fault_start (the fault happens or "
                      "not as a whole)")
        rng = list(dist.range)
    else:
        dist = None
    if (not isinstance(rng, list) or len(rng) != 2
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                       and math.isfinite(x) for x in rng) or rng[0] > rng[1]):
        fail(key, f"{key} must be [low, high] with finite numbers, low <= high "
                  f"({PARAMETERS[key][0]})")
    if not math.isfinite(float(rng[1]) - float(rng[0])):
        fail(key, f"{key}: the range [{rng[0]:g}, {rng[1]:g}] is wider than a float can "
                  "hold (high - low overflows)")
    if max(abs(rng[0]), abs(rng[1])) > MAX_MAGNITUDE:
        fail(key, f"{key}: the range [{rng[0]:g}, {rng[1]:g}] goes beyond "
                  f"+-{MAX_MAGNITUDE:g} {PARAMETERS[key][0]} (the simulator's arithmetic "
                  "on it would overflow)")
    if rng[0] < 0 and key not in _SIGNED:
        fail(key, f"{key} cannot be negative")
    if key.startswith("fault_sector") and not -180 <= rng[0] <= rng[1] <= 180:
        fail(key, f"{key} must lie in [-180, 180] degrees")
    if key == "fault_kind" and not (0 <= rng[0] and rng[1] <= len(FAULT_KINDS) - 1):
        fail(key, f"fault_kind's indices run from 0 to {len(FAULT_KINDS) - 1} "
                  f"({', '.join(FAULT_KINDS)}); a name says which")
    if key == "fault_kind" and dist is not None and any(v != int(v) for v in dist.values):
        fail(key, "fault_kind's choices are kinds: names, or whole indices")
    if key.startswith("fault_"):
        _fault_needs(key, params, fail)
    if key == "obstacle_speed" and not rng[0] > 0:
        fail(key, "obstacle_speed must be > 0 m/s")
    if key in _NEEDS and _NEEDS[key] not in params and not (
            key == "dropout_duration" and sc.dropout_start is not None):
        fail(key, f"{key} needs {_NEEDS[key]} too")
    if key.startswith("obstacle_s") and not sc.movers:
        fail(key, f"{key}: scenario {name!r} has no moving obstacle")
    return rng, dist


def _raise(msg: str):
    raise DistributionError(msg)


def _kind_index(name, fail) -> float:
    if isinstance(name, str):
        if name not in FAULT_KINDS:
            fail("fault_kind", f"fault_kind: unknown fault {name!r}; known: "
                               f"{', '.join(FAULT_KINDS)}")
        return float(FAULT_KINDS.index(name))
    return name


def _fault_kind(rng, fail) -> tuple[object, Distribution | None]:
    """``fault_kind``'s entry with names as indices: a single name is the fixed kind
    (``([i, i], its distribution)``); a choice's names become indices (``(entry, None)``,
    parsed as any entry then)."""
    if isinstance(rng, str):
        i = _kind_index(rng, fail)
        return [i, i], Distribution("fault_kind", "choice", values=(i,), weights=(1.0,))
    if isinstance(rng, dict) and isinstance(rng.get("values"), list):
        rng = dict(rng, values=[_kind_index(v, fail) for v in rng["values"]])
    return rng, None


def _fault_needs(key: str, params: dict, fail) -> None:
    """A fault parameter's partners (:data:`PARAMETERS`) present in ``params``."""
    need = {"fault_start": ("fault_kind", "fault_duration"),
            "fault_sector_low": ("fault_start", "fault_sector_high"),
            "fault_sector_high": ("fault_start", "fault_sector_low")}.get(key, ("fault_start",))
    for other in need:
        if other not in params:
            fail(key, f"{key} needs {other} too")


def apply(scenario: Scenario, values: dict[str, float]) -> Scenario:
    """``scenario`` with the parameter ``values`` (name -> value, :data:`PARAMETERS`); a
    ``fault_start`` adds one :class:`fretc.sim.faults.Fault` to the scenario's (its kind the
    ``fault_kind`` index rounded, a sector fault without ``fault_sector_*`` on
    :data:`DEFAULT_SECTOR`)."""
    changes: dict = {}
    for key in ("interceptor_delay", "stop_delay", "dropout_start", "dropout_duration",
                "lidar_sigma"):
        if key in values:
            changes[key] = float(values[key])
    if "obstacle_x" in values:
        changes["barrels"] = scenario.barrels + (
            Barrel(values["obstacle_x"], values["obstacle_y"], DRUM_RADIUS, "obstacle"),)
    if "obstacle_speed" in values or "obstacle_start" in values:
        changes["movers"] = tuple(
            replace(m, speed=values.get("obstacle_speed", m.speed),
                    t_start=values.get("obstacle_start", m.t_start))
            for m in scenario.movers)
    if changes.get("dropout_start") is not None and "dropout_duration" not in changes:
        changes["dropout_duration"] = scenario.dropout_duration
    if "fault_start" in values:  # (absent: the fault of a share does not happen this run)
        k = min(max(int(round(values["fault_kind"])), 0), len(FAULT_KINDS) - 1)
        kind = FAULT_KINDS[k]
        sector = ((float(values["fault_sector_low"]), float(values["fault_sector_high"]))
                  if "fault_sector_low" in values else None)
        if kind == "sector_nan" and sector is None:
            sector = DEFAULT_SECTOR
        changes["faults"] = scenario.faults + (
            Fault(kind, float(values["fault_start"]), float(values["fault_duration"]),
                  sector),)
    return replace(scenario, **changes)
