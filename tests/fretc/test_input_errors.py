"""Every input error is exit 2 with a positioned message, never an internal error:
FRET JSON exports, .fret files and --psl-map files fed the wrongly typed forms of each of
their values (every JSON / TOML type, surrogates, NUL, control characters)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

TEXT = "the sw shall always satisfy p"
#: a value of every JSON type, and strings that are not text or not one line
JSON_VALUES = [None, True, 1, 1.5, [], ["a"], {}, {"a": 1}, "", "\ud800", "a\x00b",
               "a\nb", "a\x1bb", "x" * 1000]


def _run(*args) -> object:
    return CliRunner().invoke(main, [str(a) for a in args])


def _assert_input_error_or_ok(res, path: Path, codes=(0, 2)) -> None:
    assert res.exit_code in codes, res.output
    assert "internal error" not in res.output and "Traceback" not in res.output
    if res.exit_code == 2:
        assert str(path) in res.output, res.output


@pytest.mark.parametrize("field", ["reqid", "fulltext", "project", "rationale",
                                   "parent_reqid"])
@pytest.mark.parametrize("value", JSON_VALUES, ids=repr)
@pytest.mark.parametrize("emit", ["ltl", "monitor"])
def test_fret_json_values_of_every_type(tmp_path, field, value, emit):
    obj = {"reqid": "R1", "fulltext": TEXT, field: value}
    p = tmp_path / "r.json"
    p.write_text(json.dumps([obj]), encoding="utf-8")
    res = _run(p, "--emit", emit, "-o", tmp_path / "out.py") if emit == "monitor" \
        else _run(p, "--emit", "ltl")
    # (exit 1: a sentence that does not parse is that requirement's error)
    _assert_input_error_or_ok(res, p, (0, 1, 2) if field == "fulltext" else (0, 2))
    if isinstance(value, str) and "\ud800" in value:  # not text: no output can hold it
        assert res.exit_code == 2 and "lone surrogate" in res.output
    if field == "project" and isinstance(value, (list, dict)):
        assert res.exit_code == 2 and "project" in res.output


def test_duplicate_ids_across_projects_name_both_places(tmp_path):
    p = tmp_path / "r.json"
    p.write_text(json.dumps([{"project": "A", "reqid": "R1", "fulltext": TEXT},
                             {"project": "B", "reqid": "R1", "fulltext": TEXT}], indent=1))
    res = _run(p, "--emit", "monitor", "-o", tmp_path / "m.py")
    assert res.exit_code == 2
    assert res.output.count(str(p)) == 2 and "'A'" in res.output and "'B'" in res.output


def test_a_newline_in_a_json_id_is_escaped_by_emit_ltl(tmp_path):
    p = tmp_path / "r.json"
    p.write_text(json.dumps([{"reqid": "R\nFAKE", "fulltext": TEXT + " &\nFORGED"}]))
    res = _run(p, "--emit", "ltl")
    assert res.exit_code == 0, res.output
    assert "R\\x0aFAKE" in res.output and "&\\x0aFORGED" in res.output, res.output
    assert not any(line.startswith(("FAKE", "FORGED")) for line in res.output.splitlines())


def test_a_byte_that_is_not_utf8_is_reported_at_its_line(tmp_path):
    p = tmp_path / "r.fret"
    p.write_bytes(b"R1: " + TEXT.encode() + b"\n" * 6 + b"R2: the sw shall \xff satisfy q\n")
    res = _run(p, "--emit", "ltl")
    assert res.exit_code == 2 and f"{p}:7:18" in res.output, res.output


TOML_VALUES = ["1", "1.5", "true", "[1]", "{a = 1}", '"ok"', '"A\\n"', '"a\\u0000"']


@pytest.mark.parametrize("key", ["agent", "variables", "comparisons", "variables.p",
                                 "variables.p.name", "variables.p.kind", "variables.p.agent",
                                 'comparisons."(x > 1)"'])
@pytest.mark.parametrize("value", TOML_VALUES)
def test_psl_map_values_of_every_type(tmp_path, key, value):
    req = tmp_path / "r.fret"
    req.write_text("R1: the sw shall always satisfy p & x > 1\n")
    head, _, last = key.rpartition(".")
    m = tmp_path / "map.toml"
    m.write_text((f"[{head}]\n" if head else "") + f"{last} = {value}\n")
    res = _run(req, "--emit", "psl", "--psl-map", m, "-o", tmp_path / "out.psl")
    _assert_input_error_or_ok(res, m)
    out = tmp_path / "out.psl"
    if out.exists():  # a name with a newline never splits a property over two lines
        for line in out.read_text().splitlines():
            assert line.startswith(("#", "//")) or ":" in line or not line.strip(), line
