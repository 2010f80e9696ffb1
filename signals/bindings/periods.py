"""The tick period a requirement's durations convert with, outside an audit: ``fretc check``,
``fretc shield`` and ``fretc testgen`` take it as ``fretc audit`` does.

A duration in time units (``within 1 second``) counts ticks of the requirement's tick period:
the file's ``@tick_period``; else the bindings' (``-b``, or a binding file beside the
requirements as the audit finds it): their ``[tick] period``, or the ``nominal_rate`` of the
topic they tick on. FRET itself reads ``1 second`` as one tick and ``500 milliseconds`` as
500 (its units are words, ../shared/fretish/README.md section 7.5); a shield synthesized so
would let a robot drive blind for 50 s where 0.5 s is written. So where no period is known, a
requirement with a duration in time units is an input error naming the period to give, never
a silent tick; ``N ticks`` needs no period. A file's period that differs from the bindings'
is an error too (the durations would convert with the wrong one), as in the audit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from fretc.common.errors import InputError
from fretc.common.units import format_period
from fretc.signals.bindings.spec import Bindings

__all__ = ["bindings_period", "with_periods", "time_unit_duration"]

NS_PER_S = 1_000_000_000


def bindings_period(bindings: Bindings | None) -> Fraction | None:
    """The period (seconds) durations convert with under ``bindings``: its ``[tick] period``,
    else its tick topic's ``nominal_rate``; None when it gives neither (or there are no
    bindings)."""
    if bindings is None:
        return None
    if bindings.tick.period_ns:
        return Fraction(bindings.tick.period_ns, NS_PER_S)
    if bindings.tick.nominal_period_ns:
        return Fraction(bindings.tick.nominal_period_ns, NS_PER_S)
    return None


def time_unit_duration(entry: Any) -> str | None:
    """The requirement's duration in time units as written (``"1 second"``), or None (no
    duration, or one in ticks)."""
    req = entry.requirement
    if req is None or getattr(req, "freeform", False):
        return None
    d = getattr(req.timing, "duration", None)
    if d is None or d.unit == "ticks" or not d.resolved:  # (undeclared: the compiler says so)
        return None
    unit = d.unit[:-1] if d.amount == "1" and d.unit.endswith("s") else d.unit
    return f"{d.amount} {unit}" + (f" ({d.name})" if d.name else "")


def with_periods(entries: Sequence[Any], bindings: Bindings | None,
                 found: str = "", override: Fraction | None = None) -> list[Any]:
    """``entries`` (:class:`fretc.fretish.entry.RequirementEntry`) each with the tick period
    its durations convert with (module docstring): its own, else the bindings'.
    ``found``: how the bindings were found, for the messages (``"-b"``, or the path of a
    file beside the requirements). ``override``: ``--tick-period`` in seconds, the period of
    every entry (as in ``fretc audit``, where it overrides the bindings and the files; the
    one way to give a FRET export, which cannot declare ``@tick_period``, a period without
    a binding file).

    Raises:
        InputError: a requirement with a duration in time units and no period known, or a
            declared period that differs from the bindings' (every such requirement named
            with its file and line)."""
    if override is not None:
        return [dataclasses.replace(e, tick_period=override) for e in entries]
    period = bindings_period(bindings)
    src = f"{bindings.source}{f' ({found})' if found else ''}" if bindings is not None else ""
    out, errors = [], []
    for e in entries:
        if e.tick_period is not None:
            if period is not None and e.tick_period != period:
                errors.append(f"{e.source}:{e.line}: {e.id} declares a tick period of "
                              f"{format_period(e.tick_period)} but the bindings {src} tick "
                              f"every {format_period(period)}: durations would convert with "
                              "the wrong period; make them equal")
            out.append(e)
        elif period is not None:
            out.append(dataclasses.replace(e, tick_period=period))
        else:
            unit = time_unit_duration(e)
            if unit is not None:
                errors.append(f"{e.source}:{e.line}: {e.id}: '{unit}' is a duration in time "
                              "units and no tick period is known to count it in ticks: "
                              + _no_period(bindings, src, fret_export=_is_export(e)))
            out.append(e)
    if errors:
        raise InputError("\n".join(errors))
    return out


def _is_export(entry: Any) -> bool:
    """Is ``entry`` read from a JSON file (a FRET export, which has no ``@tick_period``)?"""
    return str(entry.source).lower().endswith(".json")


def _no_period(bindings: Bindings | None, src: str, fret_export: bool = False) -> str:
    """What to give when no period is known (the message's end), for the file given: a FRET
    export cannot declare ``@tick_period``, so only ``--tick-period`` and ``-b`` are named
    for one."""
    if bindings is not None and bindings.tick.topic:
        return (f"the bindings {src} tick once per {bindings.tick.topic} message and give "
                "no nominal_rate in [tick]; add it, or give --tick-period 100ms"
                + ("" if fret_export else
                   ", or declare '@tick_period 100 ms' in the requirements file"))
    if fret_export:
        return ("give --tick-period 100ms, or a binding file whose [tick] period gives it "
                "(-b); a FRET export holds no tick period, and FRET would read it as that "
                "many ticks")
    return ("declare one in the requirements file ('@tick_period 100 ms'), give "
            "--tick-period 100ms, or a binding file whose [tick] period gives it (-b, or "
            "X.bindings.toml beside X.fret); FRET would read it as that many ticks")
