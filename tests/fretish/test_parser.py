"""Tests of the FRETish parser (fretish.parser, common.errors).

Reference data: shared/fretish/fret_vectors.jsonl (FRET 3.x's own keys and formulas),
shared/fretish/fret_trace_verdicts.jsonl, shared/corpora/fret_casestudies.jsonl.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import pytest

from fretc.fretish import FretishSyntaxError, parse
from fretc.compiler.printers import expr_text
from fretc.fretish import ast as A
from fretc.fretish.parser import RESERVED_LETTERS, RESERVED_WORDS, build_lark, parse_expression

from _shared import jsonl, needs_shared  # ../shared beside the repository

VECTORS = jsonl("fretish/fret_vectors.jsonl")
VECTOR_BY_ID = {v["id"]: v for v in VECTORS}
CORPUS = jsonl("corpora/fret_casestudies.jsonl")
TRACE_CASES = [(t["trace"], c) for t in jsonl("fretish/fret_trace_verdicts.jsonl") for c in t["cases"]]

# Vectors FRET rejects but we accept on purpose (../shared/fretish/README.md section 7, defect 4), with the key
# our reading gives.
ACCEPTED_FRET_REJECTS = {
    26: ("lower-case 'is false': FRET's lexer only matches FALSE through its TRUE/FALSE "
         "keyword rules after the literal 'false' token won; defect 4",
         "null,regular,immediately,satisfaction"),
    106: ("lower-case 'is true', same FRET lexer defect; defect 4",
          "null,regular,immediately,satisfaction"),
    85: ("upper-case TRUE constant: FRET only accepts the literal 'true'; defect 4",
         "null,null,always,satisfaction"),
}
# fret_defect vectors: FRET's output is broken; we parse them, except preBool(0, p), which
# we reject (defect 3).
DEFECT_REJECTED = {109: "preBool(0, p): numeric initial value of preBool (defect 3)"}

# Case-study requirements we reject, and why (FRET's requirement grammar accepts these, but
# its formula pipeline re-parses every formula with its LTL grammar, in which the letter is
# an operator).
CORPUS_REJECTED = {
    "LMCPS/LM_requirements.json#NLG-006":
        ("'T' is FRET's past-time Trigger operator (LTL.g4 binaryLTLOp); a variable named T "
         "cannot be printed in FRET's formulas; write \"T\" or rename it", "'T'"),
}


# --------------------------------------------------------------------------- helpers
def mangle(name: str) -> str:
    """FRET's identifier mangling in printed formulas (../shared/fretish/README.md section 5)."""
    return name.replace(".", "_DOT_").replace("%", "_PRC_")


def fret_text(e: A.Expr) -> str:
    """Expression in FRET's printed style (every binary operation and negation in
    parentheses, constants upper case): the SMV printer's."""
    return expr_text(e)


def has_call(e) -> bool:
    return any(isinstance(n, A.Call) for n in A.walk(e))


def error_of(text, **kw) -> FretishSyntaxError:
    with pytest.raises(FretishSyntaxError) as info:
        parse(text, **kw)
    return info.value


# --------------------------------------------------------------------------- grammar
def test_grammar_has_no_lalr_conflicts(caplog):
    """Lark resolves shift/reduce conflicts silently (as shift); with debug=True it logs
    them. The grammar must have none (reduce/reduce conflicts would raise)."""
    from lark import logger as lark_logger
    old = lark_logger.level
    lark_logger.setLevel(logging.DEBUG)
    try:
        with caplog.at_level(logging.DEBUG, logger="lark"):
            build_lark(debug=True)
    finally:
        lark_logger.setLevel(old)
    assert not [r for r in caplog.records if "conflict" in r.getMessage().lower()]


