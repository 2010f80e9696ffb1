"""A requirement ``with probability`` whose path formula PRISM's properties cannot say (a
past-time function, an uninterpreted function) has no PCTL form, with the reason in its own
entry, and nothing else fails (``--emit ltl --json`` was an internal error, exit 4,
for the whole file, and so were ``--emit monitor`` and ``fretc audit``).

The oracle is independent of the PRISM printer: PCTL has no past and PRISM's properties no
functions but ``abs``/``min``/``max`` (PRISM manual, "Properties", "Expressions"), so a
requirement has a PCTL form exactly when its PCTL tree (the bounds where FRET puts them,
around the path formula and its triggers) holds no past-time node and no other function."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from _shared import SHARED, skip_without_shared

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ("P1: upon persisted(2, alarm) agilex_agent shall with probability > 0.24 finally "
           "satisfy q\n"
           "P2: upon alarm agilex_agent shall with probability > 0.24 finally satisfy q\n")
#: the IR's past-time operators (fretc.compiler.ir): Y, Z, H, O, S, T, the first time point
#: and a past-time function (persisted, occurred, ...)
_PAST = {"Y", "Z", "H", "O", "S", "T", "FTP", "past"}
_PRISM_FUNCTIONS = {"abs", "min", "max", "absReal", "absInt", "minReal", "minInt", "maxReal",
                    "maxInt"}


def _fretc(args, cwd=ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fretc", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=dict(os.environ, COLUMNS="200"),
                          timeout=600)


def _prism_can_say(tree) -> bool:
    """No past-time node and no function but PRISM's in the IR tree ``tree``."""
    stack, seen = [tree], set()
    while stack:
        n = stack.pop()
        if id(n) in seen:
            continue
        seen.add(id(n))
        if (n.op in _PAST or n.op == "call"  # (a boolean function: none is PRISM's)
                or (n.op == "fn" and n.name not in _PRISM_FUNCTIONS)):
            return False
        stack.extend(n.args)
    return True


def _trees(fret: Path) -> dict:
    """Requirement id -> its PCTL tree (probability requirements that formalized)."""
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements

    return {c.id: c.pctl_form().tree for c in compile_entries(load_requirements(fret))
            if c.error is None and c.probability is not None}


def _check_entries(doc: list, trees: dict) -> None:
    for e in doc:
        if "probability" not in e or "error" in e:
            continue
        assert ("pctl_unsupported" in e) == (e["pctl"] is None), e["id"]
        assert (e["pctl"] is not None) == _prism_can_say(trees[e["id"]]), e["id"]
        if e["pctl"] is None:
            assert "PRISM" in e["pctl_unsupported"], e


def test_the_issues_input_gives_json_and_the_reason_in_its_entry(tmp_path):
    fret = tmp_path / "p.fret"
    fret.write_text(EXAMPLE, encoding="utf-8")
    got = _fretc([fret, "--emit", "ltl", "--json"])
    assert got.returncode == 0, got.stderr
    p1, p2 = json.loads(got.stdout)
    assert p1["pctl"] is None and "persisted(2,alarm)" in p1["pctl_unsupported"]
    assert p1["ft_inf"] and p1["key"] == "null,regular,bound,finally,satisfaction"
    assert p2["pctl"].startswith("P>=1 [") and "pctl_unsupported" not in p2
    _check_entries([p1, p2], _trees(fret))
    text = _fretc([fret, "--emit", "ltl"])
    assert text.returncode == 0, text.stderr
    assert "  pctl    none: the past-time function persisted(2,alarm)" in text.stdout
    assert text.stdout.count("  pctl    P>=1 [") == 1


def test_the_monitor_and_the_audit_of_such_a_requirement_run(tmp_path):
    fret = tmp_path / "p.fret"
    fret.write_text(EXAMPLE, encoding="utf-8")
    mon = _fretc([fret, "--emit", "monitor", "-o", tmp_path / "m.py"])
    assert mon.returncode == 0, mon.stderr
    text = (tmp_path / "m.py").read_text(encoding="utf-8")
    assert text.count("PCTL=") == 1  # P2's alone
    (tmp_path / "t.csv").write_text("time,alarm,q\n0,1,0\n0.1,1,1\n0.2,1,1\n", encoding="utf-8")
    audit = _fretc(["audit", "-r", fret, tmp_path / "t.csv", "--no-progress"])
    assert audit.returncode in (0, 5), audit.stdout + audit.stderr  # (5: too few runs)
    assert "internal error" not in audit.stderr


def _probabilistic(text: str) -> str | None:
    """A case-study sentence with ``with probability >= 0.5`` after its ``shall``."""
    m = re.search(r"\bshall\b", text)
    return None if m is None else text[:m.end()] + " with probability >= 0.5" + text[m.end():]


def test_every_probability_sentence_of_the_vectors_and_the_corpus_gives_json(tmp_path):
    """FRET's probability vectors, and every case-study sentence made a probability one:
    one ``--emit ltl --json`` each file, exit 0, a PCTL form exactly where PRISM can say it
    (the module docstring's oracle), the reason where it cannot."""
    skip_without_shared()
    vectors = [json.loads(line) for line in
               (SHARED / "fretish" / "fret_probabilistic_vectors.jsonl").read_text().splitlines()]
    corpus = [json.loads(line) for line in
              (SHARED / "corpora" / "fret_casestudies.jsonl").read_text().splitlines()]
    sentences = [v["text"] for v in vectors] + [s for s in (_probabilistic(c["text"])
                                                            for c in corpus) if s]
    fret = tmp_path / "all.fret"
    fret.write_text("".join(f"P{i}: {' '.join(s.split())}\n" for i, s in enumerate(sentences)),
                    encoding="utf-8")
    got = _fretc([fret, "--emit", "ltl", "--json"])
    doc = json.loads(got.stdout)
    assert got.returncode in (0, 1), got.stderr  # (1: a sentence that does not parse)
    assert "internal error" not in got.stderr
    probabilistic = [e for e in doc if "probability" in e and "error" not in e]
    assert len(probabilistic) > 150
    assert any(e["pctl"] is None for e in probabilistic)
    _check_entries(doc, _trees(fret))


@pytest.mark.parametrize("text", [
    "upon persisted(2, alarm) the sw shall with probability > 0.24 finally satisfy q",
    "upon alarm the sw shall with probability >= 0.9 within 3 ticks satisfy occurred(2, q)",
    "the sw shall with probability < 0.1 always satisfy preBool(false, x) & !x",
    "the sw shall with probability > 0.5 always satisfy f(x) > 2",
])
def test_a_past_time_or_uninterpreted_function_has_no_pctl_and_says_why(text):
    from _monitor_helpers import entry
    from fretc.compiler.build import compile_entry

    c = compile_entry(entry("R", text))
    assert c.error is None, c.error
    assert c.pctl() is None and c.pctl_unsupported() is not None
    out = c.to_json()
    assert out["pctl"] is None and out["pctl_unsupported"] == c.pctl_unsupported()
    assert out["pctl_bounds"] == c.pctl_form().bounds
