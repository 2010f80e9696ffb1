"""The template table in fretc's disk cache (:func:`compiler.instantiate.table_blob`): an
index behind a CRC-32 and each key's entry behind its own, checked on the key's first use.
A damaged table is never used: a damaged header or index means the table is built again;
a damaged key's entry means that key is built (and the cache entry removed)."""

from __future__ import annotations

import marshal
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from compiler import instantiate as I
from common import cache

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def entries():
    """The marshalled data of every key, as built (about 0.2 s)."""
    return tuple(marshal.dumps(I._build_key(k)) for k in I.ALL_KEYS)


@pytest.fixture(scope="module")
def blob(entries):
    return I.table_blob(entries)


def _data(table, key):
    view, _crc = table[key]
    return marshal.loads(view)


def test_round_trip(entries, blob):
    table = I.read_table(blob)
    assert table is not None and list(table) == list(I.ALL_KEYS)
    assert all(bytes(table[k][0]) == e for k, e in zip(I.ALL_KEYS, entries))
    for key in I.ALL_KEYS[::29]:
        assert I._from_table(table, key) == I._build_key(key)


@pytest.mark.parametrize("damage", [
    lambda b: b[:-1],                                  # cut short
    lambda b: b + b"\x00",                             # a byte too many
    lambda b: b[:100],                                 # cut in the index
    lambda b: b"x" + b[1:],                            # another layout
    lambda b: b[:len(I._MAGIC)] + b"\x00\x00\x00\x00" + b[len(I._MAGIC) + 4:],  # index CRC
    lambda b: b[:len(I._MAGIC) + 10] + bytes([b[len(I._MAGIC) + 10] ^ 1])
    + b[len(I._MAGIC) + 11:],                          # a flipped bit in the index
    lambda b: b"",
])
def test_damaged_header_or_index_is_not_a_table(blob, damage):
    assert I.read_table(damage(blob)) is None


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_any_flipped_byte_is_caught(blob, data):
    """Whatever byte is altered, every key's data read from the table is the key's own
    data or nothing (then built): never a wrong template."""
    pos = data.draw(st.integers(0, len(blob) - 1), label="position")
    xor = data.draw(st.integers(1, 255), label="xor")
    damaged = blob[:pos] + bytes([blob[pos] ^ xor]) + blob[pos + 1:]
    table = I.read_table(damaged)
    if table is None:
        return
    good = I.read_table(blob)
    for key in I.ALL_KEYS:
        view, crc = table[key]
        if I.zlib.crc32(view) == crc:
            assert bytes(view) == bytes(good[key][0]), key


def test_a_damaged_key_is_built_and_the_entry_removed(tmp_path, monkeypatch, entries):
    """An entry that still unmarshals but whose formula text was altered fails its CRC-32:
    the key is built (the right template), the others still come from the table, and the
    damaged cache entry is removed so the next run writes it again."""
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    i = next(i for i, e in enumerate(entries) if b"H" in e)
    forged = entries[i].replace(b"H", b"O", 1)
    assert marshal.loads(forged) != marshal.loads(entries[i])  # it still unmarshals
    good = I.table_blob(entries)
    start = len(good) - sum(map(len, entries[i:]))  # where the key's entry is
    assert good[start:start + len(forged)] == entries[i]
    name = I._cache_name()
    assert cache.write_bytes("templates", name,
                             good[:start] + forged + good[start + len(forged):])
    monkeypatch.setattr(I, "_TABLE", [])
    table = I._table()
    assert table is not None
    key = I.ALL_KEYS[i]
    assert I._from_table(table, key) is None
    assert cache.read_bytes("templates", name) is None  # removed
    other = I.ALL_KEYS[(i + 1) % len(I.ALL_KEYS)]
    assert I._from_table(table, other) == marshal.loads(entries[(i + 1) % len(entries)])
    # through template(): the key's template is the built one
    monkeypatch.setattr(I, "_TEMPLATES", {k: None for k in range(I._BUILT_BEFORE_TABLE)})
    scope, cond, timing, n = key
    t = I.template(scope, cond, timing, 5 if n == -1 else n)
    assert t.data == I._build_key(key)
    # the next process that needs the table writes it again, whole and right
    monkeypatch.setattr(I, "_TABLE", [])
    again = I._table()
    assert bytes(again[key][0]) == entries[i]
    assert cache.read_bytes("templates", name) == I.table_blob(entries)


def test_a_damaged_entry_on_disk_is_rebuilt(tmp_path, monkeypatch, entries):
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path))
    name = I._cache_name()
    cache.write_bytes("templates", name, b"\x00damaged")
    monkeypatch.setattr(I, "_TABLE", [])
    table = I._table()
    assert [bytes(table[k][0]) for k in I.ALL_KEYS] == list(entries)
    assert cache.read_bytes("templates", name) == I.table_blob(entries)


def test_cache_off_builds_every_key(monkeypatch):
    monkeypatch.setenv("FRETC_CACHE_DIR", "")
    monkeypatch.setattr(I, "_TABLE", [])
    assert I._table() is None


def _run(fret: Path, cache_dir: Path) -> str:
    env = dict(os.environ, FRETC_CACHE_DIR=str(cache_dir), PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "fretc", str(fret), "--emit", "ltl",
                           "--json"], capture_output=True, text=True, env=env,
                          check=True).stdout


def test_few_keys_never_touch_the_table(tmp_path):
    """A file of at most _BUILT_BEFORE_TABLE template keys builds them and neither reads
    nor writes the table (a first run stays quick); one more key and the table is written,
    with the same output."""
    timings = ["immediately", "always", "eventually", "never", "finally"]
    assert I._BUILT_BEFORE_TABLE == len(timings) - 1
    few = tmp_path / "few.fret"
    few.write_text("".join(f"R{i}: upon p the sw shall {t} satisfy q\n"
                           for i, t in enumerate(timings[:-1])))
    more = tmp_path / "more.fret"
    more.write_text(few.read_text() + "R9: upon p the sw shall finally satisfy q\n")
    out = _run(few, tmp_path / "c1")
    assert '"pt"' in out and not (tmp_path / "c1" / "templates").exists()
    built = _run(more, tmp_path / "c2")  # writes the table
    assert any((tmp_path / "c2" / "templates").iterdir())
    assert _run(more, tmp_path / "c2") == built == _run(more, tmp_path / "c1")