def test_reserved_words_match_grammar_keywords():
    grammar = (Path(__file__).parents[2] / "fretish/grammar.lark").read_text()
    name_rule = re.search(r"^NAME: (.*)$", grammar, re.M).group(1)
    for word in RESERVED_WORDS:
        for variant in (word, word.upper(), word.capitalize()):
            if word in ("true", "false"):
                assert parse_expression(variant) == A.BoolLit(word == "true")
                continue
            with pytest.raises(FretishSyntaxError):
                parse_expression(variant)
            assert parse_expression(f'"{variant}"') == A.Var(variant)
    assert "what" in name_rule
    for letter in RESERVED_LETTERS:
        with pytest.raises(FretishSyntaxError):
            parse_expression(letter)
        assert parse_expression(letter.lower()) == A.Var(letter.lower())
    # words that merely start with a keyword are names
    for word in ("shallow", "theme", "information", "ifx", "modes", "seconds_left", "next.x",
                 "Xpos", "Ts", "TT", "whatever", "format"):
        assert parse_expression(word) == A.Var(word)


# --------------------------------------------------------------------------- FRET vectors
@needs_shared
@pytest.mark.parametrize("v", VECTORS, ids=lambda v: f"v{v['id']}")
@pytest.mark.tor("TOR-GRM-001")
def test_fret_vector(v):
    vid = v["id"]
    if vid in ACCEPTED_FRET_REJECTS:
        assert v["parse_error"]
        assert parse(v["text"]).key == ACCEPTED_FRET_REJECTS[vid][1]
    elif vid in DEFECT_REJECTED:
        assert v["fret_defect"]
        error_of(v["text"])
    elif v["parse_error"]:
        error_of(v["text"])
    else:
        r = parse(v["text"])
        assert r.key == v["key"]
        assert r.freeform == bool(v.get("freeform"))


@needs_shared
def test_every_listed_exception_is_a_vector():
    for vid in (*ACCEPTED_FRET_REJECTS, *DEFECT_REJECTED):
        assert vid in VECTOR_BY_ID


@needs_shared
@pytest.mark.tor("TOR-SEM-009")
def test_fixed_defects_mean_what_they_say():
    r = parse(VECTOR_BY_ID[26]["text"])                      # upon p is false
    assert r.condition.expr == A.Unary("!", A.Var("p"))
    assert parse(VECTOR_BY_ID[106]["text"]).condition.expr == A.Var("p")
    assert parse(VECTOR_BY_ID[85]["text"]).response == A.BoolLit(True)
    # FRET's own spellings give the same trees
    assert parse(VECTOR_BY_ID[104]["text"]).condition.expr == A.Unary("!", A.Var("p"))
    assert parse(VECTOR_BY_ID[107]["text"]).condition.expr == A.Var("p")
    for spelling in ("true", "True", "TRUE", "tRuE"):
        assert parse(f"the sw shall always satisfy {spelling}").response == A.BoolLit(True)
        assert parse(f"upon p is {spelling} the sw shall always satisfy q").condition.expr == \
            A.Var("p")


@needs_shared
@pytest.mark.parametrize("v", [v for v in VECTORS if not v["parse_error"] and not v["fret_defect"]
                               and not v.get("freeform")], ids=lambda v: f"v{v['id']}")
def test_printed_parenthesization_matches_fret(v):
    """Our trees, printed in FRET's style, occur verbatim in FRET's formulas (only for
    expressions without functions, which FRET expands)."""
    r = parse(v["text"])
    formulas = " ".join((v["ft"], v["ft_inf"], v["pt"]))
    if not has_call(r.response):
        assert fret_text(r.response) in formulas
    if r.condition.expr is not None and not has_call(r.condition.expr):
        assert fret_text(r.condition.expr) in formulas


@pytest.mark.parametrize("vid,expected", [
    (77, "((x + (2 * (y ^ 2))) <= (z mod 3))"),
    (112, "((! (a & b)) | (c & d))"),
    (113, "(a | (b & c))"),
    (115, "((a & b) xor c)"),
    (116, "(((x * y) + z) > w)"),
    (118, "((x = 1) & (y = 2))"),
    (79, "((x - y) > 0)"),
    (80, "(x > -3.0e2)"),
    (76, "(a -> b)"),
    (74, "(a <-> b)"),
    (86, "(ROS_DOT_state = 2)"),
])
@needs_shared
@pytest.mark.tor("TOR-GRM-003")
def test_precedence_against_fret(vid, expected):
    v = VECTOR_BY_ID[vid]
    assert expected in v["ft"]
    assert fret_text(parse(v["text"]).response) == expected


