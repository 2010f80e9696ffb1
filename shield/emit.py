"""``fretc shield --emit FORM -o DIR``: each form of one synthesized shield written into DIR.

Every form is made from the same :class:`fretc.shield.build.Shield` and is deterministic
(the same requirements, bindings and choices give the same bytes). File names start with
the shield's name made a C and Python identifier (:func:`identifier`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fretc.common.outputs import output_folder, write_under
from fretc.shield.build import Shield
from fretc.shield.plan import ShieldError

__all__ = ["identifier", "render_forms", "write_forms", "check_names"]


def identifier(name: str) -> str:
    """``name`` as a Python module and C identifier: characters other than letters, digits
    and ``_`` become ``_``, a leading digit gets a ``_`` before it, lower case."""
    out = re.sub(r"[^0-9A-Za-z_]", "_", name).lower() or "shield"
    return "_" + out if out[0].isdigit() else out


def render_forms(shield: Shield, forms: Sequence[str], *, bindings: Any = None,
                 bindings_file: str | None = None, compiled: Sequence[Any] = (),
                 node: tuple[Shield, int] | None = None) -> dict[str, str | bytes]:
    """Every file of each form of ``forms``: relative path -> text (or bytes, the binding
    file copied), in order; nothing is written. ``node``: the ROS 2 node's shield and the
    ticks early it meets each deadline (:func:`fretc.shield.emit_ros2.node_margin`; default
    ``shield`` itself, no margin).

    Raises:
        ShieldError: a form that needs what was not given (the ros2 form: bindings and
            the types of its topics) or an unknown form."""
    base = identifier(shield.name)
    files: dict[str, str | bytes] = {}
    for form in dict.fromkeys(forms):
        if form == "python":
            from fretc.shield.emit_python import render_python

            files[f"{base}_shield.py"] = render_python(shield)
            if bindings_file is not None:  # what a host reads the messages with
                files[f"{base}.bindings.toml"] = Path(bindings_file).read_bytes()
        elif form == "c":
            from fretc.shield.emit_c import render_c

            files.update(render_c(shield, base))
        elif form == "ros2":
            from fretc.shield.emit_ros2 import render_ros2

            on_bus, margin = node if node is not None else (shield, 0)
            files.update(render_ros2(on_bus, base, bindings, bindings_file, margin))
        elif form == "gwendolen":
            from fretc.shield.emit_gwendolen import render_gwendolen

            files.update(render_gwendolen(shield, compiled, base))
        else:
            raise ShieldError(f"unknown form {form!r}")
    return files


def write_forms(shield: Shield, forms: Sequence[str], out_dir: Path, *,
                bindings: Any = None, bindings_file: str | None = None,
                compiled: Sequence[Any] = (), node: tuple[Shield, int] | None = None
                ) -> list[Path]:
    """Write each form of ``forms`` into ``out_dir`` (made when missing); the paths written,
    in order. Every form is made before any file is written: a form refused leaves the
    folder as it was (no partial output), and so does a file name the file system cannot
    hold (:func:`check_names`).

    Raises:
        ShieldError: as :func:`render_forms` and :func:`check_names`."""
    files = render_forms(shield, forms, bindings=bindings, bindings_file=bindings_file,
                         compiled=compiled, node=node)
    check_names(out_dir, files)  # (all before the first file: none is written on a refusal)
    output_folder(out_dir)
    written: list[Path] = []
    for fname, content in files.items():  # (never through a link planted in out_dir)
        written.append(Path(write_under(out_dir, fname, content)))
    return written


def _name_max(out_dir: Path) -> tuple[int, int]:
    """``(longest file name, longest path)`` in bytes the file system of ``out_dir`` (its
    nearest existing folder) holds: ``pathconf``'s ``PC_NAME_MAX`` and ``PC_PATH_MAX``,
    else 255 and 4096 (POSIX's usual limits, Linux's and macOS's)."""
    import os

    folder = out_dir.absolute()
    while not folder.exists() and folder.parent != folder:
        folder = folder.parent
    limits = []
    for name, default in (("PC_NAME_MAX", 255), ("PC_PATH_MAX", 4096)):
        try:
            limits.append(int(os.pathconf(folder, name)))
        except (AttributeError, OSError, ValueError):
            limits.append(default)
    return limits[0], limits[1]


def check_names(out_dir: Path, files: dict[str, str | bytes]) -> None:
    """Refuse, before anything is written, a file of ``files`` (relative paths) whose name,
    or a folder's, is longer than ``out_dir``'s file system holds (the Gwendolen form's
    ``N_LABEL.ail`` of a requirement id of hundreds of characters), or whose path is.

    Raises:
        ShieldError: naming the file (its first 60 characters), its length and the limit,
            and what to shorten."""
    import os

    from fretc.common.textsafe import one_line

    name_max, path_max = _name_max(out_dir)
    for rel in files:
        full = os.fsencode(str(out_dir.absolute() / rel))
        for part in Path(rel).parts:
            size = len(os.fsencode(part))
            if size > name_max:
                raise ShieldError(
                    f"{one_line(str(out_dir / part)[:60])}...: a file name of {size} bytes, "
                    f"more than the {name_max} the file system holds; nothing was written "
                    "(shorten the requirement id or the shield's name it is made from)")
        if len(full) >= path_max:
            raise ShieldError(
                f"{one_line(str(out_dir / rel)[:60])}...: a path of {len(full)} bytes, more "
                f"than the {path_max} the file system holds; nothing was written (a shorter "
                "-o folder, requirement id or shield name)")
