"""fretc's on-disk cache of derived data (the Lark parser tables, LTL3 automata).

Everything cached here is a pure function of its key, and every key names all the inputs
of the computation (e.g. the grammar text and Lark's version; a formula's shape and Spot's
version), so an entry is never stale: when an input changes, its key changes. Entries are
written to a temporary file in the same folder and renamed into place (``os.replace``,
atomic on POSIX and Windows), so a reader sees a whole entry or none. A cache that cannot
be read or written (read-only home, full disk, ``FRETC_CACHE_DIR=""``) is skipped
silently: the caller computes the value again, so the cache changes speed, never output.

Location: ``$FRETC_CACHE_DIR`` if set (empty: no disk cache), else
``$XDG_CACHE_HOME/fretc``, else ``~/.cache/fretc``.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pathlib is imported lazily (start-up time)
    from pathlib import Path

__all__ = ["cache_dir", "key_of", "files_key", "read_bytes", "write_bytes", "remove", "entry_path",
           "read_file", "write_file", "lark_cache_file", "read_sealed", "write_sealed", "digest"]


def _root() -> str | None:
    """:func:`cache_dir` as a string (no pathlib: this runs at every start-up)."""
    env = os.environ.get("FRETC_CACHE_DIR")
    if env is not None:
        return env if env.strip() else None
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg:
        return os.path.join(xdg, "fretc")
    home = os.path.expanduser("~")
    if home.startswith("~"):  # no home directory
        return None
    return os.path.join(home, ".cache", "fretc")


def cache_dir() -> Path | None:
    """The cache folder (a :class:`pathlib.Path`, not created here), or None when the disk
    cache is off."""
    root = _root()
    if root is None:
        return None
    from pathlib import Path
    return Path(root)


def key_of(*parts: str) -> str:
    """A hex SHA-256 of ``parts`` (joined unambiguously): a cache key.

    CPython's built-in SHA-256 (``_sha256``, 3.11; ``_sha2``, 3.12+) is used where present:
    ``hashlib`` loads OpenSSL (about 4 ms of every start-up) for the same digest."""
    h = _sha256()
    for p in parts:
        b = p.encode("utf-8")
        h.update(len(b).to_bytes(8, "little"))
        h.update(b)
    return h.hexdigest()


def files_key(kind: str, paths: Iterable[str], *parts: str) -> str:
    """A cache key (:func:`key_of`) of ``kind``, ``parts`` and the text of each file of
    ``paths`` (named by its path; a file that cannot be read by its path alone): the key of
    the code a cached value is made by, which changes when any of those files does. Raises
    nothing."""
    texts = []
    for path in paths:
        try:
            with open(path, encoding="utf-8") as f:
                texts.append(f"{path}\n{f.read()}")
        except (OSError, ValueError):
            texts.append(f"{path}\nunreadable")
    return key_of(kind, *parts, *texts)


def _sha256():
    """A new SHA-256 hash object (FIPS 180-4), without loading OpenSSL when CPython's own
    implementation is there."""
    try:
        from _sha256 import sha256  # CPython <= 3.11
    except ImportError:
        try:
            from _sha2 import sha256  # CPython >= 3.12
        except ImportError:
            from hashlib import sha256  # other interpreters
    return sha256()


def _entry(kind: str, name: str) -> str | None:
    root = _root()
    return None if root is None else os.path.join(root, kind, name)


def entry_path(kind: str, name: str) -> Path | None:
    """Where entry ``name`` of sub-folder ``kind`` lives (a :class:`pathlib.Path`; None:
    cache off)."""
    path = _entry(kind, name)
    if path is None:
        return None
    from pathlib import Path
    return Path(path)


def read_bytes(kind: str, name: str) -> bytes | None:
    """The entry's bytes, or None when missing or unreadable."""
    path = _entry(kind, name)
    return None if path is None else read_file(path)


def write_bytes(kind: str, name: str, data: bytes) -> bool:
    """Store an entry atomically (temporary file + rename). Returns False, without raising,
    when the cache folder cannot be created or written."""
    path = _entry(kind, name)
    return path is not None and write_file(path, data)


def read_sealed(kind: str, name: str, magic: bytes, made_from: bytes) -> bytes | None:
    """The payload of an entry written by :func:`write_sealed` with the same ``magic`` (the
    layout's first line) and ``made_from`` (a 32-byte SHA-256 of what the payload was made
    from), or None: no entry, another layout, made from something else, or a payload whose
    own SHA-256 does not match (damaged on disk)."""
    data = read_bytes(kind, name)
    if data is None or not data.startswith(magic):
        return None
    head = len(magic)
    payload = data[head + 64:]
    if data[head:head + 32] != made_from or data[head + 32:head + 64] != digest(payload):
        return None
    return payload


def write_sealed(kind: str, name: str, magic: bytes, made_from: bytes, payload: bytes) -> bool:
    """Store ``payload`` as entry ``name`` of ``kind``: ``magic``, ``made_from`` (32 bytes),
    the payload's SHA-256, the payload (read back by :func:`read_sealed`). An entry per
    name, replaced by the next write: the folder does not grow with each edit of what it was
    made from. False when the cache is off or not writable (never raises for that)."""
    return write_bytes(kind, name, b"".join((magic, made_from, digest(payload), payload)))


def digest(data: bytes) -> bytes:
    """The SHA-256 of ``data`` (32 bytes; FIPS 180-4), without loading OpenSSL
    (:func:`_sha256`)."""
    h = _sha256()
    h.update(data)
    return h.digest()


def remove(kind: str, name: str) -> bool:
    """Delete an entry (one found damaged, so the next run computes and writes it again).
    Returns False, without raising, when there is none or it cannot be removed."""
    path = _entry(kind, name)
    if path is None:
        return False
    try:
        os.unlink(path)
        return True
    except OSError:
        return False


def read_file(path: str) -> bytes | None:
    """The bytes of the cache file ``path`` (any folder), or None when missing or
    unreadable."""
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError:
        return None


def write_file(path: str, data: bytes) -> bool:
    """Write the cache file ``path`` (any folder, created if missing) atomically: a
    temporary file in the same folder renamed into place. Returns False, without raising,
    when that fails (a read-only folder, a full disk)."""
    tmp = None
    try:
        folder = os.path.dirname(path)
        os.makedirs(folder, exist_ok=True)
        import tempfile  # lazy: a run that only reads the cache does not need it

        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp",
                                   dir=folder)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
        return True
    except OSError:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return False


def lark_cache_file(name: str, grammar: str, lark_version: str, options: dict) -> str | None:
    """Where Lark keeps the tables of one grammar (Lark's ``cache=PATH`` option): the file
    ``lark/NAME-KEY.lark`` of the cache folder, KEY a hash of the grammar text, the Lark
    and Python versions and the parser ``options`` (Lark also stores a hash of them in the
    file and rebuilds when it does not match). Editing the grammar, upgrading Lark or Python
    gives a new file, never a stale one. None when the cache is off or its folder cannot be
    created (then Lark builds the tables in memory: the same parser, slower to start)."""
    import sys

    key = key_of(f"{name}-grammar", grammar, lark_version, "%d.%d" % sys.version_info[:2],
                 repr(sorted(options.items())))
    path = _entry("lark", f"{name}-{key[:40]}.lark")
    if path is None:
        return None
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
    except OSError:
        return None
    return path
