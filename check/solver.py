"""Spot queries of ``fretc check`` with a time budget each.

Spot's translations and game solving run in C++ and cannot be interrupted from Python, so
the queries run in one forked worker process (:class:`SpotWorker`); a query that overruns its
budget has its worker killed (a new one starts for the next query) and answers
:data:`UNKNOWN`. Queries and answers are plain Python values (formulas as Spot text), so
they pickle cheaply through a pipe.

Queries (all on infinite words, Spot's LTL semantics):

* ``("sat", base, extra)`` (``base`` one formula or a list of conjuncts, ``extra`` more
  conjuncts) -> ``(True, word)`` with ``word = (prefix, cycle)``, each a list of
  ``{ap: bool}`` letters (atoms a letter leaves free are absent), or ``(False, None)``.
* ``("realizable", f, outputs)`` (``f`` one formula or a list of conjuncts) -> ``(True, mealy_states)`` or ``(False, counter)`` where
  ``counter`` is an input lasso ``(prefix, cycle)`` that defeats every controller (no output
  sequence satisfies ``f`` along it), or None when the environment must react to the
  outputs (no fixed input sequence wins). Uses Spot's synthesis games:
  ``spot.ltl_to_game``, ``spot.solve_game``, ``spot.solved_game_to_mealy`` (Spot >= 2.10,
  ``ltlsynt``'s engine).
* ``("safety_game", pts, inputs, env_inv, ctl_inv, budget)``: the symbolic safety game of
  :func:`check.safety_game.solve_game` (its answer dict).
* ``("buchi_game", pts, liveness, inputs, env_inv, ctl_inv, budget)``: the Büchi game of
  :func:`check.buchi_game.solve_buchi_game` (its answer dict).
"""

from __future__ import annotations

import multiprocessing
import os
from typing import Any

__all__ = ["UNKNOWN", "SpotWorker", "run_query"]

#: Answer of a query whose budget ran out (or whose worker died).
UNKNOWN = "unknown"


def _letters(aut, bdds) -> list:
    import spot  # lazy: Spot loads in the query worker process only

    out = []
    for b in bdds:
        f = spot.bdd_to_formula(b, aut.get_dict())
        letter = {}
        if f.kind() == spot.op_And:
            lits = list(f)
        else:
            lits = [f]
        for lit in lits:
            if lit.kind() == spot.op_ap:
                letter[lit.ap_name()] = True
            elif lit.kind() == spot.op_Not and lit[0].kind() == spot.op_ap:
                letter[lit[0].ap_name()] = False
        out.append(letter)
    return out


def _word(aut) -> tuple[list, list] | None:
    w = aut.accepting_word()
    if w is None:
        return None
    w.simplify()
    return _letters(aut, w.prefix), _letters(aut, w.cycle)


_PRODUCTS: dict = {}
_AUTOMATA: dict = {}


def _translate(text: str):
    import spot  # lazy: Spot loads in the query worker process only

    a = _AUTOMATA.get(text)
    if a is None:
        if len(_AUTOMATA) > 1024:
            _AUTOMATA.clear()
        a = _AUTOMATA[text] = spot.translate(spot.formula(text), "high", "small")
    return a


def _conj(texts) -> str:
    return " & ".join(f"({t})" for t in texts)


def _product_game(texts, outputs):
    """The synthesis game of a conjunction built from one deterministic automaton per
    conjunct (their product, made parity, split into environment and controller moves), or
    None when some conjunct has no small deterministic automaton (then the caller uses
    ``spot.ltl_to_game`` on the whole formula). Same game as ``ltl_to_game`` up to the
    automaton construction; equal answers checked in tests/compiler/test_check.py."""
    import buddy  # lazy: with Spot, in the query worker process only
    import spot  # lazy: Spot loads in the query worker process only

    auts = []
    for t in texts:
        a = spot.translate(spot.formula(t), "high", "det")
        if not a.prop_universal().is_true():
            return None
        auts.append(a)
    auts.sort(key=lambda a: a.num_states())
    prod = auts[0]
    for a in auts[1:]:
        prod = spot.product(prod, a)
    if prod.num_sets() > 0 and not prod.acc().is_parity()[0]:
        prod = spot.to_parity(prod)
    outs = buddy.bddtrue
    wanted = set(outputs)
    for f in prod.ap():
        if f.ap_name() in wanted:
            outs = buddy.bdd_and(outs, buddy.bdd_ithvar(prod.register_ap(f)))
    game = spot.split_2step(prod, outs, True)
    spot.set_synthesis_outputs(game, outs)
    return game


