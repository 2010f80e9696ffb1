"""What a qualification report records of the installation it ran on: fretc's version and,
when it is known, the git commit it was installed from; Python and the platform; and every
installed distribution with its version and a hash of its installed files' record.

The hash of a distribution is the SHA-256 of its ``RECORD`` file (the list of its installed
files, each with its own SHA-256: PEP 376 and the wheel specification), else of its
``METADATA``: two installations of one version built the same way hash the same, and a file
changed after installation by a tool that rewrites the record shows as another hash. fretc's
own files are hashed too, as they are on disk (:func:`package_hash`: an editable install's
record lists none of them). Nothing
here runs a program (no ``git``, no ``pip``); the commit is read from the files of the
source tree an editable or local install points at (PEP 610's ``direct_url.json``).
"""

from __future__ import annotations

import hashlib
import json
import platform
import sys
from importlib import metadata
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlparse


def _direct_url(dist: metadata.Distribution) -> dict[str, Any]:
    """The distribution's ``direct_url.json`` (PEP 610) as a dict, ``{}`` without one."""
    text = dist.read_text("direct_url.json")
    try:
        doc = json.loads(text) if text else {}
    except ValueError:
        return {}
    return doc if isinstance(doc, dict) else {}


def _git_head(folder: Path) -> str | None:
    """The commit ``HEAD`` names in the git repository at ``folder`` (its ``.git`` folder
    read as files: a symbolic ref, a loose ref or ``packed-refs``), or None."""
    git = folder / ".git"
    try:
        head = (git / "HEAD").read_text("utf-8").strip()
        if not head.startswith("ref: "):
            return head or None
        ref = head[5:]
        loose = git / ref
        if loose.is_file():
            return loose.read_text("utf-8").strip() or None
        for line in (git / "packed-refs").read_text("utf-8").splitlines():
            parts = line.split()
            if len(parts) == 2 and parts[1] == ref:
                return parts[0]
    except (OSError, UnicodeDecodeError):
        return None
    return None


def _git_modified(folder: Path) -> list[str] | None:
    """The tracked files of the git tree at ``folder`` that differ from its HEAD (``git
    status --porcelain``, untracked files left out), sorted; None when git cannot say (no
    git on the PATH, not a repository)."""
    import shutil
    import subprocess

    git = shutil.which("git")
    if git is None or not (folder / ".git").exists():
        return None
    try:
        got = subprocess.run([git, "-C", str(folder), "status", "--porcelain",
                              "--untracked-files=no"], capture_output=True, text=True,
                             timeout=60, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    if got.returncode != 0:
        return None
    return sorted(line[3:] for line in got.stdout.splitlines() if len(line) > 3)


def package_files() -> list[tuple[str, Path]]:
    """The installed fretc package's files as (path relative to the package, path on disk),
    sorted by the relative path: every file under its folder and its sub-packages' folders
    (links followed, as Python imports them; ``__pycache__`` and bytecode left out)."""
    import importlib.resources
    import os

    root = Path(str(importlib.resources.files("fretc")))
    files = []
    for here, dirs, names in os.walk(root, followlinks=True):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        files += [Path(here) / n for n in names if not n.endswith((".pyc", ".pyo"))]
    return sorted(((p.relative_to(root).as_posix(), p) for p in files), key=lambda x: x[0])


def package_hash() -> tuple[str, int]:
    """(SHA-256 hex, number of files) of the installed fretc package's files as they are on
    disk (:func:`package_files`), each as its relative path and its bytes, in order."""
    digest = hashlib.sha256()
    files = package_files()
    for rel, path in files:
        name = rel.encode("utf-8")
        digest.update(len(name).to_bytes(4, "big") + name)
        data = path.read_bytes()
        digest.update(len(data).to_bytes(8, "big") + data)
    return digest.hexdigest(), len(files)


def fretc_origin() -> dict[str, Any]:
    """``{"version", "commit", "modified", "source", "files_sha256", "files"}`` of the
    installed fretc: its version, the commit (a VCS install's ``commit_id``, else the HEAD of
    the local source tree it was installed from, else None), the tracked files of that tree
    that differ from the commit (:func:`_git_modified`; [] when none, None when not known),
    the source's URL (None when installed from an index) and the hash and count of its
    package's files (:func:`package_hash`)."""
    dist = metadata.distribution("fretc")
    url = _direct_url(dist)
    commit = (url.get("vcs_info") or {}).get("commit_id")
    source = url.get("url")
    modified = None
    if commit is None and isinstance(source, str) and source.startswith("file://"):
        tree = Path(unquote(urlparse(source).path))
        commit = _git_head(tree)
        modified = _git_modified(tree) if commit is not None else None
    files_sha256, count = package_hash()
    return {"version": dist.version, "commit": commit, "modified": modified,
            "source": source, "files_sha256": files_sha256, "files": count}


def _hash(dist: metadata.Distribution) -> tuple[str | None, str]:
    """(SHA-256 hex of the distribution's RECORD, else of its METADATA; what was hashed)."""
    for name in ("RECORD", "METADATA"):
        text = dist.read_text(name)
        if text is not None:
            return hashlib.sha256(text.encode("utf-8")).hexdigest(), name
    return None, "nothing"


def requirement_names() -> set[str]:
    """The normalized names of fretc's declared dependencies (its ``Requires-Dist`` without
    an extra's marker)."""
    out = set()
    for req in metadata.requires("fretc") or []:
        if "extra ==" in req:
            continue
        name = req.split(";")[0].strip()
        for stop in "<>=!~[ (":
            name = name.split(stop)[0]
        out.add(_normalized(name))
    return out


def _normalized(name: str) -> str:
    """A distribution name normalized as PEP 503 does (lower case, ``-`` for runs of
    ``-_.``)."""
    import re

    return re.sub(r"[-_.]+", "-", name).lower()


def distributions() -> list[dict[str, Any]]:
    """Every distribution installed beside fretc, sorted by name: ``name``, ``version``,
    ``sha256`` (:func:`_hash`), ``hashed`` (``RECORD`` or ``METADATA``) and ``required``
    (a dependency fretc declares)."""
    required = requirement_names()
    seen: dict[str, dict[str, Any]] = {}
    for dist in metadata.distributions():
        name = dist.metadata["Name"]
        if not name or _normalized(name) in seen:
            continue
        digest, hashed = _hash(dist)
        seen[_normalized(name)] = {"name": name, "version": dist.version, "sha256": digest,
                                   "hashed": hashed, "required": _normalized(name) in required}
    return [seen[k] for k in sorted(seen)]


def environment() -> dict[str, Any]:
    """The installation's description for the report: ``fretc`` (:func:`fretc_origin`),
    ``python`` (version, implementation, executable), ``platform`` (system, release,
    machine, platform string) and ``distributions`` (:func:`distributions`)."""
    return {
        "fretc": fretc_origin(),
        "python": {"version": platform.python_version(),
                   "implementation": platform.python_implementation(),
                   "executable": sys.executable},
        "platform": {"system": platform.system(), "release": platform.release(),
                     "machine": platform.machine(), "platform": platform.platform()},
        "distributions": distributions(),
    }
