"""The shield's step at run time: the one implementation of the rule of
:mod:`fretc.shield.machine`, standard library only.

``fretc shield --emit python`` writes this module's source, unchanged, into the generated
module, followed by the shield's tables (:func:`fretc.shield.emit_python.tables`), so the
generated module needs nothing but Python; in process (the simulator, the tests) the same
class runs from here.

Tables: ``{"name", "digest", "inputs", "outputs", "machines": [...]}``; a machine is
``{"requirements": [ids], "inputs": [(variable, op, constant)], "outputs": [...], "texts":
[output atom texts], "init": [0/1], "nodes": [(var, low, high)], "safe": int, "next":
[int], "keep": [int], "weights": {output atom: (wanted 0/1, weight)}, "groups": [...]}``
(``op`` None for a boolean variable; ``"pred"`` for a comparison of several variables, whose
third element is then its term, :func:`term_value`: ``(variable, "pred", term)`` with
``variable`` the first it reads). A group is the output atoms of one message:
``{"atoms": [indices], "topics": [...], "numbers": {valuation: {variable: value}}, "fields":
{valuation: [(topic, path, value)]}}``, a valuation being the atoms' values as bits (first
atom least significant): the message fields the bindings give it by and that message's
numbers (:mod:`fretc.shield.plan`); a numeric output of a group whose boolean atoms an
override changed takes them (:mod:`fretc.shield.messages` publishes the fields). A machine's
``"clusters"`` (:mod:`fretc.shield.predicates`) are ``{"atoms": [output atom indices],
"variables": [...], "numbers": {valuation: {variable: value}}}``: when an override changes
one of a cluster's atoms, its variables take the numbers recorded for the new valuation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

__all__ = ["Decision", "ShieldRuntime", "CACHE_LIMIT", "truth", "nearest", "term_value"]

#: moves (and corrections) remembered per machine, keyed by (state, input atoms, output
#: atoms): the BDD walks of a tick are done once per distinct key; past the limit the memory
#: is cleared (the answers never depend on it)
CACHE_LIMIT = 1 << 16

_OPS: dict[str, Callable[[float, float], bool]] = {
    "<": lambda x, c: x < c, "<=": lambda x, c: x <= c, ">": lambda x, c: x > c,
    ">=": lambda x, c: x >= c, "=": lambda x, c: x == c, "!=": lambda x, c: x != c}
_NOT = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "=": "!=", "!=": "="}


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


def truth(spec: tuple[str, str | None, float | None], value: Any) -> bool:
    """The truth of the atom ``spec`` ``(variable, op, constant)`` for the variable's
    ``value`` (op None: a boolean variable, which must be given a bool or an int).

    Raises:
        TypeError: a boolean variable given something else. ValueError: a NaN."""
    var, op, c = spec
    if op is None:
        if value is True or value is False:
            return bool(value)
        if not isinstance(value, int):
            raise TypeError(f"{var} must be a boolean, not {value!r}")
        return bool(value)
    x = float(value)
    if x != x:
        raise ValueError(f"{var} is NaN: its comparisons have no truth value")
    assert c is not None  # a comparison has its constant
    return _OPS[op](x, c)


def term_value(t: tuple[Any, ...], values: dict[str, Any]) -> Any:
    """A comparison of several variables, or one of its terms, at the variables' ``values``
    in double arithmetic (IEEE division, as C computes it): ``("cmp", op, a, b)`` gives a
    bool; ``("var", name)``, ``("num", x)``, ``("neg", a)``, ``(op, a, b)`` for ``+ - * /``,
    ``("fn", absReal|absInt|minReal|minInt|maxReal|maxInt, a[, b])`` a float.

    Raises ValueError: a variable's value is NaN."""
    op = t[0]
    if op == "cmp":
        return _OPS[t[1]](term_value(t[2], values), term_value(t[3], values))
    if op == "var":
        x = float(values[t[1]])
        if x != x:
            raise ValueError(f"{t[1]} is NaN: its comparisons have no truth value")
        return x
    if op == "num":
        return t[1]
    if op == "neg":
        return -term_value(t[1], values)
    if op == "fn":
        xs = [term_value(a, values) for a in t[2:]]
        f = t[1][:3]
        return abs(xs[0]) if f == "abs" else min(xs) if f == "min" else max(xs)
    a, b = term_value(t[1], values), term_value(t[2], values)
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if b == 0:
        return math.nan if a == 0 or a != a else math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


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


