"""Realizability of requirement sets for ``fretc check``.

Design notes: ARCHITECTURE.md, `check/realizability.py`."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from typing import Any, TYPE_CHECKING

from fretc.common.errors import CheckError

from fretc.compiler import ir
from fretc.check.findings import Finding
from fretc.check.findings import ids as _ids
from fretc.check.findings import subsets_text
from fretc.check.checker import SPOT_MAX_BOUND
from fretc.check.smt import max_bound
from fretc.check.solver import UNKNOWN
from fretc.check.witness import formula_atoms
from fretc.check.bounds import Bound, bounds_of, feasibility
from fretc.check.numeric_abstraction import NumericAbstraction, simple_comparison
from fretc.check.predicates import PredicateBudget, clusters, mixed_invariants
from fretc.check.safety_game import Outside, game_atoms, letter_name
from fretc.check.streams import CheckStream, check_streams, stream_roles
from fretc.compiler.printers import mangle, to_smv, to_spot

if TYPE_CHECKING:
    from fretc.check.findings import CheckResult
    from fretc.check.checker import Checker

__all__ = ["check_realizability", "RealizabilityError", "MACHINE",
           "undeclared_variables"]

#: who moves first in the game: at each tick the environment sets the inputs, then the
#: controller sets the outputs knowing them (a Mealy machine; Spot's ``ltl_to_game`` and
#: ``ltlsynt`` default). A Moore machine would set the outputs before seeing the inputs.
MACHINE = ("Mealy: each tick the environment sets the inputs first, the controller then "
           "sets the outputs knowing them")


class RealizabilityError(CheckError, ValueError):
    """Bad input/output declarations (a variable both input and output)."""


def _atom_vars(atom) -> list[str]:
    return [ir.name_of(n) for n in ir.walk(atom) if n.op in ("ap", "var")]


def check_realizability(checker: Checker, result: CheckResult, inputs: Sequence[str],
                        outputs: Sequence[str],
                        streams: dict[str, CheckStream] | None = None) -> dict:
    """Decide realizability per group; append ``unrealizable`` / ``unknown`` findings
    to ``result`` and return the JSON-able summary (module docstring). A group reading
    a variable in neither ``inputs`` nor ``outputs`` is not decided: its entry's
    ``realizable`` is None, its ``undeclared`` the variables with the requirements reading
    them, and an ``undeclared`` finding (severity ``input``: exit 2) says how to declare them.
    ``streams``: the FRET stream variables the items read (:mod:`fretc.check.streams`;
    None: :func:`fretc.check.streams.check_streams` of the items): each takes the role of
    the variables its definition reads (the summary's ``streams``), a variable its
    definition reads declared neither is named with the stream reading it, and an answer
    won by the player a stream is given to is unknown (the stream is free to it at each
    tick, where its definition fixes it). A stream declared an input or an output is that
    variable, as declared.

    Raises :class:`RealizabilityError` when a variable is declared both input and output.
    """
    inputs, outputs = list(dict.fromkeys(inputs)), list(dict.fromkeys(outputs))
    both = sorted(set(inputs) & set(outputs))
    if both:
        raise RealizabilityError("declared both input and output: " + ", ".join(both))
    streams = check_streams(checker.items) if streams is None else streams
    # (a stream declared an input or output is that: read from the system, as it says)
    streams = {n: s for n, s in streams.items() if n not in inputs and n not in outputs}
    roles, _ = stream_roles(streams, inputs, outputs)
    used = []
    for x in checker.items:
        for v in x.variables:
            for u in (streams[v].reads if v in streams else (v,)):
                if u not in used:
                    used.append(u)
    declared = set(inputs) | set(outputs)
    summary: dict[str, Any] = {"machine": MACHINE, "inputs": inputs, "outputs": outputs,
               "undeclared": [v for v in used if v not in declared],
               "unused": [v for v in inputs + outputs if v not in used],
               "groups": []}
    if streams:
        summary["streams"] = {n: {"reads": list(s.reads), "role": roles.get(n)}
                              for n, s in sorted(streams.items())}
    decide = _Decider(checker, inputs + [n for n, r in roles.items() if r == "input"], roles)
    for comp in checker.groups():
        entry: dict = {"requirements": _ids(comp)}
        readers = undeclared_variables(comp, declared, streams)
        if readers:  # (FRET's rule: no role assumed, the group not decided)
            entry["realizable"] = None
            entry["undeclared"] = readers
            result.findings.append(_undeclared_finding(comp, readers, streams))
            summary["groups"].append(entry)
            continue
        ans = decide(comp)
        if ans == UNKNOWN:
            entry["realizable"] = "unknown"
            why = decide.inexact.get(tuple(x.index for x in comp))
            if why:
                entry["why"] = why
            result.findings.append(Finding(
                "unknown", "unknown", _ids(comp),
                "realizability of " + ", ".join(_ids(comp)) + " unknown: " + (
                    why or "the game ran past its work or memory budget (--budget, "
                    "--memory-budget) or Spot could not take it (see the notes)")))
        elif ans["realizable"]:
            entry["realizable"] = True
            entry["method"] = ans["method"]
            for k in ("mealy_states", "strategy"):
                if k in ans:
                    entry[k] = ans[k]
        else:
            _unrealizable(checker, decide, comp, ans, inputs, entry, result)
        summary["groups"].append(entry)
    result.notes.extend(decide.notes)
    return summary


def undeclared_variables(items: Sequence[Any], declared: set[str] | frozenset[str],
                         streams: dict[str, CheckStream] | None = None
                         ) -> dict[str, list[str]]:
    """The variables of the check items ``items`` (:class:`fretc.check.items.CheckItem`)
    that are not in ``declared`` (the inputs and the outputs), each with the ids of the
    requirements that read it, in the order the requirements read them. A stream variable
    of ``streams`` (:mod:`fretc.check.streams`) is not one: the variables its definition
    reads are, read by the requirements reading it."""
    streams = streams or {}
    out: dict[str, list[str]] = {}
    for x in items:
        for v in x.variables:
            for u in (streams[v].reads if v in streams else (v,)):
                if u not in declared:
                    out.setdefault(u, [])
                    if x.id not in out[u]:
                        out[u].append(x.id)
    return out


def _undeclared_finding(comp: Sequence[Any], readers: dict[str, list[str]],
                        streams: dict[str, CheckStream] | None = None) -> Finding:
    """The ``undeclared`` finding of a group whose realizability is not decided:
    ``readers`` (:func:`undeclared_variables`) in words, with the FRET kind an export gives
    a variable (an Internal or Mode variable fretc reads as a free one), the stream
    variables of ``streams`` whose definitions read it, and how to declare them. Its
    severity ``input`` makes the exit code 2 (an input error, as FRET refuses to check
    realizability then); the checks that need no roles are reported as ever."""
    fret: dict[str, Any] = {}
    why: dict[str, str] = {}  # (a definition fretc reads as a free variable: why)
    for x in comp:
        variables = tuple(getattr(x.compiled.entry, "variables", ()) or ())
        for v in variables:
            if v.name in readers and v.kind:
                fret.setdefault(v.name, v)
                if v.kind in ("Internal", "Mode") and v.name not in why:
                    from fretc.fretish.fret_definitions import definitions

                    reason = definitions(variables).free.get(v.name)
                    if reason:
                        why[v.name] = reason
    via = _through_streams(comp, readers, streams or {})
    names = [f"{v} (read by {', '.join(ids)}" + (
        f"{' through' if v in via[0] else ', and by'} the stream variable"
        f"{'s' * (len(via[1][v]) > 1)} {', '.join(via[1][v])}" if v in via[1] else "")
        + ")" for v, ids in readers.items()]
    listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
    kinds = [f"{v} {'an' if f.kind[0] in 'AEIOU' else 'a'} {f.kind}"
             + (f" of {f.component}" if f.component else "")
             + ("" if f.kind in ("Input", "Output") else ", a free variable to fretc")
             + (f" ({why[v]})" if v in why else "")
             for v, f in fret.items()]
    one = len(readers) == 1
    involved = [i for i in _ids(comp) if any(i in ids for ids in readers.values())]
    msg = ("realizability of " + ", ".join(_ids(comp)) + " not checked: " + listed
           + (" is" if one else " are") + " declared neither input nor output"
           + (" (FRET's export: " + "; ".join(kinds) + ")" if kinds else "")
           + "; declare " + ("it" if one else "each") + " with --inputs or --outputs, "
           "@inputs/@outputs in the .fret file, or its Input/Output role in FRET's glossary "
           "(as FRET, realizability is checked only when every variable is the "
           "environment's or the controller's)")
    details: dict[str, Any] = {"undeclared": readers, "group": _ids(comp)}
    if why:
        details["free_definitions"] = why
    if via[1]:
        details["through_streams"] = via[1]
    return Finding("undeclared", "input", involved, msg, details=details)


def _through_streams(comp: Sequence[Any], readers: dict[str, list[str]],
                     streams: dict[str, CheckStream]) -> tuple[set[str], dict[str, list[str]]]:
    """Of the undeclared ``readers``: those no requirement of ``comp`` reads itself (only
    through streams), and each one's streams of ``streams`` read by ``comp`` whose
    definitions read it (FRET's rule names a definition's own inputs)."""
    read = {v for x in comp for v in x.variables}
    via = {u: sorted(n for n, s in streams.items() if n in read and u in s.reads)
           for u in readers}
    return ({u for u in readers if u not in read},
            {u: names for u, names in via.items() if names})


class _Decider:
    """Realizability of a set of requirement items, memoized by the set. Safety
    requirements go to the symbolic safety game (:mod:`fretc.check.safety_game`) unless the
    engine is ``spot``; the rest to Spot's synthesis game. An unrealizable safety part makes
    the whole set unrealizable (a subset's environment strategy defeats the superset);
    otherwise a set with a requirement that is not safety is Spot's. Returns UNKNOWN or a
    dict: ``realizable``, ``method``, and ``mealy_states`` / ``strategy`` (realizable) or
    ``counter`` (the input lasso or None), ``note``, ``run`` (unrealizable)."""

    def __init__(self, checker, inputs: list[str], roles: dict[str, str] | None = None):
        self.checker, self.inputs = checker, inputs
        #: stream variable -> "input" or "output" (:func:`fretc.check.streams.stream_roles`)
        self.roles = roles or {}
        self.cache: dict[tuple, Any] = {}
        self.notes: list[str] = []
        #: items' indexes -> why Spot's answer for them was not exact (they are UNKNOWN)
        self.inexact: dict[tuple, str] = {}

    def __call__(self, items) -> Any:  # UNKNOWN or a dict
        key = tuple(x.index for x in items)
        if key not in self.cache:
            ans = None
            if self.checker.engine != "spot":
                ans = self._game(items)
            ans = ans if ans is not None else self._spot(items)
            self.cache[key] = self._streams_won(items, ans)
        return self.cache[key]

    def _streams_won(self, items, ans) -> Any:  # UNKNOWN or a dict
        """``ans``, or UNKNOWN when the player that wins it was given a stream variable
        (:mod:`fretc.check.streams`: free to it at each tick, where its definition fixes it
        from the past), as a win over a comparison reading a previous value proves nothing
        (:func:`_predicate_invariants`)."""
        if ans == UNKNOWN:
            return ans
        side = "output" if ans["realizable"] else "input"
        won = sorted({v for x in items for v in x.variables if self.roles.get(v) == side})
        if not won:
            return ans
        self.checker.unknown += 1
        player = "controller" if ans["realizable"] else "environment"
        self.inexact[tuple(x.index for x in items)] = (
            ("realizable" if ans["realizable"] else "unrealizable") + " with the stream "
            f"variable{'s' * (len(won) > 1)} {', '.join(won)} given to the {player} (the "
            "role of the variables its definition reads), free at each tick where its "
            "definition fixes it from the past: the {player}'s win proves nothing".replace(
                "{player}", player))
        return UNKNOWN

    def _game(self, items) -> Any:  # UNKNOWN or a dict
        """The symbolic games' answer, or None when Spot has to decide (module docstring):
        the safety game of the safety requirements; when it is won and other requirements
        remain, the Büchi game of the whole set (:mod:`fretc.check.buchi_game`)."""
        safe = [x for x in items if x.pt is not None]
        rest = [x for x in items if x.pt is None]
        if safe:
            ans = self._safety(safe, items)
            if ans is None or not rest or ans == UNKNOWN or not ans["realizable"]:
                return ans
        return self._buchi(safe, rest)

    def _safety(self, safe, items) -> Any:  # UNKNOWN or a dict
        """The safety game of ``safe`` (the safety requirements of ``items``)."""
        checker = self.checker
        pts = [x.pt for x in safe]
        regions = self._regions(pts, "safety game", safe)
        if regions is None:
            return None
        checker.queries += 1
        ans = checker.worker.ask(("safety_game", pts, self.inputs, *regions))
        if ans == UNKNOWN:
            checker.unknown += 1
            self._note(f"the safety game of {', '.join(_ids(safe))} answered unknown: "
                       + self._why())
            return UNKNOWN if len(safe) == len(items) else None
        out = {"realizable": ans["realizable"], "method": "safety game"}
        if ans["realizable"]:
            out["strategy"] = ans["strategy"]
        else:
            letters = ans["inputs"]
            out["counter"] = (letters, letters[-1:]) if letters else None
            out["note"] = ans["note"]
            out["run"] = ans["run"]
        return out

    def _regions(self, formulas, method: str, items) -> tuple | None:
        """The numeric regions of the environment's and of the controller's variables in
        ``formulas`` (the games' ``env_inv``, ``ctl_inv``), or None (noted) when an atom is
        one the games cannot give a player."""
        try:
            game_atoms(formulas)
        except Outside as exc:
            self._note(f"{method} not used for {', '.join(_ids(items))}: {exc}")
            return None
        numeric = NumericAbstraction.of(formulas)
        return (numeric.regions([v for v in numeric.atoms if v in self.inputs]),
                numeric.regions([v for v in numeric.atoms if v not in self.inputs]))

    def _why(self) -> str:
        """The reason of the worker's last unknown answer."""
        failures = self.checker.worker.failures
        return failures[-1] if failures else "no reason given"

    def _buchi(self, safe, rest, search: bool = False) -> Any:  # UNKNOWN or a dict
        """The Büchi game of ``safe`` (pt monitors) and ``rest`` (Spot's deterministic
        automata of their ft_inf), or None (Spot's game decides). With ``search``, a lost
        game comes with an input lasso that defeats every controller when one is found."""
        checker, items = self.checker, sorted(safe + rest, key=lambda x: x.index)
        pts, live = [x.pt for x in safe], [x.phi for x in rest]
        names = ", ".join(_ids(items))
        regions = self._regions(pts + live, "Büchi game", items)
        if regions is None:
            return None
        checker.queries += 1
        ans = checker.worker.ask(("buchi_game", pts, live, self.inputs, *regions, search))
        if ans == UNKNOWN or "outside" in ans:
            if ans == UNKNOWN:
                checker.unknown += 1
            self._note(f"the Büchi game of {names} "
                       + (f"answered unknown ({self._why()})" if ans == UNKNOWN
                          else f"was not used: {ans['outside']}") + "; Spot's game decides")
            return None
        if ans["realizable"]:
            return {"realizable": True, "method": "Büchi game", "strategy": ans["strategy"]}
        return {"realizable": False, "method": "Büchi game", "counter": ans.get("inputs"),
                "note": ans.get("note", ""), "run": ans.get("run", [])}

    def witness(self, items, ans: dict) -> dict:
        """``ans`` (an unrealizable answer for ``items``) with the Büchi game's input lasso
        searched for (the minimal-subset enumeration asks the games without it)."""
        if ans["method"] != "Büchi game" or ans["counter"] is not None:
            return ans
        safe = [x for x in items if x.pt is not None]
        rest = [x for x in items if x.pt is None]
        found = self._buchi(safe, rest, search=True)
        return found if isinstance(found, dict) and not found["realizable"] else ans

    def _note(self, text: str) -> None:
        if text not in self.notes:
            self.notes.append(text)

    def _spot(self, items) -> Any:  # UNKNOWN or a dict
        """Spot's synthesis game on the ft_inf formulas (as before the safety game)."""
        checker, inputs = self.checker, self.inputs
        phis = [x.phi for x in items]
        env_clusters, ctl_clusters, ctl_why, env_why, orders = _predicate_invariants(
            phis, inputs, self.roles)
        atoms = formula_atoms(phis + orders)
        outs = sorted({letter_name(a) for a in atoms
                       if not all(v in inputs for v in _atom_vars(a))})
        in_vars = sorted({c[0] for a in atoms if a.op == "cmp"
                          and (c := simple_comparison(a)) and c[0] in inputs})
        out_vars = sorted({c[0] for a in atoms if a.op == "cmp"
                           and (c := simple_comparison(a)) and c[0] not in inputs})
        # (the bounds' order comparisons with constants join the inputs' regions)
        numeric = NumericAbstraction.of(phis + orders) if orders else checker.numeric
        inv_in = ir.and_all(*(numeric.variable_invariant(v) for v in in_vars),
                            env_clusters)
        inv_out = ir.and_all(*(numeric.variable_invariant(v) for v in out_vars),
                             ctl_clusters)
        if inv_in.op == "true":  # a conjunction: one automaton per conjunct
            parts = [p for p in phis + [inv_out] if p.op != "true"] or [ir.TRUE]
            spec_text: str | tuple[str, ...] = tuple(to_spot(p) for p in parts)
        else:
            spec_text = to_spot(ir.implies(inv_in, ir.and_(ir.and_all(*phis), inv_out)))
        checker.queries += 1
        bound = max_bound(phis)
        if bound > SPOT_MAX_BOUND:  # a translation past it may not end: refused up front
            ans = checker.worker.refuse(f"Spot is given tick bounds up to {SPOT_MAX_BOUND}, "
                                        f"the synthesis game of {', '.join(_ids(items))} "
                                        f"has {bound}")
        else:
            ans = checker.worker.ask(("realizable", spec_text, outs))
        if ans == UNKNOWN:
            checker.unknown += 1
            return UNKNOWN
        if ans[0] and ctl_why or not ans[0] and env_why:
            checker.unknown += 1
            self.inexact[tuple(x.index for x in items)] = (
                ("realizable" if ans[0] else "unrealizable")
                + " over the propositional abstraction only: "
                + "; ".join(ctl_why if ans[0] else env_why))
            return UNKNOWN
        if ans[0]:
            return {"realizable": True, "method": "Spot's synthesis game",
                    "mealy_states": ans[1]}
        return {"realizable": False, "method": "Spot's synthesis game", "counter": ans[1],
                "note": "", "run": []}


def _predicate_invariants(phis: Sequence[ir.Node], inputs: Sequence[str],
                          streams: Collection[str] = ()
                          ) -> tuple[ir.Node, ir.Node, list[str], list[str], list[ir.Node]]:
    """The comparisons of several variables in ``phis`` made exact for Spot's game
    (:mod:`fretc.check.predicates`): ``(environment's invariant, controller's invariant, why
    a realizable answer is not exact, why an unrealizable one is not)``, the invariants ``G``
    of the clusters' valuations that numbers realize. A cluster z3 cannot decide tick by tick
    (a previous value, ``preReal``; past its budget) leaves its player free to choose truth
    values no numbers give: a win of that player proves nothing. A cluster of inputs and
    outputs gives the controller only the choices numbers realize whatever the inputs'
    numbers (:func:`fretc.check.predicates.mixed_invariants`): its wins are sound, its losses
    are not; except a comparison of one output with a term over the inputs (a bound,
    :mod:`fretc.check.bounds`, the shield's atoms too): which of its truth values numbers
    give at a tick is the environment's move, the order comparisons of the bounds (returned
    last, the environment's atoms) with the controller's invariant saying which truth values
    each order allows, exact both ways. A comparison reading a stream variable of
    ``streams`` is undecided as one reading a previous value
    (:func:`fretc.check.predicates.undecidable`)."""
    undecided: list = []
    bounds = _exact_bounds(phis, inputs, streams)
    orders, feasible = _feasible(phis, bounds)
    plain = [_without_bounds(f, bounds) for f in phis]
    try:
        found = clusters(plain + ([ir.and_all(*orders)] if orders else []), inputs,
                         undecided=undecided, streams=streams)
    except PredicateBudget as exc:
        return ir.TRUE, ir.TRUE, [str(exc)], [str(exc)], []
    env_inv: list[ir.Node] = []
    ctl_inv: list[ir.Node] = []
    ctl_why: list[str] = []
    env_why: list[str] = []
    for c, why in [(c, None) for c in found] + undecided:
        ins = [v for v in c.variables if v in inputs]
        text = (f"{', '.join(to_smv(a) for a in c.atoms)} compare the input(s) "
                f"{', '.join(ins)} with the output(s) "
                f"{', '.join(v for v in c.variables if v not in inputs)}")
        if ins and len(ins) < len(c.variables) and why is None:
            try:
                env, ctl = mixed_invariants(c, inputs)
            except PredicateBudget as exc:
                ctl_why.append(str(exc))
                env_why.append(str(exc))
                continue
            env_inv.append(env)
            ctl_inv.append(ctl)
            env_why.append(text + ": the game's controller, which sees their truth values "
                           "and not the numbers, is given only the choices numbers realize "
                           "whatever the inputs' numbers, and a controller that reads the "
                           "numbers may do better")
        elif ins and len(ins) < len(c.variables):
            text = (f"{why}; {text}, and the game may give them truth values no numbers "
                    "give")
            ctl_why.append(text)
            env_why.append(text)
        elif why is not None:
            side = "environment" if c.is_input else "controller"
            (env_why if c.is_input else ctl_why).append(
                f"{why}, and the game's {side} may give it truth values no numbers give")
        else:
            (env_inv if c.is_input else ctl_inv).append(c.invariant)
    env, ctl = ir.and_all(*env_inv), ir.and_all(*ctl_inv, feasible)
    return (ir.TRUE if env.op == "true" else ir.G(env),
            ir.TRUE if ctl.op == "true" else ir.G(ctl), ctl_why, env_why, orders)


def _exact_bounds(phis: Sequence[ir.Node], inputs: Sequence[str], streams: Collection[str]
                  ) -> dict[ir.Node, Bound]:
    """The bounds of ``phis`` read exactly (:mod:`fretc.check.bounds`): those of outputs
    compared with no constant by ``=``/``!=`` (no half-line) and in no other comparison of
    several variables, reading no controller's stream variable (an environment's stream, a
    role ``"input"`` in a mapping ``streams``, is an input: its number is the tick's, as
    ``preReal`` of an input is); the others stay comparisons of inputs and outputs
    (:func:`fretc.check.predicates.mixed_invariants`)."""
    if isinstance(streams, Mapping):
        streams = [n for n, role in streams.items() if role != "input"]
    bounds = bounds_of(phis, inputs)
    other: set[str] = set()
    for f in phis:
        for n in ir.walk(f):
            if n.op != "cmp" or n in bounds:
                continue
            sc = simple_comparison(n)
            if sc is None or sc[1] in ("=", "!="):
                other.update(ir.name_of(x) for x in ir.walk(n) if x.op == "var")
    return {a: b for a, b in bounds.items() if b.output not in other
            and not set(ir.variables(a)) & set(streams)}


def _feasible(phis: Sequence[ir.Node], bounds: dict[ir.Node, Bound]
              ) -> tuple[list[ir.Node], ir.Node]:
    """The order comparisons of ``bounds`` and the controller's invariant
    (:func:`fretc.check.bounds.feasibility`), with the comparisons of the bounded outputs
    with constants in ``phis``."""
    if not bounds:
        return [], ir.TRUE
    bounded = {b.output for b in bounds.values()}
    numeric = NumericAbstraction.of(phis)
    return feasibility(list(bounds.values()),
                       [a for v in bounded for a in numeric.atoms.get(v, [])])


def _without_bounds(f: ir.Node, bounds: dict[ir.Node, Bound]) -> ir.Node:
    """``f`` with each bound replaced by a boolean atom (a bound is no cluster's)."""
    if not bounds:
        return f
    names = {a: ir.ap(f"__bound_{k}") for k, a in enumerate(bounds)}

    def sub(n: ir.Node) -> ir.Node:
        got = names.get(n)
        if got is not None:
            return got
        if not n.args or n.op in ("cmp", "var", "num", "arith", "fn", "neg", "pre"):
            return n
        return ir.rebuild(n, tuple(sub(a) for a in n.args))
    return sub(f)


def _unrealizable(checker, decide: _Decider, comp, ans: dict, inputs: list[str],
                  entry: dict, result) -> None:
    """Fill ``entry`` for an unrealizable group (minimal unrealizable subsets, the
    environment's input lasso, a controller's best effort along it) and append the finding
    to ``result``."""
    entry["realizable"] = False
    entry["method"] = ans["method"]
    ans = decide.witness(comp, ans)
    found = checker.minimal_subsets(
        comp, [], lambda s: (UNKNOWN if decide(s) == UNKNOWN else not decide(s)["realizable"]))
    names = [_ids(s) for s in found.subsets]
    cut = found.cut
    entry["minimal_unrealizable"] = names
    entry["standing"] = found.standing
    entry["cut"] = cut
    inputs = [v for v in inputs if v in _variables(comp)]  # (the group's own)
    phis = [x.phi for x in comp]
    orders = _feasible(phis, _exact_bounds(phis, decide.inputs, decide.roles))[0]
    numeric = NumericAbstraction.of(phis + orders) if orders else checker.numeric
    env = _environment(numeric, ans["counter"], inputs, ans["note"])
    entry["environment"] = env
    if ans["run"]:
        entry["run"] = [_values(numeric, letter, _variables(comp)) for letter in ans["run"]]
    involved = sorted({i for s in names for i in s}, key=_ids(comp).index) or _ids(comp)
    msg = ("no controller meets " + ", ".join(_ids(comp)) + " whatever the inputs ("
           + (", ".join(inputs) or "none") + ") do: "
           + subsets_text(names, found.standing, "unrealizable subset")
           + (f" (enumeration cut by its budget of {checker.mus_budget} subset checks)"
              if cut else ""))
    result.findings.append(Finding("unrealizable", "error", involved, msg,
                                   subsets=names, standing=found.standing, cut=cut,
                                   details={"environment": env,
                                            "run": entry.get("run", [])}))


def _environment(numeric: NumericAbstraction, counter, inputs: Sequence[str],
                 note: str = "") -> dict:
    """The input lasso as rows of input values, or a note when none exists."""
    if counter is None:
        return {"note": note or "no fixed input sequence defeats every controller: the "
                                "environment must react to the outputs"}
    prefix, cycle = counter
    return {"prefix": [_values(numeric, x, inputs) for x in prefix],
            "cycle": [_values(numeric, x, inputs) for x in cycle],
            "note": "inputs tick by tick: the prefix, then the cycle repeated forever; no "
                    "output sequence meets the requirements along it"}


def _variables(comp) -> list[str]:
    out: list[str] = []
    for x in comp:
        out += [v for v in x.variables if v not in out]
    return out


def _values(numeric: NumericAbstraction, letter: dict, names: Sequence[str]) -> dict:
    """One tick's letter ``{atom name: bool}`` as values of the FRET variables ``names``
    (a number in the region the comparisons' truth values give, ``numeric``'s)."""
    cmp_atoms = {to_smv(a): a for name in numeric.atoms for a in numeric.atoms[name]}
    truth = {cmp_atoms[k]: v for k, v in letter.items() if k in cmp_atoms}
    numbers = numeric.values(truth)
    row = {}
    for v in names:
        if v in numeric.atoms:
            row[v] = numbers[v]
        else:
            row[v] = bool(letter.get(mangle(v), False))
    return row
