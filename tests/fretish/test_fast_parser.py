"""The parser's fast path (fretish.fastparse._FastParser: Lark's LALR table run by a plain loop,
one lexer regexp split by first character) against Lark itself (fretish.parser._run_lark,
the reference): on every sentence the fast path accepts, the same AST with the same spans;
every sentence Lark accepts is accepted by the fast path too (else the speed is silently
lost); and through the public ``parse``, the same error text for every rejected one."""

from __future__ import annotations

import dataclasses
import json
import random
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fretish.ast as A
import fretish.fastparse as F
import fretish.parser as P
from common.errors import FretishError
from fretish.words import RESERVED_WORDS

SHARED = Path(__file__).resolve().parents[2] / ".." / "shared" / "fretish"


def _deep(x):
    """A comparable form of an AST node with every field, spans included (spans take no part
    in the nodes' own equality and repr)."""
    if dataclasses.is_dataclass(x):
        return (type(x).__name__,) + tuple((f.name, _deep(getattr(x, f.name)))
                                           for f in dataclasses.fields(x))
    if isinstance(x, (tuple, list)):
        return tuple(_deep(y) for y in x)
    return x


def _lark(text, start="start", line=1, column=1):
    try:
        return "ok", _deep(P._run_lark(start, text, "<t>", line, column))
    except FretishError as e:
        return "error", str(e)


def _fast(text, start="start", line=1, column=1):
    """The fast path's AST (deep form), or None where it hands the text to Lark."""
    fast = P._get_fast()
    assert fast, "the fast path is not available for grammar.lark"
    P._ctx.set(text, line - 1, column - 1)
    try:
        result = fast.parse(text, start)
        (P.check_requirement if start == "start" else P.check_expression)(result)
        return _deep(result)
    except Exception:  # noqa: BLE001 - handed to Lark
        return None
    finally:
        P._ctx.text = ""


def _public(text, start="start", line=1, column=1):
    run = P.parse if start == "start" else P.parse_expression
    try:
        return "ok", _deep(run(text, source="<t>", line=line, column=column))
    except FretishError as e:
        return "error", str(e)


def _check(text, start="start", line=1, column=1):
    ref = _lark(text, start, line, column)
    fast = _fast(text, start, line, column)
    if ref[0] == "ok":
        assert fast == ref[1], text
    else:
        assert fast is None, text
    assert _public(text, start, line, column) == ref, text


def _corpus():
    texts = []
    for name in ("fret_vectors.jsonl", "fret_vectors_functions.jsonl"):
        path = SHARED / name
        if path.exists():
            texts += [json.loads(line)["text"] for line in path.open(encoding="utf-8")]
    path = SHARED / "fret_trace_verdicts.jsonl"
    if path.exists():
        texts += [json.loads(line).get("sentence", "") for line in path.open(encoding="utf-8")]
    rnd = random.Random(7)
    scopes = ["", "in m", "only after \"flight mode\"", "before mode m,", "except while x > 1",
              "unless in m", "only during m"]
    conds = ["", "upon c", "whenever c & !d,", "upon p is false and when q", "if x >= -3.5e2",
             "unless p, or where q is true"]
    timings = ["", "immediately", "at the next timepoint", "within 5 ticks", "for 2 seconds",
               "until s", "before preBool(false, p)", "with probability >= 0.9 eventually"]
    responses = ["r", "!r | q", "x + 2 * y <= 10", "persisted(3, p) -> q", "a xor b & c",
                 "if a then b", "at the previous occurrence of p, q", "-3 ^ 2 > -x ^ 2",
                 "(a <-> b) => ~c", "f(x, y) = 1"]
    for _ in range(150):
        parts = [rnd.choice(scopes), rnd.choice(conds), rnd.choice(["the sw shall",
                                                                    "shall the sw"]),
                 rnd.choice(timings), "satisfy", rnd.choice(responses)]
        text = " ".join(p for p in parts if p) + rnd.choice(["", ".", " ."])
        texts.append(text)
        words = text.split(" ")  # and a near miss: one word dropped or doubled
        i = rnd.randrange(len(words))
        texts.append(" ".join(words[:i] + words[i + 1:]))
        texts.append(" ".join(words[:i] + [words[i]] + words[i:]))
        texts.append("\n  ".join(words))  # spread over lines
        # ignored characters before and after the sentence (the lexer's last match)
        texts.append(rnd.choice(["", " ", "\n"]) + text + rnd.choice([" ", "\t\n", "  "]))
    return texts


CORPUS = _corpus()


