"""LTL3 monitors by formula progression, for formulas whose bounds are too large for Spot.

Design notes: ARCHITECTURE.md, `compiler/ltl3.py`."""

from __future__ import annotations

import re
from collections.abc import Sequence

from fretc.compiler import ir
from fretc.compiler.ir import FALSE, TRUE, Node, window
from fretc.compiler.printers import to_smv

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
    flat: list[Node] = []
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
_SHAPES: dict[str, str] = {}


def _shape(n: Node) -> str:
    """The text of ``n`` with every bound erased: formulas that differ only in bounds."""
    k = _key(n)
    got = _SHAPES.get(k)
    if got is None:
        got = _SHAPES[k] = _BOUND.sub("[]", k)
    return got


def _combine(rels) -> int | None:
    """Combine the relations of the parts of two formulas built the same monotone way."""
    out = 0
    for r in rels:
        if r is None:
            return None
        if r and out and r != out:
            return None
        out = out or r
    return out


def _relation(x: Node, y: Node) -> int | None:
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
    if op in ("F", "G") and x.lo == 0:  # (x.lo == y.lo: both bounded)
        (_, xhi), (_, yhi) = window(x), window(y)
        if xhi == yhi:
            bound = 0
        elif op == "F":
            bound = -1 if xhi < yhi else 1
        else:
            bound = 1 if xhi < yhi else -1
        return _combine([_relation(x.args[0], y.args[0]), bound])
    return None


def _rebuild(flat: list[Node], op: str) -> Node:
    """Deduplicate, drop what another part makes redundant (``&`` keeps the stronger of two
    comparable parts, ``|`` the weaker), detect ``p`` beside ``!p``, sort, rebuild."""
    by_shape: dict[str, list[Node]] = {}
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


def progress(n: Node, letter: dict[Node, bool], memo: dict[Node, Node]) -> Node:
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
        lo, hi = window(n)
        if lo > 0:
            out = Node(op, a, lo=lo - 1, hi=hi - 1)
        else:
            rest = (ir.F if op == "F" else ir.G)(a[0], 0, hi - 1)
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
#: took 110 s for 4096 states without it). 1280: the largest residual automata of FRET's
#: templates at 12 ticks (``in m upon c ... after 12 ticks``: 151 residuals x 8 letters = 1208
#: progressions) are built; those that would exceed it (``only in m whenever c ... after 12
#: ticks``) give up after about a second instead of five.
MAX_PROGRESSIONS = 1280


def progression_tables(formula: Node, atoms: list[Node],
                       max_progressions: int | None = MAX_PROGRESSIONS
                       ) -> tuple[list, list, int] | None:
    """Deterministic residual automaton of ``formula`` over the letters of ``atoms`` (bit i
    of a letter = value of ``atoms[i]``), as two tables in :mod:`fretc.compiler.automata`'s format:
    ``bad[state][letter]`` (-1 when the residual is FALSE: violated) and
    ``good[state][letter]`` (-1 when it is TRUE: satisfied), and the initial state 0.
    Returns None when there are more than :data:`MAX_ATOMS` atoms or :data:`MAX_STATES`
    residuals, or when it would take more than ``max_progressions`` progressions of a
    residual by a letter (a work bound: large bounds give many large residuals)."""
    if len(atoms) > MAX_ATOMS:
        return None
    init = _normalize(formula)
    states: list[Node] = [init]
    index: dict[str, int] = {_key(init): 0}
    letters = [{atom: bool((bits >> i) & 1) for i, atom in enumerate(atoms)}
               for bits in range(1 << len(atoms))]
    nxt: list[list[Node]] = []
    # progress is a function of (formula, letter): one memo per letter, shared by all the
    # residuals (they share most of their sub-formulas)
    memos: list[dict[Node, Node]] = [{} for _ in letters]
    i = 0
    while i < len(states):
        if max_progressions is not None and (i + 1) * len(letters) > max_progressions:
            return None
        row = []
        for letter, memo in zip(letters, memos):
            r = progress(states[i], letter, memo)
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
