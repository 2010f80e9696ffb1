"""Units of time: one duration grammar and the time formatters of every fretc output.

Design notes: ARCHITECTURE.md, `common/units.py`."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # fractions is imported lazily (start-up time)
    from fractions import Fraction

# TIME_UNITS is made on first use by the module's __getattr__ (PEP 562)
__all__ = ["NS_PER_S", "TIME_UNITS",  # noqa: F822
           "parse_seconds", "parse_duration", "format_ns",
           "format_period", "format_period_ms", "format_offset", "format_seconds"]

#: Nanoseconds per second (MCAP log times and ROS times are integer nanoseconds).
NS_PER_S = 1_000_000_000
#: The longest duration (seconds) a period or timeout may have: longer ones are input errors,
#: not numbers that overflow a float later
MAX_SECONDS = 10**12

_NUMBER = r"(?:[0-9]+(?:\.[0-9]+)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_TABLES: list = []  # [(the unit table, the duration regexp)] once built


def _tables() -> tuple:
    """``(TIME_UNITS, duration regexp)``, built on first use: a run that reads no duration
    in a time unit (``fretc FILE --emit ltl`` on sentences in ticks) does not pay for the
    regexp's compilation and the table's fractions, nor the import of :mod:`fractions`
    and :mod:`decimal` (start-up time)."""
    if not _TABLES:
        from fractions import Fraction  # lazy: fractions and decimal cost start-up time

        units: dict = {}
        for names, seconds in (
                (("ns", "nanosec", "nanosecs", "nanosecond", "nanoseconds"),
                 Fraction(1, NS_PER_S)),
                (("us", "µs", "μs", "microsec", "microsecs", "microsecond", "microseconds"),
                 Fraction(1, 1_000_000)),
                (("ms", "millisec", "millisecs", "millisecond", "milliseconds"),
                 Fraction(1, 1000)),
                (("s", "sec", "secs", "second", "seconds"), Fraction(1)),
                (("min", "mins", "minute", "minutes"), Fraction(60)),
                (("h", "hour", "hours"), Fraction(3600))):
            units.update(dict.fromkeys(names, seconds))
        _TABLES.append((units, re.compile(rf"\s*({_NUMBER})\s*([^\s0-9.+-]+)\s*\Z")))
    return _TABLES[0]


def __getattr__(name: str):
    """``TIME_UNITS`` (PEP 562): the length in seconds (a :class:`~fractions.Fraction`) of
    every time unit of the duration grammar, lower case (``hz`` is absent: it is a
    frequency); built on first use (:func:`_tables`)."""
    if name == "TIME_UNITS":
        return _tables()[0]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


_EXAMPLE = "e.g. '100 ms' or '10 Hz'"


def parse_seconds(value: str | int | float) -> Fraction:
    """A positive duration (grammar in the module docstring) as exact seconds.

    :param value: text such as ``"100 ms"``, ``"0.05 seconds"``, ``"10 Hz"`` (the period
        of that frequency, 1/10 s), or an int/float meaning seconds (a TOML number).
    :returns: the duration in seconds, exact (``"0.1 s"`` is ``Fraction(1, 10)``).
    :raises ValueError: not a number and a unit, ``ticks`` (a duration here must be a
        time), an unknown unit, or a duration that is not positive.
    """
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ValueError(f"{value!r} is not a duration")
    time_units, duration = _tables()
    from decimal import Decimal  # lazy, as in _tables
    from fractions import Fraction

    if not isinstance(value, str):
        amount, unit = Fraction(Decimal(repr(value))), "s"
    else:
        m = duration.match(value)
        if not m:
            raise ValueError(f"{value.strip()!r} is not a duration: write a number and a "
                             f"unit, {_EXAMPLE}")
        number = Decimal(m.group(1))
        if not -30 <= number.adjusted() <= 30:  # 1e999999999 s must not become an integer
            raise ValueError(f"{value.strip()!r}: the number is out of range for a duration "
                             f"(at most {MAX_SECONDS:.0e} s)")
        amount, unit = Fraction(number), m.group(2).lower()
    if unit == "hz":
        if amount <= 0:
            raise ValueError(f"{value!r}: a frequency must be positive")
        return 1 / amount
    if unit not in time_units:
        if unit in ("tick", "ticks"):
            raise ValueError(f"{value!r}: a period must be a time ({_EXAMPLE}), not ticks")
        raise ValueError(f"{value!r}: unknown time unit {unit!r} (ns, us, ms, s, min, h, Hz "
                         "or their long names: microseconds ... hours)")
    seconds = amount * time_units[unit]
    if seconds <= 0:
        raise ValueError(f"{value!r}: a duration must be positive")
    if seconds > MAX_SECONDS:
        raise ValueError(f"{value!r}: beyond the limit of {MAX_SECONDS:.0e} s (about 31,700 "
                         "years) for a duration")
    return seconds


def parse_duration(value: str | int | float) -> int:
    """A positive duration (grammar in the module docstring) in integer nanoseconds, rounded
    to the nearest nanosecond (ties to even).

    :param value: as :func:`parse_seconds` (``"100 ms"``, ``"10 Hz"``, ``0.05``).
    :returns: nanoseconds, at least 1.
    :raises ValueError: as :func:`parse_seconds`, and for a duration under half a nanosecond.
    """
    ns = round(parse_seconds(value) * NS_PER_S)
    if ns <= 0:
        raise ValueError(f"{value!r}: a duration must be at least 1 ns")
    return ns


# --------------------------------------------------------------------------- formatters
def format_ns(ns: int) -> str:
    """A duration in integer nanoseconds in the largest unit that shows it exactly:
    ``"2 s"``, ``"100 ms"``, ``"250 us"``, ``"7 ns"`` (the audit's tick and clock lines)."""
    if ns % NS_PER_S == 0:
        return f"{ns // NS_PER_S} s"
    if ns % 1_000_000 == 0:
        return f"{ns // 1_000_000} ms"
    if ns % 1000 == 0:
        return f"{ns // 1000} us"
    return f"{ns} ns"


def format_period(seconds: Fraction) -> str:
    """A period in exact seconds: :func:`format_ns` when it is a whole number of
    nanoseconds, else the float seconds (``"3.3333333333333335e-10 s"``)."""
    ns = seconds * NS_PER_S
    return format_ns(int(ns)) if ns.denominator == 1 else f"{float(seconds)} s"


def format_period_ms(seconds: Fraction) -> str:
    """A period in exact seconds as milliseconds below one second, else seconds, with
    ``%g`` digits: ``"100 ms"``, ``"2.5 ms"``, ``"1.5 s"`` (the compiler's messages)."""
    ms = seconds * 1000
    return f"{float(ms):g} ms" if ms < 1000 else f"{float(seconds):g} s"


def format_offset(ns: int | None, start: int | None, *, missing: str = "-",
                  decimals: int = 3) -> str:
    """A log time as seconds after ``start`` (both integer nanoseconds):
    ``"12.345 s"``; ``missing`` when either is None."""
    if ns is None or start is None:
        return missing
    return f"{(ns - start) / 1e9:.{decimals}f} s"


def format_seconds(seconds: float | None, *, missing: str = "-") -> str:
    """Seconds with three decimals, ``"1.250 s"``; ``missing`` for None."""
    return missing if seconds is None else f"{seconds:.3f} s"
