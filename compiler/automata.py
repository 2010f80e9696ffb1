"""The LTL3 automata of a requirement's ft_inf: built once per formula shape, cached on disk.

A generated monitor's ``status`` and the vectorized engine's LTL3 verdict both follow two
deterministic automata of ft_inf (LTL3; Bauer, Leucker & Schallhart, TOSEM 2011): ``bad``
has no run on exactly the bad prefixes (no infinite continuation satisfies ft_inf:
*violated*), ``good`` none on the good prefixes (every continuation does: *satisfied*).
:func:`ltl3_automata` gives them as :class:`Automaton` tables inside an
:class:`LTL3Automata`.

Construction: Spot's deterministic monitors of ft_inf and of its negation (exact LTL3,
:mod:`fretc.compiler.spot_monitors`) while the bounds stay small; formula progression (:mod:`fretc.compiler.ltl3`: sound, bounds kept
symbolic) beyond.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from fretc.common import cache

from fretc.compiler import ir, ltl3, spot_monitors
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_spot
from fretc.compiler.spot_monitors import spot_automata, spot_version

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
#: (:mod:`fretc.compiler.ltl3`: sound, bounds kept symbolic) and ``STATUS_NOTE`` says so.
MAX_LTL3_BOUND = 12
MAX_LTL3_BOUND_SUM = 96
#: LTL3 monitors are built for at most this many atoms: beyond it an edge condition written
#: as Boolean code can be exponential (``a xor b xor ...``: minutes for 16 atoms) and Spot's
#: determinization can take minutes and gigabytes (fuzzing: ``only after m ... finally
#: satisfy r & w0 & ... & w29``); status stays "unknown" with a note.
MAX_LTL3_ATOMS = 10
#: Spot's time grows with the size of the deterministic monitor, which for some shapes doubles
#: with every tick of bound (``only before m whenever c ... after n ticks``: 2^(n+1) states,
#: 0.5 s at n = 9, 1.7 s at 10, over 6 s at 11). Shapes whose largest bound exceeds
#: PROBE_FROM are first built with every bound lowered by the same amount (largest bound
#: PROBE_FROM - 1, then PROBE_FROM: cheap, deterministic); the monitor's size at the real
#: bound is extrapolated from the growth between the two, and above MAX_PREDICTED_STATES the
#: LTL3 automaton comes from formula progression instead (bench/bench_ltl3.py: no requirement
#: with bounds up to 12 ticks over 1 s cold).
PROBE_FROM = 6
MAX_PREDICTED_STATES = 1100


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
    :data:`fretc.compiler.ltl3.MAX_STATES` (progression would need at least that many residuals:
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
    if bounds and max(bounds) > PROBE_FROM:
        predicted = predicted_states(shape, len(atoms), max(bounds))
        if predicted > MAX_PREDICTED_STATES:
            return _progression_automata(shape, atoms, bounds, (
                f"Spot's monitor would have about {predicted} states (its growth between "
                f"bounds {PROBE_FROM - 1} and {PROBE_FROM}, extrapolated to "
                f"{max(bounds)}; more than {MAX_PREDICTED_STATES}: over a second to build)"))
    data = shape_automata("spot", shape, len(atoms), MAX_AUTOMATON_STATES, TABLE_MAX_APS)
    bad, good = _automaton(data["bad"], atoms), _automaton(data["good"], atoms)
    note = "" if bad is not None and good is not None else (
        f"Spot's deterministic monitor exceeds {MAX_AUTOMATON_STATES} states: no early "
        "verdict")
    return LTL3Automata(bad, good, note)


def predicted_states(shape: Node, n_atoms: int, largest: int) -> int:
    """The states of Spot's "bad" LTL3 monitor of ``shape`` (largest bound ``largest``)
    extrapolated from the monitors of ``shape`` with every bound lowered by the same amount
    to a largest bound of PROBE_FROM - 1 and PROBE_FROM (see :data:`MAX_PREDICTED_STATES`):
    ``s1 * (s1 / s0) ** (largest - PROBE_FROM)`` when the size grows, else ``s1``."""
    sizes = []
    for top in (PROBE_FROM - 1, PROBE_FROM):
        low = _lowered(shape, largest - top)
        data = shape_automata("spot", low, n_atoms, MAX_AUTOMATON_STATES, TABLE_MAX_APS)
        sizes.append(max(len(data[k]["table"] or data[k]["chains"] or [])
                         if data[k] is not None else MAX_AUTOMATON_STATES
                         for k in ("bad", "good")))
    s0, s1 = max(sizes[0], 1), max(sizes[1], 1)
    if s1 <= s0:
        return s1
    return int(s1 * (s1 / s0) ** (largest - PROBE_FROM))


def _lowered(n: Node, by: int) -> Node:
    """``n`` with every bound lowered by ``by`` ticks (not below 0)."""
    if not n.args:
        return n
    lo = None if n.lo is None else max(n.lo - by, 0)
    hi = None if n.hi is None else max(n.hi - by, 0)
    return Node(n.op, tuple(_lowered(a, by) for a in n.args), n.name, lo, hi)


def _progression_automata(shape: Node, atoms: list[Node], bounds: list[int],
                          why: str | None = None) -> LTL3Automata:
    """:func:`ltl3_automata` for bounds beyond what Spot determinizes quickly (``why``: the
    reason given in the note; by default the bounds' limits)."""
    why = why or (f"ft_inf's bounds (largest {max(bounds)}, sum {sum(bounds)} ticks) exceed "
                  f"what Spot determinizes quickly (largest {MAX_LTL3_BOUND}, sum "
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


# --------------------------------------------------------------------------- by shape
# The LTL3 automata of a requirement depend only on the *shape* of ft_inf: the formula with
# its atoms (variables, comparisons, calls, past-time sub-formulas, FTP) renamed a0, a1, ...
# in order of first appearance. Requirements of the same template, bounds and atom pattern
# share one construction, memoized in the process and stored in fretc's disk cache
# (common.cache, sub-folder "ltl3"), keyed by the shape, Spot's version and the text of
# this module, of compiler.spot_monitors and of compiler.ltl3 (so a change of the
# construction can never meet an old entry). Output is canonical, whatever the cache holds
# or the process did before (compiler.spot_monitors' docstring).

#: Atom operators: each distinct one becomes an atomic proposition of the automata.
ATOM_OPS = ("ap", "cmp", "call", "past", "future", "FTP", "LAST")

_SHAPE_MEMO: dict[str, dict] = {}
_LTL3_MAGIC = b"fretc ltl3 2 json\n"
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
    """A key of the construction's code: the text of this module, of
    :mod:`fretc.compiler.spot_monitors` and of :mod:`fretc.compiler.ltl3`."""
    global _SOURCE_KEY
    if _SOURCE_KEY is None:
        _SOURCE_KEY = cache.key_of(*(Path(f).read_text(encoding="utf-8")
                                     for f in (ltl3.__file__, spot_monitors.__file__,
                                               __file__)))
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
    ``"progression"`` (:func:`fretc.compiler.ltl3.progression_tables`: sound, bounds kept
    symbolic). Memoized in the process and in the disk cache; the result depends only on the
    arguments, Spot's version and the construction's code (:func:`_source_key`)."""
    text = to_spot(shape)
    version = spot_version() if kind == "spot" else "-"
    key = cache.key_of("ltl3-shape-2", kind, text, str(n_atoms), str(max_states),
                       str(table_max_aps), version, _source_key())
    got = _SHAPE_MEMO.get(key)
    if got is not None:
        return got
    name, made_from = f"{key[:40]}.json", cache.digest(key.encode("ascii"))
    # a sealed entry (fretc.common.cache: its HMAC under the cache's key): a table altered
    # or planted on disk, still valid JSON, would give a monitor a wrong LTL3 status, so it
    # is a miss and rebuilt instead
    raw = cache.read_sealed("ltl3", name, _LTL3_MAGIC, made_from)
    if raw is not None:
        try:
            got = json.loads(raw)
            if not isinstance(got, dict) or got.get("shape") != text:  # a foreign entry
                got = None
        except ValueError:
            got = None
    if got is None:
        if kind == "spot":
            got = spot_automata(text, n_atoms, max_states, table_max_aps)
        else:
            got = _progression_data(shape, n_atoms)
        got["shape"] = text
        cache.write_sealed("ltl3", name, _LTL3_MAGIC, made_from,
                           json.dumps(got, separators=(",", ":")).encode())
    _SHAPE_MEMO[key] = got
    return got


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

