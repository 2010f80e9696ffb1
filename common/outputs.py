"""Writing fretc's output files without ever writing through a link planted where they go.

Every command that writes files (``--emit ... -o``, ``testgen -o``, ``testrun``, ``shield
-o``, ``audit --json/--junit/--write-csv``, ``report -o``, ``check --witness-dir``, ...)
writes them with these functions. An output folder is often shared or prepared by someone
else (a CI workspace, ``/tmp``, a checked-out repository), and a symbolic link planted there
under the name of an output (``D/T01.csv -> ~/.bashrc``) must not make fretc overwrite the
file it points to; nor may a hard link to another file.

Design notes: ARCHITECTURE.md, `common/outputs.py`."""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterable, Iterator
from typing import IO, Any, BinaryIO, cast

from fretc.common.errors import FretcError

__all__ = ["OutputError", "write_file", "open_output", "create_output", "write_under",
           "output_folder", "sub_folder", "refuse_replacing_inputs", "same_path"]

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_EXCL = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | getattr(os, "O_CLOEXEC", 0) \
    | getattr(os, "O_BINARY", 0)


class OutputError(FretcError, OSError):
    """An output fretc cannot write where it was asked to; the message names the path and
    why (a folder in its place, a link where fretc makes a folder, no permission, a full
    disk)."""


def _fail(path: str | os.PathLike, exc: OSError, what: str = "cannot write") -> OutputError:
    reason = exc.strerror or type(exc).__name__
    return OutputError(f"{what} {os.fspath(path)}: {reason}")