# --------------------------------------------------------------------------- real corpora
@needs_shared
@pytest.mark.parametrize("req", CORPUS, ids=lambda r: r["id"])
@pytest.mark.tor("TOR-GRM-001")
def test_case_study_corpus(req):
    if req["id"] in CORPUS_REJECTED:
        _why, needle = CORPUS_REJECTED[req["id"]]
        e = error_of(req["text"])
        assert needle in e.message and e.hint
    else:
        r = parse(req["text"])
        assert r.key is not None or r.freeform


@needs_shared
def test_corpus_size_and_rejections_listed():
    assert len(CORPUS) == 198
    assert set(CORPUS_REJECTED) <= {r["id"] for r in CORPUS}


@needs_shared
def test_trace_verdict_sentences():
    assert len(TRACE_CASES) == 2640
    for _trace, case in TRACE_CASES:
        assert parse(case["sentence"]).key == case["key"], case["sentence"]


# --------------------------------------------------------------------------- sentence parts
@pytest.mark.parametrize("phrase,kind", [
    ("in m", "in"), ("during m", "in"), ("when in m", "in"), ("if in m", "in"),
    ("In mode m", "in"), ("in m mode", "in"), ("DURING M MODE", "in"),
    ("when not in m", "notin"), ("if not in m", "notin"), ("unless in m", "notin"),
    ("except in m", "notin"), ("except during m", "notin"), ("except when in m", "notin"),
    ("except if in m", "notin"),
    ("only in m", "onlyIn"), ("only during m", "onlyIn"), ("only when in m", "onlyIn"),
    ("only if in mode m", "onlyIn"),
    ("after m", "after"), ("after mode m", "after"), ("after m mode", "after"),
    ("before m", "before"), ("only after m", "onlyAfter"), ("only before m", "onlyBefore"),
])
@pytest.mark.tor("TOR-GRM-001")
def test_scope_modes(phrase, kind):
    for sep in (" ", ", "):
        r = parse(f"{phrase}{sep}the sw shall always satisfy q")
        assert r.scope.kind == kind
        assert r.scope.mode == A.Var("M" if "M" in phrase.split() else "m")


@pytest.mark.parametrize("phrase,kind", [
    ("while x > 3", "in"), ("except while x > 3", "notin"), ("only while x > 3", "onlyIn"),
    ("after x > 3", "after"), ("before x > 3", "before"), ("only after x > 3", "onlyAfter"),
    ("only before x > 3", "onlyBefore"),
])
@pytest.mark.tor("TOR-GRM-001")
def test_scope_conditions(phrase, kind):
    r = parse(f"{phrase} the sw shall always satisfy q")
    assert r.scope.kind == kind
    assert r.scope.mode == A.Binary(">", A.Var("x"), A.NumLit("3"))


@pytest.mark.tor("TOR-GRM-001")
def test_quoted_mode_and_scope_span():
    r = parse('in "flight mode" mode, the sw shall always satisfy q')
    assert r.scope.mode == A.Var("flight mode")
    assert (r.scope.span.start, r.scope.span.end) == (0, 21)
    assert r.scope.mode.span.start == 3


def test_is_true_after_a_scope_is_rejected():
    e = error_of("when in mode m is true the sw shall always satisfy q")
    assert e.column == 16 and "is true" in e.hint


@pytest.mark.parametrize("cond,expr,kind,parts", [
    ("upon p", "p", "regular", [("upon", None)]),
    ("when p", "p", "regular", [("when", None)]),
    ("if p", "p", "regular", [("if", None)]),
    ("where p", "p", "regular", [("where", None)]),
    ("unless p", "(! p)", "regular", [("unless", None)]),
    ("unless p is false", "p", "regular", [("unless", None)]),
    ("whenever p", "p", "holding", [("whenever", None)]),
    ("whenever p, whenever q", "(p & q)", "holding", [("whenever", None), ("whenever", "and")]),
    ("whenever p upon q", "(p & q)", "regular", [("whenever", None), ("upon", "and")]),
    ("upon p and when r", "(p & r)", "regular", [("upon", None), ("when", "and")]),
    ("upon p, or when r,", "(p | r)", "regular", [("upon", None), ("when", "or")]),
    ("upon p or when q and if r", "((p | q) & r)", "regular",
     [("upon", None), ("when", "or"), ("if", "and")]),
    ("upon p is FALSE, unless q", "((! p) & (! q))", "regular",
     [("upon", None), ("unless", "and")]),
    ("UPON x > 2 IS True", "(x > 2)", "regular", [("upon", None)]),
    ("upon if a then b", "(a -> b)", "regular", [("upon", None)]),
])
@pytest.mark.tor("TOR-GRM-001")
def test_conditions(cond, expr, kind, parts):
    r = parse(f"{cond} the sw shall always satisfy q")
    assert r.condition.kind == kind
    assert fret_text(r.condition.expr) == expr
    assert [(p.qualifier, p.connective) for p in r.condition.parts] == parts


