"""compiler.instantiate: the printed formulas from per-template-key templates are byte for
byte those of the full IR build (compiler.semantics.formalize + compiler.printers), on
random sentences over the whole grammar (every scope, condition kind and timing; atoms that
are constants, negations, FTP, equal to each other or to parts of each other, comparisons,
arithmetic, numeric and temporal functions, nested if-then), on FRET's vectors and on the
case-study corpus. The lazily built IR is the full build's, and the same errors come out.
"""

from __future__ import annotations

import json
import json.encoder
import random
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from fretc.compiler import fallback, ir
from fretc.compiler import instantiate as I
from fretc.compiler import instantiate_atoms as IA
from fretc.compiler import template_table as TT
from fretc.compiler.printers import to_smv, to_spot
from fretc.compiler.semantics import formalize, template_parts as _shape
from differential import random_requirement
from fretc.fretish import FretishError, parse
from fretc.fretish import ast as A

SHARED = Path(__file__).resolve().parents[3] / "shared"
ENC = json.encoder.encode_basestring_ascii  # json.dumps's escaper (ensure_ascii)
SEPS = (',\n    "ft_inf": ', ',\n    "pt": ', ',\n    "ft_spot": ', ',\n    "%ft_inf_spot": ')
FORMS = ("ft", "ft_inf", "pt", "ft_spot", "ft_inf_spot")


def _full_texts(f) -> list:
    out = [to_smv(f.ft), to_smv(f.ft_inf), to_smv(f.pt, ftp="(Z FALSE)")]
    for node in (f.ft, f.ft_inf):
        try:
            out.append(to_spot(node))
        except ValueError as exc:
            out.append(("ValueError", str(exc)))
    return out


def _template_texts(f) -> list:
    out = []
    for which in FORMS:
        try:
            out.append(I.formula_text(f, which))
        except ValueError as exc:
            out.append(("ValueError", str(exc)))
    return out


def _outcome(fn, req, period):
    try:
        return fn(req, period), None
    except FretishError as exc:
        return None, (type(exc).__name__, str(exc))


def same(text: str, period: Fraction | None = None) -> bool:
    """Assert the template path equals the full path on ``text``; True when the template
    was used (False: it fell back, or the sentence does not parse/formalize)."""
    try:
        req = parse(text)
    except FretishError:
        return False
    if req.freeform:
        return False
    full, err_full = _outcome(formalize, req, period)
    inst, err_inst = _outcome(I.instantiate, req, period)
    assert err_full == err_inst, text
    if full is None:
        return False
    assert _template_texts(inst) == _full_texts(full), text
    for attr in ("key", "variables", "warnings", "ticks", "pt_causal"):
        assert getattr(inst, attr) == getattr(full, attr), (text, attr)
    used = isinstance(inst, I.InstantiatedFormalization)
    if used:
        # the five forms at once (--json) and JSON-escaped in one piece are the same texts
        texts = _full_texts(full)
        if all(type(t) is str for t in texts):
            assert inst.printed() == tuple(texts), text
            assert inst.json_forms(ENC, SEPS) == "".join(
                ENC(t) + sep for t, sep in zip(texts, SEPS + ("",))), text
        else:
            assert inst.json_forms(ENC, SEPS) is None, text
        # the IR, built on first use, is the full build's
        assert (inst.ft, inst.ft_inf, inst.pt) == (full.ft, full.ft_inf, full.pt), text
    return used


# --------------------------------------------------------------------------- generator
# few names, so that atoms are often equal to each other or to a part of each other
BOOLS = ["p", "q", "m", "true", "false", "FTP"]
NUMS = ["x", "y", "3", "0"]


NUM_FORMS = ("({a} {op} {b})", "absReal({a})", "preReal(0, {a})", "-{a}",
             "maxReal({a}, {b})")
# a connective four times in fourteen, as often as the temporal functions together
BOOL_FORMS = ("!{a}", "!({a})", *["({a} {op} {b})"] * 4, "(if {a} then {b})",
              "persisted({bound}, {a})", "occurred({bound}, {a})", "persists({bound}, {a})",
              "occurs({bound}, {a})", "preBool({tf}, {a})", "{occ}({a}, {b})",
              "ite({a}, {b}, {c})")


@st.composite
def num_expr(draw, depth: int):
    if depth <= 0 or draw(st.integers(0, 3)) == 0:
        return draw(st.sampled_from(NUMS))
    form = draw(st.sampled_from(NUM_FORMS))
    return form.format(a=draw(num_expr(depth - 1)), b=draw(num_expr(depth - 1)),
                       op=draw(st.sampled_from(['+', '-', '*', '/', '^'])))


