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

__all__ = ["identifier", "render_forms", "write_forms"]


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
    folder as it was (no partial output).

    Raises:
        ShieldError: as :func:`render_forms`."""
    files = render_forms(shield, forms, bindings=bindings, bindings_file=bindings_file,
                         compiled=compiled, node=node)
    output_folder(out_dir)
    written: list[Path] = []
    for fname, content in files.items():  # (never through a link planted in out_dir)
        written.append(Path(write_under(out_dir, fname, content)))
    return written
