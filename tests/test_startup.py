"""Start-up of ``fretc`` as a user sees it: the first run stores the parser's tables and the
file's parsed entries in fretc's cache folder and later runs read them, with the same output (a damaged entry or
no cache included); :class:`fretc.common.errors.Where`'s defaults, ``repr`` and ``str``.
(That ``fretc FILE --emit ltl`` loads no Spot, numpy, Jinja2 or MCAP code is checked by
``tests/test_layering.py``.)"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from fretc.common.errors import Where

ROOT = Path(__file__).resolve().parents[1]

def test_where_defaults_and_keywords():
    assert Where() == Where(None, None, None, None, None)
    assert repr(Where("r.fret", 3, column=7)) == (
        "Where(file='r.fret', line=3, column=7, topic=None, log_time_ns=None)")
    assert str(Where("r.fret", 3, 7, "/scan", 12)) == "r.fret:3:7 /scan @ 12 ns"
    with pytest.raises(TypeError):
        Where(nope=1)


def _fretc(args, cache_dir) -> subprocess.CompletedProcess:
    """``fretc ARGS`` in a fresh process with fretc's cache folder at ``cache_dir``."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), FRETC_CACHE_DIR=str(cache_dir))
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
    (kept,) = (cache_dir / "fret-entries").iterdir()  # the file's entries, parsed
    stamps = entry.stat().st_mtime_ns, kept.stat().st_mtime_ns
    again = _fretc([fret, "--emit", "ltl", "--json"], cache_dir)
    assert again.stdout == first.stdout
    assert (entry.stat().st_mtime_ns, kept.stat().st_mtime_ns) == stamps
    kept.unlink()  # (the file parsed again, so that the parser's tables are read)
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