def test_condition_after_scope_with_and():
    r = parse("in m, and upon p the sw shall always satisfy q")
    assert (r.scope.kind, r.condition.kind, r.condition.expr) == ("in", "regular", A.Var("p"))


@pytest.mark.tor("TOR-GRM-001")
def test_condition_spans():
    text = "upon p is false, or when r the sw shall always satisfy q"
    r = parse(text)
    p0, p1 = r.condition.parts
    assert text[p0.span.start:p0.span.end] == "upon p is false"
    assert text[p1.span.start:p1.span.end] == "or when r"
    assert text[r.condition.span.start:r.condition.span.end] == "upon p is false, or when r"


@pytest.mark.parametrize("phrase,kind", [
    ("", "null"), ("immediately", "immediately"), ("initially", "immediately"),
    ("at the first timepoint", "immediately"), ("at the same timepoint", "immediately"),
    ("at the next timepoint", "next"), ("finally", "finally"),
    ("at the last timepoint", "finally"), ("eventually", "eventually"),
    ("always", "always"), ("never", "never"),
])
@pytest.mark.tor("TOR-GRM-001")
def test_simple_timings(phrase, kind):
    r = parse(f"the sw shall {phrase} satisfy q")
    assert r.timing.kind == kind and r.timing.phrase == phrase
    r = parse(f"the sw shall {phrase.upper()} satisfy q")
    assert r.timing.kind == kind and r.timing.phrase == phrase


def test_timing_phrase_is_normalized():
    t = parse("the sw shall, AT  the\tNext timepoint, satisfy q").timing
    assert (t.kind, t.phrase) == ("next", "at the next timepoint")


@pytest.mark.parametrize("unit,canon", [
    ("tick", "ticks"), ("ticks", "ticks"), ("microsec", "microseconds"),
    ("microsecs", "microseconds"), ("microsecond", "microseconds"),
    ("microseconds", "microseconds"), ("millisec", "milliseconds"),
    ("milliseconds", "milliseconds"), ("sec", "seconds"), ("secs", "seconds"),
    ("second", "seconds"), ("Seconds", "seconds"), ("minute", "minutes"),
    ("minutes", "minutes"), ("hour", "hours"), ("HOURS", "hours"),
])
@pytest.mark.parametrize("word", ["within", "for", "after"])
@pytest.mark.tor("TOR-GRM-001")
def test_duration_timings(word, unit, canon):
    r = parse(f"the sw shall {word} 2.5 {unit} satisfy q")
    assert r.timing == A.Timing(word, duration=A.Duration("2.5", canon), phrase=word)
    assert r.timing.duration.value == A.Duration("5/2", canon).value


@pytest.mark.parametrize("text", [
    "the sw shall within 1e3 ticks satisfy q", "the sw shall within -2 ticks satisfy q",
    "the sw shall within 2 satisfy q", "the sw shall within 2 ms satisfy q",
    "the sw shall within two ticks satisfy q",
])
def test_bad_durations(text):
    error_of(text)


@pytest.mark.tor("TOR-GRM-001")
def test_stop_timings():
    r = parse("the sw shall until stop | halt satisfy post")
    assert r.timing == A.Timing("until", stop=A.Binary("|", A.Var("stop"), A.Var("halt")),
                                phrase="until")
    r = parse("the sw shall before at the next occurrence of p, q satisfy r")
    assert r.timing.stop == A.Call("nextOcc", (A.Var("p"), A.Var("q")))


