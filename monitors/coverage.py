"""Which coverage obligations (:mod:`fretc.compiler.coverage`) a trace exercises, and at which
tick, by the audit's own judge: FRET's interval semantics over the trace's columns
(:func:`fretc.monitors.interval.evaluate_requirement`), the engine of every audit verdict.

A verdict-difference obligation is met when the requirement's verdict and its variant's
differ on the trace; the tick given is where the difference shows: the violation tick of
the one violated (when one holds and the other does not), else the first trigger of the
one not vacuous. A threshold obligation is met when its comparison takes the wanted value
at some tick; the margin given is the smallest distance between the variable and the
threshold over those ticks (in the variable's unit). Obligations the interval semantics
cannot evaluate (an uninterpreted function) are ``unknown``, never met.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from fretc.compiler.coverage import Obligation
from fretc.fretish import ast as A
from fretc.monitors.interval import Evidence, EvidenceUnsupported, evaluate_requirement

__all__ = ["Exercise", "exercised", "verdict_word"]

_CMP = {"=": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
        ">": operator.gt, ">=": operator.ge}


@dataclass(frozen=True)
class Exercise:
    """Whether one trace exercises one obligation.

    Attributes:
        status: ``met``, ``unmet`` or ``unknown`` (``why`` says why).
        tick: the 0-based tick where it shows (None when not met).
        verdicts: the requirement's and its variant's verdicts (verdict-difference
            obligations), else None.
        margin: threshold obligations: the smallest ``|variable - threshold|`` over the
            ticks on the wanted side, else None.
        why: the reason of an ``unknown``.
    """

    status: str
    tick: int | None = None
    verdicts: tuple[str, str] | None = None
    margin: float | None = None
    why: str = ""

    @property
    def met(self) -> bool:
        """True when the obligation is exercised."""
        return self.status == "met"


def verdict_word(ev: Evidence) -> str:
    """``satisfied``, ``vacuous`` or ``violated`` of an :class:`Evidence`."""
    return "violated" if not ev.holds else ("vacuous" if ev.vacuous else "satisfied")


def _difference_tick(a: Evidence, b: Evidence) -> int | None:
    if a.holds != b.holds:
        bad = a if not a.holds else b
        return bad.violation.violation_tick if bad.violation is not None else None
    live = b if a.vacuous else a
    if live.first_trigger is not None:
        return live.first_trigger
    return live.first_interval[0] if live.first_interval is not None else None


def _threshold(ob: Obligation, columns: Mapping[str, np.ndarray], n: int) -> Exercise:
    atom = ob.atom
    assert isinstance(atom, A.Binary)  # (a threshold obligation is a comparison)
    var, num = (atom.left, atom.right) if isinstance(atom.left, A.Var) else (atom.right,
                                                                               atom.left)
    if not isinstance(var, A.Var) or not isinstance(num, A.NumLit):
        return Exercise("unknown", why="not a variable compared with a number")
    if var.name not in columns:
        return Exercise("unknown", why=f"no column for {var.name}")
    x = np.asarray(columns[var.name][:n], dtype=float)
    c = float(num.value)
    left, right = (x, c) if var is atom.left else (c, x)
    with np.errstate(invalid="ignore"):
        truth = np.asarray(_CMP[atom.op](left, right), dtype=np.bool_) & ~np.isnan(x)
    on_side = truth if ob.side else (~truth & ~np.isnan(x))
    if not on_side.any():
        return Exercise("unmet")
    with np.errstate(invalid="ignore"):  # inf - inf (a value at an infinite threshold):
        # NaN, no margin to state
        margin = float(np.min(np.abs(x[on_side] - c)))
    return Exercise("met", tick=int(np.argmax(on_side)), margin=margin)


def exercised(obligations: Sequence[Obligation], req: A.Requirement,
              columns: Mapping[str, np.ndarray], n: int,
              duration_ticks: int | None) -> list[Exercise]:
    """One :class:`Exercise` per obligation of ``req`` on a trace of ``n`` ticks
    (``columns``: FRET variable -> array of ``n`` values, as the judge reads them;
    ``duration_ticks`` as ``Formalization.ticks``). Raises as
    :func:`fretc.monitors.interval.evaluate_requirement` for bad columns."""
    try:
        base = evaluate_requirement(req, columns, n, duration_ticks)
    except EvidenceUnsupported as exc:
        base, why = None, str(exc) or "the interval semantics cannot evaluate it"
    out = []
    for ob in obligations:
        if ob.kind == "threshold":
            out.append(_threshold(ob, columns, n))
            continue
        if base is None:
            out.append(Exercise("unknown", why=why))
            continue
        assert ob.variant is not None  # (an obligation other than a threshold has it)
        try:
            other = evaluate_requirement(ob.variant, columns, n, ob.variant_ticks)
        except EvidenceUnsupported as exc:
            out.append(Exercise("unknown", why=str(exc) or "cannot evaluate the variant"))
            continue
        pair = (verdict_word(base), verdict_word(other))
        if pair[0] == pair[1]:
            out.append(Exercise("unmet", verdicts=pair))
        else:
            out.append(Exercise("met", tick=_difference_tick(base, other), verdicts=pair))
    return out
