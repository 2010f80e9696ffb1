"""The cache's key does not travel with the cache (hostile round 9, C1).

Until then the seal key was a file ``seal-key`` in the cache folder it sealed, so a cache
folder copied or restored with its modes (a CI cache, a tar file, an image layer) brought a
key that sealed forged entries: one turned ``S1 violated`` (exit 1) into satisfied (exit 0).
Now the key is derived from a secret kept in the user's state folder (``FRETC_STATE_DIR``
here, a folder of the test's own: never the real home) and from the cache folder's identity:

* an entry forged under a key planted in the cache folder is a miss: the verdict stands;
* a folder copied (``shutil.copytree``, modes kept) or restored from a tar file is a miss
  for every entry, and the audit's verdicts and exit codes are the cold run's;
* the key's folder and file are used only when private (0700, 0600), and never inside the
  cache folder.
"""

from __future__ import annotations

import hashlib
import hmac
import io
import os
import shutil
import stat
import subprocess
import sys
import tarfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.common import cache

ROOT = Path(__file__).resolve().parents[2]
MAGIC, MADE = b"test entry\n", bytes(range(32))
S1 = "S1: the sw shall always satisfy speed < 17.5\n"


@pytest.fixture(autouse=True)
def _fresh(monkeypatch, tmp_path):
    """Each test checks its folders anew, with a key folder of its own."""
    for name in ("_CHECKED", "_KEYS", "_WARNED"):
        monkeypatch.setattr(cache, name, type(getattr(cache, name))())
    monkeypatch.setenv("FRETC_STATE_DIR", str(tmp_path / "state"))


