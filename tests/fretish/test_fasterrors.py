"""Syntax errors replayed without Lark (fretish.fasterrors) against Lark itself
(fretish.parser._run_lark, the reference): the same error, byte for byte, on bad sentences -
hypothesis mutations of good ones (the generated benchmark sentences, FRET's case studies),
hand-picked mistakes, expressions - and a typo costs no Lark import."""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretish import FretishSyntaxError
from fretish import parser as P
from fretish.fasterrors import lark_failure

ROOT = Path(__file__).resolve().parents[2]
CASE_STUDIES = ROOT.parent / "shared" / "corpora" / "fret_casestudies.jsonl"

SCOPES = ["", "in m", "when not in m", "only in m", "after m", "before m", "only after m",
          "only before m", "while alt > 10", "during flight mode"]
CONDITIONS = ["", "upon c", "whenever c", "when c & !d", "upon p, or when r", "if x > 3",
              "unless q is true"]
TIMINGS = ["", "immediately", "at the next timepoint", "finally", "eventually", "always",
           "never", "within 5 ticks", "for 3 ticks", "after 2 ticks", "until s", "before s",
           "within 2.5 seconds", "at the first timepoint"]
RESPONSES = ["r", "!r | q", "x + 2 * y <= 10", "persisted(3, p) -> q", "a xor b & c",
             "occurs(2, q)", "preBool(false, p)", "(x - 1) ^ 2 > -3", '"weird name" & q']


def _generated(n: int = 150) -> list:
    rnd = random.Random(7)
    out = []
    for _ in range(n):
        parts = [rnd.choice(SCOPES), rnd.choice(CONDITIONS), "the sw shall",
                 rnd.choice(TIMINGS), "satisfy", rnd.choice(RESPONSES)]
        out.append(" ".join(p for p in parts if p))
    return out


def _corpus() -> list:
    if not CASE_STUDIES.exists():
        return []
    return [json.loads(line)["text"] for line in CASE_STUDIES.read_text().splitlines()
            if line.strip()]


GOOD = _generated() + _corpus()
#: inserted by the mutations: FRETish words, operators, punctuation, reserved words, odd
#: characters
PIECES = ["&", "|", "!", "~", "(", ")", ",", ".", "-", "+", "*", "=", "==", "<=", "<", "->",
          "=>", "<->", "shall", "satisfy", "the", "within", "for", "after", "until", "3",
          "2.5", "ticks", "tickz", "seconds", "and", "or", "not", "if", "then", "upon",
          "when", "in", "mode", "only", "T", "X", "what", "globally", "is", "true", "false",
          "with", "probability", ">= 0.5", "#", "é", '"', '"q"', "%", "@", "\n", "  ", "0x",
          "persisted(", "occurs(2,", "preBool(3, p)", "next", "previous", "occurrence", "of"]


def _outcome(run, text: str, start: str, line: int, column: int):
    try:
        result = run(start, text, "<t>", line, column)
    except FretishSyntaxError as e:
        return ("error", str(e), e.message, e.line, e.column, e.text_line, e.expected,
                e.hint, e.text_line_column, e.offset)
    return ("ok", repr(result))


def _replayed(text: str, start: str, line: int, column: int) -> bool:
    """Did the replay answer (a failure, or a builder error it re-raised) instead of
    handing the text to Lark?"""
    fast = P._get_fast()
    P._ctx.set(text, line - 1, column - 1)
    try:
        return lark_failure(fast, text, start, own=(P._Fail,)) is not None
    except P._Fail:
        return True
    finally:
        P._ctx.text = ""


def _check(text: str, start: str = "start", line: int = 1, column: int = 1) -> bool:
    """The replay's outcome is Lark's; True when the replay answered."""
    assert P._get_fast(), "the fast path's tables are not available"
    mine = _outcome(P._run_slow, text, start, line, column)
    lark = _outcome(P._run_lark, text, start, line, column)
    assert mine == lark, text
    return _replayed(text, start, line, column)


@st.composite
def mutated(draw):
    text = draw(st.sampled_from(GOOD))
    for _ in range(draw(st.integers(1, 3))):
        words = text.split(" ")
        op = draw(st.sampled_from(["insert", "delete", "swap", "cut", "char"]))
        i = draw(st.integers(0, max(0, len(words) - 1)))
        if op == "insert":
            words.insert(i, draw(st.sampled_from(PIECES)))
        elif op == "delete" and len(words) > 1:
            del words[i]
        elif op == "swap" and len(words) > 1:
            j = draw(st.integers(0, len(words) - 1))
            words[i], words[j] = words[j], words[i]
        elif op == "cut":
            words = words[:i + 1]
        text = " ".join(words)
        if op == "char" and text:
            k = draw(st.integers(0, len(text) - 1))
            text = text[:k] + draw(st.sampled_from(PIECES)) + text[k + 1:]
    return text


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated(), st.integers(1, 30), st.integers(1, 9))
def test_replayed_errors_are_larks(text, line, column):
    _check(text, "start", line, column)


