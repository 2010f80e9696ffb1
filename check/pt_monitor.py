"""The monitor of FRET pt formulas as BDDs (BuDDy, shipped with Spot), shared by the safety
game (:mod:`fretc.check.safety_game`) and the satisfiability fixed points (:mod:`fretc.check.monitor_sat`).

A pt formula's monitor is a deterministic machine whose state is the previous tick's value of
each past-time sub-formula (Havelund & Rosu, "Synthesizing monitors for safety properties",
TACAS 2002): one bit per ``Y``, ``Z``, ``O``, ``H``, ``S``, ``T`` and FRET boolean stream
(IR ``stream``: its previous value, the next its value now); for a bounded ``O[0,w] x``
the ticks since ``x`` last held, saturated (``log2 w`` bits); ``O[l,h] x`` is ``O[0,h-l]`` of
``x`` delayed ``l`` ticks (``l`` bits of delay line).

Design notes: ARCHITECTURE.md, `check/pt_monitor.py`."""

from __future__ import annotations

from typing import Any

from fretc.compiler import ir
from fretc.compiler.ir import Node

__all__ = ["Monitor", "Outside", "NoRoom", "state_bits", "deadline_uses", "less_than"]


class Outside(Exception):
    """The requirement set is outside what the monitors handle; the message says why."""


class NoRoom(Exception):
    """The delay lines need more state bits than were allotted (a deadline that could not
    be one counter: :meth:`Monitor._deadline`); allot them all and build again."""


def state_bits(n: Node, seen: set, counted: frozenset = frozenset()) -> tuple[int, int]:
    """Upper bounds on the state bits the monitor of ``n`` needs (for one allocation):
    ``(delay-line bits, other bits)``; a deadline of ``counted`` is counted as its counter
    (:func:`deadline_uses`), not its delay line."""
    if n in seen:
        return (0, 0)
    seen.add(n)
    if n in counted:
        a, b, N = _deadline_of(n)
        d1, o1 = state_bits(a, seen, counted)
        d2, o2 = state_bits(b, seen, counted)
        # the deadline's counter, and room for the counters of its O[0,N-1] in the block
        return d1 + d2, o1 + o2 + 2 * (N + 1).bit_length() + 4
    delay = other = 0
    if n.op in ("Y", "Z", "O", "H", "S", "T", "FTP", "stream"):
        other = 1
        if n.hi is not None:
            lo = n.lo or 0
            delay, other = lo, (n.hi - lo + 1).bit_length() + (lo + 1).bit_length() + 2
    for a in n.args:
        d, o = state_bits(a, seen, counted)
        delay, other = delay + d, other + o
    return delay, other


def deadline_uses(formulas: list[Node]) -> dict[Node, list[Node]]:
    """The deadlines of ``formulas`` one counter may monitor (:class:`Monitor`'s
    docstring): ``deadline -> [the starts of the since formulas it is the left of]``.
    Whether each start implies the deadline's ``b`` is checked when it is encoded."""
    parents: dict[Node, list[tuple[Node, int]]] = {}
    for f in formulas:
        for n in ir.walk(f):
            for k, a in enumerate(n.args):
                if (n, k) not in parents.setdefault(a, []):
                    parents[a].append((n, k))
    out: dict[Node, list[Node]] = {}
    for phi, uses in parents.items():
        if _deadline_parts(phi) is None:
            continue
        starts, fine = [], True
        for parent, k in uses:
            if parent.op == "H" and parent.hi is None:
                continue
            if parent.op == "S" and k == 0:
                right = parent.args[1]
                starts.append(next((x for x in right.args if x != phi), right)
                              if right.op == "&" and phi in right.args else right)
                continue
            # (a conjunction at a formula's root has no parents: not fine)
            if parent.op == "&" and phi in parent.args and all(
                    p is not None and p.op == "S" and j == 1 and p.args[0] == phi
                    for p, j in parents.get(parent, [(None, -1)])):
                continue
            fine = False
        if fine:
            out[phi] = starts
    return out


