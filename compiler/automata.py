"""The LTL3 automata of a requirement's ft_inf: built once per formula shape, cached on disk.

A generated monitor's ``status`` and the vectorized engine's LTL3 verdict both follow two
deterministic automata of ft_inf (LTL3; Bauer, Leucker & Schallhart, TOSEM 2011): ``bad``
has no run on exactly the bad prefixes (no infinite continuation satisfies ft_inf:
*violated*), ``good`` none on the good prefixes (every continuation does: *satisfied*).
:func:`ltl3_automata` gives them as :class:`Automaton` tables inside an
:class:`LTL3Automata`.

Construction: Spot's deterministic monitors of ft_inf and of its negation (exact LTL3) while
the bounds stay small; formula progression (:mod:`compiler.ltl3`: sound, bounds kept
symbolic) beyond.
"""

from __future__ import annotations

import json
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from common import cache

from . import dfa, ir, ltl3
from .ir import Node
from .printers import to_spot
from .pt_step import CodegenError

#: Above this many atomic propositions the automaton step uses condition chains instead of a
#: letter-indexed table.
TABLE_MAX_APS = 10
#: Above this many states a Spot monitor is not embedded (status stays "unknown").
MAX_AUTOMATON_STATES = 5000
#: Spot's determinization of bounded operators (``F[0,n]`` unrolls into n nested ``X``) grows
#: exponentially with the bounds: measured 0.7 s for ``in m upon p ... within 12 ticks`` and
#: over a minute for 16. Spot's monitors are built only when ft_inf's largest bound and the
#: sum of its bounds stay within these limits (a deterministic rule, so the same input always
#: gives the same module); beyond them the LTL3 automaton comes from formula progression
#: (:mod:`compiler.ltl3`: sound, bounds kept symbolic) and ``STATUS_NOTE`` says so.
MAX_LTL3_BOUND = 12
MAX_LTL3_BOUND_SUM = 96
#: LTL3 monitors are built for at most this many atoms: beyond it an edge condition written
#: as Boolean code can be exponential (``a xor b xor ...``: minutes for 16 atoms) and Spot's
#: determinization can take minutes and gigabytes (fuzzing: ``only after m ... finally
#: satisfy r & w0 & ... & w29``); status stays "unknown" with a note.
MAX_LTL3_ATOMS = 10


@dataclass(frozen=True)
class Automaton:
    """A deterministic LTL3 monitor over ``atoms`` as tables.

    Attributes:
        atoms: the IR atoms; bit ``i`` of a letter is the truth of ``atoms[i]``.
        initial: the initial state.
        table: ``table[state][letter]`` = next state, -1 = no transition (rejected), or None
            when there are more than :data:`TABLE_MAX_APS` atoms.
        chains: instead of ``table``: per state a list of (Python condition over the letter
            ``sub``, destination); a state with no true condition rejects.
        empty: the automaton accepts nothing at all (rejects before any letter).
        complete: every state has a transition for every letter: it never rejects.
    """

    atoms: tuple[Node, ...]
    initial: int
    table: list[list[int]] | None
    chains: list[list[tuple[str, int]]] | None
    empty: bool
    complete: bool = False


class LTL3Automata(NamedTuple):
    """The LTL3 automata of one ft_inf: ``bad`` (rejection = *violated*), ``good``
    (rejection = *satisfied*), each None when not built, and ``note``: why not, or how they
    were built ("" when both come from Spot)."""

    bad: Automaton | None
    good: Automaton | None
    note: str

    @property
    def atoms(self) -> list[Node]:
        """The atoms of both automata, each once, ``bad``'s first."""
        out: list[Node] = []
        for aut in (self.bad, self.good):
            if aut is not None:
                out.extend(a for a in aut.atoms if a not in out)
        return out


