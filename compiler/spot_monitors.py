"""Spot's exact LTL3 monitors of a formula shape as canonical tables.

``bad`` is the deterministic monitor of the formula (no run on exactly its bad prefixes),
``good`` that of its negation (LTL3; Bauer, Leucker & Schallhart, TOSEM 2011), built by
Spot's ``monitor`` translation (:func:`spot_automata`), or for safety and guarantee formulas
by our subset construction and minimization (:mod:`fretc.compiler.dfa`).

Output is canonical, whatever the process did before: the deterministic monitor is
minimized (Spot's ``minimize_monitor`` or :func:`fretc.compiler.dfa.minimize`: the minimal DFA of
a prefix language is unique up to renaming states) and its states renumbered breadth-first
from the initial state, letters in increasing order (:func:`_bfs_tables`); Spot runs with a
fresh BDD dictionary whose variables are registered in atom order.
"""

from __future__ import annotations

import functools
from typing import Any

from fretc.compiler import dfa
from fretc.compiler.pt_step import CodegenError

#: Above this many states, the powerset of Spot's low-effort monitor is not minimized
#: (``minimize_monitor`` takes about a minute on 80,000 states); Spot's reduced translation
#: is used instead.
POWERSET_MAX = 10000#: Options of Spot's ``low`` translation (Spot's ``-x`` options): branching postponement and
#: the expansion of atomic propositions off. On the 696 sentences of FRET's trace vectors and
#: the 288 template keys at 12 ticks this makes the translation 1.4 times faster and the
#: nondeterministic monitors smaller (``only in m upon c ... after 8 ticks``: 1.7 s and 232
#: states by default, 0.33 s and 90 states).
LOW_XARGS = "branch-post=0,exprop=0"

def bdd_code(f: Any, aps: list[str]) -> str:  # f: a spot.formula (Spot has no types)
    """Python code of a Spot Boolean formula ``f`` over the letter ``sub`` (atom ``aps[i]``
    is bit ``i``). Raises :class:`~fretc.compiler.pt_step.CodegenError` for an operator that is not
    Boolean."""
    import spot  # lazy: only automaton construction needs Spot (start-up of --emit ltl)

    k = f.kind()
    if k == spot.op_tt:
        return "True"
    if k == spot.op_ff:
        return "False"
    if k == spot.op_ap:
        return f"(sub >> {aps.index(f.ap_name())} & 1)"
    if k == spot.op_Not:
        return f"(not {bdd_code(f[0], aps)})"
    if k == spot.op_And:
        return "(" + " and ".join(bdd_code(x, aps) for x in f) + ")"
    if k == spot.op_Or:
        return "(" + " or ".join(bdd_code(x, aps) for x in f) + ")"
    raise CodegenError(f"unexpected Boolean operator in an automaton edge: {f}")


@functools.lru_cache(maxsize=1)
def spot_version() -> str:
    """Spot's version (part of the LTL3 cache key): the name of the ``spottl-VERSION``
    distribution's ``.dist-info`` folder beside the ``spot`` package (PyPA "Recording
    installed projects"), read without importing Spot (40 ms of every audit's start-up when
    the automata come from the cache); Spot's own ``spot.version()`` when Spot was installed
    otherwise (Debian, conda), or more than one such folder is there."""
    import importlib.util
    import os

    spec = importlib.util.find_spec("spot")
    places = list(spec.submodule_search_locations or []) if spec is not None else []
    if len(places) == 1:
        site = os.path.dirname(places[0])
        try:
            found = [n for n in os.listdir(site)
                     if n.startswith("spottl-") and n.endswith(".dist-info")]
        except OSError:
            found = []
        if len(found) == 1:
            return found[0][len("spottl-"):-len(".dist-info")]
    import spot  # lazy: only automaton construction needs Spot (start-up of --emit ltl)
    return "spot " + spot.version()