def _fretc(args, cache_dir: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, FRETC_CACHE_DIR=str(cache_dir), COLUMNS="120", NO_COLOR="1")
    return subprocess.run([sys.executable, "-m", "fretc", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, env=env, timeout=300)


def _tar_round_trip(folder: Path, into: Path) -> None:
    """``folder`` archived with its modes and extracted as ``into`` (a CI cache's restore)."""
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w") as tar:
        tar.add(folder, arcname=into.name)
    buf.seek(0)
    with tarfile.open(fileobj=buf, mode="r") as tar:
        tar.extractall(into.parent, filter="fully_trusted")
    assert stat.S_IMODE(into.stat().st_mode) == stat.S_IMODE(folder.stat().st_mode)


def _forge_s1(entry: Path, key: bytes) -> None:
    """The S1 entry rewritten to say 99.5 where the file says 17.5, sealed as an HMAC under
    ``key`` (what a key in the cache folder allowed anyone who could copy it)."""
    from fretc.fretish import entry_cache

    magic = entry_cache._MAGIC
    legit = entry.read_bytes()
    head, payload = legit[:len(magic) + 32], legit[len(magic) + 64:]
    crafted = payload.replace(b"17.5", b"99.5")
    assert crafted != payload
    label = f"fret-entries/{entry.name}".encode() + b"\x00"
    entry.write_bytes(head + hmac.new(key, label + head + crafted, hashlib.sha256).digest()
                      + crafted)


def test_a_forged_entry_under_a_key_in_the_restored_folder_keeps_s1_violated(tmp_path):
    """The finding's smallest input: S1 violated (exit 1); its cache folder holds a
    ``seal-key`` (the old layout, or one planted) under which the S1 entry is forged to say
    99.5, and the folder is restored from a tar file: still ``S1 violated``, exit 1, and no
    key was written into the cache folder by fretc."""
    (tmp_path / "s.fret").write_text(S1, encoding="utf-8")
    (tmp_path / "t.csv").write_text("time,speed\n0,1\n0.1,20\n0.2,3\n", encoding="utf-8")
    args = ["audit", "-r", tmp_path / "s.fret", tmp_path / "t.csv", "--no-progress"]
    made = tmp_path / "made"
    cold = _fretc(args, made)
    assert cold.returncode == 1 and "S1 violated" in cold.stdout, cold.stdout + cold.stderr
    assert not (made / cache.KEY_FILE).exists()
    planted = bytes(range(32))
    (made / cache.KEY_FILE).write_bytes(planted)
    (made / cache.KEY_FILE).chmod(0o600)
    (entry,) = (made / "fret-entries").iterdir()
    _forge_s1(entry, planted)
    restored = tmp_path / "restored" / "cache"
    restored.parent.mkdir(mode=0o700)
    _tar_round_trip(made, restored)
    got = _fretc(args, restored)
    assert (got.returncode, got.stdout) == (cold.returncode, cold.stdout), got.stderr
    assert "99.5" not in got.stdout
    # and in the folder it was forged in
    again = _fretc(args, made)
    assert (again.returncode, again.stdout) == (cold.returncode, cold.stdout), again.stderr


def test_a_copied_folder_is_a_miss_and_the_verdicts_are_unchanged(tmp_path):
    """A cache folder copied with its modes (``shutil.copytree``): every entry of the copy is
    a miss, rewritten by the run (sealed for the copy's own identity), and the audit's
    output and exit code are the cold run's; the original's entries still verify."""
    (tmp_path / "s.fret").write_text(S1, encoding="utf-8")
    (tmp_path / "t.csv").write_text("time,speed\n0,1\n0.1,20\n0.2,3\n", encoding="utf-8")
    args = ["audit", "-r", tmp_path / "s.fret", tmp_path / "t.csv", "--no-progress"]
    made = tmp_path / "made"
    cold = _fretc(args, made)
    assert cold.returncode == 1, cold.stdout + cold.stderr
    copy = tmp_path / "copy"
    shutil.copytree(made, copy)  # (copy2: the modes kept)
    before = {p.relative_to(copy): p.read_bytes() for p in copy.rglob("*") if p.is_file()}
    assert before
    got = _fretc(args, copy)
    assert (got.returncode, got.stdout) == (cold.returncode, cold.stdout), got.stderr
    rewritten = [p for p, b in before.items() if (copy / p).read_bytes() != b]
    assert any(str(p).startswith("fret-entries") for p in rewritten), rewritten


def _entries(root: Path, names: list[str]) -> None:
    for n in names:
        assert cache.write_sealed("kind", n, MAGIC, MADE, n.encode())


def _reading(monkeypatch, root: Path) -> None:
    monkeypatch.setenv("FRETC_CACHE_DIR", str(root))
    monkeypatch.setattr(cache, "_CHECKED", {})
    monkeypatch.setattr(cache, "_KEYS", {})


@settings(max_examples=20, deadline=None)
@given(st.lists(st.text("abcdef0123456789", min_size=1, max_size=12), min_size=1,
                max_size=5, unique=True),
       st.sampled_from(["copytree", "tar"]))
def test_every_entry_of_a_copied_or_restored_folder_is_a_miss(tmp_path_factory, names, how):
    """Entries written in a folder read back there; the folder copied (``copytree``) or
    restored from a tar file elsewhere: none of them is read (the same user, the same key
    folder: only the folder's identity differs)."""
    base = tmp_path_factory.mktemp("copied")
    with pytest.MonkeyPatch.context() as mp:
        for name in ("_CHECKED", "_KEYS", "_WARNED"):
            mp.setattr(cache, name, type(getattr(cache, name))())
        mp.setenv("FRETC_STATE_DIR", str(base / "state"))
        root = base / "cache"
        _reading(mp, root)
        _entries(root, names)
        assert [cache.read_sealed("kind", n, MAGIC, MADE) for n in names] == \
            [n.encode() for n in names]
        other = base / "other"
        if how == "copytree":
            shutil.copytree(root, other)
        else:
            _tar_round_trip(root, other)
        _reading(mp, other)
        assert [cache.read_sealed("kind", n, MAGIC, MADE) for n in names] == [None] * len(names)
        _reading(mp, root)  # (the original still reads)
        assert cache.read_sealed("kind", names[0], MAGIC, MADE) == names[0].encode()


def test_the_folder_restored_for_another_user_key_is_a_miss(tmp_path, monkeypatch):
    """A restore on another machine or account (another state folder, so another key), at
    the same path: a miss."""
    root = tmp_path / "cache"
    _reading(monkeypatch, root)
    _entries(root, ["a"])
    monkeypatch.setenv("FRETC_STATE_DIR", str(tmp_path / "state2"))
    _reading(monkeypatch, root)
    assert cache.read_sealed("kind", "a", MAGIC, MADE) is None


@pytest.mark.skipif(cache._euid() is None, reason="no file modes on this system")
@pytest.mark.parametrize("mode", [0o640, 0o604, 0o700, 0o666])
def test_a_key_file_open_to_others_is_refused(tmp_path, monkeypatch, capsys, mode):
    root, state = tmp_path / "cache", tmp_path / "state"
    _reading(monkeypatch, root)
    _entries(root, ["a"])
    (state / cache.KEY_FILE).chmod(mode)
    _reading(monkeypatch, root)
    expected = None if mode & 0o077 else b"a"
    assert cache.read_sealed("kind", "a", MAGIC, MADE) == expected
    err = capsys.readouterr().err
    assert ("seal key" in err and "not used" in err) == (expected is None), err


@pytest.mark.skipif(cache._euid() is None, reason="no file modes on this system")
@pytest.mark.parametrize("mode", [0o750, 0o705, 0o755, 0o777])
def test_a_key_folder_open_to_others_is_refused(tmp_path, monkeypatch, capsys, mode):
    root, state = tmp_path / "cache", tmp_path / "state"
    _reading(monkeypatch, root)
    _entries(root, ["a"])
    state.chmod(mode)
    _reading(monkeypatch, root)
    assert cache.read_sealed("kind", "a", MAGIC, MADE) is None
    assert not cache.write_sealed("kind", "b", MAGIC, MADE, b"b")
    err = capsys.readouterr().err
    assert err.count("fretc: warning:") == 1 and str(state) in err and "not used" in err, err


def test_the_key_is_made_private_and_never_in_the_cache_folder(tmp_path, monkeypatch):
    root, state = tmp_path / "cache", tmp_path / "deep" / "state"
    _reading(monkeypatch, root)
    monkeypatch.setenv("FRETC_STATE_DIR", str(state))
    old = os.umask(0)
    try:
        _entries(root, ["a"])
    finally:
        os.umask(old)
    assert stat.S_IMODE(state.stat().st_mode) == 0o700
    assert stat.S_IMODE((state / cache.KEY_FILE).stat().st_mode) == 0o600
    assert sorted(p.name for p in root.iterdir()) == ["kind"]


def test_a_key_folder_inside_the_cache_folder_is_refused(tmp_path, monkeypatch, capsys):
    """``FRETC_STATE_DIR`` inside ``FRETC_CACHE_DIR``: a copy of the cache would bring the
    key, so the cache is not used (one warning)."""
    root = tmp_path / "cache"
    _reading(monkeypatch, root)
    monkeypatch.setenv("FRETC_STATE_DIR", str(root / "state"))
    assert not cache.write_sealed("kind", "a", MAGIC, MADE, b"a")
    assert "inside the cache folder" in capsys.readouterr().err
    assert not (root / "state").exists()


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="no symbolic links")
def test_a_key_file_that_is_a_link_is_refused(tmp_path, monkeypatch, capsys):
    root, state = tmp_path / "cache", tmp_path / "state"
    _reading(monkeypatch, root)
    _entries(root, ["a"])
    key = state / cache.KEY_FILE
    (tmp_path / "elsewhere").write_bytes(key.read_bytes())
    (tmp_path / "elsewhere").chmod(0o600)
    key.unlink()
    key.symlink_to(tmp_path / "elsewhere")
    _reading(monkeypatch, root)
    assert cache.read_sealed("kind", "a", MAGIC, MADE) is None
    assert "seal key" in capsys.readouterr().err


def test_no_key_folder_means_no_cache_never_a_failure(tmp_path, monkeypatch):
    """``FRETC_STATE_DIR=""``: no key, so nothing is read or written (the cache changes
    speed, never output)."""
    root = tmp_path / "cache"
    _reading(monkeypatch, root)
    monkeypatch.setenv("FRETC_STATE_DIR", "")
    assert not cache.write_sealed("kind", "a", MAGIC, MADE, b"a")
    assert cache.read_sealed("kind", "a", MAGIC, MADE) is None
    assert cache.key_dir() is None


def test_key_dir_follows_xdg_state_home(tmp_path, monkeypatch):
    monkeypatch.delenv("FRETC_STATE_DIR", raising=False)
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "xdg"))
    assert cache.key_dir() == tmp_path / "xdg" / "fretc"
    monkeypatch.setenv("XDG_STATE_HOME", "relative/state")  # invalid: ignored (XDG 0.8)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache.key_dir() == tmp_path / "home" / ".local" / "state" / "fretc"
