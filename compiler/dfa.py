"""Deterministic monitors from small nondeterministic ones: subset construction and minimization
over explicit letter tables.

An LTL3 monitor (Bauer, Leucker, Schallhart, "Runtime Verification for LTL and TLTL", TOSEM
2011) is a deterministic automaton whose missing transitions reject: its language is a prefix
language. For alphabets of few letter classes (up to :data:`SUBSET_MAX_CLASSES`) the
powerset of Spot's nondeterministic monitor and its minimization are done here on letter
tables:

Design notes: ARCHITECTURE.md, `compiler/dfa.py`."""

from __future__ import annotations

from operator import or_

import numpy as np

#: The construction here is used for at most this many letter classes (letters that satisfy
#: the same edge conditions); Spot's symbolic powerset is faster beyond.
SUBSET_MAX_CLASSES = 64
#: Above this many states the subset construction gives up (the caller falls back to Spot).
SUBSET_MAX_STATES = 200_000
#: The simulation preorder is computed for NFAs of at most this many states (its cost grows
#: with the square of the states); larger ones are determinized without pruning.
SIMULATION_MAX_STATES = 2000
#: The subset construction runs without pruning first (computing the simulation costs more
#: than it saves on small powersets) and restarts with pruning beyond this many subsets.
PRUNE_AFTER = 1000
#: :func:`minimize` refines in plain Python up to this many table cells (states x letters),
#: with numpy beyond (numpy's fixed cost per call dominates on the small tables of most
#: requirements).
PYTHON_MINIMIZE_MAX = 4096
#: NFA states per memoized chunk of a state set.
_CHUNK = 16


def simulation_dominated(succ: list[list[int]]) -> list[int]:
    """For an NFA whose states all accept, the states each state makes redundant in a set.

    :param succ: ``succ[s][letter]``: bit mask of the successors of ``s`` on ``letter``.
    :returns: ``dom[t]``: bit mask of the states ``s != t`` with ``s`` simulated by ``t``
        (the greatest direct simulation: ``s <= t`` iff for each letter and each successor
        ``s'`` of ``s`` there is a successor ``t'`` of ``t`` with ``s' <= t'``), ties between
        mutually simulating states broken by keeping the lower number. ``s <= t`` implies
        that ``s`` accepts a subset of ``t``'s words, and the relation "dominated by" is a
        strict partial order, so removing from a set every state dominated by another of the
        set keeps the set's language.
    """
    n = len(succ)
    width = len(succ[0]) if succ else 0
    pred = [[0] * n for _ in range(width)]  # pred[letter][t]: states with an edge to t
    out: list[list[tuple[int, int]]] = []
    for s, row in enumerate(succ):
        edges = []
        for a, m in enumerate(row):
            while m:
                low = m & -m
                d = low.bit_length() - 1
                pred[a][d] |= 1 << s
                edges.append((a, d))
                m ^= low
        out.append(edges)
    simby = [(1 << n) - 1] * n  # simby[s]: the states that (still may) simulate s
    changed = True
    while changed:  # greatest fixpoint: refine until stable
        changed = False
        # can[a][d]: the states with an a-successor that simulates d (this round's relation)
        can: list[dict[int, int]] = [{} for _ in range(width)]
        for s in range(n):
            cur = new = simby[s]
            for a, d in out[s]:
                sim = can[a].get(d)
                if sim is None:
                    sim, x, pa = 0, simby[d], pred[a]
                    while x:
                        low = x & -x
                        sim |= pa[low.bit_length() - 1]
                        x ^= low
                    can[a][d] = sim
                new &= sim
                if not new:
                    break
            if new != cur:
                simby[s] = new
                changed = True
    dom = [0] * n
    for s in range(n):
        x = simby[s] & ~(1 << s)
        while x:
            low = x & -x
            t = low.bit_length() - 1
            x ^= low
            if not (simby[t] >> s) & 1 or t < s:  # t strictly above s, or equal and lower
                dom[t] |= 1 << s
    return dom


