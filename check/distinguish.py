"""``fretc distinguish A B``: do two wordings of a requirement mean the same, and if not, the
shortest trace on which they disagree (a *distinguishing trace*, as FRET's formalization
validation shows an engineer: Giannakopoulou, Pressburger, Mavridou et al., ICSE 2026).

Design notes: ARCHITECTURE.md, `check/distinguish.py`."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction
from itertools import product
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.compiler import ir

if TYPE_CHECKING:
    from fretc.check.budget import Budget
    from fretc.compiler.build import Compiled

__all__ = ["Distinction", "distinguish", "MAX_LETTERS", "MAX_STATES", "DEFAULT_MAX_TICKS"]

#: the most letters (valuations of the variables) a tick of the search tries
MAX_LETTERS = 256
#: the most product states the search keeps (past it: the solver's answer)
MAX_STATES = 5_000
#: the longest trace the search builds
DEFAULT_MAX_TICKS = 2_048

_INTERPRETED = ("ap", "var", "num", "cmp", "true", "false", "!", "&", "|", "->", "xor",
                "<->", "X", "F", "G", "U", "V", "Y", "Z", "O", "H", "S", "T", "LAST", "FTP")


@dataclass
class Distinction:
    """What :func:`distinguish` found.

    Attributes:
        equivalent: True (same verdict on every finite trace), False (``trace`` separates
            them) or None (unknown: ``why``).
        trace: variable -> one value per tick (bool or float), when not equivalent.
        verdicts: the verdicts of A and B on ``trace`` (``satisfied``, ``vacuous``,
            ``violated``).
        shortest: the trace is a shortest one (found by the search); False when it is the
            solver's model.
        proof: how equivalence (or the trace) was established, in words.
        why: why the answer is unknown.
        states: product states the search visited; ``depth``: ticks it reached.
    """

    equivalent: bool | None
    trace: dict[str, list] | None = None
    verdicts: tuple[str, str] | None = None
    shortest: bool = False
    proof: str = ""
    why: str = ""
    states: int = 0
    depth: int = 0
    notes: list[str] = field(default_factory=list)


# ----------------------------------------------------------------------------- letters
def _atoms_ok(nodes) -> str | None:
    """Why the atoms of ``nodes`` cannot be enumerated, or None."""
    from fretc.check.numeric_abstraction import simple_comparison
    from fretc.compiler.printers import to_smv

    for f in nodes:
        for n in ir.walk(f):
            if n.op not in _INTERPRETED:
                return f"the atom {to_smv(n)} is not a variable or a variable compared " \
                       "with a constant"
            if n.op == "cmp" and simple_comparison(n) is None:
                return f"the comparison {to_smv(n)} is not one variable against a constant"
    return None


def _domains(formulas) -> dict[str, list]:
    """Variable -> the values a letter gives it: booleans (``ap``) False/True, a numeric
    variable one value per region of its constants (midpoints, and one beyond each end)."""
    from fretc.check.numeric_abstraction import simple_comparison

    kinds = _kinds(formulas)
    consts: dict[str, set] = {}
    for f in formulas:
        for n in ir.walk(f):
            sc = simple_comparison(n) if n.op == "cmp" else None
            if sc is not None:
                consts.setdefault(sc[0], set()).add(sc[2])
    out: dict[str, list] = {}
    for name in sorted(kinds):
        if kinds[name] == "bool":
            out[name] = [False, True]
            continue
        cs = sorted(consts.get(name, {Fraction(0)}))
        points = [cs[0] - 1]
        for i, c in enumerate(cs):
            points += [c, (c + cs[i + 1]) / 2 if i + 1 < len(cs) else c + 1]
        out[name] = [float(p) for p in points]
    return out


# ----------------------------------------------------------------------------- monitors
def _monitor_classes(ca, cb):
    """The generated monitor classes of the two compiled requirements (ids must differ)."""
    from fretc.compiler.codegen import build_monitor_modules

    classes = []
    for c in (ca, cb):
        (module,) = build_monitor_modules([c]).values()
        ns: dict = {"__name__": "fretc_distinguish_monitor"}
        exec(compile(module.text, "<fretc distinguish>", "exec"), ns)
        classes.append(ns["MONITORS"][c.id])
    return classes


def _snapshot(s: tuple) -> tuple:
    """A copy of a monitor's pt state ``s`` (its ``_s``: a window's queue is changed in
    place by ``step``)."""
    return tuple(deque([list(r) for r in x]) if isinstance(x, deque) else x for x in s)


def _key(s: tuple) -> tuple:
    """The state ``s`` with the windows' ticks made relative to the current tick (the tick
    count itself left out but for the first tick), so equal behaviours compare equal."""
    tick = s[-2]
    return (tick == 0,) + tuple(tuple((a - tick, b - tick) for a, b in x)
                                if isinstance(x, deque) else x for x in s[:-2])


def _search(classes, domains: dict[str, list], max_ticks: int, max_states: int):
    """Breadth-first search of the product (module docstring): (letters of a shortest
    distinguishing trace or None, exhausted, states, depth). Each trace is kept as a link
    to its parent's (memory: one link per state)."""
    names = list(domains)
    letters = [dict(zip(names, vals)) for vals in product(*domains.values())]
    ma, mb = classes[0](), classes[1]()
    links: list[tuple[int, int]] = [(-1, -1)]  # node -> (parent node, letter index)
    frontier = [(_snapshot(ma._s), _snapshot(mb._s), 0)]
    seen = {(_key(ma._s), _key(mb._s))}

    def run(node: int) -> list[dict]:
        out = []
        while node > 0:
            node, i = links[node]
            out.append(letters[i])
        return out[::-1]
    for depth in range(1, max_ticks + 1):
        nxt = []
        for sa, sb, node in frontier:
            for i, letter in enumerate(letters):
                ma._s, mb._s = _snapshot(sa), _snapshot(sb)
                if bool(ma.step(letter)) != bool(mb.step(letter)):
                    return run(node) + [letter], False, len(seen), depth
                k = (_key(ma._s), _key(mb._s))
                if k not in seen:
                    if len(seen) >= max_states:
                        return None, False, len(seen), depth
                    seen.add(k)
                    links.append((node, i))
                    nxt.append((_snapshot(ma._s), _snapshot(mb._s), len(links) - 1))
        if not nxt:
            return None, True, len(seen), depth
        frontier = nxt
    return None, False, len(seen), max_ticks


