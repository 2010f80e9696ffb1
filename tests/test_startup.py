"""Start-up of ``fretc`` as a user sees it: the first run stores the parser's tables in
fretc's cache folder and later runs read them, with the same output (a damaged entry or
no cache included); :class:`common.errors.Where` behaves as a ``@dataclass(frozen=True)``.
(That ``fretc FILE --emit ltl`` loads no Spot, numpy, Jinja2 or MCAP code is checked by
``tests/test_layering.py``.)"""

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


def _fretc(args, cache_dir) -> subprocess.CompletedProcess:
    """``fretc ARGS`` in a fresh process with fretc's cache folder at ``cache_dir``."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), FRETC_CACHE_DIR=str(cache_dir))
    return subprocess.run([sys.executable, "-c", "import sys; from fretc.cli import main; "
                           "sys.exit(main())", *map(str, args)], capture_output=True,
                          text=True, env=env, timeout=300)


def test_first_run_writes_the_parser_cache_and_later_runs_read_it(tmp_path):
    """A user's first ``fretc FILE --emit ltl`` builds the parser's tables and stores them
    (Lark's cache, in fretc's cache folder); the next runs read them; a damaged entry or no
    cache at all (``FRETC_CACHE_DIR=""``) gives the same output."""
    fret = tmp_path / "r.fret"
    fret.write_text("R1: upon p the sw shall within 3 ticks satisfy q\n"
                    "R2: in m the sw shall always satisfy x + 1 > 2.5\n")
    cache_dir = tmp_path / "cache"
    first = _fretc([fret, "--emit", "ltl", "--json"], cache_dir)
    assert first.returncode == 0, first.stderr
    (entry,) = (cache_dir / "lark").iterdir()
    stamp = entry.stat().st_mtime_ns
    again = _fretc([fret, "--emit", "ltl", "--json"], cache_dir)
    assert again.stdout == first.stdout and entry.stat().st_mtime_ns == stamp
    entry.write_bytes(entry.read_bytes()[:200])   # damaged: rebuilt, written again
    damaged = _fretc([fret, "--emit", "ltl", "--json"], cache_dir)
    assert damaged.stdout == first.stdout and damaged.stderr == ""
    assert entry.stat().st_size > 200
    off = _fretc([fret, "--emit", "ltl", "--json"], "")
    assert off.stdout == first.stdout and off.returncode == 0
    assert first.stdout.count('"ft"') == 2


def test_a_typo_is_reported_with_the_cache_cold_and_warm(tmp_path):
    fret = tmp_path / "r.fret"
    fret.write_text("R1: the sw shall always satisfy p &\n")
    runs = [_fretc([fret, "--emit", "ltl"], tmp_path / "cache") for _ in range(2)]
    assert [r.returncode for r in runs] == [1, 1]
    assert runs[0].stderr == runs[1].stderr
    assert "r.fret:1:" in runs[0].stderr and "unexpected end of the sentence" in runs[0].stderr
