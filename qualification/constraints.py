"""The constraints file of the qualified dependency set (``constraints.txt`` beside this
module): fretc's runtime dependencies and theirs, each pinned to the version installed when
it was written, for ``pip install -c`` (pip's constraints files).

    python -m fretc.qualification.constraints [FILE]

writes it from the running environment (default: the shipped file).
"""

from __future__ import annotations

import re
import sys
from importlib import metadata
from pathlib import Path

HERE = Path(__file__).parent
FILE = HERE / "constraints.txt"


def _name(requirement: str) -> str | None:
    """The distribution a requirement line names, normalized; None for one behind an extra
    or a marker that does not hold here."""
    from packaging.requirements import Requirement

    req = Requirement(requirement)
    if req.marker is not None and not req.marker.evaluate({"extra": ""}):
        return None
    return re.sub(r"[-_.]+", "-", req.name).lower()


def closure(root: str = "fretc") -> dict[str, str]:
    """``{normalized name: installed version}`` of ``root``'s runtime dependencies and
    theirs (no extras), sorted by name. Raises ``PackageNotFoundError`` when one is not
    installed."""
    seen: dict[str, str] = {}
    todo = [root]
    while todo:
        dist = metadata.distribution(todo.pop())
        for line in dist.requires or []:
            name = _name(line)
            if name is not None and name not in seen:
                seen[name] = metadata.version(name)
                todo.append(name)
    return dict(sorted(seen.items()))


def text(pins: dict[str, str]) -> str:
    """The file's text: a header, then ``name==version`` a line."""
    return ("# fretc's qualified dependency set: pip install -c constraints.txt ...\n"
            "# written by python -m fretc.qualification.constraints\n"
            + "".join(f"{n}=={v}\n" for n, v in pins.items()))


def main(argv: list[str] | None = None) -> int:
    """The command line (module docstring)."""
    args = sys.argv[1:] if argv is None else argv
    path = Path(args[0]) if args else FILE
    path.write_text(text(closure()), encoding="utf-8")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
