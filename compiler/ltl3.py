"""LTL3 monitors by formula progression, for formulas whose bounds are too large for Spot.

Spot determinizes bounded operators by unrolling ``F[0,n]`` into n nested ``X``, which grows
exponentially with n (see :data:`compiler.codegen.MAX_LTL3_BOUND`). Formula progression
(Bacchus & Kabanza, "Planning for temporally extended goals", AMAI 1998; used for LTL3 by
Bauer, Leucker & Schallhart, TOSEM 2011, section 4) keeps bounds symbolic instead: reading one
letter turns a formula into its *residual*, the formula the rest of the word must satisfy
(``F[0,k] q`` becomes ``q | F[0,k-1] q``). Residuals are normalized (conjunctions and
disjunctions flattened, sorted and deduplicated; ``F[0,a] x & F[0,b] x`` is ``F[0,min] x``;
the dual rules for ``|`` and ``G``), so for FRET's formulas their number stays small, and the
reachable residuals over all letters form a deterministic automaton built ahead of time.

A residual that normalizes to FALSE means no continuation satisfies the formula (violated);
TRUE means every continuation does (satisfied). The verdicts are therefore sound, never
contradicted; they can come later than the exact LTL3 verdict when a residual is unsatisfiable
(or valid) without normalizing to FALSE (TRUE).
"""

from __future__ import annotations

import re
from typing import Dict, List, Optional, Sequence, Tuple

from . import ir
from .ir import FALSE, TRUE, Node
from .printers import to_smv

#: Give up beyond this many residual states (the module then has no LTL3 automaton).
MAX_STATES = 4096
#: Letters are enumerated: at most this many atomic propositions.
MAX_ATOMS = 10


def _key(n: Node) -> str:
    return to_smv(n)


def _junction(items: Sequence[Node], op: str) -> Node:
    """Normalized ``&`` (``op == "&"``) or ``|`` of ``items``: flattened, the neutral constant
    dropped, the absorbing one returned, then :func:`_rebuild` (sorted, deduplicated, the
    redundant of two comparable parts dropped)."""
    neutral, absorbing = ("true", "false") if op == "&" else ("false", "true")
    flat: List[Node] = []
    stack = list(items)
    while stack:
        n = stack.pop()
        if n.op == op:
            stack.extend(n.args)
        elif n.op == absorbing:
            return FALSE if op == "&" else TRUE
        elif n.op != neutral:
            flat.append(n)
    return _rebuild(flat, op)


def _conj(items: Sequence[Node]) -> Node:
    """Normalized conjunction; ``F[0,a] x & F[0,b] x`` keeps the smaller window."""
    return _junction(items, "&")


def _disj(items: Sequence[Node]) -> Node:
    """Normalized disjunction (the dual of :func:`_conj`)."""
    return _junction(items, "|")


_BOUND = re.compile(r"\[\d+,\d+\]")
_SHAPES: Dict[str, str] = {}


def _shape(n: Node) -> str:
    """The text of ``n`` with every bound erased: formulas that differ only in bounds."""
    k = _key(n)
    got = _SHAPES.get(k)
    if got is None:
        got = _SHAPES[k] = _BOUND.sub("[]", k)
    return got


def _combine(rels) -> Optional[int]:
    """Combine the relations of the parts of two formulas built the same monotone way."""
    out = 0
    for r in rels:
        if r is None:
            return None
        if r and out and r != out:
            return None
        out = out or r
    return out


def _relation(x: Node, y: Node) -> Optional[int]:
    """-1 when ``x`` implies ``y``, +1 when ``y`` implies ``x``, 0 when they are the same,
    None when unknown. Sound for formulas of the same shape: ``F[0,a]`` implies ``F[0,b]``
    for a <= b, ``G[0,b]`` implies ``G[0,a]``, and the operators are monotone (``!`` and the
    left of ``->`` reverse)."""
    if x is y or _key(x) == _key(y):
        return 0
    if x.op != y.op or x.name != y.name or len(x.args) != len(y.args) or x.lo != y.lo:
        return None
    op = x.op
    if op == "!":
        r = _relation(x.args[0], y.args[0])
        return None if r is None else -r
    if op == "->":
        r = _relation(x.args[0], y.args[0])
        return _combine([None if r is None else -r, _relation(x.args[1], y.args[1])])
    if op in ("&", "|", "U", "V", "X") or (op in ("F", "G") and x.hi is None):
        return _combine(_relation(a, b) for a, b in zip(x.args, y.args))
    if op in ("F", "G") and x.lo == 0:
        if x.hi == y.hi:
            bound = 0
        elif op == "F":
            bound = -1 if x.hi < y.hi else 1
        else:
            bound = 1 if x.hi < y.hi else -1
        return _combine([_relation(x.args[0], y.args[0]), bound])
    return None