# --------------------------------------------------------------------------- the monitor
class Monitor:
    """The product monitor of pt formulas as BDDs: ``value(n)`` the truth of ``n`` at this
    tick over (state, input, output) variables; ``bits`` the state bits as ``(current,
    next, initial value, next-value BDD)``."""

    def __init__(self, bdd, first_var: int, atoms: list[Node], inputs: set[str],
                 other_bits: int = 0, delay_bits: int | None = None):
        self.b = bdd
        self.delays = self.counted = 0
        #: the bits of each counter, least significant first (:meth:`parts`)
        self.counters: list[list] = []
        self.memo: dict[Node, object] = {}
        self.bits: list[list] = []
        self.choices = 0
        self.atom_var: dict[Node, int] = {}
        self.in_vars: list[int] = []
        self.out_vars: list[int] = []
        for k, a in enumerate(atoms):
            self.atom_var[a] = first_var + k
            names = {x.name for x in ir.walk(a) if x.op in ("ap", "var")}
            (self.in_vars if names <= inputs else self.out_vars).append(first_var + k)
        self.base = first_var + len(atoms)
        self.delay_base = self.base + 2 * other_bits
        #: the delay-line bits allotted (None: no limit); past them :class:`NoRoom`
        self.delay_room = delay_bits
        self.deadlines: dict[Node, list[Node]] = {}
        #: (counter node, bit significance) -> its place in the counter block (:meth:`plan`)
        self.slots: dict[tuple[Node, int], int] = {}
        self.counter_base = self.delay_base

    def plan(self, formulas: list[Node]) -> None:
        """Find the deadlines of ``formulas`` that one counter may monitor (module
        docstring): ``deadline -> [the starts of the since formulas it is the left of]``.
        Whether each start implies the deadline's ``b`` is checked when it is encoded.
        Then place the counters' bits (module docstring, variable order)."""
        self.deadlines = deadline_uses(formulas)
        self._layout(formulas)

    def _layout(self, formulas: list[Node]) -> None:
        """One block for the bits of every counter ``formulas`` may need (a deadline's, or
        a bounded ``O``/``H``'s: a deadline that falls back to its delay line leaves its
        place unused), ordered by significance, most significant first, then by counter;
        the block ends where the delay lines start. ``state_bits`` counts at least these
        bits for these nodes, so the one-bit states below the block have room."""
        widths: dict[Node, int] = {}
        for f in formulas:
            for n in ir.walk(f):
                if n in self.deadlines:
                    widths.setdefault(n, (_deadline_of(n)[2] + 1).bit_length())
                elif n.op in ("O", "H") and n.hi is not None and n.hi > (n.lo or 0):
                    widths.setdefault(n, (n.hi - (n.lo or 0) + 1).bit_length())
        nodes = list(widths)
        order = sorted((-k, j) for j, n in enumerate(nodes) for k in range(widths[n]))
        self.slots = {(nodes[j], -minus_k): s for s, (minus_k, j) in enumerate(order)}
        self.counter_base = self.delay_base - 2 * len(self.slots)

    def parts(self) -> list[list]:
        """The state bits (``bits`` entries) in groups for a partitioned transition
        relation: each counter's bits together (its next value is a function of all of
        them), every other bit alone, in the order they were made."""
        grouped = {id(bit) for c in self.counters for bit in c}
        return [*self.counters, *([bit] for bit in self.bits if id(bit) not in grouped)]

    def _counter(self, n: Node, width: int, init: int) -> list:
        """The state bits of ``n``'s counter, least significant first, as ``(current
        variable BDD, bit)``, initially ``init``: in the counter block when :meth:`plan`
        placed it."""
        out = []
        for k in range(width):
            slot = self.slots.get((n, k))
            if slot is None:
                out.append(self._bit(bool((init >> k) & 1)))
                continue
            cur = self.counter_base + 2 * slot
            bit = [cur, cur + 1, bool((init >> k) & 1), None]
            self.bits.append(bit)
            self.counted += 1
            out.append((self.b.bdd_ithvar(cur), bit))
        self.counters.append([bit for _v, bit in out])
        return out

    def _bit(self, init: bool, delay: bool = False) -> tuple[object, list]:
        """A new one-bit state or delay-line bit: its current and next variables side by
        side, after the bits of its kind made before it (module docstring, variable
        order)."""
        if delay:
            if self.delay_room is not None and self.delays >= self.delay_room:
                raise NoRoom("a deadline needs its delay line")
            cur = self.delay_base + 2 * self.delays
            self.delays += 1
        else:
            cur = self.base + 2 * (len(self.bits) - self.delays - self.counted + self.choices)
            if cur >= self.counter_base:
                raise RuntimeError("the one-bit states ran into the counter block")
        bit = [cur, cur + 1, init, None]
        self.bits.append(bit)
        return self.b.bdd_ithvar(cur), bit

    def add_bit(self, init: bool) -> tuple[object, list]:
        """A state bit for another machine in the product (an automaton of
        :mod:`fretc.check.buchi_game`): ``(its BDD variable, [current, next, init, None])``; the
        caller sets the next-value function (index 3)."""
        return self._bit(init)

    def add_choice(self) -> int:
        """A free variable chosen each tick like an output, not a state (the choice among a
        nondeterministic automaton's edges, :mod:`fretc.check.buchi_game`): its BDD variable,
        in the slot of a state bit."""
        var = self.base + 2 * (len(self.bits) - self.delays - self.counted + self.choices)
        if var >= self.counter_base:
            raise RuntimeError("the choices ran into the counter block")
        self.choices += 1
        self.out_vars.append(var)
        return var

    def value(self, n: Node) -> Any:  # a BDD
        """Truth of ``n`` at the current tick (a BDD)."""
        got = self.memo.get(n)
        if got is None:
            got = self.memo[n] = self._encode(n)
        return got

    def _encode(self, n: Node):
        b, op = self.b, n.op
        if n in self.deadlines:
            got = self._deadline(n)
            if got is not None:
                return got
        if op in ("true", "false"):
            return b.bddtrue if op == "true" else b.bddfalse
        if n in self.atom_var:
            return b.bdd_ithvar(self.atom_var[n])
        if op == "FTP":  # a bit "some tick has passed": FTP is its negation
            v, bit = self._bit(False)
            bit[3] = b.bddtrue
            return b.bdd_not(v)
        if op == "!":
            return b.bdd_not(self.value(n.args[0]))
        if op in ("&", "|", "->", "<->", "xor"):
            x, y = self.value(n.args[0]), self.value(n.args[1])
            return {"&": b.bdd_and, "|": b.bdd_or, "->": b.bdd_imp, "<->": b.bdd_biimp,
                    "xor": b.bdd_xor}[op](x, y)
        if op in ("O", "H") and n.hi is not None:
            return self._bounded(n)
        if op in ("Y", "Z"):
            v, bit = self._bit(op == "Z")
            bit[3] = self.value(n.args[0])
            return v
        if op == "stream":  # (its previous value, false before the trace: ir.stream)
            prev, bit = self._bit(False)
            now = b.bdd_ite(prev, self.value(n.args[0]), self.value(n.args[1]))
            bit[3] = now
            return now
        if op in ("O", "H", "S", "T"):
            prev, bit = self._bit(op in ("H", "T"))
            a = self.value(n.args[0])
            if op == "O":
                now = b.bdd_or(a, prev)
            elif op == "H":
                now = b.bdd_and(a, prev)
            elif op == "S":
                now = b.bdd_or(self.value(n.args[1]), b.bdd_and(a, prev))
            else:
                now = b.bdd_and(self.value(n.args[1]), b.bdd_or(a, prev))
            bit[3] = now
            return now
        raise Outside(f"no monitor for the IR node {op!r} in a pt formula")

    def _bounded(self, n: Node):
        """``O[l,h] x`` = ``O[0,h-l]`` of ``x`` delayed ``l`` ticks; ``H`` its dual."""
        b = self.b
        x = self.value(n.args[0])
        if n.op == "H":
            x = b.bdd_not(x)
        for _ in range(n.lo or 0):  # the delay line, oldest last
            v, bit = self._bit(False, delay=True)
            bit[3] = x
            x = v
        assert n.hi is not None  # (bounded)
        w = n.hi - (n.lo or 0)
        if w > 0:
            x = self._since_counter(x, w, n)
        return b.bdd_not(x) if n.op == "H" else x

    def _deadline(self, n: Node):
        """``O[N,N] a -> O[0,N-1] b`` by the age of the oldest ``a`` not followed by ``b``
        (module docstring), or None when a since it starts does not imply ``b``.

        The counter holds that age at the previous tick, ``0 .. N`` (``N``: at least
        ``N``), or ``N + 1`` when no ``a`` is pending; the deadline is missed now when the
        age reaches ``N`` without ``b``. Each tick: ``b`` leaves pending only this tick's
        ``a``; otherwise the oldest stays and ages, or this tick's ``a`` becomes it."""
        b = self.b
        a_node, b_node, N = _deadline_of(n)
        resp = self.value(b_node)
        for start in self.deadlines[n]:
            if b.bdd_imp(self.value(start), resp) != b.bddtrue:
                return None
        a = self.value(a_node)
        none = N + 1
        width = none.bit_length()
        bits = self._counter(n, width, none)
        c = [v for v, _ in bits]
        missed = b.bdd_and(_equals(b, c, N - 1), b.bdd_not(resp))
        reset = b.bdd_or(resp, _equals(b, c, none))
        full = _equals(b, c, N)
        carry = b.bddtrue
        for k, (v, bit) in enumerate(bits):
            inc = b.bdd_ite(full, b.bddtrue if (N >> k) & 1 else b.bddfalse,
                            b.bdd_xor(v, carry))
            carry = b.bdd_and(v, carry)
            start = b.bdd_ite(a, b.bddfalse, b.bddtrue if (none >> k) & 1 else b.bddfalse)
            bit[3] = b.bdd_ite(reset, start, inc)
        return b.bdd_not(missed)

    def _since_counter(self, x, w: int, node: Node):
        """``O[0,w] x``: a counter of the ticks since ``x`` last held (before this tick),
        saturated at ``w + 1``, initially ``w + 1`` (never); true when ``x`` holds now or
        the counter is below ``w``."""
        b = self.b
        width = (w + 1).bit_length()
        init = w + 1
        bits = self._counter(node, width, init)
        cvars = [v for v, _ in bits]
        below = less_than(b, cvars, w)
        now = b.bdd_or(x, below)
        # next counter: 0 when x, else min(c + 1, w + 1)
        carry = b.bddtrue
        sat = b.bdd_not(less_than(b, cvars, w + 1))
        for k, (v, bit) in enumerate(bits):
            inc = b.bdd_xor(v, carry)
            carry = b.bdd_and(v, carry)
            capped = b.bdd_ite(sat, b.bddtrue if (init >> k) & 1 else b.bddfalse, inc)
            bit[3] = b.bdd_and(b.bdd_not(x), capped)
        return now


