"""The probability field is carried, never dropped: IR, --emit ltl (text, JSON), monitors,
and a positioned refusal in --emit psl (the PCTL's bounds: tests/compiler/test_pctl.py)."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

from click.testing import CliRunner

from fretc.compiler.build import compile_entries
from fretc.compiler.ir import ProbabilityBound
from fretc.cli import main
from fretc.fretish.files import load_requirements

import _pctl
from _shared import needs_shared

ROOT = Path(__file__).resolve().parents[2]
VECTORS = ROOT.parent / "shared" / "fretish" / "fret_vectors.jsonl"
TEXT = ("P1: the robot shall with probability >= 0.95 within 2 ticks satisfy stopped\n"
        "PL: the robot shall always satisfy stopped\n")


def _file(tmp_path, text=TEXT):
    p = tmp_path / "p.fret"
    p.write_text(text)
    return p


def test_ir_carries_the_bound_through_pickling(tmp_path):
    c, plain = compile_entries(load_requirements([str(_file(tmp_path))]))
    assert c.probability == ProbabilityBound(">=", "0.95") and plain.probability is None
    assert c.pctl() == "P>=0.95 [ (F<=2 stopped) ]"  # no trigger: one bound around the whole
    f = pickle.loads(pickle.dumps(c.formalization))  # a plan shipped to Ray workers
    assert f.probability == c.probability and f.probability.p == 0.95


def test_emit_ltl_shows_the_pctl_form(tmp_path):
    out = CliRunner().invoke(main, [str(_file(tmp_path)), "--emit", "ltl"]).output
    assert "pctl    P>=0.95 [ (F<=2 stopped) ]" in out and "applies to each trigger" in out
    doc = json.loads(CliRunner().invoke(main, [str(_file(tmp_path)), "--emit", "ltl",
                                               "--json"]).output)
    assert doc[0]["probability"] == {"op": ">=", "p": 0.95, "text": "0.95"}
    assert doc[0]["pctl"].startswith("P>=0.95 [") and "probability" not in doc[1]


@needs_shared
def test_every_probability_vector_of_fret_prints_its_bound(tmp_path):
    rows = [json.loads(line) for line in VECTORS.read_text().splitlines() if line.strip()]
    rows = [r for r in rows if "probability" in r["text"] and not r["parse_error"]]
    assert rows
    f = _file(tmp_path, "".join(f"V{r['id']}: {r['text']}\n" for r in rows))
    out = CliRunner().invoke(main, [str(f), "--emit", "ltl"]).output
    pctl = [line[10:] for line in out.splitlines() if line.startswith("  pctl    ")]
    inf = [line[10:] for line in out.splitlines() if line.startswith("  ft_inf  ")]
    assert len(pctl) == len(rows) == len(inf)
    for p, i in zip(pctl, inf):  # the bounds removed: the path formula is ft_inf
        assert _pctl.spot_text(_pctl.read(p)) == _pctl.spot_text(_pctl.read(i))


def test_psl_of_a_probability_requirement_is_a_positioned_refusal(tmp_path):
    f = _file(tmp_path)
    res = CliRunner().invoke(main, [str(f), "--emit", "psl", "-o", str(tmp_path / "out")])
    assert res.exit_code == 2
    assert f"{f}:1:21: error:" in res.output and "AJPF has no probabilities" in res.output
    assert not (tmp_path / "out").exists()


def test_monitor_module_says_the_bound_is_per_trigger(tmp_path):
    out = tmp_path / "m.py"
    res = CliRunner().invoke(main, [str(_file(tmp_path)), "--emit", "monitor", "-o", str(out)])
    assert res.exit_code == 0, res.output
    text = out.read_text()
    assert "The\nbound applies to EACH TRIGGER, across runs" in text
    ns: dict = {}
    exec(compile(text, str(out), "exec"), ns)
    m = ns["MONITORS"]["P1"]
    assert m.PROBABILITY == (">=", 0.95) and m.PCTL.startswith("P>=0.95")
    assert not hasattr(ns["MONITORS"]["PL"], "PCTL")
    mon = m()
    mon.run([{"stopped": False}] * 4)
    assert mon.finish() is False  # the path formula of this one run


def test_check_and_explain_read_the_bound_per_trigger(tmp_path):
    f = _file(tmp_path, "P2: upon too_close the robot shall with probability >= 0.9 within 1 "
                        "tick satisfy stopped\nQ: the robot shall always satisfy !stopped\n")
    res = CliRunner().invoke(main, ["check", str(f)])
    assert res.exit_code == 0, res.output  # P2 is no property of every run: no conflict
    assert "P2 (" in res.output and "bounds the chance of each trigger's obligation" in res.output
    out = CliRunner().invoke(main, ["explain", str(f), "P2"]).output
    assert "P2  (null,regular,bound,within,satisfaction)" in out
    assert "shall, with probability >= 0.9 at each trigger, satisfy stopped" in out
    assert "triggers (P>=0.9 each)" in out and "a failed trial, not a violation" in out