def test_fast_path_equals_lark_on_the_corpus():
    accepted = 0
    for text in CORPUS:
        _check(text)
        accepted += _lark(text)[0] == "ok"
    assert accepted > len(CORPUS) // 3  # the comparison covered accepted sentences


CASE_STUDIES = SHARED.parent / "corpora" / "fret_casestudies.jsonl"
from _shared import needs_shared  # noqa: E402


@needs_shared
def test_fast_path_equals_lark_on_the_case_studies():
    """NASA's case-study requirements (real text: trailing blanks, long expressions): the
    fast path accepts every one Lark accepts, with the same AST and spans."""
    texts = [json.loads(line)["text"] for line in CASE_STUDIES.open(encoding="utf-8")]
    accepted = 0
    for text in texts:
        _check(text)
        accepted += _lark(text)[0] == "ok"
    assert accepted >= len(texts) - 5


def _spans(x):
    """Every (node class, span) in an AST (spans of the requirement's parts included)."""
    if dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            v = getattr(x, f.name)
            if isinstance(v, A.Span):
                yield type(x).__name__, f.name, v
            else:
                yield from _spans(v)
    elif isinstance(x, (tuple, list)) and not isinstance(x, A.Span):
        for y in x:
            yield from _spans(y)


def _geometry(text, offset, line, column):
    """File line and column of 0-based ``offset`` in ``text`` that starts at file
    ``line``:``column``, counted by hand (a line starts after each newline)."""
    before = text[:offset]
    k = before.count("\n")
    if k == 0:
        return line, column + offset
    return line + k, offset - before.rindex("\n")


@settings(max_examples=150, deadline=None)
@given(st.sampled_from(CORPUS), st.integers(1, 40), st.integers(1, 30),
       st.lists(st.sampled_from([" ", "\n", "\n\t", "  "]), min_size=1, max_size=4))
def test_span_lines_and_columns_follow_the_offsets(text, line, column, blanks):
    """Every span's line/column pairs are the file position of its start/end offsets
    (computed by hand here), on texts spread over lines by random blanks, through the fast
    path and Lark alike (the two share the position code, so they are checked apart)."""
    parts = text.split(" ")
    text = parts[0] + "".join(blanks[i % len(blanks)] + p for i, p in enumerate(parts[1:]))
    got = []
    try:
        got.append(P.parse(text, source="<t>", line=line, column=column))
    except FretishError:
        return
    got.append(P._run_lark("start", text, "<t>", line, column))
    for req in got:
        for cls, name, span in _spans(req):
            if span == A.NO_SPAN:
                continue
            assert 0 <= span.start <= span.end <= len(text), (cls, name, span)
            assert (span.line, span.column) == _geometry(text, span.start, line, column), \
                (text, cls, name, span)
            assert (span.end_line, span.end_column) == _geometry(text, span.end, line,
                                                                 column), (text, cls, name, span)


@pytest.mark.parametrize("text", ["x + 1 > y & !p", "if a then b | c", "a < b < c", "x = !y",
                                  "f(", "\"weird var\" -> X"])
def test_fast_path_equals_lark_on_expressions(text):
    _check(text, start="expr")


def test_positions_in_file_coordinates():
    text = "in m upon p,\n  the sw shall\twithin 3 ticks satisfy x + 1 > -2"
    _check(text, line=7, column=5)
    _check(text.replace("satisfy", "satisfy satisfy"), line=7, column=5)


_WORDS = sorted(RESERVED_WORDS) + ["p", "x1", "a.b", "sw", "X", "What", "\"q r\"", "3", "-2",
                                   "1.5e3", "0.5", "&", "|", "->", "<=>", "!", "~", "(",
                                   ")", ",", ".", "+", "-", "*", "/", "^", "=", "!=", "<",
                                   ">=", "#", "é", "\"", "mode", "Shall", "SATISFY"]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(_WORDS), min_size=1, max_size=14),
       st.sampled_from([" ", "", "\n", "  \t"]))
def test_fast_path_equals_lark_on_word_soup(words, sep):
    _check(sep.join(words))


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(CORPUS), st.integers(0, 200), st.sampled_from(_WORDS))
def test_fast_path_equals_lark_on_edited_sentences(text, at, word):
    at = min(at, len(text))
    _check(text[:at] + word + text[at:])