def _deadline_parts(n: Node) -> tuple[Node, Node, int] | None:
    """``(a, b, N)`` of ``O[N,N] a -> O[0,N-1] b`` (``N >= 2``), else None."""
    if n.op != "->":
        return None
    left, right = n.args
    if (left.op != "O" or left.hi is None or left.lo != left.hi or left.lo < 2
            or right.op != "O" or (right.lo or 0) != 0 or right.hi != left.lo - 1):
        return None
    return left.args[0], right.args[0], left.lo


def _deadline_of(n: Node) -> tuple[Node, Node, int]:
    """:func:`_deadline_parts` of a node known to be a deadline."""
    got = _deadline_parts(n)
    assert got is not None
    return got


def _equals(b, bits: list, k: int):
    """BDD of ``value(bits) == k`` (``bits`` least significant first)."""
    out = b.bddtrue
    for i, v in enumerate(bits):
        out = b.bdd_and(out, v if (k >> i) & 1 else b.bdd_not(v))
    return out


def less_than(b: Any, bits: list, k: int) -> Any:  # b: the buddy module; a BDD
    """BDD of ``value(bits) < k`` (``bits`` least significant first)."""
    out = b.bddfalse
    for i, v in enumerate(bits):  # from the least significant bit up
        if (k >> i) & 1:
            out = b.bdd_or(b.bdd_not(v), out)
        else:
            out = b.bdd_and(b.bdd_not(v), out)
    if k >= (1 << len(bits)):
        return b.bddtrue
    return out


