"""``fretc testgen`` and ``fretc check``'s witnesses on requirements reading FRET stream
variables (an Internal variable whose Lustre definition reads itself through ``pre``): each
trace's stream column is the one the audit computes from the columns of the variables the
definition reads, z3 chooses those variables so that the comparisons reading the stream take
the truth values the engines' model asks (:mod:`fretc.check.stream_rows`), and every
expected verdict is the audit's, also where a comparison reads NaN (``x / 0``), which the
audit's NaN rule leaves unknown (:func:`fretc.monitors.judge3.verdict_under_nan`).

The differential check: every generated test's trace is audited by ``fretc audit`` and its
verdicts compared with the test's expected ones (a test that cannot be replayed as written
would fail it). Before, the stream column held the engines' free values, and AP-010b's
expected ``satisfied`` was ``violated`` by the audit on LMCPS."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings, strategies as st

from fretc.check.stream_rows import trace_streams, value_at, with_stream_columns
from fretc.cli import main
from fretc.compiler.stream_code import stream_columns
from fretc.fretish.fret_streams import stream_system
from fretc.fretish.fret_variables import fret_variables

LMCPS = (Path(__file__).resolve().parents[3] / "shared" / "corpora" / "fret_projects"
         / "LMCPS" / "LM_requirements.json")


def _var(name: str, kind: str, data_type: str, assignment: str = "") -> dict:
    return {"project": "P", "component_name": "ctrl", "variable_name": name, "idType": kind,
            "dataType": data_type, "assignment": assignment}


def _export(folder: Path, texts: list[str], variables: list[dict]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "p.json"
    path.write_text(json.dumps({"requirements": [
        {"reqid": f"R{k + 1}", "project": "P", "fulltext": t} for k, t in enumerate(texts)],
        "variables": variables}), encoding="utf-8")
    return path


#: a held value (LMCPS's psiAtZero's shape), a latch, an accumulator, a pre of a pre
_DEFS = [("held", "double", "y -> if b then y else pre held"),
         ("latched", "boolean", "b -> b or pre latched"),
         ("acc", "double", "0.0 -> pre acc + y"),
         ("late", "double", "y -> if b then pre (pre y) else pre late"),
         ("edge", "boolean", "false -> (b and not pre b) or (pre edge and y > 1.0)")]


def _variables() -> list[dict]:
    return [_var("b", "Input", "boolean"), _var("y", "Input", "double"),
            _var("o", "Output", "boolean")] + [_var(n, "Internal", t, d) for n, t, d in _DEFS]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.sampled_from([-2.0, 0.0, 0.5, 1.5, 3.0])),
                min_size=1, max_size=12))
def test_value_at_is_the_audits_stream_code(ticks):
    """The plain evaluator z3's queries read the past through (:func:`value_at`) gives, tick
    by tick, the audit's column (:func:`fretc.compiler.stream_code.stream_columns`) for every
    definition shape of :data:`_DEFS`."""
    variables = tuple(fret_variables({"variables": _variables(), "requirements": []}, "p"))
    rows = [{"b": b, "y": y} for b, y in ticks]
    for name, _t, _d in _DEFS:
        system = stream_system(variables, [name])
        assert system is not None
        cols = {"b": np.array([r["b"] for r in rows]), "y": np.array([r["y"] for r in rows])}
        want = stream_columns(system, cols, len(rows))
        built: list[dict] = []
        for t, r in enumerate(rows):
            row = dict(r)
            for n, e in zip(system.names, system.exprs):
                row[n] = value_at(e, built + [row], t)
            built.append(row)
        for n in system.names:
            got = [r[n] for r in built]
            assert [bool(v) if isinstance(v, bool) else float(v) for v in got] == \
                want[n].tolist(), (name, n)


def test_stream_columns_are_recomputed_from_the_rows():
    """A row's stream value is replaced by the computed one; rows without an input keep
    theirs (nothing to compute it from), and the rows given are not changed."""
    variables = tuple(fret_variables({"variables": _variables(), "requirements": []}, "p"))

    class Item:
        entry = type("E", (), {"variables": variables})()

    streams = trace_streams([Item()], ["held", "o"])
    assert streams is not None and set(streams.exprs) == {"held"}
    rows = [{"b": False, "y": 1.0, "held": 99.0}, {"b": True, "y": 2.0, "held": 99.0},
            {"b": False, "y": 3.0, "held": 99.0}]
    got = with_stream_columns(rows, streams)
    assert [r["held"] for r in got] == [1.0, 2.0, 2.0]
    assert rows[0]["held"] == 99.0


def _audit_verdicts(req: Path, trace: Path, out: Path) -> dict[str, str]:
    CliRunner().invoke(main, ["audit", "-r", str(req), str(trace), "--json", str(out),
                              "--no-progress", "--tick-period", "1s"])
    doc = json.loads(out.read_text(encoding="utf-8"))
    return {v["requirement"]: v["verdict"] for v in doc["logs"][0]["verdicts"]}


def _generated_match_the_audit(req: Path, out: Path, *args: str) -> dict:
    got = CliRunner().invoke(main, ["testgen", str(req), "-o", str(out), "--tick-period",
                                    "1s", *args])
    assert got.exit_code in (0, 3), got.output  # (3: some obligations unknown)
    doc = json.loads((out / "tests.json").read_text(encoding="utf-8"))
    assert doc["tests"], got.output
    for t in doc["tests"]:
        audited = _audit_verdicts(req, out / t["trace"], out / f"{t['id']}.json")
        assert audited == t["expected"], (t["id"], (out / t["trace"]).read_text())
    return doc


def test_generated_tests_of_stream_readers_are_the_audits(tmp_path):
    """Requirements reading a held value, a latch and an accumulator: each test's expected
    verdicts are the audit's on its trace. R4's response false needs ``held`` (the ``y`` of
    the last tick ``b`` held) 2 or more above the present ``y``: z3 must choose ``y`` and
    ``b`` across ticks by the definition. R1's response false is impossible (``held`` is
    ``y`` whenever ``b``): never covered, and never a test claiming it."""
    req = _export(tmp_path / "req", [
        "whenever b ctrl shall immediately satisfy held <= y",
        "whenever latched ctrl shall immediately satisfy o",
        "ctrl shall always satisfy acc < 10.0 | o",
        "ctrl shall always satisfy held < y + 2.0"], _variables())
    doc = _generated_match_the_audit(req, tmp_path / "t")
    covered = {(c["requirement"], c["obligation"]) for t in doc["tests"] for c in t["covers"]}
    assert {("R4", "response:held < (y + 2.0)-"), ("R4", "response:held < (y + 2.0)+"),
            ("R1", "response:held <= y+"), ("R3", "response:acc < 10.0-")} <= covered
    assert ("R1", "response:held <= y-") not in covered
    assert "R1 response:held <= y-" in {f"{o['requirement']} {o['obligation']}"
                                        for o in doc["unknown"] + doc["unmeetable"]}


def test_a_stream_of_one_component_is_computed_in_another_components_tests(tmp_path):
    """R2's traces (component ``other``, whose export defines no stream) carry ``k``'s column
    too, as every test holds every variable of the set: it is computed there as well (``k``
    is 5 at every tick), so R1's expected verdict on them is the audit's (before: the
    column's default 0, and R1 ``violated`` where the audit says ``satisfied``)."""
    variables = _variables() + [
        _var("k", "Internal", "double", "5.0 -> pre k + 0.0"),
        {**_var("c", "Input", "boolean"), "component_name": "other"},
        {**_var("p", "Output", "boolean"), "component_name": "other"}]
    req = _export(tmp_path / "req", ["ctrl shall always satisfy k > 1.0",
                                     "whenever c other shall immediately satisfy p"],
                  variables)
    doc = _generated_match_the_audit(req, tmp_path / "t")
    assert any(t["generated_for"]["requirement"] == "R2" for t in doc["tests"])


def test_a_division_by_zero_gives_the_audits_unknown(tmp_path):
    """A requirement dividing by a difference the trace leaves 0 (``y / (y - y0)``) reads
    NaN there: its expected verdict is the audit's under the NaN rule, never the interval
    semantics' reading of NaN as false."""
    variables = [_var("y", "Input", "double"), _var("y0", "Input", "double"),
                 _var("b", "Input", "boolean"), _var("o", "Output", "boolean")]
    req = _export(tmp_path / "req", ["whenever b ctrl shall immediately satisfy o",
                                     "ctrl shall always satisfy y / (y - y0) <= 2.0 | o"],
                  variables)
    _generated_match_the_audit(req, tmp_path / "t")


@pytest.mark.skipif(not LMCPS.exists(), reason="needs ../shared/corpora/fret_projects/LMCPS "
                    "(FRET's LMCPS case-study export)")
def test_lmcps_stream_readers_generated_tests_are_the_audits(tmp_path):
    """FRET's LMCPS AP-010bv2, AP-010b and AP-004b (reading psiAtZero, rollAtZero, and
    dividing by differences): every obligation covered, every expected verdict the audit's
    (before: free stream values, and 8 of the 6 tests' 18 expected verdicts were not)."""
    doc = json.loads(LMCPS.read_text(encoding="utf-8"))
    ids = ("AP-010bv2", "AP-010b", "AP-004b")
    doc["requirements"] = [r for r in doc["requirements"] if r.get("reqid") in ids]
    folder = tmp_path / "req"
    folder.mkdir()
    req = folder / "lm.json"
    req.write_text(json.dumps(doc), encoding="utf-8")
    got = _generated_match_the_audit(req, tmp_path / "t")
    assert not got["unknown"] and not got["unmeetable"]
    covered = {(c["requirement"], c["obligation"]) for t in got["tests"] for c in t["covers"]}
    assert len(covered) == len(got["obligations"])


def test_witnesses_compute_the_stream(tmp_path):
    """``fretc check --witness-dir`` on a set reading a held value: the witness's ``held``
    column is computed from its ``y`` and ``b`` columns, and its expected verdicts are the
    audit's."""
    req = _export(tmp_path / "req", ["whenever b ctrl shall immediately satisfy held <= y",
                                     "ctrl shall always satisfy o"], _variables())
    got = CliRunner().invoke(main, ["check", str(req), "--no-progress", "--json",
                                    "--witness-dir", str(tmp_path / "w")])
    doc = json.loads(got.output)
    assert doc["witnesses"], doc
    for w in doc["witnesses"]:
        path = Path(w["path"])
        lines = [x for x in path.read_text(encoding="utf-8").splitlines()
                 if not x.startswith("#")]
        head = lines[0].split(",")
        rows = [dict(zip(head, x.split(","))) for x in lines[1:]]
        held = None
        for t, r in enumerate(rows):
            y = float(r["y"])
            held = y if t == 0 or r["b"] == "true" else held
            assert math.isclose(float(r["held"]), held), (t, rows)
        assert _audit_verdicts(req, path, tmp_path / "a.json") == w["expected"]