def spot_automata(text: str, n_atoms: int, max_states: int, table_max_aps: int) -> dict:
    """The exact LTL3 monitors of the Spot formula ``text`` over atoms ``a0`` ..
    ``a{n_atoms-1}`` as :func:`fretc.compiler.automata.shape_automata`'s data ``{"bad": aut, "good": aut}``.

    ``bad`` is Spot's monitor of ``text``, ``good`` of its negation (:func:`_spot_monitor`),
    except that one translation is skipped when ``text`` is a safety (or guarantee)
    property, as decided by Spot's syntactic classes (``is_syntactic_safety``,
    ``is_syntactic_guarantee``: sound; Spot unrolls ``F[0..n]`` and ``G[0..n]`` into ``X``,
    so bounded operators keep a formula safety):

    - ``text`` itself syntactically safety: ``bad`` from Spot's terminal automaton of the
      negation (:func:`_terminal_monitor`: on the trace vectors' shapes 10 to 40 times
      faster to translate than the monitor of the safety formula);
    - safety only after Spot's basic rewriting (``tl_simplifier``, ``basics`` only:
      language-preserving; FRET writes "p W q" as "(p U q) | G p"): ``bad`` translated as
      before (the negation's automaton can be much larger there: 1.2 s against 0.01 s for
      ``... upon c ... within 9 ticks`` under an ``only after`` scope);

    then ``good`` is derived from ``bad`` by :func:`fretc.compiler.dfa.safety_complement`,
    minimized and renamed breadth-first. Guarantee formulas symmetrically (the negation is
    safety, ``good`` comes first). The tables are those the translations give (the minimal
    DFA of a prefix language is unique): ``tests/compiler/test_ltl3_exact.py`` compares
    them with Spot's own construction, ``tests/compiler/test_ltl3_derived.py`` each
    derivation with the translation it replaces. On the 681 shapes of FRET's trace vectors:
    494 syntactically safety or guarantee, 161 more after rewriting, 26 neither."""
    import spot  # lazy: only automaton construction needs Spot (start-up of --emit ltl)

    f = spot.formula(text)
    first, terminal = _safety_side(f), True
    if first is None:
        first, terminal = _safety_side(spot.tl_simplifier(
            spot.tl_simplifier_options(True, False, False)).simplify(f)), False
    got: dict[str, dict | None] = {"bad": None, "good": None}
    if first is not None:
        if terminal and n_atoms <= table_max_aps:
            # the guarantee side: the negation of the safety one
            got[first] = _terminal_monitor(f if first == "good" else spot.formula.Not(f),
                                           n_atoms, max_states)
        if got[first] is None:
            got[first] = _spot_monitor(text, first == "good", n_atoms, max_states,
                                       table_max_aps)
        other = "good" if first == "bad" else "bad"
        got[other] = _safety_complement_data(got[first], max_states)
        if got[other] is not None:
            return got
    for side in ("bad", "good"):
        if got[side] is None:
            got[side] = _spot_monitor(text, side == "good", n_atoms, max_states,
                                      table_max_aps)
    return got


def _safety_side(f) -> str | None:
    """"bad" when the Spot formula ``f`` is a syntactic safety formula (its ``bad`` monitor
    determines the other), "good" when a syntactic guarantee one (its negation is safety),
    else None."""
    return "bad" if f.is_syntactic_safety() else "good" if f.is_syntactic_guarantee() \
        else None


#: The subset construction of :func:`_terminal_monitor` gives up beyond this many sets (the
#: caller then translates the safety formula itself).
TERMINAL_MAX_SUBSETS = 20000


