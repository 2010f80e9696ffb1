"""Where fretc's cache lives and which folders it accepts: folders created
0700 whatever the umask; a folder owned by another user, or writable by others (itself, or
a folder above it without the sticky bit), skipped with one warning, never a failure; a
relative ``XDG_CACHE_HOME`` ignored (XDG Base Directory Specification); an HMAC seal under
the folder's own key (RFC 2104, checked against :mod:`hmac`), derived from a key kept outside
the cache folder (tests/common/test_cache_copied.py: a copied or restored folder)."""

from __future__ import annotations

import hashlib
import hmac
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.common import cache

ROOT = Path(__file__).resolve().parents[2]
MAGIC, MADE = b"test entry\n", bytes(range(32))


@pytest.fixture(autouse=True)
def _fresh(monkeypatch):
    """Each test checks its folders anew (the checks are remembered once a process)."""
    for name in ("_CHECKED", "_KEYS", "_WARNED"):
        if hasattr(cache, name):
            monkeypatch.setattr(cache, name, type(getattr(cache, name))())


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_folders_are_made_0700_whatever_the_umask(tmp_path, monkeypatch):
    root = tmp_path / "home" / ".cache" / "fretc"
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    old = os.umask(0)
    try:
        assert cache.write_sealed("kind", "name", MAGIC, MADE, b"payload")
    finally:
        os.umask(old)
    for folder in (tmp_path / "home", tmp_path / "home" / ".cache", root, root / "kind"):
        assert _mode(folder) == 0o700, folder
    assert _mode(root / "kind" / "name") == 0o600
    assert cache.read_sealed("kind", "name", MAGIC, MADE) == b"payload"


def _refused(capsys, root: Path) -> None:
    """The cache at ``root`` is neither read nor written, with one warning."""
    assert not cache.write_sealed("kind", "name", MAGIC, MADE, b"payload")
    assert cache.read_sealed("kind", "name", MAGIC, MADE) is None
    assert not cache.write_sealed("kind", "other", MAGIC, MADE, b"payload")
    assert not (root / "kind").exists()
    err = capsys.readouterr().err
    assert err.count("fretc: warning:") == 1 and "not used" in err, err


def test_a_cache_folder_writable_by_others_is_refused_with_one_warning(tmp_path, monkeypatch,
                                                                        capsys):
    root = tmp_path / "c"
    root.mkdir()
    root.chmod(0o777)
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    _refused(capsys, root)
    root.chmod(0o775)  # writable by the group: refused too
    monkeypatch.setattr(cache, "_CHECKED", {})
    _refused(capsys, root)


def test_a_folder_above_writable_by_others_is_refused_unless_sticky(tmp_path, monkeypatch,
                                                                     capsys):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    root = shared / "c"
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    root.mkdir(mode=0o700)
    _refused(capsys, root)
    shared.chmod(0o1777)  # as /tmp: others cannot rename or remove what is not theirs
    monkeypatch.setattr(cache, "_CHECKED", {})
    assert cache.write_sealed("kind", "name", MAGIC, MADE, b"payload")
    assert capsys.readouterr().err == ""


@pytest.mark.skipif(getattr(os, "geteuid", lambda: 1)() != 0,
                    reason="giving a folder to another user needs root")
def test_a_cache_folder_owned_by_another_user_is_refused(tmp_path, monkeypatch, capsys):
    root = tmp_path / "c"
    root.mkdir(mode=0o700)
    os.chown(root, 54321, 54321)
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    _refused(capsys, root)


def test_a_cache_folder_of_another_uid_is_refused(tmp_path, monkeypatch, capsys):
    """The same for any user running the tests: the folder is owned by someone else than
    the user fretc runs as."""
    root = tmp_path / "c"
    root.mkdir(mode=0o700)
    monkeypatch.setattr(cache, "_euid", lambda: os.stat(root).st_uid + 1)
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    _refused(capsys, root)