@settings(max_examples=80, deadline=None)
@given(st.sampled_from(RESPONSES + ["x > 3 & y", "f(a, 2.5) = b", "persisted(3, p)"]),
       st.sampled_from(PIECES), st.integers(0, 40))
def test_replayed_expression_errors_are_larks(expr, piece, k):
    text = expr[:k] + piece + expr[k:]
    _check(text, "expr")


MISTAKES = [
    "", "   ", "the sw shall always satisfy p and q", "the sw shall always satisfy p &",
    "in m mode the sw shall within 3 tickz satisfy q", "the sw shall always satisfy x + * y",
    "globally the sw shall always satisfy p", "the sw shall globally satisfy p",
    "the sw shall always satisfy x == 1", "upon p and q the sw shall always satisfy r",
    "shall always satisfy p", "the sw always satisfy p", "the sw shall always p",
    "the sw shall always satisfy \"p", "the sw shall always satisfy p #", "the sw shall",
    "the sw shall always satisfy T > 1", "the sw shall always satisfy what",
    "the sw shall with probability >= 2 always satisfy p",
    "the sw shall with probability != 0.5 always satisfy p",
    "the sw shall always satisfy preBool(3, p)", "the sw shall within 0x1 ticks satisfy p",
    "in m upon p, the sw shall within 3 ticks satisfy x + 1 > -2 )",
    "the sw shall always satisfy a < b < c", "when in m is true the sw shall always satisfy p",
    "the sw shall at the next satisfy p", "the sw shall always satisfy é",
    "upon p the\n  sw shall within\n 2 ticks satisfy q &\n", "the the sw shall satisfy p",
    "R1: the sw shall always satisfy p", "the sw shall always satisfy p.",
    "the sw shall always satisfy p. q", "only the sw shall always satisfy p",
]


@pytest.mark.parametrize("text", MISTAKES)
def test_common_mistakes_replayed_as_lark(text):
    _check(text, "start", 4, 3)


def test_the_replay_answers_most_bad_sentences():
    """The replay is not a stub that always hands over to Lark: it answers every bad
    mutation of the corpus here (a callback error included: FRET's reserved 'T')."""
    rnd = random.Random(3)
    answered = total = 0
    for text in GOOD[:200]:
        words = text.split(" ")
        words.insert(rnd.randrange(len(words) + 1), rnd.choice(PIECES))
        bad = " ".join(words)
        if _outcome(P._run_lark, bad, "start", 1, 1)[0] == "ok":
            continue
        total += 1
        answered += _check(bad)
    assert total > 100 and answered == total


def test_a_typo_imports_no_lark(tmp_path):
    """``fretc FILE`` with bad sentences reports them without importing Lark, with the
    error of before (the tests above); Lark's own parser is built only where the replay
    hands over."""
    f = tmp_path / "bad.fret"
    f.write_text("R1: the sw shall always satisfy p &\n"
                 "R2: in m mode the sw shall within 3 tickz satisfy q\n"
                 "R3: the sw shall always satisfy T > 1\n"
                 "R4: the sw shall always satisfy q\n")
    code = ("import sys, io, contextlib\nfrom fretc.cli import main\n"
            "sys.argv = ['fretc', sys.argv[1], '--emit', 'ltl']\n"
            "err = io.StringIO()\n"
            "try:\n    with contextlib.redirect_stderr(err), "
            "contextlib.redirect_stdout(io.StringIO()):\n        main()\n"
            "except SystemExit as e:\n    code = e.code\n"
            "print(code, 'lark' in sys.modules, err.getvalue().count('error:'))")
    env = dict(os.environ, PYTHONPATH=str(ROOT), FRETC_CACHE_DIR=str(tmp_path / "c"))
    runs = [subprocess.run([sys.executable, "-c", code, str(f)], capture_output=True,
                           text=True, env=env, check=True).stdout.split() for _ in range(2)]
    # the first run may build the fast path's tables with Lark (no cache yet)
    assert runs[1] == ["1", "False", "3"]
