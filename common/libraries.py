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

__all__ = ["LibraryError", "check_lark", "package_init", "LARK_REPAIR"]

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


def package_init(name: str) -> str:
    """The path of the installed package ``name``'s ``__init__.py``, found without importing
    it ("" when it is not installed). Its text names the package's version (``__version__``):
    fretc's caches of parsed and rendered text key on it (:func:`fretc.common.cache.files_key`)
    and so do not import Lark or Jinja for their versions (about 30 ms each at a start whose
    work all comes from the cache)."""
    import importlib.util

    spec = importlib.util.find_spec(name)
    return str(spec.origin) if spec is not None and spec.origin else ""
