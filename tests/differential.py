"""Differential testing of fretc's formulas against an independent interval-semantics oracle.

:func:`random_requirement` draws a random FRETish sentence over the whole grammar (all 8
scopes, the 3 condition kinds, the 12 timings, every temporal function and occurrence
phrase, nested ``if ... then`` standing as an operand, quoted and dotted names) together
with its meaning as a small tuple tree. :func:`oracle` evaluates that meaning on a trace
directly from the definitions of ``../shared/fretish/README.md``: scope intervals (section 2),
triggers (section 3), timings (section 4) and the "meaning" column of section 6b for the
temporal functions. It never looks at a formula, so it is independent of
:mod:`fretc.compiler.semantics` (which builds FRET's expansions).

:func:`check_requirement` compares ft at 0, pt at the end (finite traces) and ft_inf
(infinite words: the trace followed by the all-false state forever) with the oracle.
Used by tests/compiler/test_differential.py (a bounded sample) and bench/differential_long.py.

Trace model (../shared/fretish/README.md section 6): the finite trace is followed by an absorbing state in which
every variable is false and every number 0. Two FRET facts the oracle models explicitly:

* ``Right`` of the ``notin``/``onlyIn``/``before`` scopes has no ``LAST`` disjunct, and
  that of ``onlyAfter`` is ``m & (LAST | X !m)`` (../shared/fretish/README.md section 6b), so for the future
  functions an interval that runs to the end of the trace (with ``m`` false there, for
  ``onlyAfter``) does not end there: it continues into the absorbing state.
* At position 0 outside every scope interval (reachable only through ``preBool``'s
  previous position) ``prevOcc`` is false: FRET's ``Y`` is false at position 0.
* ``preBool`` ignores the scope (init at position 0 of the trace).
"""

from __future__ import annotations

import random
from collections.abc import Sequence

INF = 10 ** 9

BOOL_VARS = ["p", "q", "r", "weird var", "a.b", "x%"]
NUM_VARS = ["x", "temp [C]"]
MODE_VARS = ["m", "flight phase"]


def _name_text(v: str) -> str:
    return v if v.replace(".", "").replace("%", "").replace("_", "").isalnum() \
        and v[0].isalpha() else '"' + v + '"'


# --------------------------------------------------------------------------- generator
class _Gen:
    def __init__(self, rnd: random.Random, max_bound: int = 3):
        self.rnd = rnd
        self.max_bound = max_bound

    def bound(self):
        r = self.rnd
        n = r.randint(0, self.max_bound)
        if r.random() < 0.5:
            return (n,)
        m = r.randint(0, n)
        return (m, n)

    def expr(self, depth: int, allow_future=True, allow_past=True) -> tuple[tuple, str]:
        """(meaning, text). Text is parenthesized except for nested if-then as the last
        operand, which the grammar groups to the right."""
        r = self.rnd
        if depth <= 0 or r.random() < 0.25:
            if r.random() < 0.2:
                v = r.choice(NUM_VARS)
                k = r.randint(-1, 3)
                op = r.choice(["<", "<=", ">", ">=", "=", "!="])
                return ("cmp", op, v, k), f"{_name_text(v)} {op} {k}"
            v = r.choice(BOOL_VARS)
            return ("var", v), _name_text(v)
        kinds = ["not", "bin", "bin", "ifthen", "nested_if"]
        if allow_past:
            kinds += ["persisted", "occurred", "prevOcc", "preBool"]
        if allow_future:
            kinds += ["persists", "occurs", "nextOcc"]
        k = r.choice(kinds)
        sub = lambda: self.expr(depth - 1, allow_future, allow_past)  # noqa: E731
        if k == "not":
            a, ta = sub()
            return ("!", a), f"!({ta})"
        if k == "bin":
            op = r.choice(["&", "|", "xor", "->", "<->", "=>", "<=>"])
            (a, ta), (b, tb) = sub(), sub()
            canon = {"=>": "->", "<=>": "<->"}.get(op, op)
            return (canon, a, b), f"({ta}) {op} ({tb})"
        if k == "ifthen":
            (a, ta), (b, tb) = sub(), sub()
            return ("->", a, b), f"if ({ta}) then ({tb})"
        if k == "nested_if":
            # an if-then as the last operand of a binary operator, or after "!": the
            # grammar's grouping (FRET regroups these, defect 2)
            (a, ta), (b, tb), (c, tc) = sub(), sub(), sub()
            if r.random() < 0.3:
                return ("!", ("->", b, c)), f"(!if ({tb}) then ({tc}))"
            op = r.choice(["&", "|", "xor", "<->", "->"])
            return (op, a, ("->", b, c)), f"(({ta}) {op} if ({tb}) then ({tc}))"
        if k in ("persisted", "occurred", "persists", "occurs"):
            past = k in ("persisted", "occurred")
            b = self.bound()
            a, ta = self.expr(depth - 1, allow_future=not past, allow_past=past)
            return (k, b, a), f"{k}({', '.join(map(str, b))}, {ta})"
        if k in ("prevOcc", "nextOcc"):
            past = k == "prevOcc"
            (a, ta) = self.expr(depth - 1, allow_future=not past, allow_past=past)
            (b, tb) = self.expr(depth - 1, allow_future=not past, allow_past=past)
            if r.random() < 0.5:
                word = "previous" if past else "next"
                return (k, a, b), f"(at the {word} occurrence of ({ta}), ({tb}))"
            return (k, a, b), f"{k}({ta}, {tb})"
        if k == "preBool":
            init = r.random() < 0.5
            a, ta = self.expr(depth - 1, allow_future=False, allow_past=True)
            return ("preBool", init, a), f"preBool({'true' if init else 'false'}, {ta})"
        raise AssertionError(k)


