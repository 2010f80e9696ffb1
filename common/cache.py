"""fretc's on-disk cache of derived data (parser tables, parsed files, LTL3 automata, the
text and bytecode of checked monitor modules).

Everything cached here is a pure function of its key, and every key names all the inputs
of the computation, so an entry is never stale; entries are renamed into place
(``os.replace``), so a reader sees a whole entry or none; a cache that cannot be read or
written is skipped silently: the cache changes speed, never output. It is not trusted
blindly: a private folder (:func:`cache_dir`), entries sealed by an HMAC under a key kept
outside every cache folder (:func:`key_dir`), reads bounded (:data:`MAX_ENTRY_BYTES`). The
rules in full (location, modes, the seal, bounded reads): ARCHITECTURE.md ("fretc's cache").
"""

from __future__ import annotations

import os
import stat
import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pathlib is imported lazily (start-up time)
    from pathlib import Path

__all__ = ["cache_dir", "key_dir", "key_of", "files_key", "read_sealed", "write_sealed",
           "remove", "digest", "hmac_sha256", "MAX_ENTRY_BYTES", "KEY_FILE"]

#: the largest entry read or written (bytes); a larger file in the folder is a miss
MAX_ENTRY_BYTES = 64 * 1024 * 1024
#: the name of the seal key's file in the key's folder (:func:`key_dir`; never a cache folder:
#: an entry may not have this name either, the name a key had in the cache folder until hostile round 9)
KEY_FILE = "seal-key"
_KEY_BYTES = 32
#: root -> the folder to use (the same string), or "" when refused (checked once a process)
_CHECKED: dict[str, str] = {}
#: root -> its seal key (the cache folder's: :func:`_seal_key`)
_KEYS: dict[str, bytes] = {}
_WARNED: set[str] = set()


def _euid() -> int | None:
    """The effective user id, or None where there is none (Windows: no mode checks)."""
    getter = getattr(os, "geteuid", None)
    return None if getter is None else getter()


def _warn(message: str) -> None:
    """Write ``fretc: warning: MESSAGE`` to the standard error once a process."""
    if message in _WARNED:
        return
    _WARNED.add(message)
    try:
        sys.stderr.write(f"fretc: warning: {message}\n")
    except (OSError, ValueError):  # a closed standard error: nothing to tell
        pass


def _root() -> str | None:
    """The cache folder's path as configured (not checked, not created), or None when the
    disk cache is off. No pathlib: this runs at every start-up."""
    env = os.environ.get("FRETC_CACHE_DIR")
    if env is not None:
        if not env.strip():
            return None
        if os.path.isabs(env):
            return env
        _warn(f"FRETC_CACHE_DIR={env!r} is not an absolute path: ignored "
              "(the default cache folder is used)")
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg and os.path.isabs(xdg):  # XDG Base Directory Specification: relative is invalid
        return os.path.join(xdg, "fretc")
    home = os.path.expanduser("~")
    if not os.path.isabs(home):  # no home directory ("~" left as it is)
        return None
    return os.path.join(home, ".cache", "fretc")


def cache_dir() -> Path | None:
    """The cache folder as configured (a :class:`pathlib.Path`, neither checked nor created
    here), or None when the disk cache is off."""
    root = _root()
    if root is None:
        return None
    from pathlib import Path
    return Path(root)


def _key_root() -> str | None:
    """The folder of the seal key as configured (not checked, not created), or None when
    there is none (then the disk cache is not used). ``$FRETC_STATE_DIR`` if set (empty:
    none; relative: ignored with a warning, as ``FRETC_CACHE_DIR``), else
    ``$XDG_STATE_HOME/fretc`` (absolute only: XDG Base Directory Specification 0.8), else
    ``~/.local/state/fretc``. No pathlib: this runs at every start-up that reads the cache."""
    env = os.environ.get("FRETC_STATE_DIR")
    if env is not None:
        if not env.strip():
            return None
        if os.path.isabs(env):
            return env
        _warn(f"FRETC_STATE_DIR={env!r} is not an absolute path: ignored "
              "(the default state folder is used)")
    xdg = os.environ.get("XDG_STATE_HOME")
    if xdg and os.path.isabs(xdg):
        return os.path.join(xdg, "fretc")
    home = os.path.expanduser("~")
    if not os.path.isabs(home):
        return None
    return os.path.join(home, ".local", "state", "fretc")


