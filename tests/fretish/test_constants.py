"""Named durations: ``within T_stop`` with ``T_stop`` declared in the requirement file
(``@constant T_stop 1 s``) or the bindings file (``[constants] T_stop = "1 s"``) means
exactly ``within 1 second``: the same formulas, the same audit; every output shows the
value used; an undeclared or non-whole-tick constant is a positioned error."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.common.errors import FretishError
from fretc.compiler.build import compile_entries
from fretc.cli import main
from fretc.fretish.files import load_requirements

ROOT = Path(__file__).resolve().parents[2]
R2 = "R2: upon too_close agilex_agent shall within {} satisfy stopped\n"


def _formulas(path: Path) -> list:
    return [(c.formalization.ft, c.formalization.pt, c.formalization.ticks)
            for c in compile_entries(load_requirements([path]))]


def test_a_file_constant_gives_the_formulas_of_the_number(tmp_path):
    (tmp_path / "n.fret").write_text("@tick_period 100 ms\n" + R2.format("1.5 seconds"))
    (tmp_path / "c.fret").write_text("@tick_period 100 ms\n@constant T_stop 1.5 s\n"
                                     + R2.format("T_stop"))
    assert _formulas(tmp_path / "c.fret") == _formulas(tmp_path / "n.fret")
    (c,) = compile_entries(load_requirements([tmp_path / "c.fret"]))
    assert "T_stop = 1.5 seconds (15 ticks)" in c.formalization.warnings
    res = CliRunner().invoke(main, [str(tmp_path / "c.fret"), "--emit", "ltl"])
    assert res.exit_code == 0 and "T_stop = 1.5 seconds (15 ticks)" in res.output


@pytest.mark.parametrize("text, where, msg", [
    ("@tick_period 100 ms\n" + R2.format("T_stop"), ":2:", "T_stop is not declared"),
    ("@tick_period 100 ms\n@constant T_stop 1.25 s\n" + R2.format("T_stop"), ":3:",
     "T_stop = 1.25 seconds' is 12.5 ticks"),
    ("@constant T_stop fast\n" + R2.format("T_stop"), ":1:", "not a duration"),
    ("@constant T 1 s\n@constant T 2 s\n", ":2:", "second @constant T"),
    ("@constant 9x 1 s\n", ":1:", "bad constant name"),
])
def test_constant_errors_are_positioned(tmp_path, text, where, msg):
    p = tmp_path / "e.fret"
    p.write_text(text)
    try:
        compiled = compile_entries(load_requirements([p]))
        err = next(str(c.error) for c in compiled if c.error is not None)
    except FretishError as exc:
        err = str(exc)
    assert f"{p}{where}" in err and msg in err, err


def test_within_a_bindings_constant_audits_the_traces_like_within_1_second(tmp_path):
    src = (ROOT / "requirements" / "safe_ros.fret").read_text()
    assert "within 1 second satisfy stopped" in src
    (tmp_path / "safe_ros.fret").write_text(
        src.replace("within 1 second satisfy stopped", "within T_stop satisfy stopped"))
    (tmp_path / "safe_ros.bindings.toml").write_text(
        (ROOT / "requirements" / "safe_ros.bindings.toml").read_text()
        + '\n[constants]\nT_stop = "1 s"\n')
    named = load_plan(AuditConfig(requirements=(str(tmp_path / "safe_ros.fret"),)))
    plain = load_plan(AuditConfig(requirements=(str(ROOT / "requirements" / "safe_ros.fret"),)))
    for log in ("stop_delay.mcap", "nominal.mcap", "sif_disabled.mcap"):
        a = audit_log(named, str(ROOT / "traces" / log)).to_json()["verdicts"]
        b = audit_log(plain, str(ROOT / "traces" / log)).to_json()["verdicts"]
        keep = ("requirement", "verdict", "first_violation", "ticks_evaluated", "robustness",
                "intervals", "triggers", "violations")
        assert [{k: x[k] for k in keep} for x in a] == [{k: x[k] for k in keep} for x in b]
    r2 = next(r for r in named.requirements_json() if r["id"] == "R2")
    assert "T_stop = 1 seconds (10 ticks)" in json.dumps(r2)


def test_bad_bindings_constants_name_the_file_and_line(tmp_path):
    from fretc.common.problems import BindingError
    from fretc.signals.bindings import parse_bindings

    for body, msg in [('T = 5', "a duration in quotes"), ('T = "soon"', "not a duration")]:
        with pytest.raises(BindingError, match=msg) as e:
            parse_bindings('[tick]\nperiod = "100 ms"\n[variables]\n[constants]\n' + body,
                           "b.toml")
        assert "b.toml:5" in str(e.value)