def _rebuild(flat: List[Node], op: str) -> Node:
    """Deduplicate, drop what another part makes redundant (``&`` keeps the stronger of two
    comparable parts, ``|`` the weaker), detect ``p`` beside ``!p``, sort, rebuild."""
    by_shape: Dict[str, List[Node]] = {}
    for n in flat:
        group = by_shape.setdefault(_shape(n), [])
        keep = True
        for i, old in enumerate(group):
            r = _relation(n, old)
            if r is None:
                continue
            if r == 0:
                keep = False
                break
            # r == -1: n implies old
            n_wins = (r == -1) == (op == "&")
            if n_wins:
                group[i] = n
            keep = False
            break
        if keep:
            group.append(n)
    parts = [n for group in by_shape.values() for n in group]
    keys = {_key(p) for p in parts}
    for p in parts:
        if p.op == "!" and _key(p.args[0]) in keys:
            return FALSE if op == "&" else TRUE
    parts.sort(key=lambda p: (_shape(p), _key(p)))
    if not parts:
        return TRUE if op == "&" else FALSE
    out = parts[0]
    for p in parts[1:]:
        out = Node(op, (out, p))
    return out


def progress(n: Node, letter: Dict[Node, bool], memo: Dict[Node, Node]) -> Node:
    """The residual of ``n`` after one letter (``letter`` maps each atom to its value)."""
    got = memo.get(n)
    if got is not None:
        return got
    op = n.op
    a = n.args
    if n in letter:
        out = TRUE if letter[n] else FALSE
    elif op in ("true", "false"):
        out = n
    elif op == "!":
        out = ir.not_(progress(a[0], letter, memo))
    elif op == "&":
        out = _conj([progress(a[0], letter, memo), progress(a[1], letter, memo)])
    elif op == "|":
        out = _disj([progress(a[0], letter, memo), progress(a[1], letter, memo)])
    elif op == "->":
        out = _disj([ir.not_(progress(a[0], letter, memo)), progress(a[1], letter, memo)])
    elif op in ("<->", "xor"):
        x, y = progress(a[0], letter, memo), progress(a[1], letter, memo)
        same = _disj([_conj([x, y]), _conj([ir.not_(x), ir.not_(y)])])
        out = same if op == "<->" else ir.not_(same)
    elif op == "X":
        out = a[0]
    elif op in ("F", "G") and n.hi is None:
        now = progress(a[0], letter, memo)
        out = _disj([now, n]) if op == "F" else _conj([now, n])
    elif op in ("F", "G"):
        if n.lo > 0:
            out = Node(op, a, lo=n.lo - 1, hi=n.hi - 1)
        else:
            rest = (ir.F if op == "F" else ir.G)(a[0], 0, n.hi - 1)
            now = progress(a[0], letter, memo)
            out = _disj([now, rest]) if op == "F" else _conj([now, rest])
    elif op == "U":
        out = _disj([progress(a[1], letter, memo),
                     _conj([progress(a[0], letter, memo), n])])
    elif op == "V":
        out = _conj([progress(a[1], letter, memo),
                     _disj([progress(a[0], letter, memo), n])])
    else:
        raise ValueError(f"cannot progress IR node {op!r} (not an atom of the letter?)")
    memo[n] = out
    return out


def _normalize(n: Node) -> Node:
    """Bring a formula to the normal form residuals use (so the initial state compares
    equal to residuals that come back to it)."""
    if n.op == "&":
        return _conj([_normalize(x) for x in n.args])
    if n.op == "|":
        return _disj([_normalize(x) for x in n.args])
    if n.args and n.op not in ("cmp", "call", "past", "future"):
        return ir.rebuild(n, tuple(_normalize(x) for x in n.args))
    return n


