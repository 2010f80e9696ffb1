"""``--emit cocospec`` on FRET's case studies: each Internal variable's definition that fretc
writes (re-printed from its reading of FRET's Lustre subset, never the glossary's text) means
what FRET's own text means as Lustre. Both are read by the tests' Lustre reader
(``tests/_lustre_subset.py``) and run on random traces of the contract's variables: the
contract as written, and the same contract with each ghost defined by the glossary's
``assignment`` as FRET's export pastes it, give every ghost the same value at every tick
(LMCPS's NN tables, written as one ghost per ``pre`` group, included)."""

from __future__ import annotations

import json
import math
import random
import sys
from pathlib import Path

from fretc.compiler.build import compile_entries
from fretc.compiler.cocospec import emit_cocospec
from fretc.fretish.files import load_requirements

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import _lustre_subset as lus  # noqa: E402


def _same(x, y) -> bool:
    if isinstance(x, float) and isinstance(y, float):
        return (math.isnan(x) and math.isnan(y)) or math.isclose(x, y, rel_tol=1e-12,
                                                                   abs_tol=1e-12)
    return x == y


def _value(rng: random.Random, ty: str):
    if ty == "bool":
        return rng.random() < 0.5
    return rng.randint(-3, 4) if ty == "int" else rng.choice([-2.5, 0.0, 1.0, 3.5, 40.0])


def test_written_definitions_mean_the_glossarys_text(shared):
    rng = random.Random(11)
    compared = 0
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 20000))  # (FRET's 199-deep tables, read as written)
    try:
        for path in sorted((shared / "corpora/fret_projects").glob("*/*.json")):
            glossary = {(v["component_name"], v["variable_name"]): v["assignment"].strip()
                        for v in json.loads(path.read_text()).get("variables", [])
                        if v.get("idType") == "Internal" and (v.get("assignment") or "").strip()}
            files, _skipped, _notes = emit_cocospec(
                compile_entries(load_requirements([str(path)])))
            for stem, text in files.items():
                program = lus.read(text)
                if stem not in program:
                    continue
                written = program[stem]
                fret = {name: lus.Reader(glossary[(stem[:-4], name)]).expr()
                        for name in written.eqs if (stem[:-4], name) in glossary}
                theirs = {**program, stem: lus.Node(
                    stem, "contract", written.params, written.returns, written.locals,
                    {**written.eqs, **fret}, written.props)}
                signals = written.params + written.returns
                for _ in range(4):
                    trace = [{v: _value(rng, ty) for v, ty in signals} for _ in range(8)]
                    inputs = {v: (lambda t, v=v, tr=trace: tr[t][v]) for v, _ty in signals}
                    ours = lus.Instance(program, written, inputs)
                    glossary_run = lus.Instance(theirs, theirs[stem], inputs)
                    for name in fret:
                        for t in range(len(trace)):
                            a, b = ours.value(name, t), glossary_run.value(name, t)
                            assert _same(a, b), (path.name, stem, name, t, a, b)
                compared += len(fret)
    finally:
        sys.setrecursionlimit(old)
    # every Internal definition of the case studies is written: 63 of LMCPS (expressions,
    # streams, its three 199-deep tables), FSM's 7 states, the 4 modes of each LPC export
    assert compared == 78, compared