def test_fast_tables_cached_damaged_entry_rebuilt(tmp_path, monkeypatch):
    """The fast path's tables live in fretc's cache beside Lark's when the package folder
    is not used; a damaged entry is rebuilt, never trusted."""
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(P, "_PACKAGE_CACHE", None)
    monkeypatch.setattr(P, "_fast", None)
    monkeypatch.setattr(P, "_lark", None)
    text = "in m upon p, the sw shall within 3 ticks satisfy x + 1 > -2"
    ref = _public(text)
    (entry,) = (tmp_path / "lark").glob("*.fast.marshal")
    entry.write_bytes(entry.read_bytes()[:200])
    monkeypatch.setattr(P, "_fast", None)
    assert P._get_fast() and _public(text) == ref
    assert entry.stat().st_size > 200  # rewritten whole
    # an entry built from other inputs (another grammar, Lark or Python) under the same
    # name is not used: its recorded identity differs
    import marshal
    import zlib

    def framed(tables):  # an entry as written: CRC-32 of the body, then the body
        body = marshal.dumps(tables)
        return zlib.crc32(body).to_bytes(4, "big") + body

    tables = marshal.loads(entry.read_bytes()[4:])
    tables["identity"] = tables["identity"] + "\n// another grammar"
    tables["start_states"] = {}
    entry.write_bytes(framed(tables))
    monkeypatch.setattr(P, "_fast", None)
    assert P._get_fast() and _public(text) == ref
    assert marshal.loads(entry.read_bytes()[4:])["start_states"]  # rebuilt
    # an entry whose bytes were altered but still unmarshal (same identity, a table
    # emptied) fails its CRC-32 and is rebuilt, never used
    good = entry.read_bytes()
    tables = marshal.loads(good[4:])
    tables["start_states"] = {}
    entry.write_bytes(good[:4] + marshal.dumps(tables))
    monkeypatch.setattr(P, "_fast", None)
    assert P._get_fast() and _public(text) == ref
    assert entry.read_bytes() == good


def test_fast_tables_beside_the_package(tmp_path, monkeypatch):
    """The tables are kept beside the package like .pyc files: a run with an empty fretc
    cache folder ("cold") loads them from there and does not build Lark's tables; a damaged
    entry there is rebuilt; a package folder that cannot be written, or
    PYTHONDONTWRITEBYTECODE, sends the entry to fretc's cache folder."""
    text = "in m upon p, the sw shall within 3 ticks satisfy x + 1 > -2"
    ref = _public(text)
    pkg = tmp_path / "pkg" / "__pycache__"
    monkeypatch.setattr(P, "_PACKAGE_CACHE", str(pkg))
    monkeypatch.setattr(P.sys, "dont_write_bytecode", False)
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "user1"))
    monkeypatch.setattr(P, "_fast", None)
    assert P._get_fast() and _public(text) == ref
    (entry,) = pkg.glob("*.fast.marshal")
    assert not (tmp_path / "user1" / "lark").exists() or \
        not list((tmp_path / "user1" / "lark").glob("*.fast.marshal"))

    def no_lark():
        raise AssertionError("Lark's tables built or loaded on a cold run")
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "user2"))  # cold
    monkeypatch.setattr(P, "_fast", None)
    with monkeypatch.context() as m:
        m.setattr(P, "_get_parser", no_lark)
        assert P._get_fast() and _public(text) == ref

    entry.write_bytes(entry.read_bytes()[:100])  # damaged: rebuilt in place
    monkeypatch.setattr(P, "_fast", None)
    assert P._get_fast() and _public(text) == ref
    assert entry.stat().st_size > 100

    for blocked in ("file", "dont_write_bytecode"):
        monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / f"user_{blocked}"))
        monkeypatch.setattr(P, "_fast", None)
        if blocked == "file":
            blocker = tmp_path / "blocker"
            blocker.write_text("x")
            monkeypatch.setattr(P, "_PACKAGE_CACHE", str(blocker / "__pycache__"))
        else:
            monkeypatch.setattr(P, "_PACKAGE_CACHE", str(tmp_path / "pkg2"))
            monkeypatch.setattr(P.sys, "dont_write_bytecode", True)
        assert P._get_fast() and _public(text) == ref
        assert list((tmp_path / f"user_{blocked}" / "lark").glob("*.fast.marshal"))
    assert not (tmp_path / "pkg2").exists()


def _exact_type(word):
    """The terminal of ``word`` by the exact lexer (all terminals in Lark's order, split by
    first character), None when none matches it whole."""
    fast = P._get_fast()
    sid = fast.dispatch.get(word[0], len(fast.subsets) - 1)
    try:
        m = (fast.matchers[sid] or fast._matcher(sid))(word, 0)
    except F._Slow:
        return None
    return m.lastgroup if m is not None and m.end() == len(word) else None