def nearest(specs: list[tuple[str, str | None, float | None]], truths: list[int],
            x: float, integer: bool = False) -> float:
    """The number nearest ``x`` giving the comparisons ``specs`` (of one variable) the
    values ``truths``: ``x`` when it does, else the nearest end of their region (an open end
    one float inside). ``integer`` (a variable of whole numbers): ``x`` when it gives them
    and is whole or infinite, else the whole number nearest ``x`` that gives them (the
    smaller of two as near; for a NaN or infinite ``x``, nearest the region's end as above),
    so that a proposal of 4.4 under ``gear != 4`` is not left for an integer actuator to
    round to 4. Raises ValueError when no number gives them."""
    if not math.isnan(x) and all(truth(s, x) == bool(t) for s, t in zip(specs, truths)) \
            and (not integer or math.isinf(x) or x == math.floor(x)):
        return x
    if integer:
        return _nearest_whole(specs, truths, x)
    lo, hi = -math.inf, math.inf
    points: list[float] = []
    for (_v, spec_op, c), t in zip(specs, truths):
        assert spec_op is not None and c is not None  # numbers: comparisons only
        op = spec_op if t else _NOT[spec_op]
        if op in ("<", "<="):
            hi = min(hi, c)
        elif op in (">", ">="):
            lo = max(lo, c)
        elif op == "=":
            points.append(c)
    start = min(max(x, lo), hi) if not math.isnan(x) else (
        lo if math.isfinite(lo) else hi if math.isfinite(hi) else 0.0)
    for v in points + [start]:
        for w in (v, math.nextafter(v, math.inf), math.nextafter(v, -math.inf)):
            if all(truth(s, w) == bool(t) for s, t in zip(specs, truths)):
                return w
    raise ValueError("no number gives the comparisons of " + specs[0][0] + " those values")


def _nearest_whole(specs: list[tuple[str, str | None, float | None]], truths: list[int],
                   x: float) -> float:
    """:func:`nearest` for a variable of whole numbers: the truths change only at the
    constants, so the nearest whole number giving them is ``floor(x)``, ``ceil(x)``, or
    ``ceil(c) - 1``, ``floor(c)`` or ``floor(c) + 1`` of a constant ``c``
    (:meth:`fretc.check.numeric_abstraction.NumericAbstraction.region` keeps the same
    points); the candidates are compared in doubles, as the C shield does."""
    near = x
    if not math.isfinite(x):  # (NaN or infinite: the region's end, as for reals)
        near = nearest(specs, truths, x)
    cands = [math.floor(near), math.ceil(near)] if math.isfinite(near) else []
    for _v, _op, c in specs:
        assert c is not None  # numbers: comparisons only
        if math.isfinite(c):
            cands += [math.ceil(c) - 1, math.floor(c), math.floor(c) + 1]
    best = None
    for w in map(float, cands):
        if all(truth(s, w) == bool(t) for s, t in zip(specs, truths)) and (
                best is None or abs(w - near) < abs(best - near)
                or (abs(w - near) == abs(best - near) and w < best)):
            best = w
    if best is None:
        raise ValueError("no whole number gives the comparisons of " + specs[0][0]
                         + " those values")
    return best