def ltl3_automata(ft_inf: Node) -> LTL3Automata:
    """The LTL3 automata of ``ft_inf`` (an IR formula over infinite traces).

    Built once per shape of ft_inf (:func:`canonical_shape`: atoms renamed, so requirements
    of the same template, bounds and atom pattern share it) and kept in fretc's disk cache
    (:func:`shape_automata`); the tables are canonical, so the generated module is the same
    with a cold or a warm cache. Spot (exact LTL3) while ft_inf's bounds are at most
    :data:`MAX_LTL3_BOUND` ticks and sum to at most :data:`MAX_LTL3_BOUND_SUM`; formula
    progression (sound, bounds symbolic) beyond, unless a bound exceeds
    :data:`compiler.ltl3.MAX_STATES` (progression would need at least that many residuals:
    decided before any construction). Never raises for a formula's size: the automata are
    None and the note says why."""
    shape, atoms = canonical_shape(ft_inf)
    if len(atoms) > MAX_LTL3_ATOMS:
        return LTL3Automata(None, None, (
            f"no LTL3 monitor: ft_inf has {len(atoms)} atoms (more than {MAX_LTL3_ATOMS}: "
            "the deterministic monitors can take minutes and gigabytes to build); status "
            "stays 'unknown' (step and finish unaffected)"))
    bounds = [n.hi for n in ir.walk(ft_inf) if n.hi is not None]
    if bounds and (max(bounds) > MAX_LTL3_BOUND or sum(bounds) > MAX_LTL3_BOUND_SUM):
        return _progression_automata(shape, atoms, bounds)
    data = shape_automata("spot", shape, len(atoms), MAX_AUTOMATON_STATES, TABLE_MAX_APS)
    bad, good = _automaton(data["bad"], atoms), _automaton(data["good"], atoms)
    note = "" if bad is not None and good is not None else (
        f"Spot's deterministic monitor exceeds {MAX_AUTOMATON_STATES} states: no early "
        "verdict")
    return LTL3Automata(bad, good, note)


def _progression_automata(shape: Node, atoms: list[Node], bounds: list[int]) -> LTL3Automata:
    """:func:`ltl3_automata` for bounds beyond what Spot determinizes quickly."""
    why = (f"ft_inf's bounds (largest {max(bounds)}, sum {sum(bounds)} ticks) exceed what "
           f"Spot determinizes quickly (largest {MAX_LTL3_BOUND}, sum "
           f"{MAX_LTL3_BOUND_SUM})")
    if max(bounds) >= ltl3.MAX_STATES or len(atoms) > ltl3.MAX_ATOMS:
        data = {"bad": None, "good": None}
    else:
        data = shape_automata("progression", shape, len(atoms), ltl3.MAX_STATES,
                              TABLE_MAX_APS)
    if data["bad"] is None or data["good"] is None:
        return LTL3Automata(None, None, (
            f"no LTL3 monitor: {why}, and formula progression needs more than "
            f"{ltl3.MAX_STATES} residuals, {ltl3.MAX_ATOMS} atoms or "
            f"{ltl3.MAX_PROGRESSIONS} progressions; status stays "
            "'unknown' (step and finish unaffected)"))
    bad, good = _automaton(data["bad"], atoms), _automaton(data["good"], atoms)
    return LTL3Automata(bad, good, (
        f"LTL3 by formula progression ({data['bad']['states']} residual states): {why}; "
        "verdicts are sound but may come later than the exact LTL3 verdict when a "
        "residual is unsatisfiable without simplifying to FALSE"))


def _automaton(data: dict | None, atoms: list[Node]) -> Automaton | None:
    """An :class:`Automaton` over ``atoms`` (bit i of a letter = atoms[i]) from the data of
    :func:`shape_automata`."""
    if data is None:
        return None
    chains = None
    if data["chains"] is not None:
        chains = [[(cond, dst) for cond, dst in row] for row in data["chains"]]
    return Automaton(tuple(atoms), data["initial"], data["table"], chains, data["empty"],
                     complete=data["complete"])


