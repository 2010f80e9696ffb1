"""``fretc shield --explain``: what the controller may still do under the shield, per enforced
requirement, read off the closed loop (:func:`fretc.shield.prove.closed_loop`: every run of
the shield with any environment and any controller).

Design notes: ARCHITECTURE.md, `shield/explain.py`."""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from fretc.check.safety_game import letter_name
from fretc.compiler import ir
from fretc.compiler.expressions import Expander, mentions_time
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv
from fretc.shield.build import Shield
from fretc.shield.machine import Machine
from fretc.shield.prove import Loop, buddy_module, closed_loop

__all__ = ["Permission", "permissions", "explain_text"]

class Permission:
    """What requirement ``rid`` leaves the controller: ``wait`` ticks (None: unbounded,
    -1: the closed loop was too large to read), ``release``, and its ``condition`` and
    ``response`` as FRET/SMV text; ``unread``: why they are not read for it (its scope or
    timing is not the one response after its condition that they describe)."""

    def __init__(self, rid: str, condition: str, response: str, wait: int | None,
                 release: bool, unread: str | None = None, holding: bool = False):
        self.rid, self.condition, self.response = rid, condition, response
        self.wait, self.release, self.unread = wait, release, unread
        #: a ``whenever`` condition (FRET's *holding* kind): the response is asked at every
        #: tick the condition holds, not once after it becomes true
        self.holding = holding

    def text(self, period: Fraction | None) -> str:
        """One sentence per liberty."""
        if self.unread is not None:
            return (f"{self.rid}: enforced as it reads ({self.unread}); its liberties are "
                    "not read here (fretc explain gives its meaning)")
        if self.wait == -1:
            return f"{self.rid}: the closed loop is too large to read its permissions"
        when = (f"after {self.condition} becomes true" if self.condition != "TRUE"
                else "at any tick")
        if self.holding and self.condition != "TRUE":
            when = f"after each tick at which {self.condition} holds"
        if self.wait is None:
            head = f"{self.response} may never come while {self.condition} holds"
        elif self.wait == 0 and self.holding and self.condition != "TRUE":
            head = f"{self.response} must hold at every tick at which {self.condition} holds"
        elif self.wait == 0:
            head = f"{self.response} must hold at once {when}"
        else:
            secs = f" ({float(self.wait * period):g} s)" if period else ""
            ticks = "1 tick" if self.wait == 1 else f"{self.wait} ticks"
            head = f"{self.response} may wait up to {ticks}{secs} {when}"
        tail = (f"; once it holds, {self.response} may stop holding again while "
                f"{self.condition} still holds" if self.release else "")
        return f"{self.rid}: {head}{tail}"


def _bdd(n: Node, var_of: dict[str, int]) -> Any:
    """A propositional IR formula as a BuDDy BDD over the atoms' variables ``var_of``
    (atom name -> variable; an atom the machine does not read is false, as it never holds
    in its letters)."""
    buddy = buddy_module()

    if n.op in ("ap", "cmp"):
        v = var_of.get(letter_name(n))
        return buddy.bddfalse if v is None else buddy.bdd_ithvar(v)
    if n.op in ("true", "false"):
        return buddy.bddtrue if n.op == "true" else buddy.bddfalse
    args = [_bdd(a, var_of) for a in n.args]
    if n.op == "!":
        return buddy.bdd_not(args[0])
    op = {"&": buddy.bdd_and, "|": buddy.bdd_or, "->": buddy.bdd_imp,
          "<->": buddy.bdd_biimp, "xor": buddy.bdd_xor}[n.op]
    out = args[0]
    for a in args[1:]:
        out = op(out, a)
    return out


def _meets(label: Any, f: Any) -> bool:
    """Whether some move of ``label`` satisfies ``f`` (both BDDs)."""
    buddy = buddy_module()

    return bool(buddy.bdd_and(label, f) != buddy.bddfalse)


