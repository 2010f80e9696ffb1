"""Start-up work of ``fretc FILE --emit ltl`` that was moved or written out keeps
its behaviour: :class:`common.errors.Where` behaves as the ``@dataclass(frozen=True)`` it
replaces, and :mod:`common.units` builds its table and regexp on first use."""

from __future__ import annotations

import copy
import dataclasses
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from common import units
from common.errors import Where

ROOT = Path(__file__).resolve().parents[1]

#: the class as it was: what the hand-written one must behave as
Generated = dataclasses.make_dataclass(
    "Where", [(n, object, dataclasses.field(default=None))
              for n in ("file", "line", "column", "topic", "log_time_ns")], frozen=True)
Generated.__str__ = Where.__str__

texts = st.one_of(st.none(), st.text(max_size=8))
ints = st.one_of(st.none(), st.integers(-5, 10**12))
fields5 = st.tuples(texts, ints, ints, texts, ints)


@given(fields5, fields5, st.integers(0, 5))
def test_where_behaves_as_the_generated_dataclass(a, b, positional):
    mine = [Where(*a[:positional], **dict(zip(Generated.__match_args__[positional:],
                                               a[positional:]))), Where(*b)]
    ref = [Generated(*a), Generated(*b)]
    for m, r in zip(mine, ref):
        assert repr(m) == repr(r) and str(m) == str(r)
        assert (m.file, m.line, m.column, m.topic, m.log_time_ns) == (
            r.file, r.line, r.column, r.topic, r.log_time_ns)
        assert hash(m) == hash(r)
        for name in ("file", "other"):
            with pytest.raises(dataclasses.FrozenInstanceError) as em:
                setattr(m, name, 1)
            with pytest.raises(dataclasses.FrozenInstanceError) as er:
                setattr(r, name, 1)
            assert str(em.value) == str(er.value)
            with pytest.raises(dataclasses.FrozenInstanceError) as em:
                delattr(m, name)
            with pytest.raises(dataclasses.FrozenInstanceError) as er:
                delattr(r, name)
            assert str(em.value) == str(er.value)
        for twin in (pickle.loads(pickle.dumps(m)), copy.copy(m), copy.deepcopy(m)):
            assert type(twin) is Where and twin == m and hash(twin) == hash(m)
    assert (mine[0] == mine[1]) == (ref[0] == ref[1])
    assert (mine[0] != mine[1]) == (ref[0] != ref[1])
    assert mine[0] != ref[0] and mine[0] != a  # another class is never equal
    assert Where.__match_args__ == Generated.__match_args__
    match mine[0]:
        case Where(f, ln, c, t, ns):
            assert (f, ln, c, t, ns) == a


def test_where_defaults_and_keywords():
    assert Where() == Where(None, None, None, None, None)
    assert repr(Where("r.fret", 3, column=7)) == (
        "Where(file='r.fret', line=3, column=7, topic=None, log_time_ns=None)")
    assert str(Where("r.fret", 3, 7, "/scan", 12)) == "r.fret:3:7 /scan @ 12 ns"
    with pytest.raises(TypeError):
        Where(nope=1)


