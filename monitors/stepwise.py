"""The stepwise engine: a generated monitor class (``MONITORS[id]`` of the module
:mod:`fretc.compiler.codegen` renders) driven tick by tick over columns.

The audit steps the monitors while it reads the log (:mod:`fretc.audit.passes`); this
module replays them over kept columns (after a cut at the damage) and reads their verdicts.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["replay", "verdict", "to_python"]


def to_python(x: Any) -> bool | float:
    """A column item as the generated monitors read it: ``bool`` or ``float``."""
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    return float(x)


def replay(monitor_cls: type, columns: Mapping[str, np.ndarray], n: int) -> Any:
    """A new monitor of ``monitor_cls`` stepped over the first ``n`` ticks of ``columns``
    (FRET variable -> values)."""
    mon = monitor_cls()
    names = list(columns)
    cols = [columns[k] for k in names]
    for i in range(n):
        mon.step({k: to_python(c[i]) for k, c in zip(names, cols)})
    return mon


def verdict(mon: Any) -> tuple[bool, str, int | None]:  # mon: a generated monitor
    """(FRET's finite-trace verdict ``finish()``, the LTL3 ``status`` and the tick it became
    definite) of a monitor after its last step."""
    return bool(mon.finish()), mon.status, mon.status_tick