SCOPES = {
    "null": [""], "in": ["in {m}", "during {m} mode", "while {c}"],
    "notin": ["when not in {m}", "except while {c}"], "onlyIn": ["only in {m}",
                                                               "only while {c}"],
    "after": ["after {c}"], "before": ["before {c}"], "onlyAfter": ["only after {c}"],
    "onlyBefore": ["only before {c}"],
}
TIMINGS = ["", "immediately", "at the next timepoint", "finally", "eventually", "always",
           "never", "within {n} ticks", "for {n} ticks", "after {n} ticks", "until {s}",
           "before {s}"]
TIMING_KIND = {"": "null", "immediately": "immediately", "at the next timepoint": "next",
               "finally": "finally", "eventually": "eventually", "always": "always",
               "never": "never", "within {n} ticks": "within", "for {n} ticks": "for",
               "after {n} ticks": "after", "until {s}": "until", "before {s}": "before"}


def random_requirement(rnd: random.Random, depth: int = 2) -> tuple[str, dict]:
    """A random sentence and its meaning ``{scope, mode, cond_kind, cond, timing, n, stop,
    response}`` (expressions as meaning tuples)."""
    g = _Gen(rnd)
    scope = rnd.choice(list(SCOPES))
    phrase = rnd.choice(SCOPES[scope])
    mode = None
    stext = ""
    if scope != "null":
        if "{m}" in phrase:
            mv = rnd.choice(MODE_VARS)
            mode = ("var", mv)
            stext = phrase.format(m=_name_text(mv))
        else:
            mode, mt = g.expr(depth - 1)
            stext = phrase.format(c=f"({mt})")
    ck = rnd.choice(["null", "regular", "holding"])
    cond = None
    ctext = ""
    if ck != "null":
        cond, ct = g.expr(depth)
        q = "whenever" if ck == "holding" else rnd.choice(["upon", "when", "if", "where"])
        ctext = f"{q} ({ct})"
        if ck == "regular" and rnd.random() < 0.2:
            ctext += " is false"
            cond = ("!", cond)
    tphrase = rnd.choice(TIMINGS)
    tk = TIMING_KIND[tphrase]
    n = rnd.randint(0, 3)
    stop = None
    ttext = tphrase
    if tk in ("until", "before"):
        stop, st_ = g.expr(depth - 1)
        ttext = tphrase.format(s=f"({st_})")
    else:
        ttext = tphrase.format(n=n)
    resp, rt = g.expr(depth)
    parts = [stext + ("," if stext else ""), ctext + ("," if ctext else ""), "the sw shall",
             ttext, "satisfy", rt]
    text = " ".join(x for x in parts if x)
    return text, {"scope": scope, "mode": mode, "cond_kind": ck, "cond": cond,
                  "timing": tk, "n": n, "stop": stop, "response": resp}


