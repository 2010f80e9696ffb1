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

from fretc.shield.build import Shield
from fretc.shield.plan import ShieldError

__all__ = ["identifier", "write_forms"]


def identifier(name: str) -> str:
    """``name`` as a Python module and C identifier: characters other than letters, digits
    and ``_`` become ``_``, a leading digit gets a ``_`` before it, lower case."""
    out = re.sub(r"[^0-9A-Za-z_]", "_", name).lower() or "shield"
    return "_" + out if out[0].isdigit() else out


def write_forms(shield: Shield, forms: Sequence[str], out_dir: Path, *,
                bindings: Any = None, bindings_file: str | None = None,
                compiled: Sequence[Any] = ()) -> list[Path]:
    """Write each form of ``forms`` into ``out_dir`` (made when missing); the paths written,
    in order.

    Raises:
        ShieldError: a form that needs what was not given (the ros2 form: bindings)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    base = identifier(shield.name)
    written: list[Path] = []
    for form in dict.fromkeys(forms):
        if form == "python":
            from fretc.shield.emit_python import render_python

            path = out_dir / f"{base}_shield.py"
            path.write_text(render_python(shield), encoding="utf-8")
            written.append(path)
            if bindings_file is not None:  # what a host reads the messages with
                copy = out_dir / f"{base}.bindings.toml"
                copy.write_bytes(Path(bindings_file).read_bytes())
                written.append(copy)
        elif form == "c":
            from fretc.shield.emit_c import render_c

            for fname, text in render_c(shield, base).items():
                path = out_dir / fname
                path.write_text(text, encoding="utf-8")
                written.append(path)
        elif form == "ros2":
            from fretc.shield.emit_ros2 import render_ros2

            for fname, text in render_ros2(shield, base, bindings, bindings_file).items():
                path = out_dir / fname
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(text, encoding="utf-8")
                written.append(path)
        elif form == "gwendolen":
            from fretc.shield.emit_gwendolen import render_gwendolen

            for fname, text in render_gwendolen(shield, compiled, base).items():
                path = out_dir / fname
                path.write_text(text, encoding="utf-8")
                written.append(path)
        else:
            raise ShieldError(f"unknown form {form!r}")
    return written