#: Work bound of :func:`progression_tables` (residual states x letters): the residuals of a
#: bound in the thousands are large (fuzzing: ``before q whenever c ... after 999999 ticks``
#: took 110 s for 4096 states without it).
MAX_PROGRESSIONS = 4096


def progression_tables(formula: Node, atoms: List[Node],
                       max_progressions: Optional[int] = MAX_PROGRESSIONS
                       ) -> Optional[Tuple[list, list, int]]:
    """Deterministic residual automaton of ``formula`` over the letters of ``atoms`` (bit i
    of a letter = value of ``atoms[i]``), as two tables in :mod:`compiler.codegen`'s format:
    ``bad[state][letter]`` (-1 when the residual is FALSE: violated) and
    ``good[state][letter]`` (-1 when it is TRUE: satisfied), and the initial state 0.
    Returns None when there are more than :data:`MAX_ATOMS` atoms or :data:`MAX_STATES`
    residuals, or when it would take more than ``max_progressions`` progressions of a
    residual by a letter (a work bound: large bounds give many large residuals)."""
    if len(atoms) > MAX_ATOMS:
        return None
    init = _normalize(formula)
    states: List[Node] = [init]
    index: Dict[str, int] = {_key(init): 0}
    letters = [{atom: bool((bits >> i) & 1) for i, atom in enumerate(atoms)}
               for bits in range(1 << len(atoms))]
    nxt: List[List[Node]] = []
    i = 0
    while i < len(states):
        if max_progressions is not None and (i + 1) * len(letters) > max_progressions:
            return None
        row = []
        for letter in letters:
            r = progress(states[i], letter, {})
            if r.op not in ("true", "false"):
                k = _key(r)
                if k not in index:
                    if len(states) >= MAX_STATES:
                        return None
                    index[k] = len(states)
                    states.append(r)
            row.append(r)
        nxt.append(row)
        i += 1
    n = len(states)
    true_sink, false_sink = n, n + 1  # absorbing states after a definitive verdict
    bad = []
    good = []
    for row in nxt:
        bad.append([-1 if r.op == "false" else true_sink if r.op == "true" else index[_key(r)]
                    for r in row])
        good.append([-1 if r.op == "true" else false_sink if r.op == "false"
                     else index[_key(r)] for r in row])
    width = 1 << len(atoms)
    for table in (bad, good):
        table.append([true_sink] * width)
        table.append([false_sink] * width)
    return bad, good, 0


# --------------------------------------------------------------------------- by shape
# The LTL3 automata of a requirement depend only on the *shape* of ft_inf: the formula with
# its atoms (variables, comparisons, calls, past-time sub-formulas, FTP) renamed a0, a1, ...
# in order of first appearance. Requirements of the same template, bounds and atom pattern
# share one construction, memoized in the process and stored in fretc's disk cache
# (fretish.cache, sub-folder "ltl3"), keyed by the shape, Spot's version and the text of
# this module (so a change of the construction can never meet an old entry).
#
# Output is canonical, whatever the cache holds or the process did before: the
# deterministic monitor is minimized (Spot's minimize_monitor: the minimal DFA of a prefix
# language is unique up to renaming states) and its states renumbered breadth-first from the
# initial state, letters in increasing order; Spot runs with a fresh BDD dictionary whose
# variables are registered in atom order.

#: Above this many states, the powerset of Spot's low-effort monitor is not minimized
#: (``minimize_monitor`` takes about a minute on 80,000 states); Spot's reduced translation
#: is used instead.
POWERSET_MAX = 10000
#: Atom operators: each distinct one becomes an atomic proposition of the automata.
ATOM_OPS = ("ap", "cmp", "call", "past", "future", "FTP", "LAST")

_SHAPE_MEMO: Dict[str, dict] = {}
_SOURCE_KEY: Optional[str] = None