# ----------------------------------------------------------------------------- the answer
def _verdict_words(ca, cb, trace: list[dict]) -> tuple[str, str] | None:
    """The interval semantics' verdicts of A and B on ``trace`` (the audit's words), or None
    when it cannot judge one."""
    from fretc.monitors.interval import verdict_of

    n = len(trace)
    out = []
    for c in (ca, cb):
        cols = {v: np.array([row[v] for row in trace]) for v in c.formalization.variables}
        word = verdict_of(c.requirement, cols, n, c.formalization.ticks)
        if word == "unknown":
            return None
        out.append(word)
    return out[0], out[1]


def _replay(classes, trace: list[dict]) -> tuple[bool | None, bool | None]:
    """The two monitors' verdicts at the end of ``trace``."""
    out = []
    for cls in classes:
        m = cls()
        v = None
        for row in trace:
            v = bool(m.step(row))
        out.append(v)
    return out[0], out[1]


def _columns(trace: list[dict], names) -> dict[str, list]:
    return {v: [row[v] for row in trace] for v in names}


def distinguish(ca: Compiled, cb: Compiled, *, max_ticks: int = DEFAULT_MAX_TICKS,
                max_states: int = MAX_STATES, budget: Budget | None = None,
                fork: bool = True) -> Distinction:
    """Compare the compiled requirements ``ca`` and ``cb`` (:class:`fretc.compiler.build.Compiled`,
    both formalized, different ids): module docstring. ``budget``: the solver queries' work
    budget (:class:`fretc.check.budget.Budget`; default the defaults); ``fork``: run Spot in
    its bounded worker process (:class:`fretc.check.solver.SpotWorker`).

    Raises:
        ValueError: a requirement that did not formalize, or two with the same id.
    """
    for c in (ca, cb):
        if c.formalization is None:
            raise ValueError(f"{c.id} has no formalization: {c.error or 'free-form'}")
    if ca.id == cb.id:
        raise ValueError("the two requirements must have different ids")
    form_a, form_b = ca.formalization, cb.formalization
    assert form_a is not None and form_b is not None  # (refused above)
    fa, fb = form_a.ft, form_b.ft
    out = Distinction(None)
    read = [fa, fb] + [f for f in (form_a.pt, form_b.pt) if f is not None]
    blocked = _atoms_ok(read)
    classes = _monitor_classes(ca, cb)
    domains = _domains(read) if blocked is None else {}
    # the trace's variables: the formulas' (ft, and pt, which may read one ft does not)
    names = list(dict.fromkeys(list(form_a.variables)
                               + list(form_b.variables) + list(_kinds(read))))
    count = int(np.prod([len(v) for v in domains.values()], dtype=float)) if domains else 1
    exhausted = False
    if blocked is None and count <= MAX_LETTERS:
        found, exhausted, out.states, out.depth = _search(classes, domains, max_ticks,
                                                          max_states)
        if found is not None:
            return _separated(out, ca, cb, classes, found, names, shortest=True,
                              proof="a breadth-first search of the two requirements' "
                                    "generated monitors (no shorter trace separates them)")
    elif blocked is None:  # too many letters for the search: the symbolic engines take it
        out.notes.append(f"no breadth-first search: {count:,} letters a tick (at most "
                         f"{MAX_LETTERS})")
    return _solve(out, ca, cb, classes, names, blocked, exhausted, budget, fork)


