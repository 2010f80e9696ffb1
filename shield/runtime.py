"""The shield's step at run time: the one implementation of the rule of
:mod:`fretc.shield.machine`, standard library only.

``fretc shield --emit python`` writes this module's source, unchanged, into the generated
module, followed by the shield's tables (:func:`fretc.shield.emit_python.tables`), so the
generated module needs nothing but Python; in process (the simulator, the tests) the same
class runs from here. :class:`ShieldRuntime` takes the tables (a dict: ``"machines"``, their
node tables, groups, clusters, bounds, assumptions, and the ``"fallback"``) and steps them
on one tick's inputs and proposal, giving a :class:`Decision` (the outputs, ``overridden``,
``fault``, ``recovered``, ``scaled``, ``broken``). A step is all or nothing: every value is
checked (:func:`read_value`) before any machine moves; an unreadable input is any value (the
machine's belief), an unreadable proposal is replaced with its message group. The tables'
schema and the rules of beliefs, recovery, bounds and assumptions are in ARCHITECTURE.md
("The shield's step at run time").
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

from fretc.shield.runtime_bounds import bounded_value, scaled
from fretc.shield.runtime_lost import lost_decision, recovery_of, settle_lost
from fretc.shield.runtime_values import (_OPS, Unreadable, _checked, as_message, kinds,
                                         nearest, read_value, term_value, term_variables,
                                         truth)

__all__ = ["Decision", "ShieldRuntime", "CACHE_LIMIT", "BELIEF_LIMIT", "CASES_LIMIT", "truth",
           "nearest", "term_value", "Unreadable", "read_value"]

#: moves (and corrections) remembered per machine, keyed by (state, input atoms, output
#: atoms): the BDD walks of a tick are done once per distinct key; past the limit the memory
#: is cleared (the answers never depend on it)
CACHE_LIMIT = 1 << 16

#: the most states a machine's belief holds (module docstring): past it the machine's state
#: is unknown and it gives the fallback until reset
BELIEF_LIMIT = 256
#: the most cases (a state of the belief with a valuation of the unreadable inputs' atoms) a
#: machine decides one tick for; past it, as past :data:`BELIEF_LIMIT`
CASES_LIMIT = 4096




class Decision(NamedTuple):
    """One tick's answer: ``outputs`` FRET variable -> value to use; ``overridden`` whether
    the proposal was changed; ``reasons`` the requirement ids that forced the change: those
    the proposal breaks alone, else (the requirements of a component forcing it only
    together) all of the component's; empty when not overridden, or when the proposal
    breaks none and is overridden only for being no valuation the outputs can take (no
    message the bindings give: ``forwarded_zero`` without ``stopped``); ``changed`` the
    output atoms changed (FRET/SMV text)."""

    outputs: dict[str, Any]
    overridden: bool
    reasons: tuple[str, ...]
    changed: tuple[str, ...]
    #: "" for a decision on readable values; else why not (module docstring): "input x:
    #: ..." (``outputs`` the fallback's, the state unchanged), "proposal y: ..." (the
    #: proposal replaced)
    fault: str = ""
    #: the assumptions of the environment broken so far (module docstring): the shield's
    #: guarantee no longer holds, ``outputs`` are the fallback's
    broken: tuple[str, ...] = ()
    #: the requirements of the machines that no longer know their state (module
    #: docstring): their outputs are the fallback's (none without one) until reset
    lost: tuple[str, ...] = ()
    #: the twists scaled together at this tick, each with its factor (the path's curvature
    #: kept: :mod:`fretc.shield.runtime_bounds`)
    scaled: tuple[str, ...] = ()
    #: the requirements of the machines that knew their state again at this tick (module
    #: docstring: a lost state recovers)
    recovered: tuple[str, ...] = ()


def _tester(spec: tuple[str, str | None, Any]) -> Any:
    """A function: the variables' values (a dict) -> the atom's truth (as :func:`truth`,
    :func:`term_value` for a comparison of several variables)."""
    var, op, c = spec
    if op == "pred":
        def predicate(values: dict[str, Any]) -> bool:
            return bool(term_value(c, values))
        return predicate
    if op is None:
        def boolean(values: dict[str, Any]) -> bool:
            value = values[var]
            if value is True or value is False:
                return value
            return truth(spec, value)
        return boolean
    test = _OPS[op]
    assert c is not None  # a comparison has its constant
    const = c

    def compare(values: dict[str, Any]) -> bool:
        x = float(values[var])
        if x != x:
            raise ValueError(f"{var} is NaN: its comparisons have no truth value")
        return test(x, const)
    return compare


def _walk(nodes: list[tuple[int, int, int]], root: int, values: list[int]) -> int:
    n = root
    while n > 1:
        var, lo, hi = nodes[n]
        n = hi if values[var] else lo
    return n


class _Machine:
    """One component's tables and state (module docstring)."""

    def __init__(self, t: dict[str, Any], preferences: int,
                 fallback: dict[str, Any] | None = None):
        self.reqs = tuple(t["requirements"])
        self.ins, self.outs, self.texts = t["inputs"], t["outputs"], t["texts"]
        self.nodes, self.safe = t["nodes"], t["safe"]
        self.next, self.keep, self.ctl_ok = t["next"], t["keep"], t["ctl_ok"]
        self.init = tuple(t["init"])
        self.state = self.init
        self.weights = t["weights"]
        self.big = 1 << preferences
        self.groups = t["groups"]
        #: the groups' models (module docstring), each with the variables it decides
        self.models = [(g["message"], [v for v, _k, _t in g["message"]["reads"]
                                       if v not in g["message"]["passed"]])
                       for g in self.groups if g.get("message")]
        #: the outputs no requirement reads that a model writes and reads back
        self.passed = [v for model, _own in self.models for v in model["passed"]]
        self.cache: dict[tuple[tuple[int, ...], tuple[int, ...], tuple[int, ...]],
                         tuple[bool, tuple[int, ...]]] = {}
        #: the corrections made, by the same key (state, input atoms, proposed atoms):
        #: (corrected atoms, reasons, changed atoms' texts, :meth:`_plan`)
        self.corrections: dict[tuple[tuple[int, ...], tuple[int, ...], tuple[int, ...]],
                               tuple[Any, ...]] = {}
        self.variables = list(dict.fromkeys(s[0] for s in self.outs))
        self.integers = frozenset(t["integers"])
        self.in_tests = [_tester(s) for s in self.ins]
        self.out_tests = [_tester(s) for s in self.outs]
        self.clusters = t.get("clusters", [])
        clustered = {v for c in self.clusters for v in c["variables"]}
        #: the bounds (:mod:`fretc.shield.runtime_bounds`): output atom -> (down, estimate)
        self.bounds = {b["atom"]: (b["down"], b["estimate"]) for b in t.get("bounds", ())}
        bounded = {self.outs[j][0] for j in self.bounds}
        #: each bounded output's atoms, and the inputs each bound reads
        self.bound_atoms = {v: [j for j, s in enumerate(self.outs) if s[0] == v]
                            for v in self.variables if v in bounded}
        self.bound_reads = {j: term_variables(self.outs[j][2]) - {self.outs[j][0]}
                            for j in self.bounds}
        self.atoms_of = {v: [j for j, s in enumerate(self.outs) if s[0] == v]
                         for v in self.variables if v not in clustered and v not in bounded}
        self.in_kinds = kinds(self.ins)
        for j in self.bounds:
            self.in_kinds.update({v: "n" for v in sorted(self.bound_reads[j])
                                  if v not in self.in_kinds})
        self.out_kinds = kinds([(s[0], "<=", 0.0) if j in self.bounds else s
                                for j, s in enumerate(self.outs)])
        #: the twists it scales, and the fallback's numbers (a bound's number nearest them)
        self.twists = [tuple(x) for x in t.get("twists", ())]
        self.fallback_numbers = dict((fallback or {}).get("outputs", {}))
        #: what the last decision noted: bounds no number met (``fault``), twists scaled
        self.faults: list[str] = []
        self.scaled: list[str] = []
        self.env_ok = t.get("env_ok", 1)
        #: the other states the machine may be in after a tick with an unreadable input
        #: (module docstring: its belief is ``state`` and these, sorted); ``lost``: past the
        #: bounds, its state is unknown until reset
        self.others: tuple[tuple[int, ...], ...] = ()
        self.lost = False
        #: the ticks its requirements look back (None: without bound) and, while lost, the
        #: copy run from the initial state and its readable ticks in a row (module docstring)
        self.lookback: int | None = t.get("lookback")
        self.shadow: tuple[int, ...] = self.init
        self.readable = 0
        #: this machine's fallback atoms (set by :class:`ShieldRuntime`; None: no fallback)
        self.fallback_bits: tuple[int, ...] | None = None
        #: the input atoms that read each input variable
        self.reading_in = {v: [j for j, s in enumerate(self.ins)
                               if (v in term_variables(s[2]) if s[1] == "pred" else s[0] == v)]
                           for v in self.in_kinds}
        self.assume_ids = tuple(t.get("assumptions", ()))
        self.assumed = tuple(t.get("assumed", ()))
        #: the output atoms that read each output variable
        self.reading = {v: [j for j, s in enumerate(self.outs)
                            if (v in term_variables(s[2]) if s[1] == "pred" else s[0] == v)]
                        for v in self.out_kinds}

    def _both(self, inputs: dict[str, Any], outputs: dict[str, Any]) -> dict[str, Any]:
        """The values the output atoms read: the outputs', and the inputs' too when a bound
        reads them."""
        return {**inputs, **outputs} if self.bounds else outputs

    def move(self, ins: tuple[int, ...], outs: tuple[int, ...],
             state: tuple[int, ...] | None = None) -> tuple[bool, tuple[int, ...]]:
        """Whether ``outs`` is safe from ``state`` (default the current state) with ``ins``,
        and the next state when it is (remembered)."""
        if state is None:
            state = self.state
        key = (state, ins, outs)
        got = self.cache.get(key)
        if got is None:
            values = list(ins + outs + state)
            safe = _walk(self.nodes, self.safe, values) == 1
            nxt = tuple(_walk(self.nodes, r, values) for r in self.next) if safe else ()
            if len(self.cache) >= CACHE_LIMIT:
                self.cache.clear()
            got = self.cache[key] = (safe, nxt)
        return got

    def correct(self, ins: tuple[int, ...], prop: tuple[int, ...],
                unknown: frozenset[int] = frozenset(),
                state: tuple[int, ...] | None = None) -> tuple[int, ...]:
        """The safe output atoms nearest ``prop`` from ``state`` (default the current
        state): the fewest changes, then the preferences in order (a shortest path through
        the ``safe`` BDD; untested atoms keep their proposed values; equal costs take the
        low branch). The atoms ``unknown`` (a proposal that could not be read) cost nothing
        either way but their preferences.

        Raises:
            RuntimeError: no safe output (the state is outside the winning region)."""
        n_in, n_out = len(ins), len(prop)
        values = list(ins + prop + (self.state if state is None else state))
        costs: list[float] = [math.inf, 0.0]
        for var, lo, hi in self.nodes[2:self.safe + 1]:  # safe's nodes come first
            j = var - n_in
            if 0 <= j < n_out:
                costs.append(min(costs[lo] + self._cost(j, 0, prop, unknown),
                                 costs[hi] + self._cost(j, 1, prop, unknown)))
            else:
                costs.append(costs[hi] if values[var] else costs[lo])
        if costs[self.safe] == math.inf:
            raise RuntimeError("no safe output: the state left the winning region")
        out = list(prop)
        n = self.safe
        while n > 1:
            var, lo, hi = self.nodes[n]
            j = var - n_in
            if 0 <= j < n_out:
                low = (costs[lo] + self._cost(j, 0, prop, unknown)
                       <= costs[hi] + self._cost(j, 1, prop, unknown))
                out[j] = 0 if low else 1
                n = lo if low else hi
            else:
                n = hi if values[var] else lo
        return tuple(out)

    def _cost(self, j: int, v: int, prop: tuple[int, ...],
              unknown: frozenset[int] = frozenset()) -> int:
        w = self.weights.get(j)
        if j in unknown:
            return w[1] if w is not None and v != w[0] else 0
        p = prop[j]
        if v == p:
            return 0
        c = self.big
        if w is not None:
            c += (w[1] if v != w[0] else 0) - (w[1] if p != w[0] else 0)
        return c

    def decide(self, inputs: dict[str, Any], proposed: dict[str, Any],
               unknown: frozenset[str] = frozenset(), replaced: frozenset[str] = frozenset()
               ) -> tuple[dict[str, Any], tuple[str, ...], tuple[str, ...], tuple[int, ...],
                          tuple[str, ...]]:
        """This machine's decision for one tick, nothing moved: the corrected outputs
        (empty when the proposal is kept), reasons, changed atoms, the next state and the
        assumptions broken so far (module docstring).
        ``inputs`` and ``proposed`` hold checked values (:func:`read_value`) of every
        variable the machine reads but the output variables ``unknown`` (proposals that
        could not be read: their atoms are left to the correction and always changed);
        ``replaced`` the proposals replaced (their message is not written)."""
        self.faults, self.scaled = [], []
        ins = tuple([f(inputs) for f in self.in_tests])
        if unknown:
            unk = frozenset(j for v in unknown for j in self.reading.get(v, ()))
            if unk:
                decided, why, what, nxt, gone, outs = self._unknown(ins, proposed, unk,
                                                                     inputs)
                return (self._one_message(decided, outs, proposed, replaced), why, what, nxt,
                        gone)
        both = self._both(inputs, proposed)
        prop = tuple([f(both) for f in self.out_tests])
        safe, nxt = self.move(ins, prop)
        if safe:
            kept = self._whole(proposed, prop) if self.integers else {}
            return (self._one_message(kept, prop, proposed, replaced), (), (), nxt,
                    self._broken(ins, prop) if self.assumed else ())
        key = (self.state, ins, prop)
        got = self.corrections.get(key)
        if got is None:
            outs = self.correct(ins, prop)
            values = list(ins + prop + self.state)
            reasons = tuple(r for r, k in zip(self.reqs, self.keep)
                            if _walk(self.nodes, k, values) != 1)
            if not reasons and _walk(self.nodes, self.ctl_ok, values) == 1:
                reasons = self.reqs  # (no requirement alone: the machine's together)
            changed = tuple(t for t, p, o in zip(self.texts, prop, outs) if p != o)
            if len(self.corrections) >= CACHE_LIMIT:
                self.corrections.clear()
            got = self.corrections[key] = (outs, (reasons if changed else ()), changed,
                                           self._plan(outs, changed))
        outs, reasons, changed, plan = got
        decided = self._twist(self._values(plan, proposed, inputs), proposed, outs, inputs)
        return (self._one_message(decided, outs, proposed, replaced),
                reasons, changed, self.move(ins, outs)[1], self._broken(ins, outs))

    def _one_message(self, values: dict[str, Any], outs: tuple[int, ...],
                     proposed: dict[str, Any], replaced: frozenset[str]) -> dict[str, Any]:
        """``values`` (the decided outputs, a variable missing there keeping its proposal)
        with each message group's made one message (module docstring, :func:`as_message`):
        ``outs`` the decided atoms, ``replaced`` the proposals replaced this tick."""
        twist = {v for t in self.twists for v in t}
        for model, own in self.models:
            decided = {v: values.get(v, proposed.get(v)) for v in own}
            twisted = {v: values.get(v, proposed.get(v)) for v in model["passed"] if v in twist}
            got = as_message(model, outs, self.outs, decided, proposed,
                             any(v in replaced for v in own), twisted)
            if got:
                values = {**values, **got}
        return values

    @property
    def belief(self) -> tuple[tuple[int, ...], ...]:
        """The states the machine may be in (module docstring), the current one first."""
        return (self.state, *self.others)

    def input_cases(self, inputs: dict[str, Any], unread: frozenset[str]
                    ) -> list[tuple[int, ...]]:
        """The valuations of the input atoms this tick may have: each atom that reads no
        variable of ``unread`` its value on ``inputs`` (checked values), each that does
        either value, the valuations real numbers give (``env_ok``) kept, in binary order.
        Past :data:`CASES_LIMIT` valuations, the first ``CASES_LIMIT + 1`` (the caller's
        bound is then passed)."""
        free = sorted({j for v in unread for j in self.reading_in.get(v, ())})
        fixed = [0 if j in free else int(f(inputs)) for j, f in enumerate(self.in_tests)]
        if not free:
            return [tuple(fixed)]
        pad = [0] * (len(self.outs) + len(self.state))
        out: list[tuple[int, ...]] = []
        for k in range(1 << min(len(free), 30)):
            for b, j in enumerate(free):
                fixed[j] = (k >> b) & 1
            if _walk(self.nodes, self.env_ok, fixed + pad) == 1:
                out.append(tuple(fixed))
                if len(out) > CASES_LIMIT:
                    break
        return out

    def decide_cases(self, inputs: dict[str, Any], unread: frozenset[str],
                     proposed: dict[str, Any], unknown: frozenset[str],
                     fallback: tuple[list[int], dict[str, Any]] | None,
                     replaced: frozenset[str] = frozenset()
                     ) -> tuple[dict[str, Any], tuple[str, ...], tuple[str, ...],
                                tuple[tuple[int, ...], ...] | None, tuple[str, ...], str]:
        """:meth:`decide` for a belief of several states or inputs ``unread`` (variables
        whose values could not be read; ``inputs`` holds the others'): the decision safe in
        every case (module docstring), nothing moved. ``fallback``: this machine's fallback
        atoms and the fallback's outputs (None: no fallback); ``replaced`` as for
        :meth:`decide`.

        Returns ``(outputs, reasons, changed, next belief, broken, why)``: the next belief
        sorted, None when the machine no longer knows its state (``why`` then says why and
        the outputs are the fallback's, none without one); ``broken`` the assumptions broken
        in every case."""
        self.faults, self.scaled = [], []
        if self.lost:
            return lost_decision(self, fallback, proposed, "its state is unknown since an "
                                 "earlier tick (" + recovery_of(self) + ")")
        cases = [(st, i) for i in self.input_cases(inputs, unread) for st in self.belief]
        if len(cases) > CASES_LIMIT:
            return lost_decision(self, fallback, proposed,
                                 f"more than {CASES_LIMIT} cases to decide")
        unk = frozenset([*(j for v in unknown for j in self.reading.get(v, ())),
                         *(j for j, reads in self.bound_reads.items() if reads & unread)])
        both = self._both(inputs, proposed)
        prop = tuple([0 if j in unk else f(both) for j, f in enumerate(self.out_tests)])

        def safe_in_all(outs: tuple[int, ...]) -> bool:
            return all(self.move(i, outs, st)[0] for st, i in cases)

        if not unk and safe_in_all(prop):
            outs, reasons, changed = prop, (), ()
            values = self._whole(proposed, prop) if self.integers else {}
        else:
            candidates: list[tuple[int, ...]] = []
            for st, i in cases:
                c = self.correct(i, prop, unk, st)
                if c not in candidates:
                    candidates.append(c)
            if fallback is not None and tuple(fallback[0]) not in candidates:
                candidates.append(tuple(fallback[0]))
            good = [c for c in candidates if safe_in_all(c)]
            if not good:
                return lost_decision(self, fallback, proposed, "no outputs are safe for every "
                                     "value the unreadable input could have had")
            outs = min(good, key=lambda c: (sum(self._cost(j, c[j], prop, unk)
                                                for j in range(len(c))), good.index(c)))
            changed = tuple(t for j, (t, p, o) in enumerate(zip(self.texts, prop, outs))
                            if p != o or j in unk)
            reasons = ()
            if changed and not unk:
                reasons = tuple(r for r, k in zip(self.reqs, self.keep)
                                if any(_walk(self.nodes, k, list(i + prop + st)) != 1
                                       for st, i in cases))
                if not reasons and all(_walk(self.nodes, self.ctl_ok, list(i + prop + st)) == 1
                                       for st, i in cases):
                    reasons = self.reqs  # (no requirement alone: the machine's together)
            values = self._twist(self._values(self._plan(outs, changed), proposed, inputs),
                                 proposed, outs, inputs)
        values = self._one_message(values, outs, proposed, replaced)
        nexts = sorted({self.move(i, outs, st)[1] for st, i in cases})
        if len(nexts) > BELIEF_LIMIT:
            return lost_decision(self, fallback, proposed,
                                 f"more than {BELIEF_LIMIT} states it may be in")
        broken: tuple[str, ...] = ()
        if self.assumed:
            per_case = [set(self._broken(i, outs, st)) for st, i in cases]
            broken = tuple(a for a in self.assume_ids if all(a in b for b in per_case))
        return values, reasons, changed, tuple(nexts), broken, ""

    def _broken(self, ins: tuple[int, ...], outs: tuple[int, ...],
                state: tuple[int, ...] | None = None) -> tuple[str, ...]:
        """The assumptions that have not held at every tick up to this one, with these
        atoms (module docstring)."""
        if not self.assumed:
            return ()
        values = list(ins + outs + (self.state if state is None else state))
        return tuple(a for a, r in zip(self.assume_ids, self.assumed)
                     if _walk(self.nodes, r, values) != 1)

    def _unknown(self, ins: tuple[int, ...], proposed: dict[str, Any], unk: frozenset[int],
                 inputs: dict[str, Any]
                 ) -> tuple[dict[str, Any], tuple[str, ...], tuple[str, ...], tuple[int, ...],
                            tuple[str, ...], tuple[int, ...]]:
        """:meth:`decide` when the output atoms ``unk`` read a proposal that could not be
        read: the safe outputs nearest the rest of the proposal, every atom of ``unk``
        counted changed (its variable's value is never the proposal's); no reason (the
        fault is the proposal's); and the decided atoms."""
        both = self._both(inputs, proposed)
        prop = tuple([0 if j in unk else f(both) for j, f in enumerate(self.out_tests)])
        outs = self.correct(ins, prop, unk)
        changed = tuple(t for j, (t, p, o) in enumerate(zip(self.texts, prop, outs))
                        if p != o or j in unk)
        plan = self._plan(outs, changed)
        return (self._values(plan, proposed, inputs), (), changed, self.move(ins, outs)[1],
                self._broken(ins, outs), outs)

    def _values(self, plan: tuple[dict[str, Any], list[str], list[tuple[Any, ...]]],
                proposed: dict[str, Any], inputs: dict[str, Any]) -> dict[str, Any]:
        """The output values of a correction's :meth:`_plan` for the proposal ``proposed``
        (a variable missing there, a proposal that could not be read, takes the number
        nearest NaN: its region's end) and the tick's readable ``inputs`` (the bounds'
        numbers, :func:`fretc.shield.runtime_bounds.bounded_value`; a bound no number meets
        noted in :attr:`faults`)."""
        fixed, kept, near = plan
        result = dict(fixed)
        for v in kept:
            result[v] = proposed[v]
        for v, specs, truths in near:
            if specs is None:  # (a bounded output)
                idx = self.bound_atoms[v]
                result[v], why = bounded_value(
                    [self.outs[j] for j in idx], truths, [self.bounds.get(j) for j in idx],
                    float(proposed.get(v, math.nan)), inputs,
                    float(self.fallback_numbers.get(v, 0.0)))
                if why:
                    self.faults.append(f"bound {why}")
                continue
            result[v] = nearest(specs, truths, float(proposed.get(v, math.nan)),
                                v in self.integers)
        return result

    def _twist(self, values: dict[str, Any], proposed: dict[str, Any], outs: tuple[int, ...],
               inputs: dict[str, Any]) -> dict[str, Any]:
        """``values`` with each twist scaled as one where the decided atoms ``outs`` still
        hold (:func:`fretc.shield.runtime_bounds.scaled`), noted in :attr:`scaled`."""
        for names in self.twists:
            got = scaled(names, {v: values.get(v, proposed.get(v)) for v in names}, proposed)
            if got is None:
                continue
            trial = {**inputs, **proposed, **values, **got[0]}
            try:
                keeps = all(bool(self.out_tests[j](trial)) == bool(outs[j])
                            for j in {j for v in names for j in self.reading.get(v, ())})
            except (KeyError, ValueError, TypeError):  # (an input a bound reads unread)
                keeps = False
            moved = any(got[0][v] != values.get(v, proposed.get(v)) for v in names)
            if keeps and moved:
                values = {**values, **got[0]}
                self.scaled.append(f"{', '.join(names)} scaled by {got[1]!r} together (the "
                                   "curvature kept)")
        return values

    def _whole(self, proposed: dict[str, Any], prop: tuple[int, ...]) -> dict[str, float]:
        """The whole-number outputs of a proposal kept whole: one that is no whole number
        becomes the whole number nearest it with the same truths (:func:`nearest`; one
        exists: the proposal kept ``ctl_ok``, whose regions of such a variable are those a
        whole number lies in). No comparison changes: not an override."""
        out: dict[str, float] = {}
        for v in self.integers:
            x = float(proposed[v])
            if math.isfinite(x) and x != math.floor(x):
                idx = self.atoms_of[v]
                out[v] = nearest([self.outs[j] for j in idx], [prop[j] for j in idx], x, True)
        return out

    def _plan(self, outs: tuple[int, ...], changed: tuple[str, ...]
              ) -> tuple[dict[str, Any], list[str], list[tuple[Any, ...]]]:
        """How the output variables' values follow from the corrected atoms ``outs``
        (computed once per correction): ``(values fixed by the atoms, variables keeping
        the proposal's value, (variable, comparisons, truths) taking the number nearest the
        proposal's)``. A boolean takes its atom's value; a number the proposal's when its
        comparisons keep their truth, else the nearest number giving them. A number of a
        message group (module docstring) whose boolean atoms an override changed takes the
        number of the message the bindings give for the group's new valuation. The
        variables of a cluster (module docstring) keep the proposal's numbers unless an
        atom of the cluster changed; then they all take the cluster's recorded numbers."""
        result: dict[str, Any] = {}
        kept: list[str] = []
        near: list[tuple[Any, ...]] = []
        for c in self.clusters:
            if any(self.texts[j] in changed for j in c["atoms"]):
                key = sum(int(outs[j]) << k for k, j in enumerate(c["atoms"]))
                result.update(c["numbers"][key])
            else:
                kept += c["variables"]
        fixed: dict[str, float] = {}
        for g in self.groups:
            if any(self.texts[j] in changed and self.outs[j][1] is None for j in g["atoms"]):
                key = sum(int(outs[j]) << k for k, j in enumerate(g["atoms"]))
                fixed.update(g["numbers"].get(key, {}))
        for v, idx in self.bound_atoms.items():
            near.append((v, None, [outs[j] for j in idx]))
        for v, idx in self.atoms_of.items():
            if self.outs[idx[0]][1] is None:
                result[v] = bool(outs[idx[0]])
            elif v in fixed and all(truth(self.outs[j], fixed[v]) == bool(outs[j])
                                    for j in idx) and (v not in self.integers
                                                       or fixed[v] == math.floor(fixed[v])):
                result[v] = fixed[v]
            else:
                near.append((v, [self.outs[j] for j in idx], [outs[j] for j in idx]))
        return result, kept, near