@st.composite
def bool_expr(draw, depth: int):
    if depth <= 0 or draw(st.integers(0, 4)) == 0:
        if draw(st.integers(0, 5)) == 0:
            return (f"{draw(num_expr(1))} {draw(st.sampled_from(['<', '<=', '=', '!=', '>']))}"
                    f" {draw(num_expr(1))}")
        return draw(st.sampled_from(BOOLS))
    form = draw(st.sampled_from(BOOL_FORMS))
    a, b, c = (draw(bool_expr(depth - 1)) for _ in range(3))
    return form.format(a=a, b=b, c=c, op=draw(st.sampled_from(['&', '|', '->', 'xor', '<->'])),
                       bound=draw(st.sampled_from(["0", "1", "2", "0, 2", "1, 3"])),
                       tf=draw(st.sampled_from(['true', 'false'])),
                       occ=draw(st.sampled_from(['prevOcc', 'nextOcc'])))


@st.composite
def atom(draw, depth: int):
    """A sentence's mode, condition, stop or response: often a bare name or a small
    formula over the same few names, so that atoms collide."""
    if draw(st.integers(0, 2)) == 0:
        return draw(bool_expr(depth))
    return draw(st.sampled_from(["p", "q", "m", "!p", "(p & q)", "(p | q)", "(q & p)",
                                 "(!p & q)", "(p & !q)", "(p -> q)"]))


SCOPE_PHRASES = ["", "in {m}", "when not in {m}", "only in {m}", "after {c}", "before {c}",
                 "only after {c}", "only before {c}", "while {c}", "except while {c}"]
TIMING_PHRASES = ["", "immediately", "at the next timepoint", "finally", "eventually",
                  "always", "never", "within {n} ticks", "for {n} ticks", "after {n} ticks",
                  "until {s}", "before {s}", "within {n} seconds"]


@st.composite
def sentence(draw):
    parts = []
    scope = draw(st.sampled_from(SCOPE_PHRASES))
    if scope:
        mode = draw(st.sampled_from(["m", "p", "q"]))
        parts.append(scope.format(m=mode, c=f"({draw(atom(1))})") + ",")
    cond = draw(st.sampled_from(["", "upon", "whenever", "when", "if"]))
    if cond:
        c = draw(atom(2))
        neg = " is false" if cond == "upon" and draw(st.booleans()) else ""
        parts.append(f"{cond} ({c}){neg},")
    parts.append("the sw shall")
    timing = draw(st.sampled_from(TIMING_PHRASES))
    n = draw(st.sampled_from([0, 1, 2, 3, 7, 250]))
    parts.append(timing.format(n=n, s=f"({draw(atom(1))})"))
    parts.append(f"satisfy {draw(atom(2))}")
    return " ".join(p for p in parts if p)


@st.composite
def colliding_sentence(draw):
    """A sentence whose mode, condition, stop and response are each, at random, one
    shared formula or another atom: the equalities the fallback rule must catch."""
    shared = draw(atom(1))
    pick = lambda depth: shared if draw(st.booleans()) else draw(atom(depth))  # noqa: E731
    parts = []
    scope = draw(st.sampled_from(SCOPE_PHRASES))
    if scope:
        parts.append(scope.format(m=f"({pick(1)})" if "{m}" not in scope else "m",
                                  c=f"({pick(1)})") + ",")
    cond = draw(st.sampled_from(["", "upon", "whenever"]))
    if cond:
        parts.append(f"{cond} ({pick(2)}),")
    parts.append("the sw shall")
    timing = draw(st.sampled_from(TIMING_PHRASES))
    parts.append(timing.format(n=draw(st.sampled_from([0, 1, 2, 5])), s=f"({pick(1)})"))
    parts.append(f"satisfy {pick(2)}")
    return " ".join(p for p in parts if p)


# --------------------------------------------------------------------------- properties
SAMPLES = {"used": 0, "all": 0}