def bdd_code(f, aps: list[str]) -> str:
    """Python code of a Spot Boolean formula ``f`` over the letter ``sub`` (atom ``aps[i]``
    is bit ``i``). Raises :class:`~compiler.pt_step.CodegenError` for an operator that is not
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


# --------------------------------------------------------------------------- by shape
# The LTL3 automata of a requirement depend only on the *shape* of ft_inf: the formula with
# its atoms (variables, comparisons, calls, past-time sub-formulas, FTP) renamed a0, a1, ...
# in order of first appearance. Requirements of the same template, bounds and atom pattern
# share one construction, memoized in the process and stored in fretc's disk cache
# (common.cache, sub-folder "ltl3"), keyed by the shape, Spot's version and the text of
# this module and of compiler.ltl3 (so a change of the construction can never meet an old
# entry).
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

#: Options of Spot's ``low`` translation (Spot's ``-x`` options): branching postponement and
#: the expansion of atomic propositions off. On the 696 sentences of FRET's trace vectors and
#: the 288 template keys at 12 ticks this makes the translation 1.4 times faster and the
#: nondeterministic monitors smaller (``only in m upon c ... after 8 ticks``: 1.7 s and 232
#: states by default, 0.33 s and 90 states).
LOW_XARGS = "branch-post=0,exprop=0"

_SHAPE_MEMO: dict[str, dict] = {}
_SOURCE_KEY: str | None = None


def canonical_shape(formula: Node) -> tuple[Node, list[Node]]:
    """``formula`` with its atoms renamed ``a0``, ``a1``, ... (in order of first appearance in
    a pre-order walk) and the list of the original atoms, atom ``i`` named ``a{i}``."""
    atoms: dict[Node, Node] = {}
    for n in ir.walk(formula):
        if n.op in ATOM_OPS and n not in atoms:
            atoms[n] = ir.ap(f"a{len(atoms)}")
    memo: dict[Node, Node] = {}

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
    """A key of the construction's code: the text of this module and of
    :mod:`compiler.ltl3`."""
    global _SOURCE_KEY
    if _SOURCE_KEY is None:
        _SOURCE_KEY = cache.key_of(*(Path(f).read_text(encoding="utf-8")
                                     for f in (ltl3.__file__, __file__)))
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
    ``"progression"`` (:func:`compiler.ltl3.progression_tables`: sound, bounds kept
    symbolic). Memoized in the process and in the disk cache; the result depends only on the
    arguments, Spot's version and the text of this module and :mod:`compiler.ltl3`."""
    text = to_spot(shape)
    spot_version = _spot_version() if kind == "spot" else "-"
    key = cache.key_of("ltl3-shape-2", kind, text, str(n_atoms), str(max_states),
                       str(table_max_aps), spot_version, _source_key())
    got = _SHAPE_MEMO.get(key)
    if got is not None:
        return got
    name = f"{key[:40]}.json"
    raw = cache.read_bytes("ltl3", name)
    # an entry is a CRC-32 line (8 hex digits) then the JSON: a table altered on disk but
    # still valid JSON would give a monitor a wrong LTL3 status, so it is rebuilt instead
    if raw is not None and raw[8:9] == b"\n" and raw[:8] == b"%08x" % zlib.crc32(raw[9:]):
        try:
            got = json.loads(raw[9:])
            if got.get("shape") != text:  # a hash collision or a foreign file
                got = None
        except ValueError:
            got = None
    if got is None:
        if kind == "spot":
            got = spot_automata(text, n_atoms, max_states, table_max_aps)
        else:
            got = _progression_data(shape, n_atoms)
        got["shape"] = text
        body = json.dumps(got, separators=(",", ":")).encode()
        cache.write_bytes("ltl3", name, b"%08x\n" % zlib.crc32(body) + body)
    _SHAPE_MEMO[key] = got
    return got


def _spot_version() -> str:
    import spot  # lazy: only automaton construction needs Spot (start-up of --emit ltl)
    return spot.version()


def spot_automata(text: str, n_atoms: int, max_states: int, table_max_aps: int) -> dict:
    """The exact LTL3 monitors of the Spot formula ``text`` over atoms ``a0`` ..
    ``a{n_atoms-1}`` as :func:`shape_automata`'s data ``{"bad": aut, "good": aut}``.

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

    then ``good`` is derived from ``bad`` by :func:`compiler.dfa.safety_complement`,
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
    got = {"bad": None, "good": None}
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
    vectors); :func:`compiler.dfa.guarantee_bad_prefixes` turns it into a deterministic
    automaton of the prefixes that are not good for ``h`` (= not bad for ``not h``), made
    minimal and renamed breadth-first: the table of Spot's monitor of ``not h``, since the
    minimal DFA of a prefix language is unique. None (the caller translates ``not h``) when
    Spot's automaton is not weak with complete accepting SCCs, or has more than
    :data:`compiler.dfa.SUBSET_MAX_CLASSES` letter classes, or the subset construction
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
    ``g`` (:func:`compiler.dfa.safety_complement`, minimized, renamed breadth-first); None
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
    language, which :mod:`compiler.dfa` (or Spot's ``minimize_monitor``) makes minimal.
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


def letter_rows(aut, n_atoms: int) -> list[list[int]]:
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
    beyond :data:`compiler.dfa.SUBSET_MAX_CLASSES` classes."""
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
    :mod:`compiler.dfa` (the same automaton as Spot's powerset and ``minimize_monitor``,
    faster), as :func:`_spot_monitor`'s data; None when there are more than
    :data:`compiler.dfa.SUBSET_MAX_CLASSES` letter classes or the subset construction exceeds
    :data:`compiler.dfa.SUBSET_MAX_STATES`.

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


def _progression_data(shape: Node, n_atoms: int) -> dict:
    atoms = [ir.ap(f"a{i}") for i in range(n_atoms)]
    tables = ltl3.progression_tables(shape, atoms)
    if tables is None:
        return {"bad": None, "good": None}
    bad, good, init = tables
    return {"bad": {"initial": init, "table": bad, "chains": None,
                    "empty": shape.op == "false", "complete": False,
                    "states": len(bad) - 2},
            "good": {"initial": init, "table": good, "chains": None,
                     "empty": shape.op == "true", "complete": False,
                     "states": len(good) - 2}}