def determinize(succ: list[list[int]], init: int, width: int,
                limit: int = SUBSET_MAX_STATES,
                prune_after: int | None = PRUNE_AFTER) -> list[list[int]] | None:
    """The subset construction of a nondeterministic automaton given by successor masks.

    :param succ: ``succ[s][letter]`` is the bit mask of the successors of NFA state ``s`` on
        ``letter`` (bit ``t`` set: an edge to ``t``). Every state accepts (a monitor).
    :param init: the NFA's initial state.
    :param width: the number of letters (or letter classes).
    :param limit: the most DFA states built; beyond it None is returned.
    :param prune_after: when the plain construction exceeds this many sets, start again
        removing from each set the states simulated by another of the set
        (:func:`simulation_dominated`; same language, fewer sets), for NFAs of at most
        :data:`SIMULATION_MAX_STATES` states; 0: prune from the start; None: never.
    :returns: the DFA's rows, state 0 = ``{init}``; the empty set is not a state (-1). The
        rows depend on whether pruning happened; their minimal DFA does not.
    """
    if prune_after is None or not 1 < len(succ) <= SIMULATION_MAX_STATES:
        return _subsets(succ, init, width, limit, None)
    if 0 < prune_after < limit:
        rows = _subsets(succ, init, width, prune_after, None)
        if rows is not None:
            return rows
    return _subsets(succ, init, width, limit, simulation_dominated(succ))


def _subsets(succ: list[list[int]], init: int, width: int, limit: int,
             dom: list[int] | None) -> list[list[int]] | None:
    """The subset construction; each new set pruned by ``dom`` (from
    :func:`simulation_dominated`) unless None. See :func:`determinize`."""
    mask = (1 << _CHUNK) - 1
    unions: dict[tuple[int, int], list[int]] = {}  # (chunk, bits) -> successors per letter

    def union(p: int, bits: int) -> list[int]:
        got = unions.get((p, bits))
        if got is None:
            low = bits & -bits
            s = p * _CHUNK + low.bit_length() - 1
            rest = bits ^ low
            got = list(map(or_, union(p, rest), succ[s])) if rest else succ[s]
            unions[p, bits] = got
        return got

    dominated: dict[tuple[int, int], int] = {}  # (chunk, bits) -> states they dominate
    doms = dom if dom is not None else []  # (dominated_by is called only with dom)

    def dominated_by(p: int, bits: int) -> int:
        got = dominated.get((p, bits))
        if got is None:
            low = bits & -bits
            s = p * _CHUNK + low.bit_length() - 1
            rest = bits ^ low
            got = dominated_by(p, rest) | doms[s] if rest else doms[s]
            dominated[p, bits] = got
        return got

    def pruned(r: int) -> int:
        d, p, x = 0, 0, r
        while x:
            bits = x & mask
            if bits:
                d |= dominated_by(p, bits)
            x >>= _CHUNK
            p += 1
        return r & ~d

    start = 1 << init
    index = {start: 0}  # pruned set -> DFA state
    seen: dict[int, int] = {}  # unpruned successor set -> DFA state
    subsets = [start]
    rows: list[list[int]] = []
    i = 0
    while i < len(subsets):
        sub, p, masks = subsets[i], 0, None
        while sub:
            bits = sub & mask
            if bits:
                got = union(p, bits)
                masks = got if masks is None else list(map(or_, masks, got))
            sub >>= _CHUNK
            p += 1
        assert masks is not None  # (a subset has a state)
        row = []
        for r in masks:
            if not r:
                row.append(-1)
                continue
            j = seen.get(r)
            if j is None:
                q = pruned(r) if dom is not None else r
                j = index.get(q)
                if j is None:
                    j = index[q] = len(subsets)
                    if j >= limit:
                        return None
                    subsets.append(q)
                seen[r] = j
            row.append(j)
        rows.append(row)
        i += 1
    return rows


