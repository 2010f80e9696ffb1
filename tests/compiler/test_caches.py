"""fretc's disk caches (Lark parser tables, LTL3 automata by shape): safe, never stale, and
never a change of output; requirements that cannot be monitored are decided before any
automaton construction."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from fretc.compiler import automata, codegen, ltl3, spot_monitors
from fretc.compiler.build import compile_entry
from fretc.compiler.codegen import render_module
from fretc.fretish import parser as P

REPO = Path(__file__).resolve().parents[2]
#: damage done to a cache entry: cut, zeroed tail, altered magic
DAMAGES = (lambda b: b[:len(b) // 2], lambda b: b[:-10] + bytes(10), lambda b: b"x" + b[1:])


# same helpers as entry/load in tests/compiler/test_monitors_codegen.py (kept: each test file
# stands alone)
from _monitor_helpers import entry, load_source as load  # noqa: E402


SENTENCES = [
    "in m upon p the sw shall within 3 ticks satisfy q",
    "in mode2 upon alarm the sw shall within 3 ticks satisfy x > 2",  # same shape as above
    "whenever too_close agilex_agent shall eventually satisfy stopped",
    "only after m when c the sw shall for 2 ticks satisfy r | s",
    "the sw shall always satisfy (a & b) -> c",
]


# --------------------------------------------------------------------------- LTL3 by shape
def test_module_is_byte_identical_cold_warm_and_without_cache(tmp_path, monkeypatch):
    compiled = [compile_entry(entry(f"R{i}", t)) for i, t in enumerate(SENTENCES)]
    outputs = []
    for cache_dir in (tmp_path / "c", tmp_path / "c", ""):  # cold, warm from disk, off
        monkeypatch.setenv("FRETC_CACHE_DIR", str(cache_dir))
        monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
        outputs.append(render_module(compiled, "m"))
    assert outputs[0] == outputs[1] == outputs[2]
    files = list((tmp_path / "c" / "ltl3").glob("*.json"))
    # R0 and R1 share one shape: one entry for both
    assert len(files) == len(SENTENCES) - 1
    mod = load(outputs[0])
    assert mod.MONITORS["R0"]._BAD is None  # tables decoded lazily
    _m0, _m1 = mod.MONITORS["R0"](), mod.MONITORS["R1"]()
    assert mod.MONITORS["R0"]._BAD is mod.MONITORS["R1"]._BAD  # and shared


def test_shape_renames_atoms_in_order_of_appearance():
    f1 = compile_entry(entry("A", SENTENCES[0])).formalization.ft_inf
    f2 = compile_entry(entry("B", SENTENCES[1])).formalization.ft_inf
    s1, atoms1 = automata.canonical_shape(f1)
    s2, atoms2 = automata.canonical_shape(f2)
    assert s1 == s2
    assert [a.name for a in atoms1] == ["m", "p", "q"]
    assert atoms2[0].name == "mode2" and atoms2[2].op == "cmp"


def test_monitor_built_from_cache_agrees_with_spot_det(tmp_path, monkeypatch):
    """The canonical tables (low-effort translation, powerset, minimized) equal those of
    Spot's own deterministic monitor, renumbered the same way."""
    import spot

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    for text in SENTENCES:
        ft_inf = compile_entry(entry("R", text)).formalization.ft_inf
        shape, atoms = automata.canonical_shape(ft_inf)
        from fretc.compiler.printers import to_spot
        for negate in (False, True):
            ours = spot_monitors._spot_monitor(to_spot(shape), negate, len(atoms), 5000, 10)
            d = spot.make_bdd_dict()
            f = spot.formula(to_spot(shape))
            aut = spot.translate(spot.formula.Not(f) if negate else f, "monitor", "det",
                                 dict=d)
            names = [f"a{i}" for i in range(len(atoms))]
            var = {n: aut.register_ap(n) for n in names}
            rows = []
            for s in range(aut.num_states()):
                row = [-1] * (1 << len(names))
                for e in aut.out(s):
                    for letter in spot_monitors._letters(e.cond, var, names, 1 << len(names)):
                        row[letter] = e.dst
                rows.append(row)
            assert spot_monitors._bfs_tables(aut.get_init_state_number(), rows)[1] == ours["table"]