def _separated(out: Distinction, ca, cb, classes, trace: list[dict], names, *,
               shortest: bool, proof: str) -> Distinction:
    """``out`` for a distinguishing ``trace``, judged again by the interval semantics (and,
    for a solver's model, replayed on the monitors)."""
    try:
        va, vb = _replay(classes, trace)
    except KeyError as exc:  # a model without a value the monitor reads
        out.why = f"the solver's trace has no value for {exc} (an uninterpreted atom)"
        return out
    if va == vb:
        out.why = ("the solver's trace does not separate them on the monitors: its "
                   "uninterpreted atoms make it spurious")
        return out
    words = _verdict_words(ca, cb, trace)
    if words is None or (words[0] != "violated") != va or (words[1] != "violated") != vb:
        out.why = (f"the generated monitors ({va}, {vb}) and the interval semantics "
                   f"({words}) disagree on a trace of {len(trace)} ticks: please report it")
        return out
    out.equivalent, out.trace, out.verdicts = False, _columns(trace, names), words
    out.shortest, out.proof = shortest, proof
    return out


def _kinds(formulas) -> dict[str, str]:
    """Variable -> ``"bool"`` or ``"float"`` (witness columns)."""
    out: dict[str, str] = {}
    for f in formulas:
        for n in ir.walk(f):
            if n.op == "ap":
                out.setdefault(ir.name_of(n), "bool")
            elif n.op == "var":
                out[ir.name_of(n)] = "float"
    return out


def _symbolic(ck, fa, fb, kinds) -> tuple[Any, bool]:  # (rows, None or UNKNOWN; exact)
    """The pt monitors' fixed points (:mod:`fretc.check.monitor_sat`, BuDDy), in both
    directions (``ft_A & !ft_B``, ``!ft_A & ft_B``): (rows of the shorter distinguishing
    trace, None when neither direction has one, or UNKNOWN; whether the monitors answered
    both directions, so the trace is a shortest one)."""
    from fretc.check.solver import UNKNOWN
    from fretc.check.witness import finite_trace

    best, exact = None, True
    for query in ([fa, ir.not_(fb)], [ir.not_(fa), fb]):
        rows = finite_trace(ck, query, kinds)
        # (cached: the monitors' answer finite_trace used, None when z3 answered instead)
        exact = exact and ck.monitor_word(query, finite=True) is not None
        if rows == UNKNOWN:
            return UNKNOWN, False
        if rows is not None and (best is None or len(rows) < len(best)):
            best = rows
    return best, exact


