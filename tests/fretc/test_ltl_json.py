"""fretc.compile.ltl_json (the one-pass writer of ``fretc FILE --emit ltl --json``) against
the reference text ``json.dumps([c.to_json() for c in compiled], indent=2)``: random
requirement files (formalized, fallen back to the full build, failed, free-form) with ids,
sentences, rationales and parents that need escaping, FRET's vectors and the case-study
corpus, and values of unexpected types, which must take the general path."""

from __future__ import annotations

import json
import random
from fractions import Fraction
from pathlib import Path

from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.compiler.build import FORMALIZED_KEYS, Compiled, compile_entries
from differential import random_requirement
from fretc.cli import main
from fretc.cli.compile import json_indent2, ltl_json
from fretc.fretish.files import RequirementEntry, load_requirements
from fretc.fretish.parser import parse

ROOT = Path(__file__).resolve().parents[2]


def reference(compiled) -> str:
    return json.dumps([c.to_json() for c in compiled], indent=2)


def entry(rid, text, **kw) -> RequirementEntry:
    try:
        req, err = parse(text), None
    except Exception as exc:  # FretishError: the entry carries it, as the loader does
        req, err = None, exc
    return RequirementEntry(rid, text, kw.pop("source", "x.fret"), kw.pop("line", 1), 1,
                            requirement=req, error=err, **kw)


NASTY = st.text(alphabet=st.sampled_from('a"\\\n\t\x00\x1f\x7fé€😀 %{}'), max_size=6)
SENTENCES = st.one_of(
    st.integers(0, 2**32 - 1).map(lambda s: random_requirement(random.Random(s), depth=2)[0]),
    st.sampled_from([
        "upon p the sw shall always satisfy !q",             # falls back: negation
        "whenever p the sw shall until q satisfy q",         # falls back: stop = response
        "the sw shall always satisfy p and q",               # does not parse
        '"free form requirement"',                            # free-form
        'in "weird mode" the sw shall within 3 seconds satisfy "a b" > 2',
        "the sw shall within 2.5 ticks satisfy p",            # semantics error
        "only after m the sw shall for 4 ticks satisfy occurs(2, q) -> persisted(1, p)",
    ]))


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(NASTY, SENTENCES, st.one_of(st.none(), NASTY),
                          st.one_of(st.none(), NASTY),
                          st.sampled_from([None, Fraction(1, 10), Fraction(1)])),
                min_size=1, max_size=6))
def test_same_text_as_json_dumps(rows):
    entries = [entry(rid, text, rationale=rat, parent=parent, tick_period=period,
                     source=f"dir/{rid}.fret", line=i + 1)
               for i, (rid, text, rat, parent, period) in enumerate(rows)]
    compiled = compile_entries(entries)
    want = reference(compiled)
    assert ltl_json(compiled) == want
    assert json_indent2([c.to_json() for c in compiled]) == want


def test_fret_vectors_and_corpus(shared):
    texts = []
    for name in ("fret_vectors.jsonl", "fret_vectors_functions.jsonl"):
        texts += [json.loads(x)["text"]
                  for x in (shared / "fretish" / name).read_text().splitlines()]
    texts += [json.loads(x)["text"] for x in
              (shared / "corpora" / "fret_casestudies.jsonl").read_text().splitlines()]
    for period in (None, Fraction(1, 10)):
        compiled = compile_entries(entry(f"R{i}", t, tick_period=period)
                                   for i, t in enumerate(texts))
        assert ltl_json(compiled) == reference(compiled)


def test_values_of_other_types_take_the_general_path():
    """A value json_values does not document (a bool line, an int id, a tuple of
    variables, a float) is written as json.dumps writes it."""
    base = compile_entries([entry("A", "in m upon p the sw shall within 3 ticks satisfy q"),
                            entry("B", "the sw shall always satisfy x > 2")])
    for change in ({"line": True}, {"id": 7}, {"line": 2.5}, {"parent": ["a", 1]},
                   {"rationale": {"k": None}}):
        odd = []
        for c in base:
            e = c.entry
            fields = dict(vars(e))
            fields.update(change)
            odd.append(Compiled(RequirementEntry(**fields), formalization=c.formalization))
        assert ltl_json(odd) == reference(odd), change
    f = base[0].formalization
    odd = Compiled(base[0].entry, formalization=f)
    odd.__dict__["json_values"] = lambda texts=True: (
        Compiled.json_values(odd, texts)[:12] + ((f.variables[0],), [], 3, [], True))
    assert ltl_json([odd, base[1]]).startswith("[\n  {")  # general path, no crash
    assert ltl_json([]) == json.dumps([], indent=2)