@pytest.mark.parametrize("op", ["<", "<=", ">", ">=", "=", "!="])
@pytest.mark.tor("TOR-GRM-001")
def test_probability(op):  # '!=' as FRET 3.1 accepts it
    r = parse(f"the sw shall, with probability {op} 0.99, always satisfy q")
    assert r.probability == A.Probability(op, "0.99")
    assert r.timing.kind == "always"


@pytest.mark.parametrize("bound", ["> 1", ">= 1.5", "< 0", "= -0.5", "<= 2", "!= 1.5"])
@pytest.mark.tor("TOR-GRM-001")
def test_probability_out_of_range(bound):
    e = error_of(f"the sw shall with probability {bound} always satisfy q")
    assert e.hint and "with probability >= 0.99" in e.hint
    assert e.column == len("the sw shall with probability ") + 1 + bound.index(" ") + 1


@pytest.mark.parametrize("bound", [">= 1", "<= 0", "> 0", "< 1", "= 1", "= 0", "> 1e-3"])
@pytest.mark.tor("TOR-GRM-001")
def test_probability_edges(bound):
    assert parse(f"the sw shall with probability {bound} satisfy q").probability is not None


@pytest.mark.tor("TOR-GRM-001")
def test_component_forms():
    for text, comp in [("the sw shall satisfy p", "sw"), ("sw shall satisfy p", "sw"),
                       ("shall the sw satisfy p", "sw"), ("shall sw satisfy p", "sw"),
                       ('the "flight computer" shall satisfy p', "flight computer"),
                       ("THE Sw_2.a shall satisfy p", "Sw_2.a")]:
        assert parse(text).component == comp
    text = "only after p shall the sw , after 2 ticks, satisfy q"
    r = parse(text)
    assert (r.component, r.timing.kind, r.timing.duration.amount) == ("sw", "after", "2")
    assert text[r.component_span.start:r.component_span.end] == "the sw"
    assert text[r.response_span.start:r.response_span.end] == "satisfy q"


@pytest.mark.tor("TOR-GRM-004")
def test_freeform():
    r = parse('"The system shall be nice, # really."')
    assert r.freeform and r.key is None and r.text == '"The system shall be nice, # really."'
    assert parse('  "free"  .').freeform


@pytest.mark.tor("TOR-GRM-001")
def test_trailing_dot_and_whitespace():
    a = parse("  The sw shall, until stop, satisfy post.  ")
    b = parse("the sw shall until stop satisfy post")
    assert a.response == b.response == A.Var("post")
    assert a == A.Requirement(a.text, **{k: getattr(b, k) for k in
                                         ("scope", "condition", "component", "timing",
                                          "response")})
    assert parse("the sw shall satisfy ROS.state.").response == A.Var("ROS.state")
    error_of("the sw shall satisfy p..")
    error_of("the sw shall satisfy p. q")


def test_identifiers_and_functions():
    e = parse_expression('ROS.state = 2 & x% > 1 & "next" & "a \\"q\\"" & FTP')
    names = [n.name for n in A.walk(e) if isinstance(n, A.Var)]
    assert names == ["ROS.state", "x%", "next", 'a "q"', "FTP"]
    error_of("the sw shall satisfy _ok")
    c = parse_expression("persisted(2, 3, p) & occurred(3,p) & preBool(false, p) & "
                         "absReal(x - 1) < 2 & ite(a, b, c) & f()")
    calls = [(n.name, len(n.args)) for n in A.walk(c) if isinstance(n, A.Call)]
    assert calls == [("persisted", 3), ("occurred", 2), ("preBool", 2), ("absReal", 1),
                     ("ite", 3), ("f", 0)]
    assert parse_expression("at the previous occurrence of p, q") == \
        A.Call("prevOcc", (A.Var("p"), A.Var("q")))


@pytest.mark.parametrize("init", ["0", "1", "-1", "2.5", "x + 1", "-(1)"])
def test_prebool_numeric_init_rejected(init):
    e = error_of(f"the sw shall always satisfy preBool({init}, p) -> q")
    assert "preBool" in e.message and e.hint
    assert e.column == len("the sw shall always satisfy preBool(") + 1


def test_nusmv_words_are_not_reserved():
    # FRET does not reserve them either; the SMV printer mangles names it cannot print.
    for w in ("case", "esac", "init", "self", "union", "word", "count", "abs", "max", "A", "E"):
        assert parse_expression(w) == A.Var(w)
