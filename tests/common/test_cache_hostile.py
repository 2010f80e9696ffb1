"""fretc's disk cache against a hostile user of the cache folder:
a planted entry of any kind (a pickle, ``marshal`` code, module text, Lark's table file,
Jinja's compiled template) runs no code and changes no output; a crafted requirement entry
with its checksum recomputed does not turn a violation into ``satisfied``; a FIFO, a link to
``/dev/zero`` or a huge file at an entry's place blocks nothing and is not read.

The commands run in child processes (``python -m fretc``) that inherit this process's
environment, so that the tests can be run against another tree of fretc
(``PYTHONPATH=OTHER/src``): the planted entries are written in the layout the fretc imported
here reads (its modules' magic lines and made-from digests, the checksum recomputed as an
attacker without the cache's key can)."""

from __future__ import annotations

import hashlib
import hmac
import json
import marshal
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from fretc.common import cache

ROOT = Path(__file__).resolve().parents[2]
AUDIT = ["audit", "-r", "requirements/r1.fret", "traces/nominal.mcap", "--no-progress"]


def _fretc(args, cache_dir, timeout=300, limit_bytes=None) -> subprocess.CompletedProcess:
    """``python -m fretc ARGS`` from the clone's top, fretc's cache at ``cache_dir``; with
    ``limit_bytes``, the child's address space is capped there (a read without bound then
    fails with MemoryError instead of taking the machine's memory)."""
    env = dict(os.environ, FRETC_CACHE_DIR=str(cache_dir), COLUMNS="120", NO_COLOR="1")

    def cap():
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))

    return subprocess.run([sys.executable, "-m", "fretc", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, env=env, timeout=timeout,
                          preexec_fn=cap if limit_bytes else None)


class _Touch:
    """Unpickled, creates the file ``path`` (what a planted pickle could do: anything)."""

    def __init__(self, path: Path) -> None:
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _touch_code(path: Path):
    return compile(f"open({str(path)!r}, 'w').close()\n", "<planted>", "exec")


def _magic(kind: str) -> bytes | None:
    """The magic line of ``kind``'s entries in the fretc imported here (None: that fretc
    keeps the kind in another layout, handled by :func:`_forge`)."""
    from fretc.compiler import automata, code_cache, codegen, text_cache
    from fretc.fretish import entry_cache
    from fretc.signals.bindings import parse_cache

    if kind == "lark":
        try:
            from fretc.common import lark_tables
        except ImportError:
            return None
        return lark_tables._MAGIC
    return {"fret-entries": entry_cache._MAGIC, "binding-parses": parse_cache._MAGIC,
            "monitor-code": code_cache._MAGIC, "monitor-text": text_cache._MAGIC,
            "jinja": getattr(codegen, "_JINJA_MAGIC", None),
            "ltl3": getattr(automata, "_LTL3_MAGIC", None)}[kind]


def _forge(kind: str, legit: bytes, payload: bytes) -> bytes:
    """An entry of ``kind`` holding ``payload`` in place of the ``legit`` one: its magic and
    made-from digest kept, its checksum recomputed (SHA-256, as anyone can)."""
    magic = _magic(kind)
    if magic is not None:
        head = len(magic) + 32
        return legit[:head] + hashlib.sha256(payload).digest() + payload
    if kind == "jinja":  # SHA-256 then Jinja's bucket
        return hashlib.sha256(payload).digest() + payload
    if kind == "lark":  # Lark's own cache file: a hash line, then pickles
        return b"0" * 64 + b"\n" + payload
    raise AssertionError(kind)


def _payload(kind: str, legit: bytes) -> bytes:
    magic = _magic(kind)
    return legit[len(magic) + 64:] if magic is not None else legit[32:]


def _evil(kind: str, legit: bytes, marker: Path) -> bytes:
    """A planted entry of ``kind`` that creates ``marker`` if fretc runs any of its code."""
    if kind in ("fret-entries", "binding-parses", "lark"):
        return _forge(kind, legit, pickle.dumps(_Touch(marker)))
    if kind == "monitor-code":
        return _forge(kind, legit, marshal.dumps((_touch_code(marker), ())))
    if kind == "monitor-text":
        shapes = json.loads(_payload(kind, legit))["shapes"]
        text = f"open({str(marker)!r}, 'w').close()\n"
        return _forge(kind, legit, json.dumps({"text": text, "shapes": shapes}).encode())
    if kind == "jinja":
        import jinja2.bccache
        return _forge(kind, legit, jinja2.bccache.bc_magic + pickle.dumps(_Touch(marker)))
    raise AssertionError(kind)


KINDS = ("fret-entries", "binding-parses", "lark", "monitor-code", "monitor-text", "jinja")


def test_planted_entries_run_no_code_and_change_nothing(tmp_path):
    """Every entry of every kind an audit reads replaced by one that would create a marker
    file if fretc ran it (with its checksum recomputed): no marker, the same output and exit
    code as the cold run, and each planted entry replaced by a good one (it was read, and
    refused)."""
    cache_dir = tmp_path / "cache"
    cold = _fretc(AUDIT, cache_dir)
    assert cold.returncode == 0, cold.stderr
    planted = {}
    for kind in KINDS:
        files = sorted((cache_dir / kind).iterdir())
        assert files, kind
        for i, f in enumerate(files):
            f.write_bytes(_evil(kind, f.read_bytes(), tmp_path / f"ran-{kind}-{i}"))
            planted[f] = f.read_bytes()
    warm = _fretc(AUDIT, cache_dir)
    assert sorted(p.name for p in tmp_path.glob("ran-*")) == []
    assert (warm.returncode, warm.stdout) == (cold.returncode, cold.stdout), warm.stderr
    assert [str(f) for f, b in planted.items() if f.read_bytes() == b] == []


S1 = "S1: the sw shall always satisfy speed < 17.5\n"


def test_crafted_requirement_entry_does_not_turn_a_violation_into_satisfied(tmp_path):
    """The issue's input: ``S1`` violated (exit 1); its kept entry rewritten to say 99.5 where
    the file says 17.5, the checksum recomputed (SHA-256, or an HMAC under a key of the
    attacker's): still ``S1 violated``, exit 1."""
    (tmp_path / "s.fret").write_text(S1, encoding="utf-8")
    (tmp_path / "t.csv").write_text("time,speed\n0,1\n0.1,20\n0.2,3\n", encoding="utf-8")
    cache_dir = tmp_path / "cache"
    args = ["audit", "-r", tmp_path / "s.fret", tmp_path / "t.csv", "--no-progress"]
    cold = _fretc(args, cache_dir)
    assert cold.returncode == 1 and "S1 violated" in cold.stdout, cold.stdout + cold.stderr
    (entry,) = (cache_dir / "fret-entries").iterdir()
    legit = entry.read_bytes()
    magic = _magic("fret-entries")
    assert magic is not None
    payload = _payload("fret-entries", legit)
    crafted = payload.replace(b"17.5", b"99.5")
    assert crafted != payload
    other_key = bytes(range(32))
    label = f"fret-entries/{entry.name}".encode() + b"\x00"
    head = legit[:len(magic) + 32]
    for seal in (hashlib.sha256(crafted).digest(),
                 hmac.new(other_key, label + head + crafted, hashlib.sha256).digest()):
        entry.write_bytes(head + seal + crafted)
        got = _fretc(args, cache_dir)
        assert got.returncode == 1 and "S1 violated" in got.stdout, got.stdout + got.stderr
        assert "99.5" not in got.stdout


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_a_fifo_in_place_of_an_entry_blocks_nothing(tmp_path):
    """A FIFO where the requirement file's entry and the parser's tables are: the command
    ends (a blocking open would wait for a writer for ever) with the cold run's output."""
    fret = ROOT / "requirements" / "r1.fret"
    cache_dir = tmp_path / "cache"
    cold = _fretc([fret, "--emit", "ltl", "--json"], cache_dir)
    assert cold.returncode == 0, cold.stderr
    for kind in ("fret-entries", "lark"):
        for f in (cache_dir / kind).iterdir():
            f.unlink()
            os.mkfifo(f)
    try:
        got = _fretc([fret, "--emit", "ltl", "--json"], cache_dir, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.fail("fretc blocked on a FIFO in its cache folder")
    assert (got.returncode, got.stdout) == (0, cold.stdout), got.stderr


@pytest.mark.skipif(not os.path.exists("/dev/zero") or sys.platform == "darwin",
                    reason="no /dev/zero or no RLIMIT_AS")
def test_a_link_to_dev_zero_or_a_huge_file_is_not_read(tmp_path):
    """A link to ``/dev/zero`` in place of the requirement file's entry and a 3 GB sparse
    file in place of the parser's tables, the command's address space capped at 2 GB: it
    ends with the cold run's output (reading either would run out of memory)."""
    fret = ROOT / "requirements" / "r1.fret"
    cache_dir = tmp_path / "cache"
    cold = _fretc([fret, "--emit", "ltl", "--json"], cache_dir)
    assert cold.returncode == 0, cold.stderr
    for f in (cache_dir / "fret-entries").iterdir():
        f.unlink()
        f.symlink_to("/dev/zero")
    for f in (cache_dir / "lark").iterdir():
        with open(f, "r+b") as out:
            out.truncate(3 << 30)
    got = _fretc([fret, "--emit", "ltl", "--json"], cache_dir, timeout=120,
                 limit_bytes=2 << 30)
    assert (got.returncode, got.stdout) == (0, cold.stdout), got.stderr[-2000:]


def test_an_entry_over_the_bound_is_a_miss_and_never_written(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "c"))
    monkeypatch.setattr(cache, "MAX_ENTRY_BYTES", 1000)
    assert cache.write_sealed("k", "small", b"m\n", bytes(32), b"x" * 100)
    assert cache.read_sealed("k", "small", b"m\n", bytes(32)) == b"x" * 100
    assert not cache.write_sealed("k", "big", b"m\n", bytes(32), b"x" * 1000)
    assert not (tmp_path / "c" / "k" / "big").exists()
    f = tmp_path / "c" / "k" / "small"
    f.write_bytes(f.read_bytes() + b"y" * 1000)  # grown past the bound
    assert cache.read_sealed("k", "small", b"m\n", bytes(32)) is None


def test_entry_names_cannot_leave_their_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "c"))
    for kind, name in (("k", "../x"), ("..", "x"), ("k", cache.KEY_FILE), ("k", ""),
                       ("a/b", "x")):
        with pytest.raises(ValueError):
            cache.write_sealed(kind, name, b"m\n", bytes(32), b"p")
        with pytest.raises(ValueError):
            cache.read_sealed(kind, name, b"m\n", bytes(32))


def test_a_planted_ltl3_table_changes_no_monitor(tmp_path, monkeypatch):
    """An LTL3 table redirected on disk, its checksum recomputed (CRC-32 or SHA-256, as
    anyone can): the module rendered is the cold one, never one with the planted table."""
    import zlib

    from _monitor_helpers import entry
    from fretc.compiler import automata
    from fretc.compiler.build import compile_entry
    from fretc.compiler.codegen import render_module

    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
    compiled = [compile_entry(entry("R", "in m upon p the sw shall within 3 ticks satisfy q"))]
    good = render_module(compiled, "m")
    (f,) = (tmp_path / "ltl3").glob("*.json")
    raw = f.read_bytes()
    magic = _magic("ltl3")
    data = json.loads(raw[len(magic) + 64:] if magic is not None else raw[9:])
    table = data["bad"]["table"]
    table[0] = [(x + 1) % len(table) for x in table[0]]  # redirect the initial state
    body = json.dumps(data, separators=(",", ":")).encode()
    f.write_bytes(_forge("ltl3", raw, body) if magic is not None
                  else b"%08x\n" % zlib.crc32(body) + body)
    monkeypatch.setattr(automata, "_SHAPE_MEMO", {})
    assert render_module(compiled, "m") == good
