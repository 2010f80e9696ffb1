"""The questions ``fretc check`` asks of one set of requirements (satisfiability, minimal
unsatisfiable subsets), each sent to the engine that decides it: Spot up to
:data:`SPOT_MAX_BOUND` ticks, past it the pt monitors' fixed points (:mod:`fretc.check.monitor_sat`)
when every formula has them, else z3 (:mod:`fretc.check.smt`). The checks built from these
questions, and their order, are :mod:`fretc.check.analysis`'s.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any

from fretc.common.grouping import connected_groups
from fretc.compiler import ir
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_spot
from fretc.check.budget import FALLBACK_SHARE, MAX_SPENT_QUERIES, MUS_BUDGET
from fretc.check.items import CheckItem, monitored_forms
from fretc.check.numeric_abstraction import NumericAbstraction
from fretc.check.safety_game import Outside, game_atoms
from fretc.check.smt import SmtSolver, max_bound
from fretc.check.solver import UNKNOWN, SpotWorker

__all__ = ["ENGINES", "SPOT_MAX_BOUND", "MUS_BUDGET", "Checker", "Subsets", "SMALLEST",
           "MINIMAL", "NOT_SHOWN_MINIMAL"]

#: the solvers ``fretc check --engine`` names: ``auto`` Spot up to :data:`SPOT_MAX_BOUND`
#: ticks, past it the requirements' pt monitors (:mod:`fretc.check.monitor_sat`) when they take
#: the query, else z3 (:mod:`fretc.check.smt`); ``spot``; ``smt`` (z3 alone); ``bdd`` (the
#: monitors whatever the bound, z3 for the queries they do not take)
ENGINES = ("auto", "spot", "smt", "bdd")

#: the largest tick bound given to Spot's translation, with every engine (faster there,
#: bench/bench_check.py; past it Spot's automata and its time grow exponentially with the
#: bound: ``G(p -> F[0,16] q)`` takes 0.6 s, ``F[0,50]`` did not finish in 2 minutes, and a
#: translation cannot be stopped, so a query past it is refused and answers unknown)
SPOT_MAX_BOUND = 16


# --------------------------------------------------------------------------- the checker
class Checker:
    """Runs the checks of the module docstring on a list of :class:`CheckItem`.

    ``worker`` answers Spot queries (:class:`fretc.check.solver.SpotWorker`, with the queries'
    budgets); ``mus_budget`` is the number of subset checks each enumeration of minimal
    subsets may make after its first subset (:meth:`minimal_subsets`).
    """

    def __init__(self, items: Sequence[CheckItem], worker: SpotWorker,
                 mus_budget: int = MUS_BUDGET, smt: SmtSolver | None = None,
                 engine: str = "auto"):
        if engine not in ENGINES:
            raise ValueError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
        self.items = list(items)
        self.worker = worker
        self.smt = smt if smt is not None else SmtSolver(worker.budget,
                                                         deadline=worker.deadline,
                                                         worker=worker)
        self.engine = engine
        self.smt_queries = 0
        self.mus_budget = mus_budget
        allf = [x.phi for x in self.items] + [x.trigger for x in self.items if x.trigger]
        allf += [x.phi_ft for x in self.items] + [x.trigger_ft for x in self.items
                                                  if x.trigger_ft]
        self.numeric = NumericAbstraction.of(allf)
        self._cache: dict[tuple, Any] = {}
        #: formula -> ("safe" | "goal", pt formula, requirement index), on infinite runs /
        #: finite traces (:mod:`fretc.check.monitor_sat`)
        self.monitored = monitored_forms(self.items)
        self.monitor_queries = 0
        #: queries the monitors left unknown and z3 was asked (:meth:`sat_word`), and those
        #: of them z3 answered
        self.fallbacks = 0
        self.rescued = 0
        #: queries that spent their whole work budget, and the formulas they were on
        #: (:meth:`_large_word`); the (engine, query) pairs asked
        self.spent = 0
        self.not_tried = 0
        self.hard: set[Node] = set()
        self._seen: set[tuple] = set()
        self.smt_fallback = SmtSolver(worker.budget.share(FALLBACK_SHARE),
                                      deadline=worker.deadline, worker=worker)
        self.queries = 0
        self.unknown = 0

    # ---------------------------------------------------------------- queries
    def sat(self, formulas: Sequence[Node], extra: Sequence[Node] = (), *,
            word: bool = True) -> object:
        """True / False / UNKNOWN: is the conjunction of ``formulas`` and ``extra`` (with the
        numeric invariants of their comparisons) satisfiable on infinite words? (``extra``
        apart so the worker can reuse the product of ``formulas``.) ``word=False``: no
        word is wanted, and Spot's product starts from ``extra`` (the worker's
        ``satisfiable`` query: far sooner when ``extra`` is a negated requirement)."""
        return self.sat_word(formulas, extra, word=word)[0]

    def uses_smt(self, formulas: Sequence[Node]) -> bool:
        """Does a query on ``formulas`` go to z3 (:mod:`fretc.check.smt`) rather than Spot? With
        ``engine="auto"``, when a bound passes :data:`SPOT_MAX_BOUND`."""
        if self.engine != "auto":
            return self.engine in ("smt", "bdd")
        return max_bound(formulas) > SPOT_MAX_BOUND

    def sat_word(self, formulas: Sequence[Node], extra: Sequence[Node] = (), *,
                 word: bool = True) -> tuple[object, tuple | None]:
        """:meth:`sat` and an accepting lasso ``(prefix, cycle)`` when satisfiable (None
        with ``word=False`` when Spot answered)."""
        if self.uses_smt(list(formulas) + list(extra)):
            return self._large_word(list(formulas) + list(extra))

        def split(f: Node, parts: list[Node]) -> None:
            if f.op == "&":
                split(f.args[0], parts)
                split(f.args[1], parts)
            elif f.op != "true" and f not in parts:
                parts.append(f)

        base: list[Node] = []
        more: list[Node] = []
        for f in formulas:
            split(f, base)
        split(self.numeric.invariant(list(formulas) + list(extra)), base)
        for f in extra:
            split(f, more)
        if not base:
            base = [ir.TRUE]
        return self._ask_sat((tuple(to_spot(f) for f in base),
                              tuple(to_spot(f) for f in more if f not in base)),
                             max_bound(base + more), word)

    def monitor_word(self, formulas: Sequence[Node], finite: bool,
                     length: int | None = None) -> tuple[object, tuple | None] | None:
        """:meth:`sat_word` decided on the requirements' pt monitors
        (:mod:`fretc.check.monitor_sat`), or None when a formula of the query is not a monitored
        requirement, trigger or negated requirement (``finite``: read on finite traces,
        FRET's ft; ``length``: exactly that many ticks)."""
        if self.engine in ("spot", "smt"):
            return None
        forms = self.monitored[finite]
        # a formula with no pt monitor (an ``eventually``) is taken on infinite runs by
        # Spot's deterministic Büchi automaton of it, when its own bounds are small
        live = sorted({f for f in formulas if f not in forms}, key=to_spot)
        if not formulas or (live and (finite or max_bound(live) > SPOT_MAX_BOUND)):
            return None
        # in input order: one query, one variable order (the order changes the BDDs' sizes,
        # the answer not), so the cache and the time do not depend on how it was asked
        formulas = sorted({f for f in formulas if f in forms},
                          key=lambda f: (forms[f][2], forms[f][0]))
        safe, goals, last = ([forms[f][1] for f in formulas if forms[f][0] == kind]
                             for kind in ("safe", "goal", "last"))
        try:
            game_atoms(safe + goals + last + live)
        except Outside:
            return None
        names = sorted({v for f in [*formulas, *live] for v in ir.variables(f)})
        inv = self.numeric.regions(names)
        key = ("monitor", finite, length, tuple(formulas), tuple(live))
        if self._cache.get(key) == "outside":
            return None
        fresh = key not in self._cache
        # the fixed points pay their work and stop past the budget (check.budget)
        got = self._cached(key, lambda: self.worker.ask(
            ("monitor_sat", safe, goals, inv, finite, length, live, last)))
        if got[0] == "outside":  # no deterministic Büchi automaton: z3's query
            self._cache[key] = "outside"
            return None
        self.monitor_queries += fresh
        return got

    def _large_word(self, query: list[Node]) -> tuple[object, tuple | None]:
        """:meth:`sat_word` of a query whose bounds Spot is not given: the requirements'
        monitors (:mod:`fretc.check.monitor_sat`), and where they run past their work budget
        (a relation too large for one step: deadlines near 10^6 ticks) z3's lassos and
        proofs, whose encoding does not grow with the bounds, within a tenth of the budget
        (:data:`fretc.check.budget.FALLBACK_SHARE`). Once z3 answered such a query it is
        asked first. Once :data:`fretc.check.budget.MAX_SPENT_QUERIES` queries spent their
        whole budget, a later query on any of their formulas is unknown at once: the run
        ends in bounded time, and the same on every machine (the budget counts work)."""
        if self.engine != "auto":
            got = self.monitor_word(query, finite=False)
            return self._ask_smt(query) if got is None else got
        order = ("smt", "monitors") if self.rescued else ("monitors", "smt")
        asked = 0
        for engine in order:
            if self.spent >= MAX_SPENT_QUERIES and self.hard.intersection(query):
                why = (f"{self.spent} queries on these requirements spent their whole work "
                       "budget, so this one was not tried (a larger --budget tries it)")
                fresh = ("spent", tuple(query)) not in self._cache
                # _cached calls the lambda at once (never later): why is this iteration's
                got = self._cached(("spent", tuple(query)), lambda: self.worker.refuse(why))  # noqa: B023
                self.not_tried += fresh
                break
            fresh = (engine, tuple(query)) not in self._seen
            self._seen.add((engine, tuple(query)))
            got = (self.monitor_word(query, finite=False) if engine == "monitors"
                   else self._ask_smt(query, fallback=asked > 0 or order[0] == "smt"))
            if got is None:  # a formula without a monitor: z3 alone
                continue
            asked += fresh
            if asked > 1:  # one query: counted unknown once at most
                self.unknown -= 1
                self.fallbacks += 1
            if got[0] != UNKNOWN:
                self.rescued += engine == "smt" and asked > 1 and order[0] == "monitors"
                return got
            if fresh:
                self.spent += 1
                self.hard.update(query)
        return got if got is not None else (UNKNOWN, None)

    def _ask_smt(self, formulas: list[Node], fallback: bool = False):
        if fallback:
            return self._cached(("smt", tuple(formulas)),
                                lambda: self.smt_fallback.sat(formulas))
        self.smt_queries += ("smt", tuple(formulas)) not in self._cache
        return self._cached(("smt", tuple(formulas)), lambda: self.smt.sat(formulas))

    def _ask_sat(self, text, bound: int, word: bool = True):
        if bound > SPOT_MAX_BOUND:  # a translation past it may not end: refused up front
            return self._cached(text, lambda: self.worker.refuse(
                f"Spot is given tick bounds up to {SPOT_MAX_BOUND}, this query has {bound}"))
        if not word and text not in self._cache:  # (a sat answer of it has its word too)
            def ask():
                ans = self.worker.ask(("satisfiable", text[0], text[1]))
                return ans if ans == UNKNOWN else (ans, None)

            return self._cached(("satisfiable", *text), ask)
        return self._cached(text, lambda: self.worker.ask(("sat", text[0], text[1])))

    def _cached(self, key, ask):
        """The answer to a satisfiability query (``ask()`` once per ``key``): (UNKNOWN,
        None) when the solver could not tell, counted in ``unknown``."""
        got = self._cache.get(key)
        if got is None:
            self.queries += 1
            ans = ask()
            if ans == UNKNOWN:
                self.unknown += 1
                got = (UNKNOWN, None)
            else:
                got = ans
            self._cache[key] = got
        return got

    # ---------------------------------------------------------------- groups
    def groups(self) -> list[list[CheckItem]]:
        """Requirements grouped by shared variables (union-find), in input order."""
        return connected_groups(self.items, lambda item: item.variables)

    # ---------------------------------------------------------------- subsets
    def minimal_subsets(self, pool: Sequence[CheckItem], must: Sequence[CheckItem],
                        bad: Callable[[list[CheckItem]], object],
                        known_bad: bool = False) -> Subsets:
        """Minimal subsets S of ``pool`` (each containing ``must``) with ``bad(S)`` True,
        smallest first; ``bad`` must be monotone (a superset of a bad set is bad).

        A first subset is found by deletion from the whole pool (so one is reported whatever
        the budget), then subsets of sizes 1, 2, ... are checked, at most ``mus_budget``
        of them (the count, not the time: the same input gives the same subsets on any
        machine). Only subsets connected by shared variables are tried (a disconnected bad
        subset is never minimal). Each subset found has a standing (:class:`Subsets`).
        ``known_bad``: the caller has already found the whole pool bad (it is not asked
        again: a second query of the same set, its parts in another order, could run past
        the budget where the first did not, and lose the one subset known).
        """
        must_ids = {x.index for x in must}
        rest = [x for x in pool if x.index not in must_ids]
        out = Subsets()
        whole = True if known_bad else bad(list(must) + rest)
        if whole is not True:
            out.unknown = whole == UNKNOWN
            return out
        # deletion-based shrink of the whole pool: minimal unless a check was unknown
        current, shrunk = list(must) + rest, True
        for x in list(rest):
            trial = [y for y in current if y is not x]
            ans = bad(trial)
            if ans is True:
                current = trial
            elif ans == UNKNOWN:
                out.unknown, shrunk = True, False
        found = {frozenset(y.index for y in current): shrunk}
        unknown_sets: list[frozenset] = []
        checks, complete = 0, 0  # complete: every subset of fewer members was checked
        for size in range(0, len(rest) + 1):
            for combo in itertools.combinations(rest, size):
                subset = list(must) + list(combo)
                ids = frozenset(y.index for y in subset)
                if any(s <= ids for s in found) or not _connected(subset):
                    continue
                if checks >= self.mus_budget:
                    out.cut = True
                    break
                checks += 1
                ans = bad(subset)
                if ans is True:
                    found[ids] = not any(u < ids for u in unknown_sets)
                elif ans == UNKNOWN:
                    out.unknown = True
                    unknown_sets.append(ids)
            if out.cut:
                break
            complete = size + len(must) + 1
        by_index = {y.index: y for y in pool}
        order = sorted(found, key=lambda k: (len(k), sorted(k)))
        for k in order:
            subset = [by_index[i] for i in sorted(k)]
            if not found[k]:
                standing = NOT_SHOWN_MINIMAL
            elif len(k) <= complete and not any(len(u) < len(k) for u in unknown_sets):
                standing = SMALLEST if len(k) == len(order[0]) else MINIMAL
            else:
                standing = MINIMAL
            out.subsets.append(subset)
            out.standing.append(standing)
        return out


#: the standings of a subset :meth:`Checker.minimal_subsets` reports: of the fewest
#: members any bad subset has (every smaller subset checked); minimal (each smaller subset
#: of it checked, none bad); or bad but not shown minimal (a check of a smaller one was
#: unknown)
SMALLEST, MINIMAL, NOT_SHOWN_MINIMAL = "smallest", "minimal", "not shown minimal"


class Subsets:
    """The answer of :meth:`Checker.minimal_subsets`: ``subsets`` (lists of items, fewest
    members first), ``standing`` (one of :data:`SMALLEST`, :data:`MINIMAL`,
    :data:`NOT_SHOWN_MINIMAL` per subset), ``cut`` (the budget of subset checks ran out
    before every size was checked: there may be more) and ``unknown`` (some check was
    unknown: a subset may be missing)."""

    def __init__(self):
        self.subsets: list[list[CheckItem]] = []
        self.standing: list[str] = []
        self.cut = False
        self.unknown = False


def _connected(subset: Sequence[CheckItem]) -> bool:
    if len(subset) <= 1:
        return True
    reach = {0}
    names = set(subset[0].variables)
    grew = True
    while grew:
        grew = False
        for k, x in enumerate(subset):
            if k not in reach and names.intersection(x.variables):
                reach.add(k)
                names.update(x.variables)
                grew = True
    return len(reach) == len(subset)
