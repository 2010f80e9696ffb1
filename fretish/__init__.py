"""FRETish front end of fretc: parse NASA FRET's structured English into a typed AST.

* :func:`parse` - one sentence -> :class:`fretish.ast.Requirement` (``parser.py``);
* :func:`load_requirements` - ``.fret`` files and FRET JSON exports -> entries
  (``files.py``);
* errors: :class:`FretishError` and its subclasses :class:`FretishSyntaxError` (a sentence)
  and :class:`FretishFileError` (a file), rendered like compiler diagnostics.
"""

from .errors import FretishError, FretishFileError, FretishSyntaxError
from .files import RequirementEntry, load_requirements
from .parser import parse

__all__ = ["parse", "load_requirements", "RequirementEntry", "FretishError",
           "FretishSyntaxError", "FretishFileError"]
