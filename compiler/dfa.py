"""Deterministic monitors from small nondeterministic ones: subset construction and minimization
over explicit letter tables.

An LTL3 monitor (Bauer, Leucker, Schallhart, "Runtime Verification for LTL and TLTL", TOSEM
2011) is a deterministic automaton whose missing transitions reject: its language is a prefix
language. For alphabets of few letter classes (up to :data:`SUBSET_MAX_CLASSES`) the
powerset of Spot's nondeterministic monitor and its minimization are done here on letter
tables: the subset construction with successor sets as integer bit masks, looked up a byte
at a time, and Moore's partition refinement (Hopcroft and Ullman, "Introduction to Automata
Theory", section 3.4) vectorized with numpy. Spot's ``tgba_powerset`` + ``minimize_monitor``
compute the same automaton (the minimal DFA of a language is unique up to the names of its
states, and :func:`compiler.automata._bfs_tables` renames them canonically) but take seconds
where this takes a fraction of one (a 40,000-state powerset minimized to 512 states for
``only in m whenever c the sw shall after 8 ticks satisfy r``).

Tables: ``rows[state][letter]`` is the destination state or -1 (no transition: reject).
"""

from __future__ import annotations

import numpy as np

#: The construction here is used for at most this many letter classes (letters that satisfy
#: the same edge conditions); Spot's symbolic powerset is faster beyond.
SUBSET_MAX_CLASSES = 64
#: Above this many states the subset construction gives up (the caller falls back to Spot).
SUBSET_MAX_STATES = 200_000


def determinize(succ: list[list[int]], init: int, width: int,
                limit: int = SUBSET_MAX_STATES) -> list[list[int]] | None:
    """The subset construction of a nondeterministic automaton given by successor masks.

    :param succ: ``succ[s][letter]`` is the bit mask of the successors of NFA state ``s`` on
        ``letter`` (bit ``t`` set: an edge to ``t``).
    :param init: the NFA's initial state.
    :param width: the number of letters (``2 ** atoms``).
    :param limit: the most DFA states built; beyond it None is returned.
    :returns: the DFA's rows, state 0 = ``{init}``; the empty set is not a state (-1).
    """
    n = len(succ)
    nbytes = max(1, (n + 7) // 8)
    # per byte position and letter: the union of the successors of the states in that byte
    tables = []
    for p in range(nbytes):
        per_letter = []
        for a in range(width):
            t = [0] * 256
            for b in range(1, 256):
                low = b & -b
                s = p * 8 + low.bit_length() - 1
                t[b] = t[b ^ low] | (succ[s][a] if s < n else 0)
            per_letter.append(t)
        tables.append(per_letter)
    index = {1 << init: 0}
    subsets = [1 << init]
    rows: list[list[int]] = []
    i = 0
    while i < len(subsets):
        parts = [(tables[p], byte) for p, byte in
                 enumerate(subsets[i].to_bytes(nbytes, "little")) if byte]
        row = []
        for a in range(width):
            r = 0
            for per_letter, byte in parts:
                r |= per_letter[a][byte]
            if not r:
                row.append(-1)
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
    return rows


def minimize(rows: list[list[int]]) -> tuple[int, list[list[int]]]:
    """The minimal DFA of the prefix language of ``rows`` (initial state 0, -1 = reject).

    Moore's refinement: states start in one class (the rejecting sink in another) and are
    split by the classes of their successors until no class splits.

    :returns: ``(initial, rows)`` of the quotient, the sink removed (its transitions -1);
        states in an arbitrary order (rename them with ``_bfs_tables``).
    """
    table = np.asarray(rows, dtype=np.int64).reshape(len(rows), -1)
    n, width = table.shape
    table = np.where(table < 0, n, table)
    table = np.vstack([table, np.full((1, width), n, dtype=np.int64)])  # the sink, state n
    cls = np.zeros(n + 1, dtype=np.int64)
    cls[n] = 1
    count = 2
    while True:
        new = cls
        for a in range(width):  # rank (class, class of the successor on a), column by column
            _, new = np.unique(new * (n + 1) + cls[table[:, a]], return_inverse=True)
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
