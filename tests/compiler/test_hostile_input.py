"""Hostile requirements: generated monitors valid for every accepted requirement, depth and
size limits with positioned errors, a linear parser error path.

Each generated module is loaded and stepped in a separate ``python -I -S`` (as a user copies
it into a ROS node), so a module that does not load or run fails the test."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.fretish import limits
from fretc.common.errors import FretishSyntaxError
from fretc.fretish.parser import parse

ROOT = Path(__file__).resolve().parents[2]

# Loads a generated module, steps every monitor over ticks of all-0 / all-1 / mixed values
# and prints one JSON line per monitor: id, verdicts, status, finish.
_RUNNER = r"""
import json, sys
ns = {}
exec(compile(open(sys.argv[1], encoding="utf-8").read(), sys.argv[1], "exec"), ns)
out = {}
for rid, cls in ns["MONITORS"].items():
    m = cls()
    vs = []
    for t in range(6):
        vs.append(m.step({v: (t + i) % 3 == 0 for i, v in enumerate(cls.VARIABLES)}))
    out[rid] = [vs, m.status, m.finish()]
print(json.dumps({"monitors": out, "skipped": ns["SKIPPED"]}))
"""


def emit_and_run(tmp_path, text: str, name: str = "t"):
    """``fretc FILE --emit monitor -o``, then load and step it under ``python -I -S``."""
    f = tmp_path / f"{name}.fret"
    f.write_text(text, encoding="utf-8")
    out = tmp_path / f"{name}_monitors.py"
    res = CliRunner().invoke(main, [str(f), "--emit", "monitor", "-o", str(out)])
    assert res.exit_code == 0, res.output
    proc = subprocess.run([sys.executable, "-I", "-S", "-c", _RUNNER, str(out)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout)


def fret_error(text: str) -> FretishSyntaxError:
    with pytest.raises(FretishSyntaxError) as info:
        parse(text, source="r.fret", line=3)
    return info.value


# ------------------------------------------------------------------ item 1: > 10 variables
def test_more_than_ten_variables_loads_and_runs(tmp_path):
    many = " & ".join(f"a{i}" for i in range(12))
    res = emit_and_run(tmp_path, f"R: upon go the sw shall within 3 ticks satisfy {many}\n")
    vs, status, fin = res["monitors"]["R"]
    assert len(vs) == 6 and status in ("unknown", "violated", "satisfied")


def test_case_study_eb_requirements(tmp_path, shared):
    corpus = shared / "corpora" / "fret_casestudies.jsonl"
    rows = [json.loads(line) for line in corpus.read_text(encoding="utf-8").splitlines()]
    eb = [r for r in rows if r["id"].endswith(("#EB-001", "#EB-002"))]
    assert len(eb) == 2
    text = "".join(f"EB{i}: {' '.join(r['text'].split())}\n" for i, r in enumerate(eb))
    res = emit_and_run(tmp_path, text)
    assert set(res["monitors"]) == {"EB0", "EB1"}


# ------------------------------------------------------------------ item 2: long chains
@pytest.mark.parametrize("op", ["xor", "&", "|", "->", "<->"])
def test_two_hundred_chained_operators(tmp_path, op):
    chain = f" {op} ".join(f"p{i}" for i in range(200))
    t0 = time.process_time()
    res = emit_and_run(tmp_path, f"R: the sw shall always satisfy {chain}\n")
    assert "R" in res["monitors"]
    assert time.process_time() - t0 < 20


def test_chained_xor_is_evaluated_right(tmp_path):
    chain = " xor ".join(f"p{i}" for i in range(60))
    res = emit_and_run(tmp_path, f"R: the sw shall always satisfy {chain}\n")
    vs, _, _ = res["monitors"]["R"]
    # p_i = (t + i) % 3 == 0: the number of true p_i among 60 is 20 at every tick (even)
    assert vs == [False] * 6


# ------------------------------------------------------------------ item 3: inf constants
def test_overflowing_constant_is_infinity(tmp_path):
    res = emit_and_run(tmp_path, "R: the sw shall always satisfy x < 1e999 & y > -1e999\n")
    vs, _, fin = res["monitors"]["R"]
    assert vs == [True] * 6 and fin is True


def test_invalid_module_is_an_internal_error_not_exit_0(tmp_path, monkeypatch):
    """Should code generation ever produce a module that does not load or run, the CLI
    says so and exits 3; the other requirements of the file keep their monitors."""
    from fretc.compiler import codegen, pt_step

    monkeypatch.setattr(pt_step, "_number", lambda text: "inf" if "e" in text else text)
    f = tmp_path / "t.fret"
    f.write_text("A: the sw shall always satisfy x < 1e9\nB: the sw shall always satisfy p\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "monitor", "-o", str(tmp_path / "o.py")])
    assert res.exit_code == 4
    assert "internal error" in res.output and "undefined names inf" in res.output
    assert not (tmp_path / "o.py").exists()
    errors: list = []
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    text = codegen.render_module(compile_entries(load_requirements([f])), "m", errors)
    ns = {}
    exec(text, ns)
    assert list(ns["MONITORS"]) == ["B"] and "internal error" in ns["SKIPPED"]["A"]
    assert errors and errors[0].ids == ["A"]


# ------------------------------------------------------------------ item 4: deep nesting
@pytest.mark.parametrize("text,col", [
    ("the sw shall always satisfy " + "!" * 989 + "p", None),
    ("the sw shall always satisfy q" + " & p" * 989, 29),
    ("the sw shall always satisfy " + "absReal(" * 60 + "x" + ")" * 60 + " > 0", None),
])
def test_deep_nesting_is_a_positioned_error(text, col):
    e = fret_error(text)
    assert e.line == 3 and "nested more than" in str(e)
    if col is not None:
        assert e.column == col
    assert str(e).startswith("r.fret:3:")


@pytest.mark.parametrize("as_json", [False, True])
def test_deep_nesting_through_the_cli(tmp_path, as_json):
    f = tmp_path / "t.fret"
    f.write_text("A: the sw shall always satisfy " + "!" * 989 + "p\n"
                 "B: the sw shall always satisfy " + "!" * 496 + "p\n"
                 "C: the sw shall always satisfy p\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "ltl"] + (["--json"] if as_json else []))
    assert res.exit_code == 1 and res.exception is None or isinstance(res.exception,
                                                                         SystemExit)
    assert "t.fret:1:" in res.stderr and "t.fret:2:" in res.stderr
    if as_json:
        data = json.loads(res.stdout)
        assert [d["id"] for d in data] == ["A", "B", "C"] and "error" not in data[2]


def test_at_the_depth_limit_everything_works(tmp_path):
    n = limits.MAX_EXPR_DEPTH
    text = ("A: the sw shall always satisfy " + "!" * (n - 1) + "p\n"
            "B: upon q the sw shall within 4 ticks satisfy "
            + " xor ".join(f"p{i}" for i in range(n)) + "\n")
    res = emit_and_run(tmp_path, text)
    assert set(res["monitors"]) == {"A", "B"}
    f = tmp_path / "t.fret"
    for emit in (["ltl", "--json"], ["psl"]):
        r = CliRunner().invoke(main, [str(f), "--emit"] + emit)
        assert r.exit_code == 0, r.output


# ------------------------------------------------------------------ item 5: long numbers
@pytest.mark.parametrize("text", [
    "the sw shall within 1" + "0" * 4400 + " ticks satisfy p",
    "the sw shall always satisfy x < 1" + "0" * 4400,
])
def test_long_numbers_are_positioned_errors(text):
    e = fret_error(text)
    assert "beyond the limit of 100 characters" in str(e)
    assert e.column == text.index("1" + "0" * 100) + 1


@pytest.mark.parametrize("text", [
    "in m mode the sw shall after 15000 ticks satisfy p",
    "upon q the sw shall within 15000 ticks satisfy p",
    "only before m mode the sw shall after 15000 ticks satisfy p",
])
def test_long_durations_generate_valid_monitors(tmp_path, text):
    res = emit_and_run(tmp_path, f"R: {text}\n")
    assert "R" in res["monitors"]


def test_duration_limit_in_ticks(tmp_path):
    f = tmp_path / "t.fret"
    f.write_text("@tick_period 1 ms\nA: the sw shall within 10 hours satisfy p\n"
                 "B: the sw shall always satisfy persisted(2000000, p)\n"
                 "C: the sw shall within 2000000 ticks satisfy p\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "ltl"])
    assert res.exit_code == 1
    assert "t.fret:2:" in res.stderr and "36,000,000 ticks is beyond" in res.stderr
    assert "t.fret:3:" in res.stderr and "2,000,000 ticks" in res.stderr
    assert "t.fret:4:" in res.stderr


# ------------------------------------------------------------------ item 6: linear errors
def test_error_after_a_long_identifier_is_linear():
    def cost(n):
        text = "the sw shall always satisfy " + "a" * n + " > 5 )"
        t0 = time.process_time()
        with pytest.raises(FretishSyntaxError):
            parse(text)
        return time.process_time() - t0

    cost(1000)
    small, big = cost(4000), cost(40000)
    # quadratic: 100x for 10x the text (23 s at 40,000 characters before the fix)
    assert big < 2.0 and big < 25 * max(small, 1e-3)


def test_previous_word_hints_still_work():
    e = fret_error("globally the sw shall always satisfy p")
    assert "'globally' is not FRETish" in str(e)
    e = fret_error("upon p and q the sw shall always satisfy r")
    assert "after 'and'" in str(e)


# ------------------------------------------------------------------ item 15: fuzz findings
@pytest.mark.parametrize("text", [
    "before mm whenever cc the sw shall after 999999 ticks satisfy rr",  # 110 s before
    "after mm upon cc the sw shall after 8 ticks satisfy rr | "
    + " | ".join(f"p{k}" for k in range(12)),  # 7 s in Spot
    "only after mm the sw shall finally satisfy rr & "
    + " & ".join(f"w{k}" for k in range(30)),  # minutes and gigabytes in Spot
])
def test_fuzzed_slow_requirements_generate_quickly(text):
    from fretc.compiler.build import compile_entry
    from fretc.compiler.codegen import monitor_source
    from fretc.fretish.files import RequirementEntry

    entry = RequirementEntry(id="R", text=text, source="f", line=1, column=1,
                             requirement=parse(text))
    c = compile_entry(entry)
    t0 = time.process_time()
    ms = monitor_source(c, 0)
    assert time.process_time() - t0 < 5
    assert ms.status_note.startswith("no LTL3 monitor")


@pytest.mark.parametrize("call, want", [("absReal()", "absReal takes 1 argument, not 0"),
                                        ("absInt(x, y)", "absInt takes 1 argument, not 2"),
                                        ("maxReal(x)", "maxReal takes 2 arguments, not 1"),
                                        ("minInt()", "minInt takes 2 arguments, not 0"),
                                        ("maxInt(x, y, z)", "maxInt takes 2 arguments, not 3")])
def test_numeric_function_arity_is_a_positioned_error(tmp_path, call, want):
    # found by bench/fuzz.py: these generated abs()/max() calls that fail at run time
    f = tmp_path / "a.fret"
    f.write_text(f"A: the sw shall always satisfy {call} > 2\n")
    res = CliRunner().invoke(main, [str(f), "--emit", "monitor"])
    assert res.exit_code == 1, res.output
    assert f"a.fret:1:32: error: {want}" in res.output
