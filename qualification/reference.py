"""A reference evaluator of FRET's semantics on finite traces, written from the definitions
alone (docs/reference/semantics.md, which summarizes Giannakopoulou et al., REFSQ 2020 and IST
2021, and FRET's user manual): scope intervals, triggers and each timing's obligation, over
lists of booleans. It shares no code with fretc's compiler or judge (it imports nothing of
fretc), so the validation suite (:mod:`fretc.qualification.checks`) can hold the production
pipeline against it.

Its sentences: for each of FRET's 288 template keys (8 scopes x 3 conditions x 12 timings)
one FRETish sentence over the boolean variables ``m`` (the scope's mode), ``c`` (the
condition), ``r`` (the response) and ``s`` (the stop condition of ``until``/``before``), with
durations of :data:`DURATION` ticks (:func:`key_sentences`).

A trace is a list of ticks, each a dict ``{variable: bool}`` (every one of ``m c r s``).
"""

from __future__ import annotations

import random
from collections.abc import Callable, Mapping, Sequence

#: FRET's scope kinds, condition kinds and timing kinds (FRET's template keys, in the order
#: of docs/reference/semantics.md's tables)
SCOPES = ("null", "in", "notin", "onlyIn", "after", "before", "onlyAfter", "onlyBefore")
CONDITIONS = ("null", "regular", "holding")
TIMINGS = ("null", "immediately", "next", "finally", "eventually", "always", "never",
           "within", "for", "after", "until", "before")
#: the duration of ``within``/``for``/``after`` in the key sentences, in ticks
DURATION = 2
#: the variables of the key sentences
VARIABLES = ("m", "c", "r", "s")

_SCOPE_TEXT = {"null": "", "in": "in m", "notin": "when not in m", "onlyIn": "only in m",
               "after": "after m", "before": "before m", "onlyAfter": "only after m",
               "onlyBefore": "only before m"}
_CONDITION_TEXT = {"null": "", "regular": "upon c", "holding": "whenever c"}
_TIMING_TEXT = {"null": "", "immediately": "immediately", "next": "at the next timepoint",
                "finally": "finally", "eventually": "eventually", "always": "always",
                "never": "never", "within": f"within {DURATION} ticks",
                "for": f"for {DURATION} ticks", "after": f"after {DURATION} ticks",
                "until": "until s", "before": "before s"}

Trace = Sequence[Mapping[str, bool]]
Interval = tuple[int, int]


def key_sentences() -> list[tuple[str, str]]:
    """``[(key, sentence)]`` for the 288 keys: ``key`` is FRET's ``scope,condition,timing``
    and the sentence its FRETish text, e.g. ``("in,regular,within", "in m upon c the sw shall
    within 2 ticks satisfy r")``."""
    out = []
    for s in SCOPES:
        for c in CONDITIONS:
            for t in TIMINGS:
                words = (_SCOPE_TEXT[s], _CONDITION_TEXT[c], "the sw shall", _TIMING_TEXT[t],
                         "satisfy r")
                out.append((f"{s},{c},{t}", " ".join(w for w in words if w)))
    return out


def random_trace(rnd: random.Random, length: int) -> list[dict[str, bool]]:
    """A trace of ``length`` ticks (>= 1), each variable of :data:`VARIABLES` drawn fair."""
    return [{v: rnd.random() < 0.5 for v in VARIABLES} for _ in range(length)]


def _runs(values: Sequence[bool]) -> list[Interval]:
    """The maximal runs of True in ``values``, as inclusive ``(start, end)`` pairs."""
    out: list[Interval] = []
    start = None
    for i, v in enumerate(values):
        if v and start is None:
            start = i
        if not v and start is not None:
            out.append((start, i - 1))
            start = None
    if start is not None:
        out.append((start, len(values) - 1))
    return out


def scope_intervals(scope: str, mode: Sequence[bool]) -> list[Interval]:
    """The scope intervals of a finite trace whose mode is ``mode`` (one bool a tick), as
    docs/reference/semantics.md's scope table states them: the whole run; each maximal
    stretch of M (``in``) or of not M (``notin``, and ``onlyIn``, whose response is
    forbidden there); from just after the first stretch of M to the end (``after``); from
    the start up to, not including, the first point of M (``before``); and the complements
    of ``after`` and ``before`` (``onlyAfter``: from the start to the end of the first
    stretch of M, or the whole run without M; ``onlyBefore``: from the first point of M to
    the end). Raises ``ValueError`` for another scope."""
    n = len(mode)
    runs = _runs(mode)
    if scope == "null":
        return [(0, n - 1)]
    if scope == "in":
        return runs
    if scope in ("notin", "onlyIn"):
        return _runs([not v for v in mode])
    if scope == "after":
        return [(runs[0][1] + 1, n - 1)] if runs and runs[0][1] < n - 1 else []
    if scope == "before":
        first = runs[0][0] if runs else n
        return [(0, first - 1)] if first > 0 else []
    if scope == "onlyAfter":
        return [(0, runs[0][1])] if runs else [(0, n - 1)]
    if scope == "onlyBefore":
        return [(runs[0][0], n - 1)] if runs else []
    raise ValueError(f"unknown scope {scope!r}")


