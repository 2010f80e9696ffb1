"""Hostile binding files are input errors with a position, never a traceback or a blow-up:
deep nesting, long chains, chained and doubling references, deep TOML, huge durations.
The limits are the requirements' (fretish/limits.py)."""

from __future__ import annotations

import pytest

from fretc.common.problems import BindingError
from fretc.common.units import parse_seconds
from fretc.signals.bindings.files import MAX_REFERENCE_CHAIN, parse_bindings

HEAD = '[tick]\nperiod = "100 ms"\n[variables]\n'
FIELD = "/scan.ranges[0]"


def _error(text: str) -> BindingError:
    with pytest.raises(BindingError) as err:
        parse_bindings(text, "b.toml")
    return err.value


def test_five_thousand_unary_signs():
    e = _error(HEAD + f'x = "{"-" * 5000}{FIELD}"\n')
    assert "nested more than 200 levels" in str(e) and "b.toml:4" in str(e)


def test_a_long_chain_of_terms():
    assert "characters; the limit is" in str(_error(HEAD + 'x = "' + " + ".join([FIELD] * 20000)
                                                    + '"\n'))
    assert "levels deep" in str(_error(HEAD + 'x = "' + " + ".join(["1"] * 3000) + '"\n'))


def test_chained_references():
    text = HEAD + 'x = "v0"\n' + "".join(f'v{i} = "v{i + 1}"\n' for i in range(3000))
    e = _error(text + f'v3000 = "{FIELD}"\n')
    assert f"more than {MAX_REFERENCE_CHAIN} deep" in str(e)


def test_doubling_references_are_refused_in_linear_time():
    text = HEAD + 'x = "v0 > 0"\n' + "".join(f'v{i} = "v{i + 1} + v{i + 1}"\n'
                                                 for i in range(60))
    e = _error(text + f'v60 = "{FIELD}"\n')
    assert "references substituted has more than 5,000" in str(e)


def test_deep_toml():
    assert "nested too deeply" in str(_error("x = " + "[" * 5000 + "]" * 5000 + "\n"))


@pytest.mark.parametrize("text", ["1e300 h", "1e999 s", "1e99999999 s", "2e12 s"])
def test_durations_out_of_range_are_value_errors(text):
    with pytest.raises(ValueError, match="out of range|beyond the limit"):
        parse_seconds(text)


def test_a_huge_tick_period_in_bindings_is_positioned():
    e = _error('[tick]\nperiod = "1e300 h"\n[variables]\n' + f'x = "{FIELD}"\n')
    assert "b.toml:2" in str(e) and "out of range" in str(e)


def test_expressions_within_the_limits_still_bind():
    b = parse_bindings(HEAD + 'x = "v0 > 0"\n' + "".join(f'v{i} = "v{i + 1} + v{i + 1}"\n'
                                                          for i in range(8))
                       + f'v8 = "{FIELD}"\n', "b.toml")
    assert "x" in b.variables
