"""Verdicts on a damaged log: what the span read completely decides, and nothing more.

../shared/DESIGN.md, "Damage is never evidence": only the span of a log that was read completely
is judged (the ticks strictly before :attr:`fretc.logs.LogSource.intact_end`); an
obligation still open where that span ends (a cut, or the first gap) is *unknown*, not
violated; a violation decided entirely before the damage stands.

Design notes: ARCHITECTURE.md, `audit/damage.py`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from fretc.fretish import ast as A

from fretc.monitors.interval import Evidence, EvidenceUnsupported, every_trigger
from fretc.monitors.obligations import FirstEvents

__all__ = ["OpenObligation", "open_obligations", "open_reason", "verdict_at_damage"]


@dataclass(frozen=True)
class OpenObligation:
    """A trigger whose obligation the end of the intact span leaves undecided.

    Attributes:
        trigger_tick: the trigger point ``t`` (0-based tick of the intact span).
        interval: the scope interval ``(s, e)`` holding it; ``e`` is the last intact tick.
        what: the obligation still open, in tick numbers.
    """

    trigger_tick: int
    interval: tuple[int, int]
    what: str


def open_obligations(req: A.Requirement, columns: Mapping[str, np.ndarray], n: int,
                     duration_ticks: int | None = None, limit: int = 1
                     ) -> list[OpenObligation]:
    """Triggers of ``req`` whose obligation is neither met nor missed at the end of a trace
    of ``n`` ticks that a damage cut short (FRET's interval semantics, as
    :func:`fretc.monitors.interval.evaluate_requirement`; only the scope interval reaching
    the last tick can hold one).

    Args:
        req: a parsed, not free-form requirement.
        columns: FRET variable -> 1-D array of ``n`` values.
        n: ticks of the intact span (>= 1).
        duration_ticks: the timing's duration in ticks (``Formalization.ticks``).
        limit: stop after this many.

    Returns:
        Up to ``limit`` :class:`OpenObligation`, earliest trigger first.

    Raises:
        EvidenceUnsupported: as :func:`fretc.monitors.interval.evaluate_requirement`.
    """
    if req.freeform or req.response is None:
        raise EvidenceUnsupported("a free-form requirement has no semantics")
    if n < 1:
        return []
    scope, timing = req.scope.kind, req.timing.kind
    negate = scope.startswith("only")
    k = 0
    if timing in A.DURATION_TIMINGS:
        assert req.timing.duration is not None  # (a duration timing has it)
        k = int(duration_ticks) if duration_ticks is not None else int(
            req.timing.duration.amount)
    # (the scope intervals and triggers of the verdict's evidence, monitors.interval)
    got = every_trigger(req, columns, n, k)
    last = [j for j, (_s, e) in enumerate(got.intervals) if e == n - 1]
    if not last:
        return []
    chk = FirstEvents(got.R, got.S)
    s, e = got.intervals[last[0]]
    points = got.triggers[last[0]]
    out: list[OpenObligation] = []
    kind = "eventually" if timing == "null" else timing
    want = not negate
    nWant, nUnwant = (chk.nR, chk.nNR) if want else (chk.nNR, chk.nR)
    # only the triggers near the end can be open for bounded timings: look at those first
    for t in points:
        why = _open(kind, negate, want, t, e, k, chk, nWant, nUnwant)
        if why is not None:
            out.append(OpenObligation(t, (s, e), why))
            if len(out) >= limit:
                break
    return out


def open_reason(timing: str, negate: bool, t: int, e: int, k: int,
                chk: FirstEvents) -> str | None:
    """Why the obligation of the trigger ``t`` is still open at ``e``, the last tick read
    (its interval reaching it), or None when the ticks up to ``e`` meet or miss it: the rule
    of :func:`open_obligations` for one trigger (``chk`` over those ticks, ``k`` the
    duration in ticks or 0, ``negate`` an only* scope)."""
    want = not negate
    nWant, nUnwant = (chk.nR, chk.nNR) if want else (chk.nNR, chk.nR)
    kind = "eventually" if timing == "null" else timing
    return _open(kind, negate, want, t, e, k, chk, nWant, nUnwant)


def _open(kind: str, negate: bool, want: bool, t: int, e: int, k: int,
          chk: FirstEvents, nWant, nUnwant) -> str | None:
    """Why the obligation of trigger ``t`` is open at the end ``e`` of the intact span, or
    None when it is met or missed already (FRET's obligations,
    :data:`fretc.monitors.obligations.OBLIGATIONS`)."""
    rname = "R" if want else "!R"
    if kind == "immediately":
        return None
    if kind == "next":
        return f"{rname} at t+1={t + 1}, past the damage" if t == e else None
    if kind == "finally":
        return f"{rname} at the end of the scope interval, which the damage hides"
    if kind == "eventually":
        if not negate and nWant[t] > e:
            return f"R has not held since the trigger t={t}"
        return None
    if kind in ("always", "never"):
        if negate:  # "!name somewhere in [t, e]" not found yet
            bad = (chk.nNR if kind == "always" else chk.nR)[t]
            return f"the only* obligation of t={t} is not met yet" if bad > e else None
        return None  # an invariant that held so far holds over the intact span
    if kind == "within":
        if e >= t + k:
            return None
        if not negate:
            return f"R not yet held in [{t}, {t + k}], whose end lies past the damage" \
                if nWant[t] > e else None
        return (f"!R must hold on [{t}, {t + k}], whose end lies past the damage"
                if nUnwant[t] > e else None)
    if kind == "for":
        if e >= t + k:
            return None
        if not negate:
            return (f"R must hold on [{t}, {t + k}], whose end lies past the damage"
                    if nUnwant[t] > e else None)
        return (f"!R not yet held in [{t}, {t + k}], whose end lies past the damage"
                if chk.nNR[t] > e else None)
    if kind == "after":
        if e >= t + k + 1:
            return None
        if chk.nR[t] <= e:  # R already held early: met (negated) or missed (plain)
            return None
        return f"R at t+k+1={t + k + 1}, past the damage"
    if kind in ("until", "before"):
        nS = chk.nS
        assert nS is not None  # (until and before have a stop condition)
        if (kind == "until") == want:
            if nS[t] > e and nUnwant[t] > e:
                return f"{rname} held from t={t} but the stop condition has not come yet"
            return None
        if nWant[t] > e and nS[t] > e:
            return f"neither {rname} nor the stop condition has held since t={t}"
        return None
    return None


def verdict_at_damage(holds: bool, vacuous: bool, status: str | None,
                      status_tick: int | None, n: int, evidence: Evidence | None,
                      opened: list[OpenObligation], has_ltl3: bool
                      ) -> tuple[str, str | None]:
    """The verdict of a requirement over the intact span of a damaged log (module
    docstring).

    Args:
        holds: FRET's finite-trace verdict over the ``n`` intact ticks.
        vacuous: it holds because no scope interval or trigger occurred.
        status, status_tick: the earliest definitive LTL3 verdict over the intact ticks
            (``"violated"``, ``"satisfied"``, ``"unknown"``) and its tick.
        evidence: the interval semantics over the intact ticks (None if unavailable).
        opened: :func:`open_obligations` over the intact ticks.
        has_ltl3: the requirement has an online monitor (``status`` is meaningful).

    Returns:
        ``(verdict, why)``: verdict one of ``satisfied``, ``vacuous``, ``violated``,
        ``unknown``; ``why`` a sentence for ``unknown`` (else None).
    """
    if has_ltl3:
        if status == "violated" and status_tick is not None and status_tick < n:
            return "violated", None
        if status == "satisfied":
            return ("vacuous" if vacuous else "satisfied"), None
    elif not holds and evidence is not None:
        decided = [w for w in evidence.listed if w.interval[1] < n - 1]
        if decided:
            return "violated", None
    if not holds:
        where = ""
        if evidence is not None and evidence.violation is not None:
            where = (f" (trigger at tick {evidence.violation.trigger_tick}: "
                     f"{evidence.violation.reason})")
        return "unknown", ("the intact span ends at the damage with an obligation still "
                           "open" + where + "; a violation only because the log was cut short "
                           "is not evidence")
    if opened:
        o = opened[0]
        return "unknown", (f"an obligation is open at the damage: trigger at tick "
                           f"{o.trigger_tick}, {o.what}")
    if not has_ltl3:
        return "unknown", ("the intact span " + ("never fires the requirement"
                                                 if vacuous else "satisfies it")
                           + ", but it has no LTL3 verdict (no online monitor) to tell "
                           "whether the rest of the run could still violate it")
    return "unknown", ("the intact span " + ("never fires the requirement" if vacuous
                                             else "satisfies it")
                       + " so far, but its LTL3 verdict at the damage is not definite: the "
                       "part of the run after the damage could still violate it")