def canonical_shape(formula: Node) -> Tuple[Node, List[Node]]:
    """``formula`` with its atoms renamed ``a0``, ``a1``, ... (in order of first appearance in
    a pre-order walk) and the list of the original atoms, atom ``i`` named ``a{i}``."""
    atoms: Dict[Node, Node] = {}
    for n in ir.walk(formula):
        if n.op in ATOM_OPS and n not in atoms:
            atoms[n] = ir.ap(f"a{len(atoms)}")
    memo: Dict[Node, Node] = {}

    def go(n: Node) -> Node:
        got = memo.get(n)
        if got is None:
            got = atoms.get(n)
            if got is None:
                got = Node(n.op, tuple(go(a) for a in n.args), n.name, n.lo, n.hi) \
                    if n.args else n
            memo[n] = got
        return got

    return go(formula), list(atoms)


def _source_key() -> str:
    global _SOURCE_KEY
    if _SOURCE_KEY is None:
        from pathlib import Path

        from fretish.cache import key_of
        _SOURCE_KEY = key_of(Path(__file__).read_text(encoding="utf-8"))
    return _SOURCE_KEY


def shape_automata(kind: str, shape: Node, n_atoms: int, max_states: int,
                   table_max_aps: int) -> dict:
    """The LTL3 automata of a canonical ``shape`` (:func:`canonical_shape`) over ``n_atoms``
    atoms, as plain data: ``{"bad": aut, "good": aut}`` where each ``aut`` is None (too
    large) or ``{"initial", "table", "chains", "empty", "complete", "states"}`` (``table``
    indexed ``[state][letter]``, letter bit ``i`` = atom ``a{i}``, -1 = no transition;
    ``chains`` instead when there are more than ``table_max_aps`` atoms: per state a list of
    (Python condition over ``sub``, destination)).

    ``kind`` is ``"spot"`` (Spot's monitors of ft_inf and of its negation: exact LTL3) or
    ``"progression"`` (:func:`progression_tables`: sound, bounds kept symbolic). Memoized
    in the process and in the disk cache; the result depends only on the arguments, Spot's
    version and this module's text."""
    from fretish import cache

    from .printers import to_spot

    text = to_spot(shape)
    spot_version = _spot_version() if kind == "spot" else "-"
    key = cache.key_of("ltl3-shape-1", kind, text, str(n_atoms), str(max_states),
                       str(table_max_aps), spot_version, _source_key())
    got = _SHAPE_MEMO.get(key)
    if got is not None:
        return got
    name = f"{key[:40]}.json"
    raw = cache.read_bytes("ltl3", name)
    if raw is not None:
        import json
        try:
            got = json.loads(raw)
            if got.get("shape") != text:  # a hash collision or a foreign file
                got = None
        except ValueError:
            got = None
    if got is None:
        if kind == "spot":
            got = {"bad": _spot_monitor(text, False, n_atoms, max_states, table_max_aps),
                   "good": _spot_monitor(text, True, n_atoms, max_states, table_max_aps)}
        else:
            got = _progression_data(shape, n_atoms)
        got["shape"] = text
        import json
        cache.write_bytes("ltl3", name, json.dumps(got, separators=(",", ":")).encode())
    _SHAPE_MEMO[key] = got
    return got


def _spot_version() -> str:
    import spot
    return spot.version()


def _spot_monitor(text: str, negate: bool, n_atoms: int, max_states: int,
                  table_max_aps: int) -> Optional[dict]:
    """Spot's minimal deterministic monitor of ``text`` (or of its negation) as data.

    Spot's translator in ``monitor`` mode at the ``low`` optimization level gives a
    nondeterministic monitor quickly (``translate(f, 'monitor', 'det')`` takes seconds to
    minutes on 12-tick bounds); its powerset is a deterministic monitor of the same prefix
    language, which ``minimize_monitor`` makes minimal."""
    import spot

    d = spot.make_bdd_dict()
    f = spot.formula(text)
    if negate:
        f = spot.formula.Not(f)
    aut = spot.translate(f, "monitor", "low", dict=d)
    from . import dfa  # numpy: not imported by `fretc FILE --emit ltl`

    if n_atoms <= min(dfa.SUBSET_MAX_APS, table_max_aps):
        got = _table_monitor(aut, n_atoms, max_states)
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
    var = {}
    for name in names:
        var[name] = aut.register_ap(name)  # present ones keep their number
    if n_atoms <= table_max_aps:
        width = 1 << n_atoms
        memo: dict = {}
        rows = []
        for s in range(aut.num_states()):
            row = [-1] * width
            for e in aut.out(s):
                for letter in _cached_letters(memo, e.cond, var, names, width):
                    row[letter] = e.dst
            rows.append(row)
        init, rows = _bfs_tables(aut.get_init_state_number(), rows)
        complete = not empty and all(x >= 0 for row in rows for x in row)
        return {"initial": init, "table": rows, "chains": None, "empty": empty,
                "complete": complete, "states": len(rows)}
    from .codegen import _bdd_code

    edges = []
    for s in range(aut.num_states()):
        out = [(_bdd_code(spot.bdd_to_formula(e.cond, d), names), e.dst) for e in aut.out(s)]
        edges.append(sorted(out))
    init, chains = _bfs_chains(aut.get_init_state_number(), edges)
    return {"initial": init, "table": None, "chains": chains, "empty": empty,
            "complete": False, "states": len(chains)}