@settings(max_examples=400, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(sentence(), st.sampled_from([None, Fraction(1, 10), Fraction(1)]))
@example("upon p the sw shall always satisfy p", None)  # equal atoms
@example("upon p the sw shall always satisfy !p", None)  # negation at top level
@example("in m upon true the sw shall within 3 ticks satisfy q", None)  # constant
@example("whenever p the sw shall until p satisfy q", None)  # equal stop and condition
@example("the sw shall always satisfy persisted(0, p) & FTP", None)  # FTP conjunction
@example("after p the sw shall for 1 ticks satisfy q", None)  # n = 1 key
def test_template_equals_full_build(text, period):
    SAMPLES["all"] += 1
    SAMPLES["used"] += same(text, period)


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(colliding_sentence())
def test_template_equals_full_build_with_colliding_atoms(text):
    same(text)


@pytest.mark.slow
@settings(max_examples=5000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(colliding_sentence())
def test_template_equals_full_build_with_colliding_atoms_long(text):
    same(text)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.integers(0, 2**32 - 1))
def test_template_equals_full_build_differential_generator(seed):
    text, _ = random_requirement(random.Random(seed), depth=2)
    same(text)


@pytest.mark.slow
@settings(max_examples=8000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(sentence(), st.sampled_from([None, Fraction(1, 10), Fraction(1)]))
def test_template_equals_full_build_long(text, period):
    same(text, period)


@pytest.mark.slow
@settings(max_examples=5000, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 3))
def test_template_equals_full_build_differential_generator_long(seed, depth):
    text, _ = random_requirement(random.Random(seed), depth=depth)
    same(text)


def _vector_sentences() -> list:
    texts = []
    for name in ("fret_vectors.jsonl", "fret_vectors_functions.jsonl"):
        texts += [json.loads(line)["text"]
                  for line in (SHARED / "fretish" / name).read_text().splitlines()]
    for line in (SHARED / "fretish" / "fret_trace_verdicts.jsonl").read_text().splitlines():
        texts += [c["sentence"] for c in json.loads(line)["cases"]]
    return sorted(set(texts))


def test_template_equals_full_build_on_fret_vectors(shared):
    texts = _vector_sentences()
    used = sum(same(t) for t in texts)
    # the template serves most sentences (the fallbacks are the unsafe atoms)
    assert used > len(texts) // 2, (used, len(texts))


def test_template_equals_full_build_on_corpus(shared):
    texts = [json.loads(line)["text"] for line in
             (SHARED / "corpora" / "fret_casestudies.jsonl").read_text().splitlines()]
    for period in (None, Fraction(1, 10)):
        for t in texts:
            same(t, period)


# --------------------------------------------------------------------------- the rule
@pytest.mark.parametrize("text", [
    "whenever p the sw shall until q satisfy q",     # stop = response: r | stop folds
    "upon p the sw shall always satisfy !q",         # negation at top level
    "upon p the sw shall always satisfy true",       # constant
    "in m the sw shall always satisfy FTP",          # FTP
])
def test_unsafe_atoms_fall_back(text):
    """Each case is one a placeholder would fold differently: the full build is used."""
    f = I.instantiate(parse(text))
    assert not isinstance(f, I.InstantiatedFormalization)
    assert same(text) is False


@pytest.mark.parametrize("text", [
    "upon p the sw shall always satisfy p",          # equal, but never compared here
    "in m upon m the sw shall always satisfy q",
    "in m the sw shall always satisfy persisted(2, m)",
])
def test_equal_atoms_the_construction_never_compares_use_the_template(text):
    assert isinstance(I.instantiate(parse(text)), I.InstantiatedFormalization)
    assert same(text) is True


def test_safe_atoms_use_the_template_and_templates_are_shared():
    a = I.instantiate(parse("in m upon p the sw shall within 5 ticks satisfy q"))
    b = I.instantiate(parse("in mode2 upon c > 3 the sw shall within 9 ticks satisfy r | s"))
    assert isinstance(a, I.InstantiatedFormalization)
    assert isinstance(b, I.InstantiatedFormalization)
    assert a._tmpl is b._tmpl  # one template for n >= 2
    assert "[0,5]" in I.formula_text(a, "ft") and "[0,9]" in I.formula_text(b, "ft")


def test_template_count_is_bounded():
    """Keys are (scope, condition kind, timing, n in {0, 1, >= 2}): at most 480."""
    rnd = random.Random(3)
    for _ in range(300):
        text, _ = random_requirement(rnd, depth=1)
        try:
            I.instantiate(parse(text))
        except FretishError:
            pass
    for n in range(0, 40):
        I.instantiate(parse(f"upon p the sw shall within {n} ticks satisfy q"))
    keys = set(TT._TEMPLATES)
    assert len(keys) <= 8 * 3 * (8 + 4 * 3)
    assert {k[3] for k in keys} <= {None, 0, 1, -1}


def test_pickles_as_the_full_build():
    """A plan shipped to workers pickles its formalizations: an instantiated one arrives
    as the full build, whose printed texts are the same."""
    import pickle

    text = "in m upon p the sw shall within 3 ticks satisfy occurs(1, q)"
    f = I.instantiate(parse(text))
    assert isinstance(f, I.InstantiatedFormalization)
    g = pickle.loads(pickle.dumps(f))
    assert type(g) is I.Formalization
    assert _template_texts(f) == _template_texts(g) == _full_texts(formalize(parse(text)))
    assert (g.key, g.variables, g.ticks, g.pt_causal) == (f.key, f.variables, f.ticks,
                                                          f.pt_causal)


@pytest.mark.parametrize("text", [
    "upon x + 1 the sw shall satisfy y + 2",                  # condition and response bad
    "upon x + 1 the sw shall until s - 1 satisfy persists(2, q)",
    "in m the sw shall until s * 2 satisfy y + 2",            # stop and response bad
])
def test_the_first_bad_expression_of_the_sentence_is_reported(text):
    """Both paths convert the condition, stop and response in sentence order: the error
    (and its span) is the first bad expression's, the same with and without a template."""
    req = parse(text)
    errors = []
    for fn in (formalize, I.instantiate):
        with pytest.raises(FretishError) as exc:
            fn(req)
        errors.append((str(exc.value), exc.value.span))
    assert errors[0] == errors[1]
    assert errors[0][1].column == text.index("x + 1" if "x + 1" in text else "s * 2") + 1


# --------------------------------------------------------------------------- shortcuts
def _atoms_of(text: str, period=None):
    """The instantiation of ``text`` (None when it falls back or fails)."""
    try:
        f = I.instantiate(parse(text), period)
    except FretishError:
        return None
    return f if isinstance(f, I.InstantiatedFormalization) else None


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(sentence(), colliding_sentence()))
def test_plain_comparisons_agree_with_the_general_check(text):
    """plain_compared_safe (conditions reduced once per template for atoms shared by ft,
    ft_inf and pt) gives _compared_safe's answer on every plain requirement."""
    try:
        req = parse(text)
    except FretishError:
        return
    if req.freeform:
        return
    try:
        scope, cond, timing, n, _ = _shape(req, None)
    except FretishError:
        return
    exprs = (req.scope.mode if scope != "null" else None,
             req.condition.expr if cond != "null" else None,
             req.timing.stop if timing in A.STOP_TIMINGS else None, req.response)
    x = IA.PlainExpander()
    try:
        one = [None if e is None else x.bool(e) for e in exprs]
    except (IA.Timed, FretishError):
        return
    tmpl = TT.template(scope, cond, timing, n)
    atoms = tuple(one) * 3
    assert fallback.plain_compared_safe(tmpl, one, atoms, n) == fallback._compared_safe(tmpl, atoms, n)