def test_future_pt_is_skipped_before_any_automaton(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("automaton built for a requirement that is skipped")

    monkeypatch.setattr(codegen, "ltl3_automata", boom)
    c = compile_entry(entry(
        "R", "the sw shall always satisfy persists(999999, occurs(999999, p))"))  # input limit 10^6
    mod = load(render_module([c], "m"))
    assert "R" in mod.SKIPPED and "future" in mod.SKIPPED["R"]


def test_huge_bound_gets_no_progression_attempt(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))

    def boom(*a, **k):
        raise AssertionError("progression attempted on a bound beyond MAX_STATES")

    monkeypatch.setattr(ltl3, "progression_tables", boom)
    c = compile_entry(entry("R", "upon p the sw shall within 5000 ticks satisfy q"))
    mod = load(render_module([c], "m"))
    m = mod.MONITORS["R"]()
    assert "no LTL3 monitor" in m.STATUS_NOTE
    m.step({"p": True, "q": False})
    assert m.status == "unknown"


def test_damaged_ltl3_entry_is_recomputed(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
    compiled = [compile_entry(entry("R", SENTENCES[0]))]
    good = render_module(compiled, "m")
    for f in (tmp_path / "ltl3").glob("*.json"):
        f.write_text('{"shape": "something else", "bad": null, "good": null}')
    monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
    assert render_module(compiled, "m") == good


def test_altered_ltl3_entry_is_recomputed(tmp_path, monkeypatch):
    """An entry whose table was altered on disk but is still valid JSON with the right
    shape (a flipped transition) fails its seal and is recomputed, never used."""
    import json

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
    compiled = [compile_entry(entry("R", SENTENCES[0]))]
    good = render_module(compiled, "m")
    (f,) = (tmp_path / "ltl3").glob("*.json")
    raw = f.read_bytes()
    head = len(automata._LTL3_MAGIC) + 64  # magic, made-from digest, seal
    data = json.loads(raw[head:])
    table = data["bad"]["table"]
    table[0] = [(x + 1) % len(table) for x in table[0]]  # redirect the initial state
    f.write_bytes(raw[:head] + json.dumps(data, separators=(",", ":")).encode())
    monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
    assert render_module(compiled, "m") == good
    assert f.read_bytes() == raw  # rewritten as computed


# --------------------------------------------------------------------------- Lark tables
TEXT = "in m upon p, the sw shall within 3 ticks satisfy x + 1 > -2"


def _parsed(lark) -> str:
    """The AST ``lark`` gives for TEXT (its builder set up as fretish.parser._run does)."""
    lark.options.transformer.begin(TEXT, 1, 1)
    return repr(lark.parse(TEXT, start="start"))


def _reference():
    return _parsed(P.build_lark())


def test_lark_tables_cached_and_reused(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    first = P.cached_lark()
    entries = list((tmp_path / "lark").iterdir())
    assert len(entries) == 1 and entries[0].suffix == ".lark"
    assert not list((tmp_path / "lark").glob(".*"))  # no temporary file left

    stamp = entries[0].stat().st_mtime_ns
    second = P.cached_lark()   # loaded: the entry is not written again
    assert entries[0].stat().st_mtime_ns == stamp
    assert _parsed(second) == _parsed(first)


def test_lark_cache_unwritable_or_damaged_falls_back(tmp_path, monkeypatch):
    ref = _reference()
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("x")
    monkeypatch.setenv("FRETC_CACHE_DIR", str(blocker))  # mkdir fails under a file
    assert _parsed(P.cached_lark()) == ref
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "c"))
    P.cached_lark()
    (entry_file,) = (tmp_path / "c" / "lark").iterdir()
    entry_file.write_bytes(entry_file.read_bytes()[:1000])  # truncated
    assert _parsed(P.cached_lark()) == ref
    assert entry_file.stat().st_size > 1000  # rewritten whole


