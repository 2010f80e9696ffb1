"""Start-up work of ``fretc FILE --emit ltl`` (issue 9) that was moved or written out keeps
its behaviour: :class:`fretish.errors.Where` behaves as the ``@dataclass(frozen=True)`` it
replaces, and :mod:`fretish.units` builds its table and regexp on first use."""

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

from fretish import units
from fretish.errors import Where

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
    code = ("import fretish.units as u\n"
            "assert not u._TABLES\n"
            "assert u.parse_seconds('100 ms') * 10 == 1\n"
            "assert len(u._TABLES) == 1\n"
            "print(sorted(u.TIME_UNITS)[:3], u.TIME_UNITS['h'])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True).stdout
    assert out.strip() == "['h', 'hour', 'hours'] 3600"
    assert units.TIME_UNITS["µs"] * 1_000_000 == 1 == units.parse_seconds("10 Hz") * 10
    ns = {}
    exec("from fretish.units import *", ns)
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
            "import fretish.units as u\n"
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