class _Machine:
    """One component's tables and state (module docstring)."""

    def __init__(self, t: dict[str, Any], preferences: int):
        self.reqs = tuple(t["requirements"])
        self.ins, self.outs, self.texts = t["inputs"], t["outputs"], t["texts"]
        self.nodes, self.safe = t["nodes"], t["safe"]
        self.next, self.keep, self.ctl_ok = t["next"], t["keep"], t["ctl_ok"]
        self.init = tuple(t["init"])
        self.state = self.init
        self.weights = t["weights"]
        self.big = 1 << preferences
        self.groups = t["groups"]
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
        self.atoms_of = {v: [j for j, s in enumerate(self.outs) if s[0] == v]
                         for v in self.variables if v not in clustered}

    def move(self, ins: tuple[int, ...], outs: tuple[int, ...]) -> tuple[bool, tuple[int, ...]]:
        """Whether ``outs`` is safe from the current state with ``ins``, and the next
        state when it is (remembered)."""
        key = (self.state, ins, outs)
        got = self.cache.get(key)
        if got is None:
            values = list(ins + outs + self.state)
            safe = _walk(self.nodes, self.safe, values) == 1
            nxt = tuple(_walk(self.nodes, r, values) for r in self.next) if safe else ()
            if len(self.cache) >= CACHE_LIMIT:
                self.cache.clear()
            got = self.cache[key] = (safe, nxt)
        return got

    def correct(self, ins: tuple[int, ...], prop: tuple[int, ...]) -> tuple[int, ...]:
        """The safe output atoms nearest ``prop``: the fewest changes, then the preferences
        in order (a shortest path through the ``safe`` BDD; untested atoms keep their
        proposed values; equal costs take the low branch)."""
        n_in, n_out = len(ins), len(prop)
        values = list(ins + prop + self.state)
        costs: list[float] = [math.inf, 0.0]
        for var, lo, hi in self.nodes[2:self.safe + 1]:  # safe's nodes come first
            j = var - n_in
            if 0 <= j < n_out:
                costs.append(min(costs[lo] + self._cost(j, 0, prop),
                                 costs[hi] + self._cost(j, 1, prop)))
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
                low = costs[lo] + self._cost(j, 0, prop) <= costs[hi] + self._cost(j, 1, prop)
                out[j] = 0 if low else 1
                n = lo if low else hi
            else:
                n = hi if values[var] else lo
        return tuple(out)

    def _cost(self, j: int, v: int, prop: tuple[int, ...]) -> int:
        p = prop[j]
        if v == p:
            return 0
        c = self.big
        w = self.weights.get(j)
        if w is not None:
            c += (w[1] if v != w[0] else 0) - (w[1] if p != w[0] else 0)
        return c

    def step(self, inputs: dict[str, Any], proposed: dict[str, Any]
             ) -> tuple[dict[str, Any], tuple[str, ...], tuple[str, ...]]:
        """This machine's corrected outputs (empty when the proposal is kept), reasons and
        changed atoms for one tick; advances."""
        ins = tuple([f(inputs) for f in self.in_tests])
        prop = tuple([f(proposed) for f in self.out_tests])
        safe, nxt = self.move(ins, prop)
        if safe:
            self.state = nxt
            return (self._whole(proposed, prop) if self.integers else {}), (), ()
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
        outs, reasons, changed, (fixed, kept, near) = got
        self.state = self.move(ins, outs)[1]
        result = dict(fixed)
        for v in kept:
            result[v] = proposed[v]
        for v, specs, truths in near:
            result[v] = nearest(specs, truths, float(proposed[v]), v in self.integers)
        return result, reasons, changed

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
        self.machines = [_Machine(t, prefs) for t in tables["machines"]]

    def reset(self) -> None:
        """Back to the initial state (before the first tick)."""
        for m in self.machines:
            m.state = m.init

    @property
    def state(self) -> tuple[tuple[int, ...], ...]:
        """Each machine's state bits."""
        return tuple(m.state for m in self.machines)

    def accepts(self, state: tuple[tuple[int, ...], ...], inputs: dict[str, Any],
                outputs: dict[str, Any]) -> bool:
        """Whether ``outputs`` (every output variable's value) keep every requirement
        winnable from ``state`` (as :attr:`state` gave it) with ``inputs``; nothing
        advances. A host publishing a tick's outputs as several messages uses it to order
        them so that a sampler between two of them sees an accepted valuation.

        Raises:
            KeyError, ValueError, TypeError: as :meth:`step`."""
        for m, bits in zip(self.machines, state):
            values = [f(inputs) for f in m.in_tests] + [f(outputs) for f in m.out_tests]
            if _walk(m.nodes, m.safe, values + list(bits)) != 1:
                return False
        return True

    def step(self, inputs: dict[str, Any], proposed: dict[str, Any]) -> Decision:
        """One tick: ``inputs`` maps every input variable to its value (bool, or a number
        for a numeric one), ``proposed`` every output variable to the controller's value.
        Returns the :class:`Decision`: the proposal unchanged when it keeps every
        requirement winnable (but for a whole-number output's proposal that is no whole
        number: the nearest whole number with its truths, not an override), else the nearest
        safe outputs and the requirements that forced them. Output variables no enforced
        requirement reads are passed through.

        Raises:
            KeyError: a variable is missing. ValueError: a numeric value is NaN.
            TypeError: a boolean variable given a non-boolean."""
        outputs = {v: proposed[v] for v in self.outputs}
        reasons: list[str] = []
        changed: list[str] = []
        for m in self.machines:
            values, why, what = m.step(inputs, proposed)
            outputs.update(values)
            reasons += why
            changed += what
        return Decision(outputs, bool(changed), tuple(reasons), tuple(changed))