@settings(max_examples=200, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(sentence())
def test_variables_walk_matches_ir_variables(text):
    """variables_into (shared sub-formulas skipped) lists ir.variables' names in order."""
    f = _atoms_of(text)
    if f is None:
        return
    seen: dict = {}
    done: set = set()
    want: dict = {}
    for a in f._atoms:
        if a is not None:
            IA.variables_into(a, seen, done)
            want.update(dict.fromkeys(ir.variables(a)))
    assert list(seen) == list(want), text


def test_future_function_names_are_the_expanders():
    from fretc.compiler.expressions import _FUTURE_FUNCS
    assert IA._FUTURE_FUNCTIONS == frozenset(_FUTURE_FUNCS)


def test_ft_inf_atoms_are_rebuilt_with_future_functions():
    """ft_inf's Right is FALSE where ft's is LAST: an atom with a future-time function has
    its own ft_inf conversion (ft's reused otherwise)."""
    f = _atoms_of("in m the sw shall always satisfy occurs(2, q)")
    assert f is not None and f._atoms[3] is not f._atoms[7] and f._atoms[3] != f._atoms[7]
    g = _atoms_of("in m the sw shall always satisfy persisted(2, q)")
    assert g is not None and g._atoms[3] is g._atoms[7]
    assert same("in m the sw shall always satisfy occurs(2, q)")
    assert same("in m the sw shall always satisfy persisted(2, q) | occurs(1, p)")


def test_shared_leaves_and_endpoints_are_bounded(monkeypatch):
    """The name leaves and named-mode endpoints are made once per name, and both tables
    are emptied together at their bound; texts stay the full build's."""
    monkeypatch.setattr(IA, "_LEAVES", {})
    monkeypatch.setattr(IA, "_ENDPOINTS", {})
    monkeypatch.setattr(IA, "_LEAVES_MAX", 3)
    a = _atoms_of("in m upon p the sw shall within 3 ticks satisfy q")
    b = _atoms_of("in m upon p the sw shall within 4 ticks satisfy q")
    assert a._atoms[1] is b._atoms[1]  # the leaf of p, shared
    texts = ["in m upon p%d the sw shall always satisfy persisted(2, q%d) & x%d > %d"
             % (i, i, i, i) for i in range(12)]
    for _i, t in enumerate(texts):
        assert same(t)
        assert len(IA._LEAVES) <= 3
    # the named-mode endpoints were emptied with the leaves (one mode name, m)
    assert len(IA._ENDPOINTS) <= 1
    assert IA._ENDPOINTS.get(("in", "m")) in (None, IA.named_endpoints("in", IA._LEAVES.get(
        ("ap", "m")) or IA.name_node("ap", "m")))


class _NotDigits(str):
    """A duration's text that does not look like a whole number: read as a Fraction."""

    def isdigit(self) -> bool:
        return False


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.from_regex(r"[0-9]{1,7}", fullmatch=True),
       st.sampled_from(["ticks", "seconds", "milliseconds", "minutes", "microseconds"]),
       st.sampled_from([None, Fraction(1, 10), Fraction(1), Fraction(3, 7)]))
