"""FRETish front end of fretc: parse NASA FRET's structured English into a typed AST.

* :func:`parse` - one sentence -> :class:`fretc.fretish.ast.Requirement` (``parser.py``);
* :func:`load_requirements` - ``.fret`` files and FRET JSON exports -> entries
  (``files.py``);
* errors (defined in :mod:`fretc.common.errors`): :class:`FretishError` and its subclasses
  :class:`FretishSyntaxError` (a sentence) and :class:`FretishFileError` (a file), rendered
  like compiler diagnostics.
"""

from fretc.common.errors import FretishError, FretishFileError, FretishSyntaxError

# The parser and the file loader are imported on first use (PEP 562): importing a small
# module of this package (``fretish.words``) must not load them.
_LAZY = {"parse": "parser", "load_requirements": "files", "RequirementEntry": "files"}


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value

__all__ = ["parse", "load_requirements", "RequirementEntry", "FretishError",
           "FretishSyntaxError", "FretishFileError"]