def _wait(loop: Loop, m: Machine, c: Any, r: Any) -> int | None:
    """The longest run of ``c & !r`` ticks from a tick where ``c`` becomes true (module
    docstring); None when unbounded. ``c``, ``r``: BDDs over the atoms."""
    buddy = buddy_module()

    waiting = buddy.bdd_and(c, buddy.bdd_not(r))
    graph = loop.graph
    memo: dict[tuple[int, ...], int | None] = {}
    active: set[tuple[int, ...]] = set()

    def longest(s: tuple[int, ...]) -> int | None:
        if s in memo:
            return memo[s]
        if s in active:
            return None  # a cycle of c & !r: unbounded
        active.add(s)
        best: int | None = 0
        for nxt, label in graph[s].items():
            if _meets(label, waiting):
                sub = longest(nxt)
                best = None if sub is None or best is None else max(best, 1 + sub)
        active.discard(s)
        memo[s] = best
        return best

    starts = {tuple(int(b) for b in m.init)}
    for edges in graph.values():
        for nxt, label in edges.items():
            if _meets(label, buddy.bdd_not(c)):
                starts.add(nxt)
    out = 0
    for s in starts:
        got = longest(s)
        if got is None:
            return None
        out = max(out, got)
    return out


def _release(loop: Loop, c: Any, r: Any) -> bool:
    """Whether some tick with ``c & r`` may be followed by one with ``c & !r``."""
    buddy = buddy_module()

    held, dropped = buddy.bdd_and(c, r), buddy.bdd_and(c, buddy.bdd_not(r))
    after = {nxt for edges in loop.graph.values() for nxt, label in edges.items()
             if _meets(label, held)}
    return any(_meets(label, dropped) for s in after for label in loop.graph[s].values())


def permissions(shield: Shield, compiled: Sequence[Any]) -> list[Permission]:
    """The :class:`Permission` of each enforced requirement (module docstring)."""
    by_id = {c.id: c for c in compiled}
    ex = Expander("pt", ir.TRUE, ir.TRUE)
    out = []
    for m in shield.machines:
        loop = closed_loop(m, assumed=True)  # (the runs that keep the assumptions)
        for rid in m.requirements:
            req = by_id[rid].entry.requirement
            c = ir.TRUE if req.condition.expr is None else ex.bool(req.condition.expr)
            r = ex.bool(req.response)
            unread = _unread(req)
            if unread is not None:
                out.append(Permission(rid, to_smv(c), to_smv(r), 0, False, unread))
                continue
            if loop is None:
                out.append(Permission(rid, to_smv(c), to_smv(r), -1, False))
                continue
            var_of = {a.name: v for a, v in zip((*m.inputs, *m.outputs), loop.var)}
            cb, rb = _bdd(c, var_of), _bdd(r, var_of)
            out.append(Permission(rid, to_smv(c), to_smv(r), _wait(loop, m, cb, rb),
                                  _release(loop, cb, rb),
                                  holding=req.condition.kind == "holding"))
    return out


def _unread(req: Any) -> str | None:
    """Why the wait and the release (module docstring) do not describe ``req``, or None:
    they are read for the one response the requirement asks after its condition (no scope;
    ``immediately`` or ``within``, or ``always`` without a condition). A scope bounds where
    the response is asked (outside it, "may never come" is no liberty the scope grants),
    and ``for``, ``next``, ``until``, ``never``, ``always`` after a condition and the rest
    ask for more than one response, or at one tick only."""
    kind = req.timing.kind or "null"
    if any(e is not None and mentions_time(e) for e in (req.condition.expr, req.response)):
        return "a condition or response reading the past (a past-time function, a stream)"
    if req.scope.kind != "null":
        return f"the '{req.scope.kind}' scope"
    if kind in ("immediately", "within") or (kind == "always" and req.condition.expr is None):
        return None
    return f"the '{kind}' timing"


def explain_text(shield: Shield, compiled: Sequence[Any] = ()) -> str:
    """The terminal report of ``--explain``."""
    lines = ["what the controller may still do under the shield:"]
    lines += ["  " + p.text(shield.period) for p in permissions(shield, compiled)]
    return "\n".join(lines)