def test_lark_cache_key_follows_the_grammar(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    P.cached_lark()
    edited = tmp_path / "grammar.lark"
    edited.write_text(type(tmp_path)(P._GRAMMAR_FILE).read_text(encoding="utf-8")
                      + "\n// edited\n",
                      encoding="utf-8")
    monkeypatch.setattr(P, "_GRAMMAR_FILE", edited)
    P.cached_lark()
    assert len(list((tmp_path / "lark").iterdir())) == 2  # a new entry, not the old one


@pytest.mark.parametrize("value", [""])
def test_cache_off(value, tmp_path, monkeypatch):
    from fretc.common import cache
    monkeypatch.setenv("FRETC_CACHE_DIR", value)
    assert cache.cache_dir() is None
    assert not cache.write_sealed("x", "y", b"m\n", bytes(32), b"z")
    assert _parsed(P.cached_lark()) == _reference()


# --------------------------------------------------------------------------- module bytecode
def _counting_compile(monkeypatch):
    """Count the compile() calls of codegen.check_module (the module's and each shape's)."""
    calls = []

    def counting(source, filename, mode, *args, **kwargs):
        calls.append(filename)
        return compile(source, filename, mode, *args, **kwargs)

    monkeypatch.setattr(codegen, "compile", counting, raising=False)
    return calls


def test_checked_module_code_is_reused_and_still_checked(tmp_path, monkeypatch):
    """A second check of the same module text takes its code objects from the disk cache
    (no compile) and gives the same module; the names check still runs on them: a builtin
    no longer allowed is reported although the code came from the cache."""
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    compiled = [compile_entry(entry(f"R{i}", t)) for i, t in enumerate(SENTENCES)]
    calls = _counting_compile(monkeypatch)
    first = render_module(compiled, "m")
    n_shapes = len(load(first)._SHAPES)
    assert len(calls) == 1 + n_shapes
    assert len(list((tmp_path / "monitor-code").iterdir())) == 1
    calls.clear()
    errors: list = []
    assert render_module(compiled, "m", errors) == first and not errors
    assert calls == []  # warm: nothing compiled
    monkeypatch.setattr(codegen, "_ALLOWED_BUILTINS", codegen._ALLOWED_BUILTINS - {"type"})
    render_module(compiled, "m", errors)
    assert errors and "undefined names type" in str(errors[0])
    assert errors[0].ids == [c.id for c in compiled]
    # the module's own check used the cached code; only the modules of each requirement
    # alone, checked after it (they fail before their shape is compiled), are compiled
    assert calls == ["<fretc monitors m>"] * len(compiled)


def test_module_code_entry_of_another_text_or_damaged_is_recompiled(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    one = [compile_entry(entry("R", SENTENCES[0]))]
    two = [compile_entry(entry("R", SENTENCES[3]))]
    calls = _counting_compile(monkeypatch)
    text_one = render_module(one, "m")
    render_module(two, "m")  # same module name, another text: replaces the entry
    assert len(list((tmp_path / "monitor-code").iterdir())) == 1
    calls.clear()
    assert render_module(one, "m") == text_one and len(calls) == 2  # a miss: compiled
    (f,) = (tmp_path / "monitor-code").iterdir()
    for damage in DAMAGES:
        f.write_bytes(damage(f.read_bytes()))
        calls.clear()
        assert render_module(one, "m") == text_one and len(calls) == 2


def test_module_code_cache_off_or_unwritable(tmp_path, monkeypatch):
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("x")
    outputs = []
    for value in ("", str(blocker)):
        monkeypatch.setenv("FRETC_CACHE_DIR", value)
        outputs.append(render_module([compile_entry(entry("R", SENTENCES[0]))], "m"))
    assert outputs[0] == outputs[1]


def test_templates_compiled_once_and_reloaded_from_disk(tmp_path, monkeypatch):
    """Jinja's compiled templates are kept in the cache: a new process (a new environment)
    renders from them without compiling the templates; a damaged entry is compiled again."""
    import jinja2

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    compiled = [compile_entry(entry("R", SENTENCES[0]))]
    codegen._env.cache_clear()
    first = render_module(compiled, "m")
    entries = sorted((tmp_path / "jinja").iterdir())
    assert len(entries) == 2  # the module and the shape template
    compiles = []
    real = jinja2.Environment.compile

    def counting(self, *a, **k):
        compiles.append(a)
        return real(self, *a, **k)

    monkeypatch.setattr(jinja2.Environment, "compile", counting)
    codegen._env.cache_clear()
    shutil.rmtree(tmp_path / "monitor-text")  # rendered again, not read (text_cache)
    assert render_module(compiled, "m") == first and compiles == []
    for damage in (lambda b: b[:40], lambda b: b[:-10] + bytes(10), lambda b: b[:60]):
        entries[0].write_bytes(damage(entries[0].read_bytes()))
        codegen._env.cache_clear()
        compiles.clear()
        shutil.rmtree(tmp_path / "monitor-text")
        assert render_module(compiled, "m") == first and len(compiles) == 1
    codegen._env.cache_clear()


def _no_jinja(monkeypatch) -> list:
    """Count the renders that reach Jinja (``codegen._env``)."""
    calls: list = []
    real = codegen._env

    def counted():
        calls.append(1)
        return real()

    monkeypatch.setattr(codegen, "_env", counted)
    return calls


def _shapes(module) -> dict:
    return {i: m.source.shape for i, m in module.monitors.items()}


@pytest.mark.parametrize("fret", sorted(p.name for p in
                                        (REPO / "requirements").glob("*.fret")) + ["sentences"])
def test_module_text_from_the_cache_is_the_rendered_text(fret, tmp_path, monkeypatch):
    """Cold, warm (read from disk, Jinja not called) and cache off give the same module text
    and the same shape of every monitor, for every requirement file of the repository."""
    from fretc.compiler.codegen import build_monitor_module
    from fretc.fretish.files import load_requirements

    entries = ([entry(f"R{i}", t) for i, t in enumerate(SENTENCES)] if fret == "sentences"
               else load_requirements(str(REPO / "requirements" / fret)))
    compiled = [compile_entry(e) for e in entries]
    renders = _no_jinja(monkeypatch)
    got = []
    for cache_dir in (tmp_path / "c", tmp_path / "c", ""):  # cold, warm, off
        monkeypatch.setenv("FRETC_CACHE_DIR", str(cache_dir))
        renders.clear()
        module = build_monitor_module([compile_entry(e) for e in entries] if got else compiled,
                                      "m")
        got.append((module.text, _shapes(module), len(renders)))
    assert got[0][:2] == got[1][:2] == got[2][:2]
    assert [n for _t, _s, n in got] == [1, 0, 1]


def test_module_text_entry_of_other_inputs_code_or_damaged_is_rendered(tmp_path, monkeypatch):
    """One entry per module name: another requirement under the same name replaces it; an
    entry made from other inputs or other code, or damaged, is a miss (rendered again, the
    same text), never another module's text."""
    from fretc.compiler import text_cache

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    one = [compile_entry(entry("R", SENTENCES[0]))]
    two = [compile_entry(entry("R", SENTENCES[3]))]
    renders = _no_jinja(monkeypatch)
    text_one, text_two = render_module(one, "m"), render_module(two, "m")
    assert text_one != text_two and len(renders) == 2
    assert len(list((tmp_path / "monitor-text").iterdir())) == 1
    assert render_module(one, "m") == text_one and len(renders) == 3  # replaced: a miss
    assert render_module(one, "m") == text_one and len(renders) == 3  # now a hit
    monkeypatch.setattr(text_cache, "_CODE_KEY", "other code")
    assert render_module(one, "m") == text_one and len(renders) == 4
    (f,) = (tmp_path / "monitor-text").iterdir()
    for damage in DAMAGES:
        f.write_bytes(damage(f.read_bytes()))
        renders.clear()
        assert render_module(one, "m") == text_one and len(renders) == 1


def test_module_text_code_key_follows_the_templates(tmp_path, monkeypatch):
    from fretc.compiler import text_cache

    monkeypatch.setattr(text_cache, "_CODE_KEY", None)
    key = text_cache._code_key()
    copy = tmp_path / "templates"
    shutil.copytree(text_cache._TEMPLATES, copy)
    shape = copy / "monitor_shape.py.j2"
    shape.write_text(shape.read_text() + "\n")
    monkeypatch.setattr(text_cache, "_TEMPLATES", str(copy))
    monkeypatch.setattr(text_cache, "_CODE_KEY", None)
    assert text_cache._code_key() != key


def test_binding_grammar_tables_cached_and_same_parse(tmp_path, monkeypatch):
    """The binding expression parser keeps its Lark tables in the same cache folder; a
    parser loaded from the file and one built in memory (cache off) give the same trees, and
    a damaged file is rebuilt."""
    from fretc.signals.bindings import parse as BP

    text = 'max("actuator_outputs".output[0:4]) <= 2000 & /odom.twist.twist.linear.x@abs < 1'

    def tree():
        BP._parser.cache_clear()
        return BP._parser().parse(text)  # Tree equality: rule names and tokens

    monkeypatch.setenv("FRETC_CACHE_DIR", "")
    ref = tree()
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    assert tree() == ref
    (entry_file,) = (tmp_path / "lark").glob("bindings-*.lark")
    stamp = entry_file.stat().st_mtime_ns
    assert tree() == ref  # loaded, not written again
    assert entry_file.stat().st_mtime_ns == stamp
    entry_file.write_bytes(entry_file.read_bytes()[:500])  # truncated
    assert tree() == ref
    assert entry_file.stat().st_size > 500
    BP._parser.cache_clear()
