"""The columns of the stream variables a requirement reads, computed from its clock's pass
(:func:`with_streams`).

A FRET Internal variable whose definition reads itself through ``pre`` (``psiAtZero`` is
``Psi -> if (hdg and not pre hdg) then Psi else pre psiAtZero``) and that no binding binds
is computed by the audit tick by tick over the requirement's own ticks, from the columns of
the variables its definition reads (its :class:`fretc.fretish.fret_streams.StreamSystem`'s
inputs, which are the requirement's variables read from the log: :mod:`fretc.audit.plan`),
exactly as Lustre defines it (:mod:`fretc.compiler.stream_code`). Every judge of the audit
takes the requirement through :func:`fretc.audit.finalize.finalize`, which calls this first;
the CSV judge that streams rows does not (:func:`fretc.audit.streamed.unstreamed_reason`), so
such a requirement's verdict is the whole-trace judge's on every path.

Unknown values (a gap, an ``unknown`` cell, a ``gap`` row, and NaN under fretc's NaN rule):
a stream holds what it read, so from the first tick at which an input it reads is unknown,
each stream variable is unknown at every later tick (sound: no verdict rests on a value
computed from an unknown one; the three-valued judge decides over them,
:mod:`fretc.audit.unknown_ticks`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fretc.audit.columns import ClockPass
from fretc.audit.model import RequirementPlan
from fretc.compiler.stream_code import stream_columns

__all__ = ["with_streams"]


def with_streams(r: RequirementPlan, res: ClockPass, nan_unknown: bool) -> ClockPass:
    """``res`` with the columns of ``r``'s stream variables (module docstring) added, and
    their unknown masks in ``res.unknown`` (from the first tick an input is unknown on, or
    with ``nan_unknown`` reads NaN); ``res`` itself when ``r`` reads none, or when an input
    has no column (its requirement is an error already)."""
    system = r.streams
    if system is None or any(name not in res.columns for name in system.inputs):
        return res
    n = len(res.times)
    columns = {**res.columns, **stream_columns(system, res.columns, n)}
    bad = np.zeros(n, np.bool_)
    for name in system.inputs:
        mask = res.unknown.get(name)
        if mask is not None:
            bad |= mask[:n]
        col = res.columns[name][:n]
        if nan_unknown and col.dtype.kind == "f":
            bad |= np.isnan(col)
    unknown = dict(res.unknown)
    if bad.any():
        held = np.zeros(n, np.bool_)
        held[int(np.argmax(bad)):] = True
        for name in system.names:
            unknown[name] = held
    return replace(res, columns=columns, unknown=unknown)