# --------------------------------------------------------------------------- oracle
class _World:
    """A trace with its scope's interval starts and ends (for the functions)."""

    def __init__(self, trace: Sequence[dict], scope: str, mode_series: list | None,
                 infinite: bool):
        self.trace = trace
        self.L = len(trace)
        self.infinite = infinite
        self.scope = scope
        self.intervals = _intervals(scope, mode_series, self.L, infinite)
        L = self.L
        starts = {s for s, _ in self.intervals}
        # function endpoints: Left at interval starts, Right at interval ends; for notin,
        # onlyIn and before FRET's Right has no LAST, so an interval reaching the end of
        # a finite trace has no Right
        ends = set()
        for _s, e in self.intervals:
            if e < L - 1 or (e == L - 1 and not infinite and (
                    scope in ("null", "in", "after", "onlyBefore")
                    or (scope == "onlyAfter" and mode_series[-1]))):
                ends.add(e)
        self.start_before = []
        cur = -INF
        for i in range(L):
            if i in starts:
                cur = i
            self.start_before.append(cur)
        self.end_after = [INF] * L
        cur = INF
        for i in range(L - 1, -1, -1):
            if i in ends:
                cur = i
            self.end_after[i] = cur

    def s_of(self, t: int, free: bool) -> int:
        if free or t >= self.L:
            return -INF if free else self.start_before[-1]
        return self.start_before[t]

    def e_of(self, t: int, free: bool) -> int:
        if free or t >= self.L:
            return INF
        return self.end_after[t]

    def var(self, name: str, t: int, numeric: bool):
        if t >= self.L or t < 0:
            return 0 if numeric else False
        return self.trace[t].get(name, 0 if numeric else False)


def _runs(series: list[bool]) -> list[tuple[int, int]]:
    out = []
    i = 0
    L = len(series)
    while i < L:
        if series[i]:
            j = i
            while j + 1 < L and series[j + 1]:
                j += 1
            out.append((i, j))
            i = j + 1
        else:
            i += 1
    return out


def _intervals(scope: str, m: list | None, L: int, infinite: bool):
    """Scope intervals [s, e] (../shared/fretish/README.md section 2); ``only*`` scopes give the complement
    intervals on which the negated obligation applies."""
    if scope == "null":
        return [(0, L - 1)]
    if scope == "in":
        return _runs(m)
    if scope in ("notin", "onlyIn"):
        return _runs([not v for v in m])
    runs = _runs(m)
    first = runs[0] if runs else None
    if scope == "after":
        if first is None or first[1] >= L - 1:
            return []
        return [(first[1] + 1, L - 1)]
    if scope == "onlyAfter":
        return [(0, first[1] if first else L - 1)]
    if scope == "before":
        if first is None:
            return [(0, L - 1)]
        return [(0, first[0] - 1)] if first[0] > 0 else []
    if scope == "onlyBefore":
        return [(first[0], L - 1)] if first else []
    raise AssertionError(scope)


