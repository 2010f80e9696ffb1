"""common.cache.key_of: the same digest as hashlib's SHA-256 over the same framing (it uses
CPython's built-in SHA-256 to avoid loading OpenSSL at start-up), and unambiguous framing."""

from __future__ import annotations

import hashlib

from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.common import cache
from fretc.common.cache import key_of


def _reference(*parts: str) -> str:
    h = hashlib.sha256()
    for p in parts:
        b = p.encode("utf-8")
        h.update(len(b).to_bytes(8, "little") + b)
    return h.hexdigest()


@settings(max_examples=200, deadline=None)
@given(st.lists(st.text(max_size=40), max_size=5))
def test_key_is_hashlib_sha256_of_the_framed_parts(parts):
    assert key_of(*parts) == _reference(*parts)


def test_framing_separates_parts():
    assert key_of("ab", "c") != key_of("a", "bc")
    assert key_of("") != key_of()
    assert len(key_of("abc")) == 64 and int(key_of("abc"), 16) >= 0


def test_files_key_follows_each_file_and_part(tmp_path):
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("x = 1\n")
    b.write_text("y = 2\n")
    key = cache.files_key("k", [str(a), str(b)], "3.11")
    assert cache.files_key("k", [str(a), str(b)], "3.11") == key
    assert cache.files_key("k", [str(a), str(b)], "3.12") != key
    assert cache.files_key("other", [str(a), str(b)], "3.11") != key
    b.write_text("y = 3\n")
    changed = cache.files_key("k", [str(a), str(b)], "3.11")
    assert changed != key
    b.unlink()  # a file that cannot be read gives a key of its own, no error
    assert cache.files_key("k", [str(a), str(b)], "3.11") not in (key, changed)