def _device(path: str) -> bool:
    """True when ``path`` itself (not followed) is a character device or a FIFO the user
    named (``-o /dev/null``, ``-o /dev/tty``, a named pipe): the output is written through
    it, as a shell's ``>`` would, never renamed over it (as root that replaced ``/dev/null``
    with a regular file). Raises :class:`OutputError` for what fretc does not write: a
    block device or a socket, or a link to any of these (``/dev/stdout``: leave ``-o`` out
    for the standard output); False for anything else (a file, a link to a file, nothing)."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
        return True
    kind = (None if stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode) else
            "a block device" if stat.S_ISBLK(st.st_mode) else
            "a socket" if stat.S_ISSOCK(st.st_mode) else None)
    if kind is None and stat.S_ISLNK(st.st_mode):
        try:
            to = os.stat(path).st_mode
        except OSError:
            return False
        if not (stat.S_ISREG(to) or stat.S_ISDIR(to)):
            kind = "a link to a device, a pipe or a socket"
    if kind is not None:
        raise OutputError(f"cannot write {path}: it is {kind}; fretc writes files (or a "
                          "character device or named pipe given by its own name, such as "
                          "/dev/null)")
    return False


def _temporary(path: str) -> tuple[int, str]:
    """A new file beside ``path`` (``.NAME.XXXXXXXX.tmp``) created exclusively, never through a
    link; its descriptor and name. Raises OSError."""
    folder, name = os.path.split(path)
    for _ in range(100):
        tmp = os.path.join(folder, f".{name[:200]}.{os.urandom(6).hex()}.tmp")
        try:
            return os.open(tmp, _EXCL, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name beside {path}")


@contextlib.contextmanager
def open_output(path: str | os.PathLike, mode: str = "w", *, encoding: str | None = "utf-8",
                newline: str | None = None) -> Iterator[Any]:
    """A file object to write the output ``path`` through (``mode`` ``"w"`` or ``"wb"``;
    ``encoding`` and ``newline`` as :func:`open`'s, for text): a temporary file beside it,
    renamed over ``path`` when the ``with`` block ends without an exception, removed when it
    raises (``path`` is then left as it was). The folder must exist.

    Raises:
        OutputError: the temporary file cannot be made or written, or renamed over ``path``
            (a folder there, no permission).
        ValueError: a ``mode`` other than ``"w"`` and ``"wb"``."""
    if mode not in ("w", "wb"):
        raise ValueError(f"open_output writes a whole file (mode 'w' or 'wb'), not {mode!r}")
    target = os.fspath(path)
    if _device(target):  # (written through, as the shell's > does)
        try:
            with open(target, mode, encoding=encoding if mode == "w" else None,
                      newline=newline if mode == "w" else None) as dev:
                yield dev
        except OSError as exc:
            if isinstance(exc, OutputError) or exc.filename not in (None, target):
                raise
            raise _fail(target, exc) from None
        return
    try:
        fd, tmp = _temporary(target)
    except OSError as exc:
        raise _fail(target, exc) from None
    try:
        if mode == "wb":
            f: IO[Any] = os.fdopen(fd, "wb")
        else:
            f = os.fdopen(fd, "w", encoding=encoding, newline=newline)
        with f:
            yield f
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if (isinstance(exc, OSError) and not isinstance(exc, OutputError)
                and exc.filename in (None, tmp, target)):  # (not another file the block read)
            raise _fail(target, exc) from None
        raise


def write_file(path: str | os.PathLike, data: str | bytes, *, encoding: str = "utf-8",
               newline: str | None = None) -> None:
    """Write ``data`` (text in ``encoding``, or bytes) as the output file ``path``, whole or
    not at all, never through a link at ``path`` (:func:`open_output`). The folder must
    exist.

    Raises:
        OutputError: it cannot be written (the message names ``path``)."""
    if isinstance(data, bytes):
        with open_output(path, "wb") as f:
            f.write(data)
    else:
        with open_output(path, "w", encoding=encoding, newline=newline) as f:
            f.write(data)


def create_output(path: str | os.PathLike) -> BinaryIO:
    """A new binary file at ``path`` for an output written as it goes (a recording, read
    while it grows): what stands at ``path`` (an older output, a link) is removed, then the
    file is created exclusively without following a link; another file made there meanwhile
    is an error, never overwritten. The caller closes it.

    Raises:
        OutputError: a folder at ``path``, or the file cannot be made."""
    target = os.fspath(path)
    if _device(target):  # (written through, never removed: /dev/null stays a device)
        try:
            return cast(BinaryIO, open(target, "wb"))
        except OSError as exc:
            raise _fail(target, exc) from None
    try:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(target)  # a link is removed itself, never what it points to
        return cast(BinaryIO, os.fdopen(os.open(target, _EXCL, 0o666), "wb"))
    except OSError as exc:
        raise _fail(target, exc) from None


def write_under(folder: str | os.PathLike, relative: str, data: str | bytes) -> str:
    """Write ``data`` as the output file ``folder/relative``, ``relative`` a ``/``-separated
    path of names fretc chose (a ROS 2 package's ``pkg/launch/pkg.launch.py``): each folder
    on the way made as :func:`sub_folder` makes one (a link or a file there refused), the
    file written by :func:`write_file`. ``folder`` must exist. Returns the file's path.

    Raises:
        OutputError: a link or a file where a folder goes, or the file cannot be written.
        ValueError: ``relative`` is empty, absolute or holds ``.``, ``..`` or an empty
            name."""
    parts = relative.split("/")
    if not relative or any(p in ("", ".", "..") for p in parts):
        raise ValueError(f"not a relative path of plain names: {relative!r}")
    here = os.fspath(folder)
    for name in parts[:-1]:
        here = sub_folder(here, name)
    target = os.path.join(here, parts[-1])
    write_file(target, data)
    return target


def output_folder(path: str | os.PathLike) -> str:
    """The output folder the user named, made (with its parents) when missing; a link to a
    folder is followed (the user named it). Returns ``path`` as a string.

    Raises:
        OutputError: a file stands there, or the folder cannot be made."""
    target = os.fspath(path)
    try:
        os.makedirs(target, exist_ok=True)
    except OSError as exc:
        raise _fail(target, exc, "cannot make the output folder") from None
    return target


def sub_folder(parent: str | os.PathLike, name: str) -> str:
    """The folder ``name`` inside the output folder ``parent`` (which must exist), made when
    missing: a folder fretc names itself, so a link or a file standing there (planted in the
    output folder) is refused, never followed. Returns its path as a string.

    Raises:
        OutputError: a link or a file at ``parent/name``, or the folder cannot be made."""
    target = os.path.join(os.fspath(parent), name)
    try:
        os.mkdir(target)
        return target
    except FileExistsError:
        pass
    except OSError as exc:
        raise _fail(target, exc, "cannot make the folder") from None
    if os.path.islink(target) or not os.path.isdir(target):
        what = "a symbolic link" if os.path.islink(target) else "not a folder"
        raise OutputError(f"{target} is {what}: fretc writes its files into a folder of its "
                          "own there, never through a link (remove it, or choose another "
                          "output folder)")
    return target


#: A path given as one of a command's inputs or outputs: (what it is, as the user knows it:
#: ``"--json"``, ``"the log"``; the path, None or ``"-"`` (standard output, input) skipped)
Named = tuple[str, "str | os.PathLike[str] | None"]


def same_path(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether paths ``a`` and ``b`` name one file or folder: equal once resolved (links
    followed, ``os.path.realpath``), or one by its device and inode (a hard link,
    ``os.path.samefile``) when both exist. Never raises."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _inside(path: str, folder: str) -> bool:
    """Whether ``path`` resolved lies inside the folder ``folder`` resolved."""
    real, top = os.path.realpath(path), os.path.realpath(folder)
    return real.startswith(top.rstrip(os.sep) + os.sep)


def refuse_replacing_inputs(outputs: Iterable[Named],
                            inputs: Iterable[Named]) -> None:
    """Refuse outputs that would replace an input of the same command (hostile round 9, R1 and
    N4), before anything is written: an output file that is an input file (resolved, links
    followed; a hard link to it), or that lies inside an input folder read whole (a rosbag2
    folder). ``outputs`` and ``inputs`` are ``(what, path)`` pairs (``("--json", "a.json")``,
    ``("the log", "runs/a.csv")``); a path None or ``"-"`` (standard input or output) is
    skipped. A folder output is checked by the files the command writes in it: the caller
    names them (``DIR/NAME.shielded.mcap``, ``DIR/STEM.csv``).

    Raises:
        OutputError: the first output that is an input, naming both as given (and where they
            resolve to when that differs): a usage error, exit 2, nothing written."""
    ins = [(w, os.fspath(p)) for w, p in inputs if p is not None and os.fspath(p) != "-"]
    for what, path in outputs:
        if path is None or os.fspath(path) == "-":
            continue
        out = os.fspath(path)
        for in_what, src in ins:
            whole = os.path.isdir(src)
            if (_inside(out, src) or same_path(out, src)) if whole else same_path(out, src):
                moved = [f"{x} resolves to {os.path.realpath(x)}" for x in dict.fromkeys(
                    (out, src)) if os.path.realpath(x) != os.path.abspath(x)]
                where = f" ({'; '.join(moved)})" if moved else ""
                rel = "inside" if whole and not same_path(out, src) else "the same file as"
                raise OutputError(
                    f"{what} {out} is {rel} {in_what} {src}{where}: an output never replaces "
                    "an input of the same command; nothing was written (name another output)")
