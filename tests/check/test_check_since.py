"""``fretc check`` reads a FRET boolean stream monotone in its previous value (the mode latch
``m := false -> (enter or (pre m and not exit))``) as its past-time formula ``P S psi``
(fretish/fret_since.py): no stream, no stream abstraction note, and the safety game's answer
is exact where the stream read as a free proposition of the environment's was not."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

LATCH = "false -> (enter or (pre m and not exit))"


def _var(name: str, kind: str, assignment: str = "") -> dict:
    return {"project": "P", "component_name": "ctrl", "variable_name": name, "idType": kind,
            "dataType": "boolean", "assignment": assignment}


def _check(tmp_path: Path, texts: list[str], m: str = LATCH, *args: str
           ) -> tuple[int, dict]:
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"requirements": [
        {"reqid": f"R{k + 1}", "project": "P", "fulltext": t} for k, t in enumerate(texts)],
        "variables": [_var("enter", "Input"), _var("exit", "Input"), _var("o", "Output"),
                      _var("m", "Internal", m)]}), encoding="utf-8")
    got = CliRunner().invoke(main, ["check", str(path), "--no-progress", "--json", *args])
    return got.exit_code, json.loads(got.output)


def _no_stream(doc: dict) -> None:
    assert "streams" not in doc["realizability"], doc["realizability"]
    assert not [a for a in doc["abstractions"] if "stream variable" in a["why"]]
    assert any(n.startswith("m: FRET defines it (Internal) as " + LATCH + "; that definition "
                            "is a stream with state monotone in its previous value: exactly "
                            "the past-time formula P S psi") for n in doc["notes"]), doc["notes"]


def test_the_latch_is_exact_where_a_free_stream_was_not(tmp_path):
    """``exit & !enter`` resets the latch: o may be false then, so the set is realizable.
    A stream not monotone in its previous value in its place (``pre m xor exit``) reads
    booleans only: check reads it by its state bit (tests/check/test_stream_bits.py), no
    stream, and exactly: ``exit & !enter`` after a tick where it was false makes it true,
    so o must be true and false, unrealizable (read as an independent proposition of the
    environment's, as before, the answer was unknown)."""
    texts = ["whenever m ctrl shall immediately satisfy o",
             "whenever exit & !enter ctrl shall immediately satisfy !o"]
    code, doc = _check(tmp_path, texts)
    assert code == 0 and [g["realizable"] for g in doc["realizability"]["groups"]] \
        == [True], doc
    _no_stream(doc)
    (tmp_path / "t").mkdir()
    code, doc = _check(tmp_path / "t", texts, "false -> (enter or (pre m xor exit))")
    assert "streams" not in doc["realizability"], doc["realizability"]
    assert code == 1 and [g["realizable"] for g in doc["realizability"]["groups"]] \
        == [False], doc


def test_the_latch_set_by_enter_is_unrealizable_with_the_latch_read_exactly(tmp_path):
    """``enter`` at a tick after the first sets the latch: o must be true and false. The
    inputs that defeat every controller are those: a tick, then ``enter``."""
    code, doc = _check(tmp_path, ["whenever m ctrl shall immediately satisfy o",
                                  "whenever enter ctrl shall immediately satisfy !o"])
    [group] = doc["realizability"]["groups"]
    assert code == 1 and group["realizable"] is False, doc
    _no_stream(doc)


def test_a_latch_at_its_first_tick_is_false(tmp_path):
    """``false -> ...``: at the first tick the latch is false whatever ``enter`` does, so
    asking for it ``at the first timepoint`` is unrealizable (read as a free proposition it
    would be the environment's to give)."""
    code, doc = _check(tmp_path, ["ctrl shall at the first timepoint satisfy m & o"])
    assert code == 1 and [g["realizable"] for g in doc["realizability"]["groups"]] == [False]
    _no_stream(doc)


def test_witnesses_say_nothing_of_a_stream_for_the_latch(tmp_path):
    """The witnesses' note on stream columns (check's witness note) names streams only:
    the latch is a definition there, its values the formula's."""
    code, doc = _check(tmp_path, ["whenever m ctrl shall immediately satisfy o"], LATCH,
                       "--witness-dir", str(tmp_path / "w"))
    assert code == 0 and doc["witnesses"], doc
    assert not [n for n in doc["notes"] if "stream variable" in n], doc["notes"]
    _no_stream(doc)
