"""The queries of ``fretc check`` that run in Spot's process: Spot's automata and games,
and the BDD fixed points (BuDDy, shipped with Spot), each within the query's budgets.

The queries run in one forked worker process (:class:`SpotWorker`); no answer depends on
time: the BDD engines count their work (:mod:`fretc.check.budget`), what Spot is given is
bounded before it starts (:data:`SPOT_MAX_STATES`), BuDDy's node table is capped at the memory
budget (past it the query answers :data:`UNKNOWN` and the next one starts a new worker).
Queries and answers are plain Python values (formulas as Spot text), pickled through a pipe:
``("sat", base, extra)``, ``("satisfiable", base, extra)``, ``("realizable", f, outputs)``,
``("call", function, args)``, ``("safety_game", ...)``, ``("buchi_game", ...)``,
``("monitor_sat", ...)``, ``("smt", formulas)``. Each query's arguments and answer, and why
the worker is built so: ARCHITECTURE.md ("Spot's worker").
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from typing import Any

from fretc.check.budget import DEFAULT_QUERY_CPU, UNKNOWN, Budget, BudgetSpent, RunStopped

__all__ = ["UNKNOWN", "SpotWorker", "run_query", "SPOT_MAX_STATES"]

#: the most states of a product automaton Spot builds for one query: a product past it is
#: refused (the query answers unknown), so the next product and the emptiness check stay
#: bounded (the benchmark's products at 16 ticks have at most a few thousand states)
SPOT_MAX_STATES = 200_000

#: the most states of the product a ``satisfiable`` query builds from its ``extra`` conjuncts
#: before it tests a word of it on the other conjuncts and, when that does not decide, asks
#: ``sat`` (:meth:`_Session.satisfiable`); 0: ask ``sat`` at once
SPOT_PROBE_STATES = 16_000

#: the most states of the automaton Spot's synthesis complements to find a defeating input
#: lasso (complementation is exponential in it): past it no lasso is searched
SPOT_MAX_COMPLEMENT = 64


def _bounded(aut, what: str):
    """``aut``, or :class:`fretc.check.budget.BudgetSpent` when it has more states than
    :data:`SPOT_MAX_STATES`."""
    if aut.num_states() > SPOT_MAX_STATES:
        raise BudgetSpent(f"Spot's {what} has {aut.num_states()} states, past the limit of "
                          f"{SPOT_MAX_STATES}")
    return aut


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


class _Session:
    """The Spot state of one job (a query worker's life, an in-process :class:`SpotWorker`'s):
    a BDD dictionary of its own, so the variables of the atoms are numbered by this job's
    queries alone (Spot's process-wide default dictionary keeps the numbering of whatever
    the process, or the parent a worker was forked from, registered before, and the words
    Spot finds depend on it), and the automata built in it: one per conjunct of a ``sat``
    query (``automata``) and the products of the bases (``products``), shared by the
    queries of one group."""

    def __init__(self) -> None:
        import spot  # lazy: Spot loads in the query worker process only

        self.dict = spot.make_bdd_dict()
        self.automata: dict[str, Any] = {}
        self.products: dict[tuple[str, ...], Any] = {}

    def translate(self, text: str):
        """Spot's small automaton of ``text`` in this session's dictionary (kept)."""
        import spot  # lazy: Spot loads in the query worker process only

        a = self.automata.get(text)
        if a is None:
            if len(self.automata) > 1024:
                self.automata.clear()
            a = self.automata[text] = spot.translate(spot.formula(text), "high", "small",
                                                     dict=self.dict)
        return a

    def sat(self, base: list[str], extra: list[str]) -> tuple[bool, Any]:
        """The ``sat`` query of the conjuncts ``base`` and ``extra``."""
        import spot  # lazy: Spot loads in the query worker process only

        # one automaton per conjunct (deterministic when Spot finds a small one), then
        # their product, smallest first: far smaller than translating the conjunction when
        # the conjuncts are many. The product of the base is kept: the queries of one
        # group share it (non-vacuity adds one trigger to the same base).
        key = tuple(sorted(base))
        aut = self.products.get(key)
        if aut is None:
            for a in sorted((self.translate(t) for t in base), key=lambda a: a.num_states()):
                aut = a if aut is None else _bounded(spot.product(aut, a), "product")
                if aut.is_empty():
                    break
            if len(self.products) > 64:
                self.products.clear()
            self.products[key] = aut
        assert aut is not None  # (a query has a formula)
        if aut.is_empty():
            return (False, None)
        for t in extra:
            aut = _bounded(spot.product(aut, self.translate(t)), "product")
            if aut.is_empty():
                return (False, None)
        return (True, _word(aut))

    def satisfiable(self, base: list[str], extra: list[str],
                    probe: int | None = None) -> bool:
        """The answer of the ``sat`` query of ``base`` and ``extra`` without its word.

        The product of :meth:`sat` starts from the base, smallest automaton first; when the
        extra conjunct is a negated requirement (is it implied by the others?), the product
        of the base is as large as that of the whole set, and emptiness shows only at the
        end. Here the product starts from ``extra`` and takes the base smallest first while
        it has at most ``probe`` states (default :data:`SPOT_PROBE_STATES`): an empty
        product is the answer False; a product of every conjunct that is not empty, True;
        else an accepting word of the product so far, each letter a value of every atom, is
        tested on each conjunct left (the product of the word's automaton with it): in all,
        True. Otherwise
        :meth:`sat` decides. Each answer is an exact emptiness check, so it is the one
        :meth:`sat` gives, sooner (FRET's Lift+Cruise set: 57 redundancy queries of 76
        conjuncts, ``bench/bench_check.py --redundancy``)."""
        import spot  # lazy: Spot loads in the query worker process only

        probe = SPOT_PROBE_STATES if probe is None else probe
        base_auts = sorted((self.translate(t) for t in base), key=lambda a: a.num_states())
        auts = [self.translate(t) for t in extra] + base_auts
        aut, used = None, 0
        for a in auts:
            nxt = a if aut is None else spot.product(aut, a)
            if nxt.num_states() > probe:
                break
            aut, used = nxt, used + 1
            if aut.is_empty():
                return False
        else:
            return aut is not None and not aut.is_empty()
        if aut is not None:
            lasso = self._one_word(aut, auts).as_automaton()
            if all(not spot.product(lasso, a).is_empty() for a in auts[used:]):
                return True
        return self.sat(base, extra)[0]

    def _one_word(self, aut, auts: list):
        """An accepting word of ``aut`` whose every letter gives each atom of ``auts`` a
        value (Spot's letters leave atoms free: a lasso of them stands for many words, and
        each conjunct could accept another one of them)."""
        import spot  # lazy: Spot loads in the query worker process only (before buddy)
        import buddy  # lazy: Spot's BDD library, with Spot in the query worker process

        atoms = buddy.bddtrue
        for a in auts:
            atoms = atoms & a.ap_vars()
        found = aut.accepting_word()
        word = spot.twa_word(self.dict)
        for letters, out in ((found.prefix, word.prefix), (found.cycle, word.cycle)):
            for b in letters:
                out.append(buddy.bdd_satoneset(b, atoms, buddy.bddfalse))
        return word

    def realizable(self, texts: list[str], outputs: list[str]) -> tuple[bool, Any]:
        """The ``realizable`` query of the conjunction of ``texts``, ``outputs`` the
        controller's atoms."""
        import spot  # lazy: Spot loads in the query worker process only

        si = spot.synthesis_info()
        si.dict = self.dict
        game = _product_game(texts, outputs, self.dict) if len(texts) > 1 else None
        if game is None:
            game = spot.ltl_to_game(spot.formula(_conj(texts)), outputs, si)
        if spot.solve_game(game):
            mealy = spot.solved_game_to_mealy(game, si)
            return (True, mealy.num_states())
        # a fixed input sequence that defeats every controller: an input word along which
        # no output sequence satisfies f (outputs quantified away, then complemented)
        aut = spot.translate(spot.formula(_conj(texts)), dict=self.dict)
        if aut.num_states() > SPOT_MAX_COMPLEMENT:
            return (False, None)
        strip = spot.remove_ap()
        for o in outputs:
            strip.add_ap(o)
        counter = spot.complement(strip.strip(aut))
        return (False, _word(counter))


#: the session of this query worker process (:func:`_serve` starts it)
_WORKER_SESSION: list[_Session] = []


def _conj(texts) -> str:
    return " & ".join(f"({t})" for t in texts)


def _product_game(texts, outputs, bdd_dict=None):
    """The synthesis game of a conjunction built from one deterministic automaton per
    conjunct (their product, made parity, split into environment and controller moves), or
    None when some conjunct has no small deterministic automaton (then the caller uses
    ``spot.ltl_to_game`` on the whole formula). Same game as ``ltl_to_game`` up to the
    automaton construction; equal answers checked in tests/check/test_check.py. Its
    automata are made in ``bdd_dict`` (a Spot BDD dictionary; None: a new one)."""
    import buddy  # lazy: with Spot, in the query worker process only
    import spot  # lazy: Spot loads in the query worker process only

    d = spot.make_bdd_dict() if bdd_dict is None else bdd_dict
    auts = []
    for t in texts:
        a = spot.translate(spot.formula(t), "high", "det", dict=d)
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


def run_query(query: tuple, budget: Budget | None = None,
              session: _Session | None = None) -> Any:
    """Answer one query in this process (see the module docstring for the shapes) within
    ``budget`` (default: the defaults); raises :class:`fretc.check.budget.BudgetSpent` past it.
    ``session``: the job's Spot state for the ``sat`` and ``realizable`` queries (a
    ``_Session``: its BDD dictionary and automata; default: the query worker's, else a new
    one for this query alone), so the answer depends on the query and the job's earlier
    queries only, never on other Spot work of the process."""
    budget = budget or Budget()
    kind = query[0]
    if kind in ("sat", "satisfiable", "realizable"):
        if session is None:
            session = _WORKER_SESSION[0] if _WORKER_SESSION else _Session()
        texts = [query[1]] if isinstance(query[1], str) else list(query[1])
        if kind == "sat":
            return session.sat(texts, list(query[2]) if len(query) > 2 else [])
        if kind == "satisfiable":
            return session.satisfiable(texts, list(query[2]))
        return session.realizable(texts, list(query[2]))
    if kind in ("call", "safety_game", "buchi_game", "monitor_sat"):
        # the games' BDD dictionary (check.safety_game) new for each query: its numbering
        # is the query's alone
        from fretc.check.safety_game import new_bdd_dict  # lazy: BuDDy games only when asked

        new_bdd_dict()
    if kind == "call":  # a later layer's function run here (the caller passes it in)
        fn, args = query[1], query[2]
        return fn(*args, budget=budget)
    if kind == "safety_game":
        from fretc.check.safety_game import solve_game  # lazy: BuDDy games only when asked

        return solve_game(*query[1:], budget=budget)  # type: ignore[misc]  # the query's fields come before budget
    if kind == "buchi_game":
        from fretc.check.buchi_game import solve_buchi_game  # lazy: BuDDy games only when asked

        pts, live, inputs, env_inv, ctl_inv, search = query[1:]
        return solve_buchi_game(pts, live, inputs, env_inv, ctl_inv, budget, search)
    if kind == "monitor_sat":
        from fretc.check.monitor_sat import decide  # lazy: BuDDy fixed points only when asked

        safe, goals, inv, finite, length, live, last = query[1:]
        return decide(safe, goals, inv, finite, length, budget, live, last)
    if kind == "smt":
        from fretc.check.smt import solve_capped  # lazy: z3 only when a query needs it

        return solve_capped(query[1], budget)
    raise ValueError(f"unknown query {kind!r}")


def _serve(conn, memory: int) -> None:  # pragma: no cover - runs in the worker process
    import spot  # noqa: F401  lazy: Spot initializes BuDDy (and makes it importable)
    import buddy  # lazy: with Spot, in the query worker process only

    # BuDDy reports a full node table on the standard error before it stops the process:
    # the parent says it in the answer instead; a fault handler inherited from the parent
    # (python -X faulthandler, pytest's) would print "Fatal Python error" and a traceback
    # of this process on its own copy of the standard error
    import faulthandler

    faulthandler.disable()
    os.dup2(os.open(os.devnull, os.O_WRONLY), 2)
    buddy.bdd_setmaxnodenum(memory)
    # the worker's own Spot state: nothing the parent registered in Spot's default BDD
    # dictionary before the fork numbers this job's atoms
    _WORKER_SESSION[:] = [_Session()]
    while True:
        try:
            query, budget = conn.recv()
        except EOFError:
            return
        _cpu_limit(budget.cpu if budget is not None else DEFAULT_QUERY_CPU)
        try:
            answer = run_query(query, budget)
        except BudgetSpent as exc:
            conn.send(("budget", str(exc)))
            continue
        except Exception as exc:  # a Spot error is an answer, not a crash
            conn.send(("error", f"{type(exc).__name__}: {exc}"))
            continue
        if query[0] == "smt":
            if answer[3]:  # z3 ran out of memory: its state is unusable, the worker ends
                conn.send(("last", answer[:3]))
                return
            answer = answer[:3]
        conn.send(("ok", answer))


def _cpu_limit(seconds: float) -> None:  # pragma: no cover - runs in the worker process
    """End this process (SIGXCPU) when the next query takes more than ``seconds`` of CPU:
    the soft RLIMIT_CPU set that far above what the process has used."""
    import resource

    used = resource.getrusage(resource.RUSAGE_SELF)
    soft = int(used.ru_utime + used.ru_stime + seconds) + 1
    hard = resource.getrlimit(resource.RLIMIT_CPU)[1]
    if hard != resource.RLIM_INFINITY:
        soft = min(soft, hard)
    resource.setrlimit(resource.RLIMIT_CPU, (soft, hard))


#: deaths of the query worker in a row (killed from outside, a crash: not its own limits)
#: after which no new worker is started and the rest of the run's queries are unknown
MAX_DEATHS = 3


class SpotWorker:
    """A forked process answering :func:`run_query` queries within ``budget`` (a
    :class:`fretc.check.budget.Budget`; default the defaults).

    ``fork``: run the queries in a worker process (False: in this process, with no cap on
    BuDDy's node table; for tests). Either way the queries' automata are made in a BDD
    dictionary of the worker's own, so its answers do not depend on other Spot work of the
    process (see ``_Session``). ``deadline``: the run's wall-clock limit
    (``time.monotonic()`` value, None for none): past it :meth:`ask` kills the worker and
    raises :class:`fretc.check.budget.RunStopped`. Use as a context manager, or call
    :meth:`close`. :meth:`ask` returns the answer, or :data:`UNKNOWN` when the query ran past
    its budget or Spot could not take it (a bound beyond Spot's repetition limit of 254, a
    formula it does not parse); ``failures`` keeps the reasons, so the answer says what was
    tried, and ``spent`` counts the queries past their budget.
    """

    def __init__(self, budget: Budget | None = None, *, fork: bool = True,
                 deadline: float | None = None):
        self.budget = budget or Budget()
        self.fork = fork
        self.deadline = deadline
        self._proc: Any = None  # the worker's multiprocessing Process, once started
        self._conn: Any = None  # and our end of its Pipe
        self._session: _Session | None = None  # the Spot state of the queries run here
        self.spent = 0
        self.failures: list[str] = []
        self.deaths = 0  # worker deaths in a row not caused by its limits

    def _start(self) -> None:
        methods = multiprocessing.get_all_start_methods()
        ctx = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
        parent, child = ctx.Pipe()
        # (every start method's context has Process)
        self._proc = ctx.Process(target=_serve, args=(child, self.budget.memory),  # type: ignore[attr-defined]
                                 daemon=True)
        self._proc.start()
        child.close()
        self._conn = parent

    def refuse(self, reason: str) -> str:
        """Answer :data:`UNKNOWN` to a query refused before it reached an engine (a bound
        past what Spot is given), keeping ``reason``."""
        self.spent += 1
        self.failures.append(reason)
        return UNKNOWN

    def ask(self, query: tuple) -> Any:
        """The answer to one :func:`run_query` query (a tuple naming the query and its
        formulas), or :data:`UNKNOWN` when it ran past its budget or Spot could not take it
        (the reason kept in :attr:`failures`). Never raises for Spot's errors; raises
        :class:`fretc.check.budget.RunStopped` past the run's deadline."""
        if not self.fork:
            try:
                if self._session is None:
                    self._session = _Session()
                return run_query(query, self.budget, self._session)
            except BudgetSpent as exc:
                return self.refuse(str(exc))
            except Exception as exc:  # a Spot error is an unknown answer, not a crash
                self.failures.append(_one_line(f"{type(exc).__name__}: {exc}"))
                return UNKNOWN
        if self.deaths >= MAX_DEATHS:
            return self.refuse(f"the query's worker process ended {self.deaths} times in a "
                               "row (killed from outside or crashed): no further queries")
        status, value = self.call(query)
        if status == "ended":
            if value == -signal.SIGABRT:
                return self.refuse(self.budget.memory_spent("BuDDy's node table is full"))
            if value == -signal.SIGXCPU:
                return self.refuse(f"the query took its CPU limit of {self.budget.cpu:g} s "
                                   "(--query-cpu): a step past what the work budget foresaw")
            self.deaths += 1
            return self.refuse(f"the query's worker process ended (exit code {value})")
        self.deaths = 0
        if status == "budget":
            return self.refuse(value)
        if status == "error":
            self.failures.append(_one_line(value))
            return UNKNOWN
        return value

    def call(self, query: tuple) -> tuple[str, Any]:
        """Send ``query`` to the worker process (started when there is none) and return
        ``(status, value)``: ``("ok", answer)``; ``("budget", reason)`` past a budget;
        ``("error", message)`` for an engine's error; ``("ended", exit code)`` when the
        worker ended before answering (BuDDy stops it with SIGABRT when its node table is
        full; any other crash). Counts nothing (the caller does); raises
        :class:`fretc.check.budget.RunStopped` past the run's deadline."""
        if self._proc is None or not self._proc.is_alive():
            self._start()
        try:
            self._conn.send((query, self.budget))
        except OSError:  # the worker ended before the query: a new one takes it
            self._kill()
            self._start()
            self._conn.send((query, self.budget))
        wait = None if self.deadline is None else max(0.0, self.deadline - time.monotonic())
        if not self._conn.poll(wait):
            self._kill()
            raise RunStopped("the run's wall-clock limit (--timeout) passed")
        try:
            status, value = self._conn.recv()
        except (EOFError, OSError):  # BuDDy aborts the worker when its node table is full
            self._proc.join()
            code = self._proc.exitcode
            self._kill()
            return "ended", code
        if status == "last":  # the worker ends after this answer (z3 out of memory)
            self._proc.join()
            self._kill()
            status = "ok"
        return status, value

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

    def __enter__(self) -> SpotWorker:
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
