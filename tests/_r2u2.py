"""The tests' and the benchmark's side of R2U2 (:mod:`fretc.qualification.r2u2` runs it):
a skip with :data:`NOT_BUILT` where ``tools/r2u2/build.sh`` has not been run, and the defect
of R2U2's engine the tests pin (:data:`SINCE_DEFECT`)."""

from __future__ import annotations

import pytest

from fretc.qualification.r2u2 import (NOT_BUILT, R2U2, Spec, compile_batches, locate,
                                      per_tick, read_spec, run, type_check, write_trace)

__all__ = ["NOT_BUILT", "SINCE_DEFECT", "Spec", "compile_batches", "locate", "needs_r2u2",
           "per_tick", "read_spec", "run", "type_check", "write_trace"]

#: R2U2's C engine at the pinned commit: ``a S[l,u] b`` stays true once ``a`` is true again
#: after it failed, while the ``b`` before the failure is within ``u`` ticks (its ``edge`` is
#: not forgotten when ``a`` fails): on ``a`` = 0,0,1,1,0 and ``b`` = 1,0,0,0,0 its results
#: are ``0:0,T 1:F 3:T`` (T,F,T,T and none for the last tick, with one more SCQ slot) where
#: MLTL gives T,F,F,F,F; ``T``, the dual, likewise; and the results of formulas over such
#: operators may stop before the trace's last tick. The tests compare R2U2's verdicts with
#: fretc's only for formulas without ``S`` and ``T``.
SINCE_DEFECT = ("a", (0, 0, 1, 1, 0), "b", (1, 0, 0, 0, 0), "(a S[0,M] b)",
                [(0, True), (1, False), (2, True), (3, True)],
                (True, False, False, False, False))


def needs_r2u2() -> R2U2:
    """The R2U2 build, or skip the calling test with :data:`NOT_BUILT`."""
    tool = locate()
    if tool is None:
        pytest.skip(NOT_BUILT)
    return tool