def run_query(query: tuple) -> Any:
    """Answer one query in this process (see the module docstring for the shapes)."""
    import spot  # lazy: Spot loads in the query worker process only

    kind = query[0]
    if kind == "sat":
        base = [query[1]] if isinstance(query[1], str) else list(query[1])
        extra = list(query[2]) if len(query) > 2 else []
        # one automaton per conjunct (deterministic when Spot finds a small one), then
        # their product, smallest first: far smaller than translating the conjunction when
        # the conjuncts are many. The product of the base is kept: the queries of one
        # component share it (non-vacuity adds one trigger to the same base).
        key = tuple(sorted(base))
        aut = _PRODUCTS.get(key)
        if aut is None:
            for a in sorted((_translate(t) for t in base), key=lambda a: a.num_states()):
                aut = a if aut is None else spot.product(aut, a)
                if aut.is_empty():
                    break
            if len(_PRODUCTS) > 64:
                _PRODUCTS.clear()
            _PRODUCTS[key] = aut
        if aut.is_empty():
            return (False, None)
        for t in extra:
            aut = spot.product(aut, _translate(t))
            if aut.is_empty():
                return (False, None)
        if aut.is_empty():
            return (False, None)
        return (True, _word(aut))
    if kind == "safety_game":
        from .safety_game import solve_game  # lazy: BuDDy games only when asked

        return solve_game(*query[1:])
    if kind == "buchi_game":
        from .buchi_game import solve_buchi_game  # lazy: BuDDy games only when asked

        return solve_buchi_game(*query[1:])
    if kind == "monitor_sat":
        from .monitor_sat import decide  # lazy: BuDDy fixed points only when asked

        return decide(*query[1:])
    if kind == "realizable":
        texts = [query[1]] if isinstance(query[1], str) else list(query[1])
        outputs = list(query[2])
        si = spot.synthesis_info()
        game = _product_game(texts, outputs) if len(texts) > 1 else None
        if game is None:
            game = spot.ltl_to_game(spot.formula(_conj(texts)), outputs, si)
        if spot.solve_game(game):
            mealy = spot.solved_game_to_mealy(game, si)
            return (True, mealy.num_states())
        # a fixed input sequence that defeats every controller: an input word along which
        # no output sequence satisfies f (outputs quantified away, then complemented)
        aut = spot.translate(spot.formula(_conj(texts)))
        strip = spot.remove_ap()
        for o in outputs:
            strip.add_ap(o)
        counter = spot.complement(strip.strip(aut))
        return (False, _word(counter))
    raise ValueError(f"unknown query {kind!r}")


def _serve(conn) -> None:  # pragma: no cover - runs in the worker process
    while True:
        try:
            query = conn.recv()
        except EOFError:
            return
        try:
            conn.send(("ok", run_query(query)))
        except Exception as exc:  # a Spot error is an answer, not a crash
            conn.send(("error", f"{type(exc).__name__}: {exc}"))


class SpotWorker:
    """A forked process answering :func:`run_query` queries with a time budget each.

    ``timeout`` is in seconds (None: no budget, queries run in this process). Use as a
    context manager, or call :meth:`close`. :meth:`ask` returns the answer, or
    :data:`UNKNOWN` when the budget ran out or Spot could not take the query (a bound
    beyond Spot's repetition limit of 254, a formula it does not parse); ``failures`` keeps
    Spot's messages, so the answer says what was tried.
    """

    def __init__(self, timeout: float | None = None):
        self.timeout = timeout
        self._proc = None
        self._conn = None
        self.timeouts = 0
        self.failures: list[str] = []

    def _start(self) -> None:
        methods = multiprocessing.get_all_start_methods()
        ctx = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
        parent, child = ctx.Pipe()
        self._proc = ctx.Process(target=_serve, args=(child,), daemon=True)
        self._proc.start()
        child.close()
        self._conn = parent

    def ask(self, query: tuple, timeout: float | None = None) -> Any:
        """The answer to one :func:`run_query` query (a tuple naming the query and its formulas),
        or :data:`UNKNOWN` when the budget ran out or Spot could not take the query (its
        message kept in :attr:`failures`). ``timeout``: this query's budget in seconds
        (default the worker's). Never raises for Spot's errors."""
        if self.timeout is None:
            try:
                return run_query(query)
            except Exception as exc:  # a Spot error is an unknown answer, not a crash
                self.failures.append(_one_line(f"{type(exc).__name__}: {exc}"))
                return UNKNOWN
        if self._proc is None or not self._proc.is_alive():
            self._start()
        self._conn.send(query)
        if not self._conn.poll(self.timeout if timeout is None else timeout):
            self.timeouts += 1
            self._kill()
            return UNKNOWN
        try:
            status, value = self._conn.recv()
        except EOFError:
            self._kill()
            return UNKNOWN
        if status == "error":
            self.failures.append(_one_line(value))
            return UNKNOWN
        return value

    def _kill(self) -> None:
        if self._proc is not None:
            self._proc.kill()
            self._proc.join()
        if self._conn is not None:
            self._conn.close()
        self._proc = self._conn = None

    def close(self) -> None:
        """Stop the worker (idempotent)."""
        if self._proc is not None and self._proc.is_alive():
            self._conn.close()
            self._proc.join(timeout=1)
        self._kill()

    def __enter__(self) -> "SpotWorker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):  # pragma: no cover
        try:
            if self._proc is not None and os.getpid() != getattr(self._proc, "pid", None):
                self._kill()
        except Exception:
            pass


def _one_line(message: str) -> str:
    """A Spot error as one line: its kind and its last line (Spot's parser prints the
    formula and a caret before the reason)."""
    lines = [x.strip() for x in message.splitlines() if x.strip()]
    kind = message.split(":", 1)[0]
    return lines[0] if len(lines) <= 1 else f"{kind}: {lines[-1]}"