def key_dir() -> Path | None:
    """The folder that holds the cache's seal key (module docstring: ``$FRETC_STATE_DIR``,
    else ``$XDG_STATE_HOME/fretc``, else ``~/.local/state/fretc``; a :class:`pathlib.Path`,
    neither checked nor created here), or None when there is none (``FRETC_STATE_DIR=""``,
    no home): then the disk cache is not used."""
    root = _key_root()
    if root is None:
        return None
    from pathlib import Path
    return Path(root)


def _unsafe(st: os.stat_result, euid: int, own_only: bool) -> str | None:
    """Why a folder with status ``st`` cannot hold the cache (None: it can). ``own_only``:
    the cache folder itself (owned by the user, writable by no one else); otherwise a folder
    above it (owned by the user or root; writable by others only with the sticky bit)."""
    if not stat.S_ISDIR(st.st_mode):
        return "is not a folder"
    if st.st_uid != euid and (own_only or st.st_uid != 0):
        return f"is owned by another user (uid {st.st_uid})"
    if st.st_mode & 0o022 and (own_only or not st.st_mode & stat.S_ISVTX):
        return f"is writable by others (mode {stat.S_IMODE(st.st_mode):04o})"
    return None


def _problem(root: str, what: str = "the cache folder", closed: bool = False) -> str | None:
    """Why the existing folder ``root`` cannot hold the cache (or, ``what`` naming it, the
    seal key), or None. ``closed``: the folder must also be unreadable by group and others
    (mode 0700 or less: the seal key's folder). Raises OSError when it cannot be
    examined."""
    euid = _euid()
    if euid is None:
        return None
    real = os.path.realpath(root)
    st = os.stat(real)
    why = _unsafe(st, euid, True)
    if why is None and closed and st.st_mode & 0o077:
        why = f"is open to others (mode {stat.S_IMODE(st.st_mode):04o}, not 0700)"
    if why is not None:
        return f"{what} {root} {why}"
    # the folders above it as named (where a link to it would be replaced) and as resolved
    for start in {os.path.dirname(os.path.abspath(root)), os.path.dirname(real)}:
        parent = start
        while True:
            why = _unsafe(os.stat(parent), euid, False)
            if why is not None:
                return f"the folder {parent} above {what} {root} {why}"
            up = os.path.dirname(parent)
            if up == parent:
                break
            parent = up
    return None


def _make_private(folder: str) -> None:
    """Create ``folder`` and its missing parents with mode 0700 (whatever the umask; the XDG
    specification's mode for a folder it creates). Raises OSError."""
    missing = []
    while not os.path.isdir(folder):
        missing.append(folder)
        up = os.path.dirname(folder)
        if up == folder:
            break
        folder = up
    for path in reversed(missing):
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:
            continue  # made by another process meanwhile (checked below as any folder)
        os.chmod(path, 0o700)


def _usable(create: bool) -> str | None:
    """The cache folder when it can be used (checked once a process: see the module's
    docstring), creating it when ``create``; else None (one warning when it is refused)."""
    root = _root()
    if root is None:
        return None
    got = _CHECKED.get(root)
    if got is not None:
        return got or None
    try:
        if not os.path.lexists(root):
            if not create:
                return None  # (not remembered: a later write creates it)
            _make_private(root)
        why = _problem(root)
    except OSError:
        _CHECKED[root] = ""
        return None
    if why is not None:
        _warn(f"{why}: the cache is not used (it must be private to you, as ~/.ssh: "
              f"chmod 700 it, or set FRETC_CACHE_DIR to another folder)")
        _CHECKED[root] = ""
        return None
    _CHECKED[root] = root
    return root


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


def digest(data: bytes) -> bytes:
    """The SHA-256 of ``data`` (32 bytes; FIPS 180-4), without loading OpenSSL
    (:func:`_sha256`)."""
    h = _sha256()
    h.update(data)
    return h.digest()


def hmac_sha256(key: bytes, *parts: bytes | memoryview) -> bytes:
    """HMAC-SHA256 (RFC 2104, FIPS 198-1) of the concatenation of ``parts`` under ``key``
    (32 bytes), with :func:`_sha256` (``hmac`` imports ``hashlib``, which loads OpenSSL at
    every start-up). Raises ValueError for a key longer than SHA-256's 64-byte block."""
    if len(key) > 64:
        raise ValueError("an HMAC key of at most 64 bytes")
    block = key.ljust(64, b"\x00")
    inner = _sha256()
    inner.update(bytes(b ^ 0x36 for b in block))
    for p in parts:
        inner.update(p)
    outer = _sha256()
    outer.update(bytes(b ^ 0x5C for b in block))
    outer.update(inner.digest())
    return outer.digest()


