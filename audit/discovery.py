"""Finding the inputs on disk: the logs named by paths (:func:`find_logs`) and by the LOGS
arguments' lists and globs (:func:`expand_log_args`), and the binding files next to
requirement files (:func:`discover_bindings`)."""

from __future__ import annotations

import glob
import os
from collections.abc import Sequence
from pathlib import Path

from fretc.audit.config import AuditInputError
from fretc.logs.factory import unseekable

__all__ = ["LOG_SUFFIXES", "discover_bindings", "expand_log_args", "find_logs"]

#: File kinds audited when a folder is given.
LOG_SUFFIXES = (".mcap", ".bag", ".csv", ".ulg", ".bin")


def discover_bindings(requirement_paths: Sequence[str]) -> list[Path]:
    """Binding files for requirement paths: for a folder, its ``*.bindings.toml``; for a
    file ``X.fret`` (or ``X.json``), ``X.bindings.toml`` beside it if it exists, else every
    ``*.bindings.toml`` in its folder. Sorted by name, without duplicates."""
    out: list[Path] = []
    for p in requirement_paths:
        path = Path(p)
        if path.is_dir():
            found = sorted(path.glob("*.bindings.toml"))
        else:
            own = path.with_name(path.name.split(".")[0] + ".bindings.toml")
            found = [own] if own.is_file() else sorted(path.parent.glob("*.bindings.toml"))
        for f in found:
            if f not in out:
                out.append(f)
    return out


def find_logs(paths: Sequence[str]) -> list[str]:
    """Logs named by ``paths``: files as given; a rosbag2 folder (``metadata.yaml``) as one
    log; other folders searched recursively (sorted) for ``*.mcap``, ``*.bag``, ``*.csv``
    and rosbag2 folders, except a ``X.csv`` beside a log ``X.mcap`` (or another kind) of
    the same stem: the same run as ``fretc audit --write-csv`` samples it, which would count
    twice in the fleet statistics (name it to audit it).

    Raises:
        AuditInputError: a path that does not exist, or a folder holding no log, or one
            that is neither a file nor a folder (a FIFO, ``/dev/stdin``, ``<(...)``:
            :func:`fretc.logs.factory.unseekable`).
    """
    out: list[str] = []
    for p in paths:
        path = Path(p)
        if not path.exists():
            raise AuditInputError(f"{p}: no such file or folder")
        refused = unseekable(path)  # (a FIFO, /dev/stdin, <(...))
        if refused is not None:
            raise AuditInputError(f"{p}: {refused}")
        if path.is_file() or (path / "metadata.yaml").is_file():
            out.append(str(path))
            continue
        found = _walk_logs(path)
        if not found:
            raise AuditInputError(f"{p}: no logs (*.mcap, *.bag, *.csv, rosbag2 folders)")
        out.extend(found)
    return list(dict.fromkeys(out))  # each once, in order


def _walk_logs(folder: Path) -> list[str]:
    out: list[str] = []
    for child in sorted(folder.iterdir(), key=lambda c: c.name):
        if child.name.startswith("."):
            continue
        if child.is_dir():
            if (child / "metadata.yaml").is_file():
                out.append(str(child))
            else:
                out.extend(_walk_logs(child))
        elif child.suffix.lower() in LOG_SUFFIXES:
            out.append(str(child))
    logs = {Path(x).stem for x in out if Path(x).suffix.lower() not in ("", ".csv")}
    return [x for x in out if not (Path(x).suffix.lower() == ".csv" and Path(x).stem in logs
                                   and Path(x).parent == folder)]


def expand_log_args(args: Sequence[str]) -> list[str]:
    """Expand ``@FILE`` lists and globs in the LOGS arguments, in order.

    ``@FILE``: one path or glob per line; blank lines and ``#`` comments skipped; a relative
    path starts at FILE's folder. A glob (``*``, ``?``, ``[``) that is not an existing path
    is expanded with ``**`` recursion, sorted. Other arguments are kept as given (folders are
    searched later by :func:`fretc.audit.find_logs`).

    Raises:
        AuditInputError: an unreadable list file, or a glob that matches nothing (naming
            the file and line for a list entry).
    """
    out: list[str] = []
    for a in args:
        if a.startswith("@") and len(a) > 1:
            lst = Path(a[1:])
            try:
                lines = lst.read_text(encoding="utf-8").splitlines()
            except OSError as exc:
                raise AuditInputError(f"{a}: cannot read the log list: {exc}") from None
            for n, line in enumerate(lines, 1):
                entry = line.split("#", 1)[0].strip() if line.lstrip().startswith("#") \
                    else line.strip()
                if not entry:
                    continue
                p = entry if os.path.isabs(entry) else str(lst.parent / entry)
                out.extend(_glob_one(p, f"{lst}:{n}"))
            continue
        out.extend(_glob_one(a, None))
    return out


def _glob_one(p: str, where: str | None) -> list[str]:
    if os.path.exists(p) or not any(c in p for c in "*?["):
        return [p]
    found = sorted(glob.glob(p, recursive=True))
    if not found:
        raise AuditInputError(f"{where + ': ' if where else ''}{p}: no file matches")
    return found
