"""A machine of the shield's runtime that no longer knows its state
(:mod:`fretc.shield.runtime`, "an input that cannot be read"): its decision, and how it
knows its state again.

Design notes: ARCHITECTURE.md, `shield/runtime_lost.py`."""

from __future__ import annotations

from typing import Any

from fretc.shield.runtime_values import term_variables

__all__ = ["lost_decision", "recovery_of", "follow", "settle_lost"]


def lost_decision(m: Any, fallback: tuple[list[int], dict[str, Any]] | None,
                  proposed: dict[str, Any], why: str
                  ) -> tuple[dict[str, Any], tuple[str, ...], tuple[str, ...], None,
                             tuple[str, ...], str]:
    """The decision of the lost machine ``m`` (the shape of its ``decide_cases``): the
    fallback's values of its outputs (none without a fallback), every output atom whose
    fallback truth is not the proposal's changed, ``why`` as the reason."""
    if fallback is None:
        return {}, (), tuple(m.texts), None, (), why + "; no fallback: no outputs"
    bits, values = fallback
    mine = {v: values[v] for v in [*m.out_kinds, *m.passed] if v in values}
    changed = []
    for j, (spec, f, t) in enumerate(zip(m.outs, m.out_tests, m.texts)):
        need = term_variables(spec[2]) if spec[1] == "pred" else {spec[0]}
        try:
            ok = need <= proposed.keys() and int(f(proposed)) == bits[j]
        except (TypeError, ValueError):
            ok = False
        if not ok:
            changed.append(t)
    return mine, (), tuple(changed), None, (), why


def recovery_of(m: Any) -> str:
    """How the lost machine ``m`` knows its state again (module docstring), as a phrase:
    by itself after how many readable ticks (and how many so far), or a reset."""
    if m.lookback is None or m.fallback_bits is None:
        return ("its requirements look back without bound" if m.lookback is None
                else "no fallback") + ": reset the shield"
    return (f"it recovers by itself after {m.lookback + 1} ticks in a row whose inputs it "
            f"reads, as far as its requirements look back; {m.readable} so far")


def follow(m: Any, ins: dict[str, Any], unread: frozenset[str]) -> bool:
    """One tick of the lost machine ``m``'s copy (module docstring) on the checked inputs
    ``ins`` (``unread``: the variables that could not be read) and the fallback's outputs;
    True when ``m`` knows its state again (the copy's, taken)."""
    bits = m.fallback_bits
    if m.lookback is None or bits is None:
        return False
    if any(m.reading_in.get(v) for v in unread) or any(v not in ins for v in m.in_kinds):
        m.shadow, m.readable = m.init, 0
        return False
    i = tuple([int(f(ins)) for f in m.in_tests])
    safe, nxt = m.move(i, tuple(bits), m.shadow)
    if not safe:  # (a copy not yet in the winning region: it starts again)
        m.shadow, m.readable = m.init, 0
        return False
    m.shadow, m.readable = nxt, m.readable + 1
    if m.readable <= m.lookback:
        return False
    m.state, m.others, m.lost = m.shadow, (), False
    m.shadow, m.readable = m.init, 0
    return True


def settle_lost(m: Any, why: str, ins: dict[str, Any], unread: frozenset[str]
                ) -> tuple[str, bool]:
    """After a tick the machine ``m`` gave as lost (``why`` its decision's reason): lost
    from now (its copy started), or its copy stepped (:func:`follow`). Returns the note for
    the decision's fault and whether ``m`` knows its state again."""
    if not m.lost:
        m.lost, m.shadow, m.readable = True, m.init, 0
        return why + " (" + recovery_of(m) + ")", False
    if follow(m, ins, unread):
        return (f"its state known again after {m.lookback + 1} ticks whose inputs it read "
                "(the fallback given once more)"), True
    return ("its state is unknown since an earlier tick (" + recovery_of(m) + ")"
            + ("; no fallback: no outputs" if m.fallback_bits is None else "")), False