def triggers(condition: str, cond: Sequence[bool], start: int, end: int) -> list[int]:
    """The trigger points of the interval ``[start, end]``: its first point without a
    condition; every point where the condition holds (``holding``, ``whenever``); where it
    becomes true inside the interval or already holds at its first point (``regular``)."""
    if condition == "null":
        return [start]
    if condition == "holding":
        return [t for t in range(start, end + 1) if cond[t]]
    if condition == "regular":
        return [t for t in range(start, end + 1) if cond[t] and (t == start or not cond[t - 1])]
    raise ValueError(f"unknown condition {condition!r}")


def obligation(timing: str, negate: bool, r: Sequence[bool], s: Sequence[bool], t: int,
               e: int, k: int = DURATION) -> bool:
    """Does the obligation of ``timing`` hold for a trigger at ``t`` in an interval ending at
    ``e`` (docs/reference/semantics.md's timing table; ``k`` the duration in ticks)?
    ``negate``: an only-scope, whose response is forbidden (the timing's obligation is read
    with the response negated, as FRET's only-templates do)."""
    def rr(j: int) -> bool:
        return r[j] != negate

    def anywhere(lo: int, hi: int) -> bool:
        return any(rr(j) for j in range(lo, min(hi, e) + 1))

    def everywhere(lo: int, hi: int) -> bool:
        return all(rr(j) for j in range(lo, min(hi, e) + 1))

    def nowhere(lo: int, hi: int) -> bool:
        return not anywhere(lo, hi)

    first_s = next((j for j in range(t, e + 1) if s[j]), None)
    checks: dict[str, Callable[[], bool]] = {
        "immediately": lambda: rr(t),
        "next": lambda: t == e or rr(t + 1),
        "finally": lambda: rr(e),
        "eventually": lambda: anywhere(t, e),
        "null": lambda: anywhere(t, e),
        "always": lambda: everywhere(t, e),
        "never": lambda: nowhere(t, e),
        "within": lambda: e < t + k or anywhere(t, t + k),
        "for": lambda: everywhere(t, t + k),
        "after": lambda: nowhere(t, t + k) and (e < t + k + 1 or rr(t + k + 1)),
        "until": lambda: everywhere(t, e if first_s is None else first_s - 1),
        "before": lambda: _before(rr, s, t, e),
    }
    if not negate or timing in ("immediately", "next", "finally"):
        return checks[timing]()
    # an only-scope: the response must not do what the timing asks (FRET's negated
    # templates, docs/reference/semantics.md's scope table: "the response forbidden there")
    negated: dict[str, Callable[[], bool]] = {
        "eventually": lambda: everywhere(t, e),
        "null": lambda: everywhere(t, e),
        "always": lambda: anywhere(t, e),
        "never": lambda: not everywhere(t, e),
        "within": lambda: everywhere(t, t + k),
        "for": lambda: e < t + k or anywhere(t, t + k),
        "after": lambda: (e < t + k or not everywhere(t, t + k)
                          or everywhere(t, t + k + 1)),
        "until": lambda: _before(rr, s, t, e),
        "before": lambda: everywhere(t, e if first_s is None else first_s - 1),
    }
    return negated[timing]()


def _before(holds: Callable[[int], bool], s: Sequence[bool], t: int, e: int) -> bool:
    """``before S``: the response at some point before S first holds after ``t`` (S may
    not hold from ``t`` to the response's first point, that point included)."""
    first = next((j for j in range(t, e + 1) if holds(j)), None)
    last = e if first is None else first
    return not any(s[j] for j in range(t, last + 1))


def verdict(key: str, trace: Trace, k: int = DURATION) -> str:
    """FRET's finite-trace verdict of the key sentence of ``key`` (:func:`key_sentences`)
    on ``trace``: ``"violated"`` when some trigger's obligation fails, ``"vacuous"`` when
    none fails and no scope interval or no trigger exists, else ``"satisfied"``
    (docs/guide/audits.md, "Verdicts"). Raises ``ValueError`` for an empty trace or an
    unknown key part."""
    if not trace:
        raise ValueError("a verdict needs at least one tick")
    scope, condition, timing = key.split(",")
    col = {v: [bool(tick[v]) for tick in trace] for v in VARIABLES}
    count = failed = 0
    intervals = scope_intervals(scope, col["m"])
    for start, end in intervals:
        for t in triggers(condition, col["c"], start, end):
            count += 1
            if not obligation(timing, scope.startswith("only"), col["r"], col["s"], t, end, k):
                failed += 1
    if failed:
        return "violated"
    return "vacuous" if not intervals or count == 0 else "satisfied"