_RESERVED = sorted(RESERVED_WORDS | set("XFGUVYZHOST") | {"what"})


@settings(max_examples=300, deadline=None)
@given(st.one_of(
    st.tuples(st.sampled_from(_RESERVED), st.lists(st.booleans(), min_size=12, max_size=12))
    .map(lambda t: "".join(c.upper() if up else c.lower() for c, up in zip(t[0], t[1]))),
    st.from_regex(r"[A-Za-z][A-Za-z0-9_%.]{0,10}", fullmatch=True)))
def test_word_terminal_equals_the_exact_lexers(word):
    """The whole-text lexer's word classification (known reserved words, NAME tried first,
    then the exact lexer) gives the exact lexer's terminal for any letter case."""
    fast = P._get_fast()
    try:
        got = fast.words.get(word) or fast._word_type(word)
    except F._Slow:
        got = None
    assert got == _exact_type(word), word


_DEEP = ["!", "-", "f(", "g(1, ", "(", "if p then ", "a & ", "x ^ ", "~"]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(_DEEP), max_size=60),
       st.sampled_from(["p", "1", "9" * 99, "9" * 100, "1.5e" + "7" * 96, "-" + "8" * 100]))
def test_short_sentences_cannot_exceed_the_limits(prefixes, leaf):
    """limits.check_requirement skips the walk for a text of at most SHORT_TEXT characters,
    and for one of at most SHORT_TEXT_NO_NUMBER characters without a long run of number
    characters: the walk finds nothing there, even for the deepest expressions that fit."""
    from fretish import limits
    expr = "".join(prefixes) + leaf
    expr += ")" * (expr.count("(") - expr.count(")"))
    text = f"the sw shall satisfy {expr}"
    if len(text) > limits.SHORT_TEXT and (len(text) > limits.SHORT_TEXT_NO_NUMBER
                                          or limits._NUMBER_RUN.search(text)):
        return
    try:
        req = P._run_lark("start", text, "<t>", 1, 1)
    except FretishError:
        return
    for e in limits._expressions(req):
        limits._check(e, [0])  # raises LimitError beyond a limit


_OPERATORS = sorted(P._PREC)


@settings(max_examples=250, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["v", "v", "v", "!", "-"]),
                          st.sampled_from(_OPERATORS)), min_size=1, max_size=7),
       st.sampled_from(["v", "!", "-"]))
def test_climb_shortcuts_equal_precedence_climbing(pairs, last):
    """The builder's ``climb`` (one-operator chains and left folds built directly, other
    plain precedence chains by ``_shunt``) gives
    what the general precedence climbing (``_climb``) gives, spans and errors included."""
    def operand(kind, at):
        var = A.Var(f"v{at}", P._mk(at, at + 1))
        if kind == "v":
            return var
        return A.Unary("!" if kind == "!" else "-", var, P._mk(at - 1, at + 1))

    chain, at = [], 1
    for kind, op in pairs:
        chain.append(operand(kind, at))
        chain.append((op, P._BINOPS[op], at + 1, at + 2))
        at += 3
    chain.append(operand(last, at))

    def outcome(run):
        try:
            return "ok", _deep(run(list(chain)))
        except P._Fail as f:
            return "error", f.message, f.span
    P._ctx.set("x" * (at + 2), 0, 0)
    try:
        got = outcome(lambda c: P._Builder().climb([c]))
        ref = outcome(lambda c: P._climb(c, 0, 1)[0])
    finally:
        P._ctx.text = ""
    assert got == ref, [x if type(x) is tuple else type(x).__name__ for x in chain]


def test_lexer_by_character_equals_the_whole_text_lexer(monkeypatch):
    """The exact lexer's fallback (``_tokens_by_char``, used when the terminals do not
    allow the whole-text regexp) gives the same tokens, so the same ASTs and spans."""
    fast = P._get_fast()
    texts = CORPUS[::3]
    whole = [_fast(t) for t in texts]
    monkeypatch.setattr(fast, "findall", None)
    assert [_fast(t) for t in texts] == whole
    assert sum(x is not None for x in whole) > len(texts) // 3


_NAMES_RUN = r"[A-Za-z](?:[A-Za-z0-9_%]|\.(?=[A-Za-z0-9_%]))*"


