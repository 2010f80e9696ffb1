"""Roles of the test sets' variables: ``fretc check`` assumes no role (a variable of a
realizability check declared neither input nor output is an input error), so a test whose
set means "these are the inputs, every other variable is the controller's" says so."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


def rest_as_outputs(compiled: Sequence[Any], inputs: Sequence[str]) -> list[str]:
    """Every variable the requirements of ``compiled`` (:class:`fretc.compiler.build.Compiled`)
    read that is not one of ``inputs``, sorted: their outputs."""
    return sorted({v for c in compiled if c.formalization is not None
                   for v in c.formalization.variables if v not in inputs})