def _table_monitor(aut, n_atoms: int, max_states: int) -> dict | None:
    """The minimal deterministic monitor of Spot's nondeterministic monitor ``aut`` by
    :mod:`compiler.dfa` (the same automaton as Spot's powerset and ``minimize_monitor``,
    faster on small alphabets), as :func:`_spot_monitor`'s data; None when the subset
    construction exceeds :data:`compiler.dfa.SUBSET_MAX_STATES`."""
    from . import dfa  # numpy: not imported by `fretc FILE --emit ltl`

    names = [f"a{i}" for i in range(n_atoms)]
    var = {name: aut.register_ap(name) for name in names}
    width = 1 << n_atoms
    memo: dict = {}
    succ = [[0] * width for _ in range(aut.num_states())]
    for s in range(aut.num_states()):
        for e in aut.out(s):
            for letter in _cached_letters(memo, e.cond, var, names, width):
                succ[s][letter] |= 1 << e.dst
    rows = dfa.determinize(succ, aut.get_init_state_number(), width)
    if rows is None:
        return None
    init, rows = _bfs_tables(*dfa.minimize(rows))
    empty = bool(aut.is_empty())
    complete = not empty and all(x >= 0 for row in rows for x in row)
    return {"initial": init, "table": rows, "chains": None, "empty": empty,
            "complete": complete, "states": len(rows)}


def _cached_letters(memo: dict, cond, var: Dict[str, int], names: List[str],
                    width: int) -> List[int]:
    """:func:`_letters` memoized by the BDD's id in ``memo`` (edges of an automaton share few
    distinct conditions; over 10 atoms each walk costs 1024 x 10 restrictions)."""
    key = cond.id()
    got = memo.get(key)
    if got is None:
        got = memo[key] = _letters(cond, var, names, width)
    return got


def _letters(cond, var: Dict[str, int], names: List[str], width: int) -> List[int]:
    """The letters (bit ``i`` = value of ``names[i]``) satisfying the BDD ``cond``: one walk
    of the BDD per letter, restricted variable by variable."""
    import buddy

    if cond == buddy.bddtrue:
        return list(range(width))
    out = []
    pos = [buddy.bdd_ithvar(var[n]) for n in names]
    neg = [buddy.bdd_nithvar(var[n]) for n in names]
    for letter in range(width):
        c = cond
        for i in range(len(names)):
            c = buddy.bdd_restrict(c, pos[i] if (letter >> i) & 1 else neg[i])
            if c == buddy.bddfalse:
                break
        if c == buddy.bddtrue:
            out.append(letter)
    return out


def _bfs_tables(init: int, rows: List[List[int]]) -> Tuple[int, List[List[int]]]:
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


def _bfs_chains(init: int, edges) -> Tuple[int, list]:
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


def _progression_data(shape: Node, n_atoms: int) -> dict:
    atoms = [ir.ap(f"a{i}") for i in range(n_atoms)]
    tables = progression_tables(shape, atoms)
    if tables is None:
        return {"bad": None, "good": None}
    bad, good, init = tables
    return {"bad": {"initial": init, "table": bad, "chains": None,
                    "empty": shape.op == "false", "complete": False,
                    "states": len(bad) - 2},
            "good": {"initial": init, "table": good, "chains": None,
                     "empty": shape.op == "true", "complete": False,
                     "states": len(good) - 2}}