def value(w: _World, e: tuple, t: int, free: bool = False):
    """The meaning of expression ``e`` at position ``t`` (section 6b's meaning column)."""
    k = e[0]
    if k == "var":
        return bool(w.var(e[1], t, False))
    if k == "cmp":
        x = w.var(e[2], t, True)
        y = e[3]
        return {"<": x < y, "<=": x <= y, ">": x > y, ">=": x >= y, "=": x == y,
                "!=": x != y}[e[1]]
    if k == "!":
        return not value(w, e[1], t, free)
    if k in ("&", "|", "xor", "->", "<->"):
        a, b = value(w, e[1], t, free), value(w, e[2], t, free)
        return {"&": a and b, "|": a or b, "xor": a != b, "->": (not a) or b,
                "<->": a == b}[k]
    v = lambda j: value(w, e[-1], j, free)  # noqa: E731  (argument p)
    if k in ("persisted", "occurred", "persists", "occurs"):
        b = e[1]
        m, n = (0, b[0]) if len(b) == 1 else b
        s, end = w.s_of(t, free), w.e_of(t, free)
        if k == "persisted":   # p at t-n..t-m, and s <= t-n
            return s <= t - n and all(v(j) for j in range(max(t - n, 0), t - m + 1)) \
                if not free else all(v(j) for j in range(max(t - n, 0), t - m + 1))
        if k == "occurred":    # p at some j in [max(s, t-n), t-m]
            return any(v(j) for j in range(max(s, t - n, 0), t - m + 1))
        if k == "persists":    # p at t+m..t+n, and e >= t+n
            return end >= t + n and all(v(j) for j in range(t + m, t + n + 1))
        return any(v(j) for j in range(t + m, min(t + n, end) + 1))   # occurs
    # same shape as nextOcc below: the past mirror (kept: previous positions, s_of, Y false at 0)
    if k == "prevOcc":
        p = lambda j: value(w, e[1], j, free)  # noqa: E731
        q = lambda j: value(w, e[2], j, free)  # noqa: E731
        s = w.s_of(t, free)
        if not free and t == s:
            return True
        if t == 0:
            # position 0 outside every interval (reached only through preBool's previous
            # position): no previous position, FRET's Y is false
            return False
        prev = [j for j in range(max(s, 0), t) if p(j)]
        if not prev:
            return not free
        return q(prev[-1])
    # same shape as prevOcc above: the future mirror (kept: next positions, e_of, a horizon)
    if k == "nextOcc":
        p = lambda j: value(w, e[1], j, free)  # noqa: E731
        q = lambda j: value(w, e[2], j, free)  # noqa: E731
        end = w.e_of(t, free)
        if not free and t == end:
            return True
        horizon = min(end, max(t, w.L) + 2)  # past the trace every position is the same
        for j in range(t + 1, horizon + 1):
            if p(j):
                return q(j)
        return not free
    if k == "preBool":
        return e[1] if t == 0 else value(w, e[2], t - 1, free)
    raise AssertionError(k)


def world_signals(meaning: dict, trace: Sequence[dict], infinite: bool = False):
    """``(world, R, S, C)``: the scope intervals of ``meaning`` on ``trace`` (its mode read
    with the endpoint-free functions) and the response, stop and condition as functions of a
    position (S, C None when absent)."""
    scope = meaning["scope"]
    mode_series = None
    if scope != "null":
        w0 = _World(trace, "null", None, infinite)
        mode_series = [value(w0, meaning["mode"], i, free=True) for i in range(len(trace))]
    w = _World(trace, scope, mode_series, infinite)
    R = lambda j: value(w, meaning["response"], j)  # noqa: E731
    S = (lambda j: value(w, meaning["stop"], j)) if meaning["stop"] else None  # noqa: E731
    C = (lambda j: value(w, meaning["cond"], j)) if meaning["cond"] else None  # noqa: E731
    return w, R, S, C


def trigger_points(meaning: dict, C, s: int, last: int) -> list[int]:
    """The trigger points in ``[s, last]`` of an interval starting at ``s`` (section 2)."""
    if meaning["cond_kind"] == "null":
        return [s]
    if meaning["cond_kind"] == "holding":
        return [t for t in range(s, last + 1) if C(t)]
    return [t for t in range(s, last + 1) if C(t) and (t == s or not C(t - 1))]


def oracle(meaning: dict, trace: Sequence[dict], infinite: bool = False) -> bool:
    """Truth of the requirement on ``trace`` by FRET's interval semantics. ``infinite``:
    the trace is followed by the all-false state forever and intervals reaching the end do
    not end (ft_inf); otherwise the trace ends at its last position (ft, pt)."""
    L = len(trace)
    if infinite:
        # unroll the absorbing state far enough for every bound and nested lookahead
        trace = list(trace) + [{}] * 12
        L = len(trace)
    w, R, S, C = world_signals(meaning, trace, infinite)
    negate = meaning["scope"].startswith("only")
    tk, n = meaning["timing"], meaning["n"]
    for s, e in w.intervals:
        if infinite and e == L - 1:
            e = INF
        for t in trigger_points(meaning, C, s, min(e, L - 1)):
            if not _obligation(tk, negate, n, t, e, R, S, L):
                return False
    return True