def _terminal_monitor(h, n_atoms: int, max_states: int) -> dict | None:
    """The LTL3 monitor of ``not h`` (a safety property) from Spot's automaton of the
    guarantee formula ``h`` (a ``spot.formula``), as :func:`_spot_monitor`'s data.

    Spot translates a guarantee formula quickly into a terminal automaton (10 to 40 times
    faster than the monitor of its safety negation on the 696 sentences of FRET's trace
    vectors); :func:`fretc.compiler.dfa.guarantee_bad_prefixes` turns it into a deterministic
    automaton of the prefixes that are not good for ``h`` (= not bad for ``not h``), made
    minimal and renamed breadth-first: the table of Spot's monitor of ``not h``, since the
    minimal DFA of a prefix language is unique. None (the caller translates ``not h``) when
    Spot's automaton is not weak with complete accepting SCCs, or has more than
    :data:`fretc.compiler.dfa.SUBSET_MAX_CLASSES` letter classes, or the subset construction
    exceeds :data:`TERMINAL_MAX_SUBSETS` sets, or the monitor more than ``max_states``
    states."""
    import spot  # lazy: only automaton construction needs Spot (start-up of --emit ltl)

    aut = spot.translate(h, "low", xargs=LOW_XARGS, dict=spot.make_bdd_dict())
    if not spot.is_weak_automaton(aut):
        return None
    got = _letter_classes(aut, n_atoms)
    if got is None:
        return None
    succ, class_of, n_classes = got
    si = spot.scc_info(aut)
    target = 0
    for scc in range(si.scc_count()):
        if not si.is_accepting_scc(scc):
            continue
        inside = 0
        for s in si.states_of(scc):
            inside |= 1 << s
        for s in si.states_of(scc):  # complete: every letter stays in the SCC
            if not all(m & inside for m in succ[s]):
                return None
        target |= inside
    rows = dfa.guarantee_bad_prefixes(succ, aut.get_init_state_number(), n_classes, target,
                                      TERMINAL_MAX_SUBSETS)
    if rows is None:
        return None
    empty = all(d < 0 for d in rows[0]) and len(rows) == 1
    init, rows = dfa.minimize(rows)
    rows = [[row[c] for c in class_of] for row in rows]
    init, rows = _bfs_tables(init, rows)
    if len(rows) > max_states:
        return None
    complete = not empty and all(x >= 0 for row in rows for x in row)
    return {"initial": init, "table": rows, "chains": None, "empty": empty,
            "complete": complete, "states": len(rows)}


def _safety_complement_data(data: dict | None, max_states: int) -> dict | None:
    """The data of the monitor of ``not g`` from ``data``, the monitor of a safety property
    ``g`` (:func:`fretc.compiler.dfa.safety_complement`, minimized, renamed breadth-first); None
    when ``data`` is None or has no table (the caller translates instead) or the result
    has more than ``max_states`` states."""
    if data is None or data["table"] is None:
        return None
    # letters whose columns agree lead everywhere to the same states: one column per class
    number: dict[tuple, int] = {}
    class_of = [number.setdefault(col, len(number)) for col in zip(*data["table"])]
    rows = dfa.safety_complement([list(col) for col in zip(*number)] if number else [[]])
    empty = all(d < 0 for d in rows[0]) and len(rows) == 1
    init, rows = dfa.minimize(rows)
    init, rows = _bfs_tables(init, [[row[c] for c in class_of] for row in rows])
    if len(rows) > max_states:
        return None
    complete = not empty and all(x >= 0 for row in rows for x in row)
    return {"initial": init, "table": rows, "chains": None, "empty": empty,
            "complete": complete, "states": len(rows)}