def _read_regular(path: str, limit: int) -> bytes | None:
    """The bytes of ``path`` when it is a regular file of the user's of at most ``limit``
    bytes, opened without following a symbolic link and without blocking (a FIFO), checked
    with ``fstat`` after the open; else None. Raises nothing."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) \
        | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except (OSError, ValueError):
        return None
    try:
        st = os.fstat(fd)
        euid = _euid()
        if (not stat.S_ISREG(st.st_mode) or st.st_size > limit
                or (euid is not None and st.st_uid != euid)):
            return None
        chunks, size = [], 0
        while True:
            chunk = os.read(fd, min(limit + 1 - size, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
            if size > limit:  # grew since the fstat
                return None
        return b"".join(chunks)
    except OSError:
        return None
    finally:
        os.close(fd)


def _write_atomic(folder: str, name: str, data: bytes) -> bool:
    """Write ``folder/name`` (``folder`` made 0700 if missing) atomically: a temporary file
    (``mkstemp``: created exclusively, mode 0600) renamed over it, which replaces a symbolic
    link there rather than writing through it. False, without raising, when that fails."""
    tmp = None
    try:
        _make_private(folder)
        import tempfile  # lazy: a run that only reads the cache does not need it

        fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, os.path.join(folder, name))
        return True
    except OSError:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return False


def _seal_key(root: str, create: bool) -> bytes | None:
    """The seal key of the cache folder ``root``: HMAC-SHA256 of the folder's identity (its
    resolved path, device and inode numbers) under the user's secret key
    (:func:`_user_key`, made when missing and ``create``), so that a copy of the folder, or
    the folder restored from an archive, has another key (module docstring); None when
    there is no usable secret key (the cache is then not used; one warning when one is
    refused)."""
    got = _KEYS.get(root)
    if got:
        return got
    secret = _user_key(root, create)
    if secret is None:
        return None
    try:
        real = os.path.realpath(root)
        st = os.stat(real)
    except OSError:
        return None
    identity = f"{real}\x00{st.st_dev}\x00{st.st_ino}".encode("utf-8", "surrogatepass")
    key = hmac_sha256(secret, b"fretc cache folder key 1\x00", identity)
    _KEYS[root] = key
    return key


def _inside(path: str, folder: str) -> bool:
    """Whether ``path`` is ``folder`` or inside it, both resolved."""
    p, f = os.path.realpath(path), os.path.realpath(folder)
    return p == f or p.startswith(f.rstrip(os.sep) + os.sep)


def _user_key(root: str, create: bool) -> bytes | None:
    """The user's secret key (32 bytes) in :func:`key_dir`'s folder, made (with the folder,
    mode 0700) when missing and ``create``; None when there is none, or the folder or the
    file is refused (module docstring: one warning, and the cache folder ``root`` is not
    used)."""
    folder = _key_root()
    if folder is None:
        return None
    path = os.path.join(folder, KEY_FILE)
    try:
        if _inside(folder, root):
            why: str | None = (f"the seal key's folder {folder} is inside the cache folder "
                               f"{root} (a copy of the cache would bring its key)")
        elif not os.path.lexists(folder):
            if not create:
                return None
            _make_private(folder)
            why = _problem(folder, "the seal key's folder", closed=True)
        else:
            why = _problem(folder, "the seal key's folder", closed=True)
    except OSError:
        return None
    if why is not None:
        _warn(f"{why}: the cache is not used (the key's folder must be private to you: "
              "chmod 700 it, or set FRETC_STATE_DIR to another folder)")
        _CHECKED[root] = ""
        return None
    key = _read_regular(path, _KEY_BYTES)
    if key is None and create and not os.path.lexists(path):
        key = _make_key(folder, path)
    if key is not None and len(key) == _KEY_BYTES and _private(path):
        return key
    if key is not None or os.path.lexists(path):
        _warn(f"the cache's seal key {path} is not a private regular file of "
              f"{_KEY_BYTES} bytes (mode 0600): the cache is not used (remove the file: "
              "fretc makes another)")
        _CHECKED[root] = ""
    return None


def _private(path: str) -> bool:
    """Whether ``path`` is readable and writable by its owner alone (mode 0600 or less)."""
    try:
        return _euid() is None or not os.lstat(path).st_mode & 0o077
    except OSError:
        return False


def _make_key(root: str, path: str) -> bytes | None:
    """A new seal key written to ``path`` (in the folder ``root``): 32 bytes of
    ``os.urandom`` in a temporary file (mode 0600) linked to its name (``link`` never
    replaces: when another process made one first, that one is read). None when the folder
    cannot be written."""
    import tempfile

    key = os.urandom(_KEY_BYTES)
    try:
        fd, tmp = tempfile.mkstemp(prefix=".seal-key.", suffix=".tmp", dir=root)
    except OSError:
        return None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(key)
        try:
            os.link(tmp, path)
        except FileExistsError:
            return _read_regular(path, _KEY_BYTES)
        return key
    except OSError:
        return None
    finally:
        try:
            os.unlink(tmp)
        except OSError:
            pass


def _check_name(kind: str, name: str) -> None:
    """Raise ValueError unless ``kind`` and ``name`` are plain file names (no separator, not
    ``.``/``..``, not the seal key): an entry lives in ``<cache>/<kind>/<name>``."""
    for part in (kind, name):
        if (not part or part in (".", "..") or "/" in part or "\\" in part or "\x00" in part
                or part == KEY_FILE):
            raise ValueError(f"not a cache entry name: {part!r}")


def _seal(key: bytes, kind: str, name: str, head: bytes, payload: bytes | memoryview) -> bytes:
    """The seal of an entry: HMAC-SHA256 of ``kind/name``, a NUL, its magic and made-from
    digest (``head``) and its payload."""
    return hmac_sha256(key, f"{kind}/{name}".encode("utf-8", "surrogatepass"), b"\x00", head,
                       payload)


def read_sealed(kind: str, name: str, magic: bytes, made_from: bytes) -> bytes | None:
    """The payload of entry ``name`` of sub-folder ``kind`` written by :func:`write_sealed`
    with the same ``magic`` (the layout's first line) and ``made_from`` (a 32-byte SHA-256
    of what the payload was made from), or None: cache off or refused, no entry, not a
    regular file of the user's or over :data:`MAX_ENTRY_BYTES`, another layout, made from
    something else, or a seal (HMAC-SHA256 under the cache's key) that does not verify
    (altered, planted, written under another key, or in another folder: a copy). Raises
    ValueError for a ``kind`` or ``name`` that is not a plain file name."""
    _check_name(kind, name)
    root = _usable(create=False)
    if root is None:
        return None
    key = _seal_key(root, create=False)
    if key is None:
        return None
    data = _read_regular(os.path.join(root, kind, name), MAX_ENTRY_BYTES)
    head = len(magic)
    if data is None or not data.startswith(magic) or data[head:head + 32] != made_from:
        return None
    if data[head + 32:head + 64] != _seal(key, kind, name, data[:head + 32],
                                          memoryview(data)[head + 64:]):
        return None
    return data[head + 64:]


def write_sealed(kind: str, name: str, magic: bytes, made_from: bytes, payload: bytes) -> bool:
    """Store ``payload`` as entry ``name`` of ``kind``: ``magic``, ``made_from`` (32 bytes),
    the seal (HMAC-SHA256 of the kind, name and the rest under the cache's key), the payload
    (read back by :func:`read_sealed`). An entry per name, replaced by the next write: the
    folder does not grow with each edit of what it was made from. False when the cache is
    off, refused or not writable, or the entry would be over :data:`MAX_ENTRY_BYTES` (never
    raises for that). Raises ValueError for a ``kind`` or ``name`` that is not a plain file
    name."""
    _check_name(kind, name)
    if len(made_from) != 32:
        raise ValueError("made_from is a 32-byte digest")
    if len(magic) + 64 + len(payload) > MAX_ENTRY_BYTES:
        return False
    root = _usable(create=True)
    if root is None:
        return False
    key = _seal_key(root, create=True)
    if key is None:
        return False
    sealed = b"".join((magic, made_from, _seal(key, kind, name, magic + made_from, payload),
                       payload))
    return _write_atomic(os.path.join(root, kind), name, sealed)


def remove(kind: str, name: str) -> bool:
    """Delete an entry (one found damaged, so the next run computes and writes it again).
    Returns False, without raising, when there is none or it cannot be removed."""
    _check_name(kind, name)
    root = _usable(create=False)
    if root is None:
        return False
    try:
        os.unlink(os.path.join(root, kind, name))
        return True
    except OSError:
        return False