def _obligation(tk, negate, n, t, e, R, S, L) -> bool:
    """What a trigger at t must see in its interval ending at e (../shared/fretish/README.md section 4);
    ``negate``: the only* form (the response must not hold, FRET's dual timings)."""
    top = min(e, L - 1 + 2)       # positions past L-1 all repeat the last state
    rng = lambda a, b: range(a, min(b, top) + 1)  # noqa: E731
    nR = lambda j: not R(j)  # noqa: E731

    def eventually(f):
        return any(f(j) for j in rng(t, e))

    def always(f):
        return all(f(j) for j in rng(t, e))

    def within(f, k):
        return e < t + k or any(f(j) for j in rng(t, t + k))

    def for_(f, k):
        return all(f(j) for j in rng(t, min(t + k, e)))

    def until(f):
        k = next((j for j in range(t, top + 1) if S(j)), INF)
        return all(f(j) for j in rng(t, min(k - 1, e)))

    def before(f):
        k = next((j for j in rng(t, e) if f(j)), INF)
        return not any(S(j) for j in rng(t, min(k, e)))

    # same cases as compiler.scope_timing.ft_timing (kept: an independent oracle of truth values,
    # not formulas)
    if tk == "immediately":
        return nR(t) if negate else R(t)
    if tk == "next":
        return t == e or (nR(t + 1) if negate else R(t + 1))
    if tk == "finally":
        if e >= INF:
            return True
        return nR(e) if negate else R(e)
    if tk in ("eventually", "null"):
        return always(nR) if negate else eventually(R)
    if tk == "always":
        return eventually(nR) if negate else always(R)
    if tk == "never":
        return eventually(R) if negate else always(nR)
    if tk == "within":
        return for_(nR, n) if negate else within(R, n)
    if tk == "for":
        return within(nR, n) if negate else for_(R, n)
    if tk == "after":
        if negate:
            return within(R, n) or for_(nR, n + 1)
        return for_(nR, n) and within(R, n + 1)
    if tk == "until":
        return before(nR) if negate else until(R)
    if tk == "before":
        return until(nR) if negate else before(R)
    raise AssertionError(tk)


# --------------------------------------------------------------------------- checking
def random_trace(rnd: random.Random, length: int) -> list[dict]:
    return [{**{v: rnd.random() < 0.5 for v in BOOL_VARS + MODE_VARS},
             **{v: rnd.randint(-1, 3) for v in NUM_VARS}} for _ in range(length)]


def check_requirement(text: str, meaning: dict, rnd: random.Random, traces: int = 30):
    """Compare fretc's ft, pt and ft_inf with the oracle on random traces. Returns None or
    a description of the first disagreement."""
    from fretc.compiler.evaluate import ft_at, pt_at
    from fretc.compiler.semantics import formalize
    from fretc.fretish import parse

    f = formalize(parse(text))
    for _ in range(traces):
        trace = random_trace(rnd, rnd.randint(1, 8))
        want = oracle(meaning, trace)
        got_ft = ft_at(f.ft, trace)
        if got_ft != want:
            return f"ft {got_ft}, oracle {want} on {trace}"
        got_pt = pt_at(f.pt, trace)
        if got_pt != want:
            return f"pt {got_pt}, oracle {want} on {trace}"
        want_inf = oracle(meaning, trace, infinite=True)
        got_inf = ft_inf_at(f.ft_inf, trace)
        if got_inf != want_inf:
            return f"ft_inf {got_inf}, oracle {want_inf} on {trace} + all-false forever"
    return None


def ft_inf_at(node, trace: Sequence[dict]) -> bool:
    """ft_inf at 0 on the infinite word ``trace`` + all-false state forever. The word is
    unrolled by 12 all-false states so that derived past atoms (past functions inside a
    future formula, evaluated pointwise) reach their steady value, which the absorbing
    state then keeps (:mod:`fretc.compiler.evaluate` would read them as false there)."""
    from fretc.compiler.evaluate import _Evaluator

    class _Inf(_Evaluator):
        def _compute(self, n):
            if n.op in ("past", "future"):
                s = self.series(n.args[0])
                return s[:self.L] + [s[self.L - 1]]
            return super()._compute(n)

    return bool(_Inf(list(trace) + [{}] * 12).series(node)[0])