def minimize(rows: list[list[int]]) -> tuple[int, list[list[int]]]:
    """The minimal DFA of the prefix language of ``rows`` (initial state 0, -1 = reject).

    Moore's refinement: states start in one class (the rejecting sink in another) and are
    split by the classes of their successors until no class splits (one sort of the rows
    ``(class, classes of the successors)`` per round).

    :returns: ``(initial, rows)`` of the quotient, the sink removed (its transitions -1);
        states in an arbitrary order (rename them with ``_bfs_tables``).
    """
    if len(rows) * (len(rows[0]) if rows else 0) <= PYTHON_MINIMIZE_MAX:
        return _minimize_small(rows)
    table = np.asarray(rows, dtype=np.int64).reshape(len(rows), -1)
    n, width = table.shape
    table = np.where(table < 0, n, table)
    table = np.vstack([table, np.full((1, width), n, dtype=np.int64)])  # the sink, state n
    cls = np.zeros(n + 1, dtype=np.int64)
    cls[n] = 1
    count = 2
    signature = np.empty((n + 1, width + 1), dtype=np.int64)
    row_type = np.dtype((np.void, 8 * (width + 1)))  # a row as one sortable value
    while True:
        signature[:, 0] = cls
        signature[:, 1:] = cls[table]
        _, new = np.unique(signature.view(row_type).ravel(), return_inverse=True)
        new = new.ravel()
        new_count = int(new.max()) + 1
        cls = new
        if new_count == count:
            break
        count = new_count
    sink = int(cls[n])
    firsts = np.unique(cls[:n], return_index=True)[1]  # one representative per class
    reps = [int(s) for s in sorted(firsts) if int(cls[s]) != sink]
    number = {int(cls[s]): i for i, s in enumerate(reps)}
    out = [[number.get(int(cls[d]), -1) for d in table[s]] for s in reps]
    return number[int(cls[0])], out


def _minimize_small(rows: list[list[int]]) -> tuple[int, list[list[int]]]:
    """:func:`minimize` in plain Python: the same refinement, the same result."""
    n = len(rows)
    sink = n
    table = [[d if d >= 0 else sink for d in row] for row in rows]
    width = len(table[0]) if table else 0
    table.append([sink] * width)
    cls = [0] * n + [1]
    count = 2
    while True:
        signatures: dict[tuple, int] = {}
        new = [signatures.setdefault((cls[s], *[cls[d] for d in table[s]]), len(signatures))
               for s in range(n + 1)]
        cls = new
        if len(signatures) == count:
            break
        count = len(signatures)
    sink_class = cls[n]
    number: dict[int, int] = {}
    reps: list[int] = []
    for s in range(n):
        c = cls[s]
        if c != sink_class and c not in number:
            number[c] = len(reps)
            reps.append(s)
    out = [[number.get(cls[d], -1) for d in table[s]] for s in reps]
    return number[cls[0]], out


def safety_complement(rows: list[list[int]]) -> list[list[int]]:
    """The LTL3 monitor of ``not g`` from the LTL3 monitor of a *safety* property ``g``.

    :param rows: the monitor of ``g`` (initial state 0, ``rows[state][letter]``, -1 = no
        run: the prefix is bad for ``g``).
    :returns: the rows (initial state 0, -1 = no run) of a deterministic automaton, not
        minimal, whose prefix language is that of the monitor of ``not g``: the prefixes
        that some infinite continuation extends to a word violating ``g``. Minimize it
        (:func:`minimize`) to get the table Spot's monitor of ``not g`` gives.

    The rule: in a safety property every violating word has a bad prefix (Alpern &
    Schneider, "Defining liveness", IPL 1985; Kupferman & Vardi, "Model checking of safety
    properties", FMSD 2001), so a prefix ``u`` has a violating continuation iff some finite
    extension of ``u`` is bad, i.e. iff the monitor of ``g`` can reach "no run" from the
    state ``u`` leads to. Hence: "no run" becomes a state looping on every letter (every
    continuation of a bad prefix violates ``g``) and the states that cannot reach "no run"
    become "no run" (``u`` is a good prefix of ``g``). Wrong for a ``g`` that is not safety
    (``F a``: no bad prefix, yet ``G !a`` is satisfiable): the caller decides safety.
    """
    n = len(rows)
    width = len(rows[0]) if rows else 0
    pred: list[set[int]] = [set() for _ in range(n)]
    reach = [False] * n  # reach[s]: "no run" is reachable from s
    queue = []
    for s, row in enumerate(rows):
        for d in row:
            if d < 0:
                if not reach[s]:
                    reach[s] = True
                    queue.append(s)
            else:
                pred[d].add(s)
    while queue:
        d = queue.pop()
        for s in pred[d]:
            if not reach[s]:
                reach[s] = True
                queue.append(s)
    if not n or not reach[0]:  # g is valid: not g has no run at all
        return [[-1] * width]
    sink = n
    out = [[(d if reach[d] else -1) if d >= 0 else sink for d in row] if reach[s]
           else [-1] * width for s, row in enumerate(rows)]
    out.append([sink] * width)
    return out