def test_units_table_is_built_on_first_use():
    code = ("import common.units as u\n"
            "assert not u._TABLES\n"
            "assert u.parse_seconds('100 ms') * 10 == 1\n"
            "assert len(u._TABLES) == 1\n"
            "print(sorted(u.TIME_UNITS)[:3], u.TIME_UNITS['h'])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True).stdout
    assert out.strip() == "['h', 'hour', 'hours'] 3600"
    assert units.TIME_UNITS["µs"] * 1_000_000 == 1 == units.parse_seconds("10 Hz") * 10
    ns = {}
    exec("from common.units import *", ns)
    assert ns["TIME_UNITS"] is units.TIME_UNITS
    with pytest.raises(AttributeError):
        units.NOT_THERE  # noqa: B018


def test_emit_ltl_in_ticks_builds_no_unit_table(tmp_path):
    """``fretc FILE --emit ltl`` on sentences in ticks neither compiles the duration
    regexp nor builds the unit table; one in seconds does, with the same output as
    before."""
    fret = tmp_path / "r.fret"
    fret.write_text("R1: upon p the sw shall within 3 ticks satisfy q\n"
                    "R2: the sw shall always satisfy r\n")
    secs = tmp_path / "s.fret"
    secs.write_text("@tick_period 100 ms\nR1: upon p the sw shall within 2 seconds "
                    "satisfy q\n")
    code = ("import sys, io, contextlib\nfrom fretc.cli import main\n"
            "sys.argv = ['fretc', sys.argv[1], '--emit', 'ltl', '--json']\n"
            "out = io.StringIO()\n"
            "try:\n    with contextlib.redirect_stdout(out):\n        main()\n"
            "except SystemExit as e:\n    assert not e.code, e.code\n"
            "import common.units as u\n"
            "print(len(u._TABLES), '\"ft\"' in out.getvalue())")
    env = dict(os.environ, PYTHONPATH=str(ROOT), FRETC_CACHE_DIR=str(tmp_path / "c"))
    run = [subprocess.run([sys.executable, "-c", code, str(f)], capture_output=True,
                          text=True, env=env, check=True).stdout.split() for f in (fret, secs)]
    assert run == [["0", "True"], ["1", "True"]]


def _python(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True).stdout


def test_import_freezes_its_objects_and_restores_the_collector():
    """``import fretc.cli`` pauses the cyclic collector while it loads, moves what exists
    to the permanent generation and puts the collector back as it was."""
    out = _python("import gc\nimport fretc.cli\n"
                  "print(gc.isenabled(), gc.get_freeze_count() > 1000)")
    assert out.split() == ["True", "True"]
    out = _python("import gc\ngc.disable()\nimport fretc.cli\n"
                  "print(gc.isenabled(), gc.get_freeze_count() > 1000)")
    assert out.split() == ["False", "True"]
    # objects made afterwards are collected as before
    out = _python("import gc, weakref\nimport fretc.cli\n"
                  "class C: pass\n"
                  "a = C(); a.me = a; w = weakref.ref(a); del a\n"
                  "gc.collect(); print(w() is None)")
    assert out.strip() == "True"


def test_exit_freeze_only_when_the_command_paused_the_collector():
    out = _python("import gc\nfrom fretc import cli\n"
                  "n = gc.get_freeze_count(); x = [[] for _ in range(500)]\n"
                  "cli._freeze_if_paused(); a = gc.get_freeze_count()\n"
                  "gc.disable(); cli._freeze_if_paused(); b = gc.get_freeze_count()\n"
                  "print(a == n, b >= n + 500)")
    assert out.split() == ["True", "True"]


# --------------------------------------------------------------------------- written-out
# records (fretish.records): RequirementEntry, Compiled, Formalization behave as the
# @dataclass classes they replace
def _records():
    from compiler.build import Compiled
    from compiler.semantics import Formalization
    from fretish.files import RequirementEntry

    F = dataclasses.field
    return [
        (RequirementEntry, [
            ("id", str), ("text", str), ("source", str), ("line", int), ("column", int),
            ("rationale", object, F(default=None)), ("parent", object, F(default=None)),
            ("tick_period", object, F(default=None)), ("requirement", object, F(default=None)),
            ("error", object, F(default=None)), ("extra", dict, F(default_factory=dict)),
            ("inputs", tuple, F(default=())), ("outputs", tuple, F(default=()))]),
        (Compiled, [
            ("entry", object), ("formalization", object, F(default=None)),
            ("error", object, F(default=None)),
            ("_cache", dict, F(default_factory=dict, repr=False))]),
        (Formalization, [
            ("key", str), ("ft", object), ("ft_inf", object), ("pt", object),
            ("variables", list), ("warnings", list, F(default_factory=list)),
            ("ticks", object, F(default=None)), ("pt_causal", bool, F(default=True))]),
    ]


values = st.one_of(st.none(), st.integers(-3, 3), st.text(max_size=3),
                   st.lists(st.integers(0, 2), max_size=2))


@pytest.mark.parametrize("index", [0, 1, 2])
@given(data=st.data())
def test_records_behave_as_the_generated_dataclasses(index, data):
    import inspect

    cls, spec = _records()[index]
    ref = dataclasses.make_dataclass(cls.__name__, spec)
    names = [s[0] for s in spec]
    required = [s[0] for s in spec if len(s) == 2]
    assert cls.__match_args__ == ref.__match_args__ == tuple(names)
    def params(c):  # names, kinds and defaults (annotations are the source's strings)
        return [(p.name, p.kind, repr(p.default))
                for p in inspect.signature(c).parameters.values()]

    assert params(cls) == params(ref)
    assert cls.__hash__ is None and ref.__hash__ is None
    for name in names:  # class attributes: the plain defaults, as @dataclass leaves them
        assert getattr(cls, name, "absent") == getattr(ref, name, "absent"), name
    # the same arguments, positional for a prefix and keywords for the rest
    given_names = required + data.draw(st.lists(st.sampled_from(names[len(required):]),
                                                unique=True))
    args = {n: data.draw(values) for n in given_names}
    cut = data.draw(st.integers(0, len(required)))
    pos = [args[n] for n in names[:cut]]
    kw = {n: v for n, v in args.items() if n not in names[:cut]}
    a, b = cls(*pos, **kw), ref(*pos, **kw)
    assert repr(a).replace(type(a).__qualname__, "X", 1) == \
        repr(b).replace(type(b).__qualname__, "X", 1)
    assert [getattr(a, n) for n in names] == [getattr(b, n) for n in names]
    for n, _type, *f in spec:  # default factories: a new object per instance
        if n not in args and f and f[0].default_factory is not dataclasses.MISSING:
            assert getattr(a, n) is not getattr(cls(*pos, **kw), n)
    # equality: field by field, only with the same class
    other = dict(args)
    flip = data.draw(st.sampled_from(given_names))
    other[flip] = data.draw(values)
    a2, b2 = cls(**other), ref(**other)
    assert (a == a2) == (b == b2) and (a != a2) == (b != b2)
    assert a == cls(*pos, **kw) and a != b and a.__eq__(b) is NotImplemented
    with pytest.raises(TypeError) as mine:
        hash(a)
    with pytest.raises(TypeError) as theirs:
        hash(b)
    assert str(mine.value).replace(cls.__name__, "X") == \
        str(theirs.value).replace(cls.__name__, "X")
    if required:  # the same error for a missing argument
        with pytest.raises(TypeError) as mine:
            cls()
        with pytest.raises(TypeError) as theirs:
            ref()
        assert str(mine.value).split("__init__")[1] == str(theirs.value).split("__init__")[1]
    # still dataclasses: fields() and replace() as before
    assert dataclasses.is_dataclass(cls)
    assert [(f.name, f.default, f.default_factory, f.init, f.repr, f.compare)
            for f in dataclasses.fields(cls)] == [
        (f.name, f.default, f.default_factory, f.init, f.repr, f.compare)
        for f in dataclasses.fields(ref)]
    change = {flip: other[flip]}
    r1, r2 = dataclasses.replace(a, **change), dataclasses.replace(b, **change)
    assert type(r1) is cls and [getattr(r1, n) for n in names] == [getattr(r2, n) for n in names]
    twin = pickle.loads(pickle.dumps(a))
    assert type(twin) is cls and twin == a
    assert copy.copy(a) == a and copy.deepcopy(a) == a


def test_compile_path_imports_no_fractions(tmp_path):
    """``fretc FILE --emit ltl`` on sentences in ticks imports neither :mod:`fractions` nor
    :mod:`decimal`, nor the lazy modules (``compiler.ifthen``, ``unicodedata``); a tick
    period, a decimal duration, a probability and an
    ``if ... then`` load them on use, with the output of before."""
    plain = tmp_path / "r.fret"
    plain.write_text("R1: upon p the sw shall within 3 ticks satisfy q\n"
                     "R2: in m the sw shall always satisfy x + 1 > 2.5\n")
    timed = tmp_path / "s.fret"
    timed.write_text("@tick_period 100 ms\n"
                     "R1: upon p the sw shall within 2 seconds satisfy q\n"
                     "R2: upon p the sw shall with probability >= 0.5 always satisfy "
                     "if q then r\n"
                     "    rationale: attributes are read\n"
                     "R3: the sw shall within 1.5 ticks satisfy q\n")
    code = ("import sys, io, contextlib\nfrom fretc.cli import main\n"
            "sys.argv = ['fretc', sys.argv[1], '--emit', 'ltl', '--json']\n"
            "out = io.StringIO()\n"
            "try:\n    with contextlib.redirect_stdout(out):\n        main()\n"
            "except SystemExit as e:\n    code = e.code\n"
            "lazy = ('fractions', 'decimal', 'compiler.ifthen', 'unicodedata', 'dataclasses')\n"
            "print(code, *[m in sys.modules for m in lazy], out.getvalue().count('\"ft\"'))")
    env = dict(os.environ, PYTHONPATH=str(ROOT), FRETC_CACHE_DIR=str(tmp_path / "c"))
    # a first run builds the parser's tables (with Lark) where no cache holds them yet
    run = [[subprocess.run([sys.executable, "-c", code, str(f)], capture_output=True,
                           text=True, env=env, check=True).stdout.split()
            for _ in range(2)][1] for f in (plain, timed)]
    # dataclasses stays (fretish.ast's nodes are dataclasses): only the others are lazy
    assert run[0] == ["0", "False", "False", "False", "False", "True", "2"]
    assert run[1] == ["1", "True", "True", "True", "False", "True", "2"]