def _spot_monitor(text: str, negate: bool, n_atoms: int, max_states: int,
                  table_max_aps: int) -> dict | None:
    """Spot's minimal deterministic monitor of ``text`` (or of its negation) as data.

    Spot's translator in ``monitor`` mode at the ``low`` optimization level (without
    branching postponement and the expansion of propositions: :data:`LOW_XARGS`) gives a
    nondeterministic monitor quickly (``translate(f, 'monitor', 'det')`` takes seconds to
    minutes on 12-tick bounds); its powerset is a deterministic monitor of the same prefix
    language, which :mod:`fretc.compiler.dfa` (or Spot's ``minimize_monitor``) makes minimal.
    The minimal monitor does not depend on which nondeterministic monitor it comes from, so
    the translator's options change the time, never the table."""
    import spot  # lazy: only automaton construction needs Spot (start-up of --emit ltl)

    d = spot.make_bdd_dict()
    f = spot.formula(text)
    if negate:
        f = spot.formula.Not(f)
    aut = spot.translate(f, "monitor", "low", xargs=LOW_XARGS, dict=d)
    if n_atoms <= table_max_aps:
        got = _table_monitor(aut, n_atoms)
        if got is not None:
            return got if got["states"] <= max_states else None
    if not aut.is_deterministic():
        det = spot.tgba_powerset(aut)
        if det.num_states() > POWERSET_MAX:
            # the powerset of the unreduced monitor is too large to minimize quickly: let
            # Spot reduce the formula and the automaton first (high level, without its
            # implication-based formula rewriting, which is slow on long bounds)
            det = spot.translate(f, "monitor", "det", xargs="tls-impl=0", dict=d)
        aut = det
    aut = spot.minimize_monitor(aut)
    if aut.num_states() > max_states:
        return None
    empty = bool(aut.is_empty())
    names = [f"a{i}" for i in range(n_atoms)]
    if n_atoms <= table_max_aps:
        init, rows = _bfs_tables(aut.get_init_state_number(), letter_rows(aut, n_atoms))
        complete = not empty and all(x >= 0 for row in rows for x in row)
        return {"initial": init, "table": rows, "chains": None, "empty": empty,
                "complete": complete, "states": len(rows)}
    for name in names:
        aut.register_ap(name)  # present ones keep their number
    edges = []
    for s in range(aut.num_states()):
        out = [(bdd_code(spot.bdd_to_formula(e.cond, d), names), e.dst) for e in aut.out(s)]
        edges.append(sorted(out))
    init, chains = _bfs_chains(aut.get_init_state_number(), edges)
    return {"initial": init, "table": None, "chains": chains, "empty": empty,
            "complete": False, "states": len(chains)}


def letter_rows(aut: Any, n_atoms: int) -> list[list[int]]:  # aut: a spot.twa_graph
    """The transition table of a deterministic Spot automaton over the atoms ``a0`` ..
    ``a{n_atoms-1}``: ``rows[state][letter]`` is the successor state (-1: no edge), a letter
    being the bit vector of the atoms' values (bit i = ``a{i}``), ``2**n_atoms`` per row.
    States keep Spot's numbers. Registers the atoms on ``aut`` (present ones keep their
    number)."""
    names = [f"a{i}" for i in range(n_atoms)]
    var = {name: aut.register_ap(name) for name in names}
    width = 1 << n_atoms
    memo: dict = {}
    rows = []
    for s in range(aut.num_states()):
        row = [-1] * width
        for e in aut.out(s):
            for letter in _cached_letters(memo, e.cond, var, names, width):
                row[letter] = e.dst
        rows.append(row)
    return rows


def _letter_classes(aut, n_atoms: int):
    """The letter classes of a Spot automaton ``aut`` over ``a0`` .. ``a{n_atoms-1}``:
    letters satisfying the same edge conditions lead everywhere to the same states.
    Returns ``(succ, class_of, n_classes)``, ``succ[s][c]`` the bit mask of the successors
    of state ``s`` on class ``c`` and ``class_of[letter]`` the class of a letter; None
    beyond :data:`fretc.compiler.dfa.SUBSET_MAX_CLASSES` classes."""
    names = [f"a{i}" for i in range(n_atoms)]
    var = {name: aut.register_ap(name) for name in names}
    width = 1 << n_atoms
    memo: dict = {}
    edges = [[(_cached_letters(memo, e.cond, var, names, width), e.dst) for e in aut.out(s)]
             for s in range(aut.num_states())]
    signature = [0] * width
    for bit, letters in enumerate(memo.values()):
        for letter in letters:
            signature[letter] |= 1 << bit
    number: dict[int, int] = {}
    class_of = [number.setdefault(sig, len(number)) for sig in signature]
    if len(number) > dfa.SUBSET_MAX_CLASSES:
        return None
    classes_of: dict[int, list[int]] = {}  # id of a letter list -> the classes it covers
    succ = [[0] * len(number) for _ in edges]
    for s, out in enumerate(edges):
        for letters, dst in out:
            covered = classes_of.get(id(letters))
            if covered is None:
                covered = classes_of[id(letters)] = sorted({class_of[x] for x in letters})
            for c in covered:
                succ[s][c] |= 1 << dst
    return succ, class_of, len(number)