def test_a_relative_xdg_cache_home_is_ignored(tmp_path, monkeypatch):
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.delenv("FRETC_CACHE_DIR", raising=False)
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", "repo/.cache")
    assert cache.cache_dir() == home / ".cache" / "fretc"
    assert cache.write_sealed("kind", "name", MAGIC, MADE, b"payload")
    assert not (tmp_path / "repo").exists()
    assert (home / ".cache" / "fretc" / "kind" / "name").is_file()
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))  # absolute: used
    assert cache.cache_dir() == tmp_path / "xdg" / "fretc"


def test_a_relative_fretc_cache_dir_is_ignored_with_a_warning(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("FRETC_CACHE_DIR", "carried")
    assert cache.cache_dir() == tmp_path / "home" / ".cache" / "fretc"
    assert "not an absolute path" in capsys.readouterr().err
    assert cache.write_sealed("kind", "name", MAGIC, MADE, b"payload")
    assert not (tmp_path / "carried").exists()


def test_the_command_skips_a_cache_others_can_write_with_one_warning(tmp_path):
    """``fretc FILE --emit ltl`` with a cache folder of mode 0777: exit 0, the output of a
    run without cache, one warning, nothing written there."""
    root = tmp_path / "c"
    root.mkdir()
    root.chmod(0o777)
    fret = ROOT / "requirements" / "safe_ros.fret"

    def run(cache_dir):
        env = dict(os.environ, FRETC_CACHE_DIR=cache_dir)
        return subprocess.run([sys.executable, "-m", "fretc", str(fret), "--emit", "ltl"],
                              cwd=ROOT, capture_output=True, text=True, env=env, timeout=300)

    got, off = run(str(root)), run("")
    assert (got.returncode, got.stdout) == (0, off.stdout)
    assert got.stderr.count("fretc: warning:") == 1 and str(root) in got.stderr, got.stderr
    assert list(root.iterdir()) == []


def test_seal_key_is_private_and_kept_outside_the_cache(tmp_path, monkeypatch, capsys):
    """The key is made in the state folder (``FRETC_STATE_DIR``), never in the cache folder:
    mode 0600 in a folder of mode 0700, 32 bytes, one a user; a key readable by others is
    refused (the cache is then not used, one warning)."""
    root, state = tmp_path / "c", tmp_path / "state" / "fretc"
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    monkeypatch.setenv("FRETC_STATE_DIR", str(state))
    assert cache.write_sealed("kind", "name", MAGIC, MADE, b"payload")
    assert not (root / cache.KEY_FILE).exists()
    key = state / cache.KEY_FILE
    assert _mode(key) == 0o600 and len(key.read_bytes()) == 32 and _mode(state) == 0o700
    first = key.read_bytes()
    monkeypatch.setattr(cache, "_KEYS", {})
    assert cache.write_sealed("kind", "name2", MAGIC, MADE, b"payload")
    assert key.read_bytes() == first  # (one key a user)
    key.chmod(0o644)  # readable by others: refused
    monkeypatch.setattr(cache, "_KEYS", {})
    assert cache.read_sealed("kind", "name", MAGIC, MADE) is None
    assert "seal key" in capsys.readouterr().err


def test_an_entry_sealed_under_another_folders_key_is_a_miss(tmp_path, monkeypatch):
    for name in ("a", "b"):
        monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / name))
        assert cache.write_sealed("kind", "name", MAGIC, MADE, name.encode())
    (tmp_path / "b" / "kind" / "name").write_bytes((tmp_path / "a" / "kind" / "name").read_bytes())
    assert cache.read_sealed("kind", "name", MAGIC, MADE) is None  # b's key
    monkeypatch.setenv("FRETC_CACHE_DIR", str(tmp_path / "a"))
    assert cache.read_sealed("kind", "name", MAGIC, MADE) == b"a"
    assert cache.read_sealed("kind", "name", MAGIC, bytes(32)) is None  # made from another


@settings(max_examples=100, deadline=None)
@given(st.binary(min_size=0, max_size=64), st.lists(st.binary(max_size=200), max_size=4))
def test_hmac_is_the_standard_librarys(key, parts):
    assert cache.hmac_sha256(key, *parts) == hmac.new(key, b"".join(parts),
                                                      hashlib.sha256).digest()