def guarantee_bad_prefixes(succ: list[list[int]], init: int, width: int, target: int,
                           limit: int) -> list[list[int]] | None:
    """The LTL3 monitor of a safety property ``f`` from a terminal automaton of ``not f``.

    :param succ: ``succ[s][letter]``: bit mask of the successors of state ``s`` of a
        nondeterministic automaton ``A`` of the guarantee property ``h = not f`` in which
        the states of ``target`` (a bit mask) accept every continuation and the other states
        none by themselves: ``A`` accepts an infinite word iff one of its runs reaches
        ``target`` (a *terminal* Büchi automaton: its accepting SCCs are complete and lead to
        no rejecting SCC).
    :param init: ``A``'s initial state.
    :param width: the number of letters (or letter classes).
    :param limit: the most subsets built; beyond it None is returned.
    :returns: the rows (initial state 0, ``rows[state][letter]``, -1 = no run) of a
        deterministic automaton, not minimal, whose prefix language is that of the LTL3
        monitor of ``f``: the prefixes that are not bad for ``f``, i.e. not good for ``h``.

    The rule (Kupferman & Vardi, "Model checking of safety properties", FMSD 2001): the
    subset construction of ``A`` as an automaton of finite words, a set meeting ``target``
    accepting; ``u`` is good for ``h`` iff every infinite path of the subset automaton from
    the set ``u`` leads to meets an accepting set (König's lemma), i.e. iff no cycle of
    non-accepting sets (the empty set included: it loops on every letter) is reachable from
    it without passing an accepting set. Those sets become "no run".
    """
    start = 1 << init
    if start & target:
        return [[-1] * width]
    index = {start: 0}
    subsets = [start]
    rows: list[list[int]] = []
    i = 0
    while i < len(subsets):
        sub = subsets[i]
        masks = [0] * width
        x = sub
        while x:
            low = x & -x
            s = low.bit_length() - 1
            x ^= low
            masks = list(map(or_, masks, succ[s]))
        assert masks is not None  # (a subset has a state)
        row = []
        for r in masks:
            if r & target:
                row.append(-1)  # accepting set: a good prefix of h
                continue
            j = index.get(r)
            if j is None:
                j = index[r] = len(subsets)
                if j >= limit:
                    return None
                subsets.append(r)
            row.append(j)
        rows.append(row)
        i += 1
    # keep[s]: an infinite path of non-accepting sets starts at s (greatest fixpoint: drop
    # the sets whose every letter leads to an accepting set or to a dropped set)
    n = len(rows)
    pred: list[list[int]] = [[] for _ in range(n)]
    alive = [0] * n  # successors (with multiplicity) among the kept sets
    for s, row in enumerate(rows):
        for d in row:
            if d >= 0:
                pred[d].append(s)
                alive[s] += 1
    keep = [True] * n
    queue = [s for s in range(n) if alive[s] == 0]
    for s in queue:
        keep[s] = False
    while queue:
        d = queue.pop()
        for s in pred[d]:
            alive[s] -= 1
            if alive[s] == 0 and keep[s]:
                keep[s] = False
                queue.append(s)
    if not keep[0]:
        return [[-1] * width]
    return [[d if d >= 0 and keep[d] else -1 for d in row] if keep[s] else [-1] * width
            for s, row in enumerate(rows)]