class ShieldRuntime:
    """A shield from its tables (module docstring): :meth:`step` each tick, :meth:`reset` to
    the initial state."""

    def __init__(self, tables: dict[str, Any]):
        self.tables = tables
        self.name = tables["name"]
        self.inputs = tuple(tables["inputs"])
        self.outputs = tuple(tables["outputs"])
        prefs = len(tables.get("preferences", ()))
        #: the fallback (module docstring), None when the shield has none
        self.fallback: dict[str, Any] | None = tables.get("fallback")
        self.machines = [_Machine(t, prefs, self.fallback) for t in tables["machines"]]
        for n, m in enumerate(self.machines):
            m.fallback_bits = (tuple(self.fallback["atoms"][n]) if self.fallback is not None
                               else None)
        self.input_kinds: dict[str, str] = {}
        self.output_kinds: dict[str, str] = {}
        for m in self.machines:
            for v, k in m.in_kinds.items():
                self.input_kinds.setdefault(v, k)
            for v, k in m.out_kinds.items():
                self.output_kinds.setdefault(v, k)
        #: the outputs no machine reads, passed through
        self.passed = [v for v in self.outputs if v not in self.output_kinds]
        #: each output variable of a message group -> the group's variables: read from one
        #: message, replaced together when one cannot be read (module docstring)
        self.mates: dict[str, tuple[str, ...]] = {}
        for m in self.machines:
            for g in m.groups:
                group = tuple(dict.fromkeys([*(m.outs[j][0] for j in g["atoms"]),
                                             *g.get("decides", ())]))
                self.mates.update({v: group for v in group})
        #: the outputs no machine reads that a message group's model writes (module
        #: docstring) or a twist scales: their proposals go to the machines
        self.written = list(dict.fromkeys(
            [*(v for m in self.machines for v in m.passed),
             *(v for m in self.machines for t in m.twists for v in t
               if v not in self.output_kinds)]))
        #: the outputs no machine reads that a twist scales: a proposal of theirs that is
        #: given is checked as a proposal (a NaN or infinite one replaced with its message)
        self.twisted = [v for m in self.machines for t in m.twists for v in t
                        if v not in self.output_kinds]

    def reset(self) -> None:
        """Back to the initial state (before the first tick)."""
        for m in self.machines:
            m.state, m.others, m.lost = m.init, (), False
            m.shadow, m.readable = m.init, 0

    @property
    def state(self) -> tuple[Any, ...]:
        """Each machine's state: its state bits (a tuple of 0/1) while it knows its state,
        else ``("belief", state bits, ...)`` (the states it may be in after a tick with an
        unreadable input, module docstring) or ``("lost", copy's state, readable ticks)``
        (its state unknown; the copy that recovers it, module docstring)."""
        return tuple(("lost", m.shadow, m.readable) if m.lost else ("belief", *m.belief)
                     if m.others else m.state for m in self.machines)

    def restore(self, state: tuple[Any, ...]) -> None:
        """Put back a :attr:`state` read before a step (a host whose tick failed after
        the step, before it published: the tick is then not taken)."""
        for m, bits in zip(self.machines, state, strict=True):
            bits = tuple(bits)
            if bits and bits[0] == "lost":
                m.state, m.others, m.lost = m.init, (), True
                m.shadow, m.readable = ((tuple(bits[1]), int(bits[2])) if len(bits) == 3
                                        else (m.init, 0))
            elif bits and bits[0] == "belief":
                m.state, m.others, m.lost = tuple(bits[1]), tuple(bits[2:]), False
            else:
                m.state, m.others, m.lost = bits, (), False

    def accepts(self, state: tuple[Any, ...], inputs: dict[str, Any],
                outputs: dict[str, Any]) -> bool:
        """Whether ``outputs`` (every output variable's value) keep every requirement
        winnable from ``state`` (as :attr:`state` gave it: every state of a belief) with
        ``inputs`` (an input that cannot be read: with every value it could have had);
        nothing advances. A host publishing a tick's outputs as several messages uses it to
        order them so that a sampler between two of them sees an accepted valuation.

        Raises:
            Unreadable (a ValueError): a value the step could not read."""
        ins, unread = self._readable(inputs)
        outs = {v: read_value(v, k, outputs, True) for v, k in self.output_kinds.items()}
        for m, held in zip(self.machines, state):
            both = m._both(ins, outs)
            out_bits = [f(both) for f in m.out_tests]
            bits: tuple[Any, ...] = tuple(held)
            if bits and bits[0] == "lost":
                continue  # (the fallback's outputs: any order)
            for st in (bits[1:] if bits and bits[0] == "belief" else (bits,)):
                for i in m.input_cases(ins, frozenset(unread)):
                    if _walk(m.nodes, m.safe, list(i) + out_bits + list(st)) != 1:
                        return False
        return True

    def step(self, inputs: dict[str, Any], proposed: dict[str, Any]) -> Decision:
        """One tick: ``inputs`` maps every input variable to its value (bool, or a number
        for a numeric one), ``proposed`` every output variable to the controller's value.
        Returns the :class:`Decision`: the proposal unchanged when it keeps every
        requirement winnable (but for a whole-number output's proposal that is no whole
        number: the nearest whole number with its truths, not an override), else the nearest
        safe outputs and the requirements that forced them. Output variables no enforced
        requirement reads are passed through. All or nothing (module docstring): a value
        that cannot be read never raises; an input leaves the state as it was and gives the
        fallback (``Decision.fault`` says why), a proposal is replaced."""
        unread: dict[str, str] = {}
        try:
            ins = _checked(self.input_kinds, inputs, False)
        except Unreadable:
            ins, unread = self._readable(inputs)
        try:  # (the common case: every proposal readable)
            props = _checked(self.output_kinds, proposed, True)
            if self.twisted:
                _checked({v: "n" for v in self.twisted if v in proposed}, proposed, True)
            faults: list[str] = []
            replaced: list[str] = []
            frozen: frozenset[str] = frozenset()
        except Unreadable:
            props, faults, replaced, frozen = self._replaced(proposed)
        if self.written:
            props = {**{v: proposed[v] for v in self.written if v in proposed}, **props}
        if unread or any(m.others or m.lost for m in self.machines):
            return self._step_cases(ins, frozenset(unread), props, faults, replaced, frozen,
                                    proposed, [f"input {why}" for why in unread.values()])
        # every machine decides before any moves: a step is all or nothing
        moves = [m.decide(ins, props, frozen, frozenset(replaced)) for m in self.machines]
        outputs = {v: proposed[v] for v in self.passed if v in proposed}
        outputs.update(props)
        reasons: list[str] = []
        changed: list[str] = []
        broken: list[str] = []
        for m, (values, why, what, nxt, gone) in zip(self.machines, moves):
            m.state = nxt
            if values:
                outputs.update(values)
            if what:
                reasons += why
                changed += what
            if gone:
                broken += gone
            if replaced:  # (a replaced proposal's atoms are changed, whatever their truth)
                changed += [m.texts[j] for v in replaced for j in m.reading.get(v, ())
                            if m.texts[j] not in what]
        if broken:  # (the guarantee no longer holds: the fallback, as for unread inputs)
            outs, moved = self._fallback_outputs(proposed)
            return Decision(outs, True, tuple(reasons), moved, "; ".join(faults),
                            tuple(broken))
        if len(outputs) != len(self.outputs):  # (a missing output no machine reads)
            outputs = {v: outputs[v] for v in self.outputs if v in outputs}
        faults += [n for m in self.machines for n in m.faults]
        return Decision(outputs, bool(changed) or bool(faults), tuple(reasons),
                        tuple(changed), "; ".join(faults),
                        scaled=tuple(n for m in self.machines for n in m.scaled))

    def _readable(self, inputs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str]]:
        """The input values that can be read (:func:`read_value`), and each other input
        variable -> why not (module docstring: it is any value)."""
        ins: dict[str, Any] = {}
        unread: dict[str, str] = {}
        for v, k in self.input_kinds.items():
            try:
                ins[v] = read_value(v, k, inputs)
            except Unreadable as exc:
                unread[v] = str(exc)
        return ins, unread

    def _step_cases(self, ins: dict[str, Any], unread: frozenset[str], props: dict[str, Any],
                    faults: list[str], replaced: list[str], frozen: frozenset[str],
                    proposed: dict[str, Any], input_faults: list[str]) -> Decision:
        """:meth:`step` when an input cannot be read or a machine's belief holds several
        states (module docstring): each machine decides for every case
        (:meth:`_Machine.decide_cases`), all before any moves."""
        fb = self.fallback
        moves = [m.decide_cases(ins, unread, props, frozen,
                                (fb["atoms"][k], fb["outputs"]) if fb is not None else None,
                                frozenset(replaced))
                 for k, m in enumerate(self.machines)]
        outputs = {v: proposed[v] for v in self.passed if v in proposed}
        outputs.update(props)
        reasons: list[str] = []
        changed: list[str] = []
        broken: list[str] = []
        notes = list(input_faults)
        silent = False
        unknown_state: list[str] = []
        recovered: list[str] = []
        for m, (values, why, what, nxt, gone, lost_why) in zip(self.machines, moves):
            if nxt is None:
                lost_why, known = settle_lost(m, lost_why, ins, unread)
                recovered += m.reqs if known else ()
                unknown_state += m.reqs
                notes.append(f"the machine of {', '.join(m.reqs)}: {lost_why}")
                if not values:
                    silent = True
            else:
                m.state, m.others = nxt[0], nxt[1:]
            outputs.update(values)
            reasons += why
            changed += what
            broken += gone
            if replaced:
                changed += [m.texts[j] for v in replaced for j in m.reading.get(v, ())
                            if m.texts[j] not in what]
        fault = "; ".join(notes + faults)
        lost = tuple(unknown_state)
        back = tuple(recovered)
        if broken:
            outs, moved = self._fallback_outputs(proposed)
            return Decision(outs, True, tuple(reasons), moved, fault, tuple(broken), lost,
                            recovered=back)
        if silent:
            return Decision({}, True, tuple(reasons), tuple(changed), fault, (), lost,
                            recovered=back)
        outputs = {v: outputs[v] for v in self.outputs if v in outputs}
        bound = [n for m in self.machines for n in m.faults]
        return Decision(outputs, bool(changed) or bool(faults) or bool(bound), tuple(reasons),
                        tuple(changed), "; ".join([fault, *bound]) if fault else "; ".join(bound),
                        (), lost, tuple(n for m in self.machines for n in m.scaled), back)

    def _replaced(self, proposed: dict[str, Any]
                  ) -> tuple[dict[str, Any], list[str], list[str], frozenset[str]]:
        """A proposal some of whose values cannot be read (module docstring): the values
        read, each other and every variable of its message group (:attr:`mates`) replaced
        by the fallback's (or left to the correction: the ``unknown`` variables); the faults
        and the replaced variables."""
        props: dict[str, Any] = {}
        unknown: set[str] = set()
        faults: list[str] = []
        bad: set[str] = set()
        fallback = self.fallback["outputs"] if self.fallback is not None else {}
        checked = {**self.output_kinds, **{v: "n" for v in self.twisted if v in proposed}}
        for v, k in checked.items():
            try:
                props[v] = read_value(v, k, proposed, True)
            except Unreadable as exc:
                faults.append(f"proposal {exc}")
                bad.add(v)
        replaced = [v for v in self.output_kinds
                    if v in bad or any(w in bad for w in self.mates.get(v, ()))]
        for v in replaced:
            if v in fallback:
                props[v] = fallback[v]
            else:
                props.pop(v, None)
                unknown.add(v)
        for v in self.twisted:  # (a twist's output no requirement reads: the fallback's, or rest)
            if v in bad or any(w in bad for w in self.mates.get(v, ())):
                props[v] = float(fallback.get(v, 0.0))
        return props, faults, replaced, frozenset(unknown)

    def fault(self, why: str, proposed: dict[str, Any]) -> Decision:
        """The decision of a tick the host could not decide on (``why`` says why, e.g. its
        messages could not be made; an unreadable input is decided by :meth:`step` as any
        value, module docstring): the fallback's outputs (none without a fallback), every
        machine's state as it was;
        ``changed`` the output atoms whose fallback truth is not the proposal's (or whose
        proposal cannot be read either)."""
        if self.fallback is None:
            return Decision({}, True, (), (), why + "; no fallback: no outputs")
        outputs, changed = self._fallback_outputs(proposed)
        return Decision(outputs, True, (), changed, why)

    def _fallback_outputs(self, proposed: dict[str, Any]
                          ) -> tuple[dict[str, Any], tuple[str, ...]]:
        """The fallback's outputs (none without a fallback; the outputs no machine reads
        passed through) and the output atoms whose fallback truth is not the proposal's
        (or whose proposal cannot be read)."""
        if self.fallback is None:
            return {}, ()
        outputs = {v: proposed[v] for v in self.outputs
                   if v not in self.output_kinds and v in proposed}
        outputs.update(self.fallback["outputs"])
        checked: dict[str, Any] = {}
        for v, k in self.output_kinds.items():
            try:
                checked[v] = read_value(v, k, proposed, True)
            except Unreadable:
                pass
        changed: list[str] = []
        for m, bits in zip(self.machines, self.fallback["atoms"]):
            for j, (spec, f, t) in enumerate(zip(m.outs, m.out_tests, m.texts)):
                need = term_variables(spec[2]) if spec[1] == "pred" else {spec[0]}
                if not need <= checked.keys() or int(f(checked)) != bits[j]:
                    changed.append(t)
        return {v: outputs[v] for v in self.outputs if v in outputs}, tuple(changed)
