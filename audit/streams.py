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
each stream variable is unknown at a tick where its definition's value could differ for some
value of the unknown inputs it reads, by Kleene's logic over the definition, tick by tick
(``false and x`` is known whatever ``x``; ``if c then a else b`` with ``c`` known is the
branch taken; a value held through ``pre`` is as known as when it was read; after a tick
that stands for an unknown number of ticks, a gap of the tick topic or a ``gap`` row, no held
value is known), so a stream reset by known values is known again; the three-valued judge decides over the ticks it is
unknown at (:mod:`fretc.audit.unknown_ticks`). Sound: no verdict rests on a value an unknown
input could change.
"""

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