def test_formalized_keys_are_to_json_keys():
    c = compile_entries([entry("A", "the sw shall always satisfy p")])[0]
    assert tuple(c.to_json()) == FORMALIZED_KEYS


def test_command_prints_the_reference_text(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text('A: in m upon p the sw shall within 3 ticks satisfy "q\\"x"\n'
                 "B: the sw shall always satisfy p and q\n"
                 "C: upon p the sw shall always satisfy !q\n"
                 "   rationale: caf\u00e9 \\ \"quoted\"\n", encoding="utf-8")
    res = CliRunner().invoke(main, [str(f), "--emit", "ltl", "--json"])
    assert res.exit_code == 1  # B does not parse
    compiled = compile_entries(load_requirements([str(f)]))
    assert res.stdout == reference(compiled) + "\n"


# ---------------------------------------------------------------- the command's streaming path
@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(st.text(alphabet=st.sampled_from('ab{}"\n, '), max_size=5), max_size=70))
def test_json_list_written_in_batches_is_the_joined_list(items):
    """_write_json_list writes what ``ltl_json`` returns (plus a newline) for any number of
    items, across the batch boundaries (0, 1, 31, 32, 33, 64, 65 ... items)."""
    import io

    from fretc.cli.compile import _WRITE_BATCH, _write_json_list

    assert _WRITE_BATCH < 70
    out = io.StringIO()
    _write_json_list(out, items)
    want = "[]" if not items else "[\n  " + ",\n  ".join(items) + "\n]"
    assert out.getvalue() == want + "\n"


def test_json_list_batches_at_the_boundaries():
    import io

    from fretc.cli.compile import _WRITE_BATCH, _write_json_list

    for n in (0, 1, _WRITE_BATCH - 1, _WRITE_BATCH, _WRITE_BATCH + 1, 2 * _WRITE_BATCH,
              2 * _WRITE_BATCH + 1):
        items = [json.dumps({"i": i}, indent=2).replace("\n", "\n  ") for i in range(n)]
        out = io.StringIO()
        _write_json_list(out, items)
        assert out.getvalue() == json.dumps([{"i": i} for i in range(n)], indent=2) + "\n"


def test_command_drops_each_requirement_once_its_text_is_made(tmp_path, monkeypatch):
    """``--emit ltl --json`` keeps the texts, not the requirements: when a requirement is
    compiled, the entries (parsed sentences) of the requirements before it are freed,
    except a failed one's (its error is printed before the list). Output as the
    reference."""
    import gc
    import weakref

    import fretc.compiler.build as build

    f = tmp_path / "r.fret"
    f.write_text("".join(f"R{i}: upon p{i} the sw shall within {i + 2} ticks satisfy q\n"
                         for i in range(5))
                 + "BAD: the sw shall within 2.5 ticks satisfy p\n"
                 + "".join(f"S{i}: the sw shall always satisfy x{i} > {i}\n"
                           for i in range(5)), encoding="utf-8")
    seen: list = []
    alive_before: list = []
    real = build.compile_entry

    def spy(entry):
        alive_before.append([r() is not None for r in seen])
        seen.append(weakref.ref(entry))
        return real(entry)

    monkeypatch.setattr(build, "compile_entry", spy)
    was = gc.isenabled()
    try:
        res = CliRunner().invoke(main, [str(f), "--emit", "ltl", "--json"])
    finally:
        if was:
            gc.enable()
    monkeypatch.setattr(build, "compile_entry", real)
    assert res.exit_code == 1
    compiled = compile_entries(load_requirements([str(f)]))
    assert res.stdout == reference(compiled) + "\n"
    assert "2.5 ticks" in res.stderr
    assert len(alive_before) == 11
    bad = 5
    for k, alive in enumerate(alive_before):
        # only the failed requirement's entry is kept (the one just compiled is not in
        # the list yet)
        assert alive == [i == bad for i in range(k)], (k, alive)
