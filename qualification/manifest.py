"""The manifest of a release: the SHA-256 of each of fretc's installed package files, written
when the release is made and published with it, so that ``fretc qualify --manifest FILE``
says whether the installation qualified is the release (DO-330 7.2's tool configuration
index; IEC 61508-3 7.4.4.13's identification of the tool version).

    python -m fretc.qualification.manifest FILE

writes the manifest of the installed fretc to FILE (JSON: ``version``, ``files``: relative
path -> SHA-256 hex).
"""

from __future__ import annotations

import hashlib
import json
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

from fretc.qualification.environment import package_files


def manifest() -> dict[str, Any]:
    """``{"version", "files": {relative path: sha256 hex}}`` of the installed fretc."""
    return {"version": metadata.version("fretc"),
            "files": {rel: hashlib.sha256(path.read_bytes()).hexdigest()
                      for rel, path in package_files()}}


def compare(published: dict[str, Any]) -> dict[str, Any]:
    """The installed files against a published manifest: ``{"version": its version,
    "changed", "missing", "extra": [relative paths, sorted]}`` (``missing``: in the manifest,
    not installed; ``extra``: installed, not in it).

    Raises:
        ValueError: ``published`` is not a manifest (no ``files`` mapping of strings)."""
    files = published.get("files") if isinstance(published, dict) else None
    if not isinstance(files, dict) or not all(isinstance(k, str) and isinstance(v, str)
                                              for k, v in files.items()):
        raise ValueError("not a fretc manifest: a JSON object with 'files', each a path and "
                         "its SHA-256")
    here = manifest()["files"]
    return {"version": published.get("version"),
            "changed": sorted(k for k in files if k in here and here[k] != files[k]),
            "missing": sorted(k for k in files if k not in here),
            "extra": sorted(k for k in here if k not in files)}


def main(argv: list[str] | None = None) -> int:
    """The command line (module docstring)."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m fretc.qualification.manifest FILE", file=sys.stderr)
        return 2
    Path(args[0]).write_text(json.dumps(manifest(), indent=1, sort_keys=True) + "\n",
                             encoding="utf-8")
    print(f"wrote {args[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