def test_whole_durations_read_without_fraction(amount, unit, period):
    """duration_ticks reads a whole number as written (``007``) as its int: the same
    ticks, warnings and errors as the exact Fraction of the text."""
    from fretc.compiler import semantics
    from fretc.fretish import ast as A

    def outcome(d):
        warnings: list = []
        try:
            ticks = semantics.duration_ticks(d, period, warnings)
            return (type(ticks), ticks), warnings
        except FretishError as exc:
            return str(exc), warnings

    assert outcome(A.Duration(amount, unit)) == outcome(A.Duration(_NotDigits(amount), unit))


# ------------------------------------------------ --json: the forms joined from their pieces
_TEXT = st.text(alphabet=st.sampled_from('(a) &"\\%s{}\x00\x1fé€'), max_size=4)


def _form(fields_from: list):
    """A template form: literal texts (with ``%``, quotes, backslashes, NULs) between
    fields drawn from ``fields_from``, as ``(format, order)``."""
    return st.lists(st.tuples(_TEXT, st.sampled_from(fields_from)), max_size=6).flatmap(
        lambda segs: _TEXT.map(lambda tail: (
            "".join(t.replace("%", "%%") + "%s" for t, _ in segs) + tail.replace("%", "%%"),
            tuple(f for _, f in segs))))


_SMV_FIELDS = list(range(TT.BOUND0 + 6))
_SPOT_FIELDS = list(range(2 * TT.ATOMS)) + list(range(TT.BOUND0, TT.BOUND0 + 6))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.tuples(_form(_SMV_FIELDS), _form(_SMV_FIELDS), _form(_SMV_FIELDS),
                 _form(_SPOT_FIELDS), _form(_SPOT_FIELDS)),
       st.lists(_TEXT, min_size=12, max_size=12), st.lists(_TEXT, min_size=12, max_size=12),
       st.lists(_TEXT, min_size=6, max_size=6), st.booleans())
def test_json_pieces_fill_as_the_escaped_format(forms, smv, spot, bounds, plain):
    """json_format's pieces, filled with the escaped values by its getters and joined
    (InstantiatedFormalization.json_forms), give the five forms filled in by ``%`` and
    then escaped by json, separators between them: for any literal text (``%`` included,
    which takes the NUL-filling path) and any field order, with all twelve atoms or plain
    ones (the same four in every formula)."""
    enc = json.encoder.encode_basestring_ascii
    seps = (',\n    "ft_inf": ', ',\n    "pt": ', ',\n    "ft_spot": ', ',\n    "ft_inf_spot": ')
    if plain:
        smv, spot = smv[:4] * 3, spot[:4] * 3
    buffer, pick, pick_plain = TT.json_format(forms, enc, seps)

    def raw(i, f):
        if f >= TT.BOUND0:
            return bounds[f - TT.BOUND0]
        return smv[f] if i < 3 else spot[f]

    want = "".join((seps[i - 1] if i else "") + enc(fmt % tuple(raw(i, f) for f in fields))
                   for i, (fmt, fields) in enumerate(forms))
    e = [enc(x)[1:-1] for x in smv + bounds + spot + bounds]  # all twelve atoms' values
    if plain:
        values, getter = e[:4] + e[12:18] + e[18:22], pick_plain
    else:
        values, getter = e, pick
    got = buffer.copy()
    got[1::2] = getter(values)
    assert "".join(got) == want