@settings(max_examples=400, deadline=None)
@given(st.text(alphabet="aZ09_%. x-", min_size=1, max_size=14))
def test_word_regexp_is_names_run(text):
    """The whole-text lexer's word regexp (single-class repeats) takes, from every
    position, the same word as NAME's run in grammar.lark (a letter, then letters, digits,
    ``_``, ``%`` and inner dots)."""
    import re
    fast = P._get_fast()
    for i in range(len(text)):
        a = re.compile(fast._WORD).match(text, i)
        b = re.compile(_NAMES_RUN).match(text, i)
        assert (a and a.group()) == (b and b.group()), (text, i)


# pieces of text around the chunk lexer's conditions: words and operators written against
# each other, quoted strings holding blanks and '#', blanks str.split() cuts at but the
# grammar does not ignore, a character no terminal starts with, a non-ASCII letter
_PIECES = ["p", "x1.y", "shall", "the", "satisfy", "sw", "f(", ")", ",", "3", "-2.5e3", ">=",
           "<->", "!", "&", ".", "a.", '"a b"', '"q #1"', '"', "\x0b", "\x1c", "@", "é", "if",
           "then", "upon", "in", "mode", "within", "ticks"]
_BLANKS = ["", " ", "  ", "\t", "\n ", "\r\n", "\f"]


@settings(max_examples=600, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(_BLANKS), st.sampled_from(_PIECES)), max_size=14),
       st.sampled_from(_BLANKS))
def test_chunk_lexer_equals_the_whole_text_lexer(pairs, tail):
    """Wherever parse() takes the chunk lexer (a text without the characters of
    ``chunk_stop``), it gives the tokens of the whole-text lexer, or both refuse the text;
    texts the chunk lexer must not take (a quoted string with a space inside, blanks other
    than the space) are generated, and are sent to the whole-text lexer."""
    fast = P._get_fast()
    text = "".join(b + p for b, p in pairs) + tail

    def tokens(lex):
        try:
            return lex(text)
        except F._Slow:
            return None
    if fast.chunk_stop(text) is None:
        assert tokens(fast._tokens_by_chunk) == tokens(fast._tokens), repr(text)
    else:
        assert any(c in text for c in '"\t\n\r\f'), repr(text)


def test_chunk_lexer_sends_quoted_spaces_and_other_blanks_away():
    """The texts that would be cut wrongly at spaces take the whole-text lexer: a quoted
    name holding a space, blanks other than the space; a character no terminal matches
    (a vertical tab) is refused either way."""
    fast = P._get_fast()
    for text in ['the "my sw" shall satisfy p', "the sw shall\tsatisfy p",
                 "the sw shall\n  satisfy p"]:
        assert fast.chunk_stop(text) is not None
        assert _public(text) == _lark(text) and _lark(text)[0] == "ok"
    assert fast.chunk_stop("the sw shall satisfy p\x0b& q") is None
    assert _public("the sw shall satisfy p\x0b& q")[0] == "error"
    assert fast.chunk_stop("in m upon x > 3.5e2, the sw shall within 3 ticks satisfy "
                           "f(a, -b) & !c.") is None


def test_nodes_written_out_equal_their_classes():
    """The builder writes the most frequent nodes (A.Var, A.NumLit) out instead of calling
    their classes: each one's fields, in order, are those its class's __init__ stores."""
    seen = set()
    for text in CORPUS[:200] + ["the sw shall satisfy x > -3.5 & y", "the sw shall satisfy\n  a + 1"]:
        try:
            req = P.parse(text)
        except FretishError:
            continue
        for e in (req.response, req.condition.expr):
            for node in A.walk(e) if e is not None else ():
                if type(node) in (A.Var, A.NumLit):
                    seen.add(type(node))
                    remade = type(node)(**node.__dict__)
                    assert list(node.__dict__.items()) == list(remade.__dict__.items())
    assert seen == {A.Var, A.NumLit}


def test_parses_in_threads_equal_parses_alone():
    """Parses running in several threads at once (the builder's context is one object,
    held by a lock during each parse) give each text its own AST, spans and errors."""
    import threading
    texts = CORPUS[:120] + ["the sw shall satisfy\n   x > 1", "in m the sw shall satisfy (p"]
    alone = [_public(t, line=i + 1, column=3) for i, t in enumerate(texts)]
    got: dict = {}

    def work(k):
        for _ in range(3):
            for i in range(k, len(texts), 4):
                got[i] = _public(texts[i], line=i + 1, column=3)
                assert got[i] == alone[i], texts[i]
    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    import sys
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)   # switch threads as often as possible
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old)
    assert [got[i] for i in range(len(texts))] == alone
