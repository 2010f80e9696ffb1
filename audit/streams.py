"""The columns of the stream variables a requirement reads, computed from its clock's pass
(:func:`with_streams`).

Design notes: ARCHITECTURE.md, `audit/streams.py`."""

from __future__ import annotations

from dataclasses import replace

from fretc.audit.columns import ClockPass
from fretc.audit.model import RequirementPlan
from fretc.compiler.stream_code import stream_columns

__all__ = ["with_streams"]


def with_streams(r: RequirementPlan, res: ClockPass, nan_unknown: bool) -> ClockPass:
    """``res`` with the columns of ``r``'s stream variables (module docstring) added, and
    their unknown masks in ``res.unknown`` (where an input it reads is unknown, or with
    ``nan_unknown`` reads NaN, could change its value); ``res`` itself when ``r`` reads
    none, or when an input has no column (its requirement is an error already)."""
    system = r.streams
    if system is None or any(name not in res.columns for name in system.inputs):
        return res
    n = len(res.times)
    got = stream_columns(system, res.columns, n, res.unknown, nan_unknown, res.tick_gaps)
    unknown = dict(res.unknown)
    for name in system.names:
        mask = got.pop(f"{name}?")
        if mask.any():
            unknown[name] = mask
        else:
            unknown.pop(name, None)
    return replace(res, columns={**res.columns, **got}, unknown=unknown)
