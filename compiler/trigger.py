"""The trigger formula of a requirement (:func:`trigger_pt`): the pt formula true at the last
tick of a trace iff no trigger of the requirement occurred in any scope interval. The audit
reads it for its *vacuous* verdict of the entities judged at once
(:mod:`fretc.audit.entities.batch`), the C monitors for theirs (:mod:`fretc.compiler.c_codegen`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.pt_step import CodegenError, check_monitorable

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["trigger_pt"]


def trigger_pt(compiled: Compiled) -> Node | None:
    """The pt formula that is true at the last tick of a trace iff no trigger of the
    requirement has occurred in any scope interval (the audit's *vacuous*: FRET's
    finite-trace verdict of the same scope and condition with the timing ``immediately``
    and the response ``false``, ``true`` for the ``only`` scopes whose obligation is
    negated: every trigger then fails at once). None when the audit's interval semantics
    cannot say vacuous either (an uninterpreted function, a free-form requirement)."""
    from fretc.compiler.semantics import SemanticsError, formalize
    from fretc.fretish import ast as A

    req = compiled.requirement
    f = compiled.formalization
    if req is None or req.freeform or f is None or ir.has_op(f.pt, ("call",)) or any(
            n.op == "fn" and n.name not in _KNOWN_FN for n in ir.walk(f.pt)):
        return None
    only = req.scope.kind.startswith("only")
    probe = dataclasses.replace(req, timing=A.Timing("immediately"),
                                response=A.BoolLit(only), probability=None)
    try:
        got = formalize(probe, compiled.entry.tick_period)
        check_monitorable(got.pt)
    except (SemanticsError, CodegenError):
        return None
    return got.pt


_KNOWN_FN = ("absReal", "absInt", "minReal", "minInt", "maxReal", "maxInt")
