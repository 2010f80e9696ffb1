"""One duration grammar (common/units.py) for requirement files and bindings."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given, settings, strategies as st

from fretc.fretish.files import load_requirements, parse_tick_period
from fretc.common.units import (NS_PER_S, format_ns, format_offset, format_period, format_period_ms,
    format_seconds, parse_duration, parse_seconds)
from fretc.signals.bindings import parse_bindings

# Each written both ways: the disagreement the issue names ('10 Hz' and '500 ns' used to be
# bindings-only, '1 h' and '100 milliseconds' requirement-file-only).
SAME = [("10 Hz", Fraction(1, 10)), ("500 ns", Fraction(1, 2 * 10**6)), ("1 h", Fraction(3600)),
        ("100 milliseconds", Fraction(1, 10)), ("2.5 ms", Fraction(1, 400)),
        ("1 min", Fraction(60)), ("3 secs", Fraction(3)), ("20 µs", Fraction(1, 50000)),
        ("1e3 ms", Fraction(1)), ("4 HZ", Fraction(1, 4)), ("2 hours", Fraction(7200))]


@pytest.mark.parametrize("text, seconds", SAME)
def test_requirement_files_and_bindings_read_durations_alike(tmp_path, text, seconds):
    assert parse_tick_period(text) == seconds
    f = tmp_path / "r.fret"
    f.write_text(f"@tick_period {text}\nR1: the sw shall always satisfy p\n", encoding="utf-8")
    assert load_requirements([f])[0].tick_period == seconds
    b = parse_bindings(f'[tick]\nperiod = "{text}"\n[variables]\np = "/a.x > 1"\n')
    assert b.tick.period_ns == round(seconds * NS_PER_S)


@pytest.mark.parametrize("text", ["", "ms", "100", "1 tick", "2 ticks", "10 parsecs", "-1 s",
                                  "0 ms", "0 Hz", "1 ms 2", "1. s"])
def test_both_reject(text):
    with pytest.raises(ValueError):
        parse_tick_period(text)
    with pytest.raises(ValueError):
        parse_duration(text)


def test_numbers_are_seconds_and_rounding_is_to_nearest_ns():
    assert parse_duration(0.05) == 50_000_000 and parse_duration(2) == 2 * NS_PER_S
    assert parse_duration("3 Hz") == 333_333_333 and parse_duration("1.5 ns") == 2
    with pytest.raises(ValueError):
        parse_duration("0.4 ns")
    with pytest.raises(ValueError):
        parse_duration(True)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 10**12))
def test_format_ns_parses_back(ns):
    assert parse_duration(format_ns(ns)) == ns
    assert format_period(Fraction(ns, NS_PER_S)) == format_ns(ns)


def test_formatters_print_what_the_outputs_print():
    assert [format_ns(n) for n in (2 * NS_PER_S, 100_000_000, 250_000, 7)] == \
        ["2 s", "100 ms", "250 us", "7 ns"]
    assert format_period(Fraction(1, 3 * NS_PER_S)) == f"{float(Fraction(1, 3 * NS_PER_S))} s"
    assert [format_period_ms(p) for p in (Fraction(1, 10), Fraction(1, 400), Fraction(3, 2))] \
        == ["100 ms", "2.5 ms", "1.5 s"]
    assert format_offset(1_500_000_000, 250_000_000) == "1.250 s"
    assert format_offset(None, 0) == "-" and format_offset(5, None, missing="?") == "?"
    assert format_offset(3 * NS_PER_S, 0, decimals=1) == "3.0 s"
    assert format_seconds(1.25) == "1.250 s" and format_seconds(None) == "-"
    assert parse_seconds("10 Hz") == Fraction(1, 10)
