"""Checks of the libraries fretc runs on, where another distribution can break them.

ROS 2 Jazzy's wheels on PyPI (``ros-jazzy-rclpy`` and the message packages) depend on
``lark-parser`` 0.12 (through ``rosidl_parser``), which installs into the same ``lark``
folder as Lark 1.x, fretc's parser library, and may overwrite its files, depending on the
order pip installs them in. fretc's grammars need Lark 1.x: its parsers check the version
they import and say how to repair the environment, rather than failing later on a
transformer called the old way.
"""

from __future__ import annotations

from fretc.common.errors import FretcError

__all__ = ["LibraryError", "check_lark", "lark_init_text", "LARK_REPAIR"]

#: the command that puts Lark 1.x back over lark-parser 0.12's files
LARK_REPAIR = "pip install --force-reinstall --no-deps 'lark>=1.1.9'"


class LibraryError(FretcError):
    """A library fretc needs is missing or replaced; the message says how to repair it."""


def check_lark(version: str) -> None:
    """Raise :class:`LibraryError` unless ``version`` (``lark.__version__``) is Lark 1.x or
    later."""
    major = version.split(".", 1)[0]
    if not major.isdigit() or int(major) < 1:
        raise LibraryError(
            f"the 'lark' package imported is version {version}, not Lark 1.x: lark-parser "
            "0.x (a dependency of ROS 2's rosidl packages, e.g. pip install ros-jazzy-rclpy) "
            f"has replaced Lark's files; repair it with: {LARK_REPAIR}")


def lark_init_text() -> str:
    """The text of Lark's ``__init__.py``, which names its version (``__version__``): a key
    part of fretc's caches of parsed text that follows Lark's version without importing Lark
    (about 30 ms of a start whose parses all come from the cache). Raises nothing: a Lark
    that cannot be found or read gives a key of its own (the parse then fails as it
    would)."""
    import importlib.util

    spec = importlib.util.find_spec("lark")
    origin = spec.origin if spec is not None else None
    try:
        with open(str(origin), encoding="utf-8") as f:
            return f"{origin}\n{f.read()}"
    except OSError:
        return f"{origin}\nunreadable"
