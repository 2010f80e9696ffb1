"""The FRETish parser's tables shipped with fretc (``fretish/grammar_tables.json``, written by
``python -m fretc.fretish.make_tables``; :mod:`fretc.common.lark_tables`): a first run reads
them instead of building them from the grammar, they are those of ``grammar.lark`` (the
parser they make gives every sentence the AST, and every broken sentence the error, of a
parser built from the grammar), and tables of another grammar are never used."""

from __future__ import annotations

import json
import re
from pathlib import Path

import lark
import pytest

from fretc.common import lark_tables
from fretc.fretish import parser as P

ROOT = Path(__file__).resolve().parents[2]
VECTORS = ROOT.parent / "shared" / "fretish" / "fret_trace_verdicts.jsonl"


def _shipped() -> dict:
    return json.loads(Path(P.TABLES_FILE).read_text(encoding="utf-8"))


def _sentences() -> list[str]:
    """The shipped requirements' sentences, and FRET's vectors when ../shared is there."""
    out = []
    for f in sorted((ROOT / "requirements").rglob("*.fret")):
        for line in f.read_text(encoding="utf-8").splitlines():
            m = re.match(r"\s*([A-Za-z_][\w.-]*)\s*:\s*(.+)$", line)
            if m and not line.lstrip().startswith(("#", "@")):
                out.append(m.group(2))
    if VECTORS.exists():  # (FRET's 696 distinct sentences)
        for line in VECTORS.read_text(encoding="utf-8").splitlines():
            out += [c["sentence"] for c in json.loads(line).get("cases", ())]
    return list(dict.fromkeys(out))


def _outcome(parser, text: str) -> str:
    """What ``parser`` makes of ``text`` (its builder set up as fretish.parser._run does):
    the AST, or the error's kind, place and expected tokens."""
    parser.options.transformer.begin(text, 1, 1)
    try:
        return repr(parser.parse(text, start="start"))
    except lark.exceptions.UnexpectedInput as exc:
        return repr((type(exc).__name__, getattr(exc, "line", None), getattr(exc, "column", None),
                     sorted(getattr(exc, "expected", None) or ())))
    except Exception as exc:  # noqa: BLE001 - a builder's error: compared as it is
        return repr((type(exc).__name__, str(exc)))


def test_the_shipped_tables_are_those_of_the_grammar():
    doc = _shipped()
    if doc["lark"] != lark.__version__:
        pytest.skip(f"the shipped tables were made with Lark {doc['lark']}, this is "
                    f"{lark.__version__}: python -m fretc.fretish.make_tables")
    assert doc["key"] == lark_tables.shipped_key("fretish", P._read_grammar(),
                                                 P._LARK_OPTIONS), (
        "grammar.lark changed since the shipped tables: python -m fretc.fretish.make_tables")


def test_a_first_run_reads_them_and_parses_as_the_grammar(tmp_path, monkeypatch):
    """An empty cache folder: the parser comes from the shipped tables (never built), then
    is kept in the cache; every sentence, and every sentence with a word left out, parses
    (or fails) as with a parser built from the grammar."""
    if _shipped()["lark"] != lark.__version__:
        pytest.skip("the shipped tables were made with another Lark")
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    built = P.build_lark()

    def refuse(**_options):
        raise AssertionError("built, not read from the shipped tables")

    monkeypatch.setattr(P, "build_lark", refuse)
    shipped = P.cached_lark()
    assert len(list((tmp_path / "lark").iterdir())) == 1  # kept in the cache
    texts = _sentences()
    assert len(texts) > 20
    broken = [" ".join(w for k, w in enumerate(t.split()) if k != j)
              for t in texts[:40] for j in range(len(t.split()))]
    for text in texts + broken:
        assert _outcome(shipped, text) == _outcome(built, text), text


def test_tables_of_another_grammar_are_not_used(tmp_path, monkeypatch):
    """Shipped tables whose key is not the grammar's (an edited grammar, another Lark) are
    left aside: the parser is built from the grammar."""
    doc = _shipped()
    doc["key"] = "0" * 64
    other = tmp_path / "tables.json"
    other.write_text(json.dumps(doc), encoding="utf-8")
    monkeypatch.setenv("FRETC_CACHE_DIR", "")
    monkeypatch.setattr(P, "TABLES_FILE", str(other))
    calls = []
    real = P.build_lark

    def counted(**options):
        calls.append(1)
        return real(**options)

    monkeypatch.setattr(P, "build_lark", counted)
    parser = P.cached_lark()
    assert calls == [1]
    text = "the sw shall always satisfy x"
    assert _outcome(parser, text) == _outcome(real(), text)