def _solve(out: Distinction, ca, cb, classes, names, blocked: str | None, exhausted: bool,
           budget, fork: bool) -> Distinction:
    """The solvers' half (module docstring): the pt monitors' fixed points when the search
    stopped at its bounds, Spot's (or z3's) proof of equivalence, a model to replay, or the
    reason it is unknown."""
    from fretc.check.budget import Budget
    from fretc.check.checker import Checker
    from fretc.check.items import make_item
    from fretc.check.solver import UNKNOWN, SpotWorker
    from fretc.check.witness import finite_trace

    fa, fb = ca.formalization.ft, cb.formalization.ft
    kinds = _kinds([fa, fb] + [f for f in (ca.formalization.pt, cb.formalization.pt) if f])
    query = [ir.or_(ir.and_(fa, ir.not_(fb)), ir.and_(ir.not_(fa), fb))]
    searched = (f"the product of the two generated monitors: all {out.states} reachable "
                "states visited, none separating them" if exhausted else "")
    with SpotWorker(budget or Budget(), fork=fork) as worker:
        items = [make_item(0, ca), make_item(1, cb)]
        if not exhausted and blocked is None:
            rows, exact = _symbolic(Checker(items, worker, engine="bdd"), fa, fb, kinds)
            if rows is not None and rows != UNKNOWN:
                rows = [{k: row[k] for k in names} for row in rows]
                return _separated(out, ca, cb, classes, rows, names, shortest=exact,
                                  proof="a reachability fixed point over the two "
                                        "requirements' pt monitors (BuDDy"
                                        + ("; no shorter trace separates them)" if exact
                                           else ")"))
            if rows is None:
                out.equivalent = True
                out.proof = ("the pt monitors' fixed points (BuDDy): no finite trace of "
                             "ft_A & !ft_B or of !ft_A & ft_B")
        ck = Checker(items, worker)
        engine = "z3" if ck.uses_smt(query) else "Spot"
        answer = finite_trace(ck, query, kinds)
        failures = worker.failures + ck.smt.failures
    if answer is None:
        out.equivalent = True
        out.proof = (f"{engine}: no finite trace satisfies ft_A xor ft_B (FRET's finite-trace "
                     "model)" + "".join(f"; and {x}" for x in (out.proof, searched) if x))
        return out
    if answer == UNKNOWN:
        if out.equivalent or exhausted:
            out.equivalent = True
            out.proof = out.proof or searched
            out.notes.append(f"{engine} could not decide it"
                             + (f": {failures[0]}" if failures else ""))
            return out
        out.why = (blocked or ("the search stopped at its bounds" if out.states else
                               "the letters were too many to search")
                   + f" ({out.states} states, {out.depth} ticks)") + \
            f"; {engine} could not decide it" + \
            (f": {failures[0]}" if failures else "")
        return out
    if exhausted or out.equivalent:
        out.equivalent = None
        out.why = (f"{engine} finds a trace that the monitors do not: please report it")
        return out
    rows = [{k: row[k] for k in names} for row in answer]
    out = _separated(out, ca, cb, classes, rows, names, shortest=False,
                     proof=f"{engine}'s model of ft_A xor ft_B, replayed on the generated "
                           "monitors (not known to be the shortest: "
                           + (blocked or f"the search stopped at its bounds, "
                              f"{out.states} states, {out.depth} ticks") + ")")
    if out.equivalent is None and blocked:
        out.why = f"{blocked}; {out.why}"
    return out