def _table_monitor(aut, n_atoms: int) -> dict | None:
    """The minimal deterministic monitor of Spot's nondeterministic monitor ``aut`` by
    :mod:`fretc.compiler.dfa` (the same automaton as Spot's powerset and ``minimize_monitor``,
    faster), as :func:`_spot_monitor`'s data; None when there are more than
    :data:`fretc.compiler.dfa.SUBSET_MAX_CLASSES` letter classes or the subset construction exceeds
    :data:`fretc.compiler.dfa.SUBSET_MAX_STATES`.

    Letters that satisfy the same edge conditions of ``aut`` lead everywhere to the same
    states, so the construction runs over these classes (``rr | p0 | ... | p9`` is one class
    boundary, not 2**11 letters) and the rows are expanded to letters at the end."""
    got = _letter_classes(aut, n_atoms)
    if got is None:
        return None
    succ, class_of, n_classes = got
    rows = dfa.determinize(succ, aut.get_init_state_number(), n_classes)
    if rows is None:
        return None
    init, rows = dfa.minimize(rows)
    rows = [[row[c] for c in class_of] for row in rows]
    init, rows = _bfs_tables(init, rows)
    empty = bool(aut.is_empty())
    complete = not empty and all(x >= 0 for row in rows for x in row)
    return {"initial": init, "table": rows, "chains": None, "empty": empty,
            "complete": complete, "states": len(rows)}


def _cached_letters(memo: dict, cond, var: dict[str, int], names: list[str],
                    width: int) -> list[int]:
    """:func:`_letters` memoized by the BDD's id in ``memo`` (edges of an automaton share few
    distinct conditions; over 10 atoms each walk costs 1024 x 10 restrictions)."""
    key = cond.id()
    got = memo.get(key)
    if got is None:
        got = memo[key] = _letters(cond, var, names, width)
    return got


def _letters(cond, var: dict[str, int], names: list[str], width: int) -> list[int]:
    """The letters (bit ``i`` = value of ``names[i]``), in increasing order, satisfying the
    BDD ``cond`` (a condition over other variables satisfies none): ``cond`` restricted atom
    by atom, depth first, each partial restriction shared by the letters below it, a branch
    cut where it becomes FALSE and completed at once where it becomes TRUE."""
    import buddy  # lazy: Spot's BDD library, with Spot (start-up of --emit ltl)

    if cond == buddy.bddtrue:
        return list(range(width))
    n = len(names)
    pos = [buddy.bdd_ithvar(var[x]) for x in names]
    neg = [buddy.bdd_nithvar(var[x]) for x in names]
    out: list[int] = []
    stack = [(cond, 0, 0)]
    while stack:
        c, i, letter = stack.pop()
        if c == buddy.bddfalse:
            continue
        if c == buddy.bddtrue:
            out.extend(letter | (k << i) for k in range(1 << (n - i)))
            continue
        if i == n:
            continue
        stack.append((buddy.bdd_restrict(c, pos[i]), i + 1, letter | 1 << i))
        stack.append((buddy.bdd_restrict(c, neg[i]), i + 1, letter))
    out.sort()
    return out


def _bfs_tables(init: int, rows: list[list[int]]) -> tuple[int, list[list[int]]]:
    """Renumber states breadth-first from ``init`` (letters in increasing order), dropping
    unreachable ones: the initial state becomes 0."""
    order = {init: 0}
    queue = [init]
    i = 0
    while i < len(queue):
        for dst in rows[queue[i]]:
            if dst >= 0 and dst not in order:
                order[dst] = len(queue)
                queue.append(dst)
        i += 1
    return 0, [[order[d] if d >= 0 else -1 for d in rows[s]] for s in queue]


def _bfs_chains(init: int, edges) -> tuple[int, list]:
    order = {init: 0}
    queue = [init]
    i = 0
    while i < len(queue):
        for _, dst in edges[queue[i]]:
            if dst not in order:
                order[dst] = len(queue)
                queue.append(dst)
        i += 1
    return 0, [[[cond, order[d]] for cond, d in edges[s]] for s in queue]


