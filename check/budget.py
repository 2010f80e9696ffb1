"""The budgets of ``fretc check``'s queries, counted in work the engines do, never in seconds:
the same input gets the same answers on an idle and on a loaded machine.

Design notes: ARCHITECTURE.md, `check/budget.py`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Budget", "BudgetSpent", "RunStopped", "Meter", "DEFAULT_WORK", "DEFAULT_MEMORY",
           "MIN_MEMORY", "MUS_BUDGET", "UNKNOWN", "STEP_KNEE", "DEFAULT_QUERY_CPU", "step_cost",
           "Z3_RLIMIT_PER_UNIT", "FALLBACK_SHARE", "MAX_SPENT_QUERIES", "NODES_PER_VARIABLE", "NODES_PER_Z3_TERM", "BYTES_PER_NODE"]

#: Answer of a query past its budget (or that its engine could not take).
UNKNOWN = "unknown"

#: work units per query by default: 3.6 times what the costliest query of the benchmark's
#: sets needs (11 million units, the vacuity of the 1000-tick set); about 4 s of this machine
#: on the benchmark's relations, about a minute where a step is costliest per unit
DEFAULT_WORK = 40_000_000
#: a transition relation of up to this many BDD nodes costs one unit a node a step; past it
#: a step costs ``nodes * (nodes / STEP_KNEE) ** 1.5`` (:func:`step_cost`)
STEP_KNEE = 20_000
#: CPU seconds one query may take (``fretc check --query-cpu``): a single BuDDy operation
#: cannot be metered or stopped from Python, so a query whose steps the work budget did not
#: foresee is stopped there (its worker process ends) and answers unknown
DEFAULT_QUERY_CPU = 60
#: BDD nodes of BuDDy's table per query by default (about 200 MB of nodes and caches)
DEFAULT_MEMORY = 8_000_000
#: subset checks per enumeration of minimal subsets by default (``fretc check --mus-budget``)
MUS_BUDGET = 256
#: the share of the work budget z3 has where it is asked after the monitors ran past theirs
#: (or first, once it answered such a query): z3 spends about 2 * 10^6 rlimit a second on
#: the lassos of deadlines near 10^6 ticks, so a tenth is some 20 s of this machine
FALLBACK_SHARE = 0.1
#: queries of a run that may spend their whole work budget on one set of formulas; a later
#: query on any of those formulas is unknown at once (the run ends in bounded time:
#: ``fretc check``'s 20-requirement set with 10^6-tick deadlines in about a minute of CPU)
MAX_SPENT_QUERIES = 2
#: z3's ``rlimit`` per work unit (z3 spends about 10^7 rlimit a second on these queries)
Z3_RLIMIT_PER_UNIT = 10
#: the memory one BDD variable takes in BuDDy and Spot's dictionary, in BDD nodes (measured:
#: 2 million variables took about 900 MB, some 23 nodes of 20 bytes each)
NODES_PER_VARIABLE = 32
#: the memory one term of z3's lasso encoding takes, in BDD nodes (measured about 150
#: bytes a term)
NODES_PER_Z3_TERM = 8
#: the bytes one BDD node of the memory budget stands for where an engine counts bytes (z3):
#: a BuDDy node is 20 bytes, its caches add about a quarter (the default budget of 8 million
#: nodes is about 200 MB)
BYTES_PER_NODE = 25


class BudgetSpent(Exception):
    """A query ran past its work or memory budget; the message says which, in its unit."""


class RunStopped(Exception):
    """The run's wall-clock limit (``fretc check --timeout``) passed: the whole run stops
    with no report (no answer is changed by it; exit code 3)."""


@dataclass(frozen=True)
class Budget:
    """The budgets of one query: ``work`` in work units, ``memory`` in BDD nodes (module
    docstring), ``cpu`` the CPU seconds it may take in the worker process. Raises
    ``ValueError`` for a budget under 1 (work), under :data:`MIN_MEMORY` (memory: BuDDy's
    table starts that large), or a CPU limit that is not a finite positive number."""

    work: int = DEFAULT_WORK
    memory: int = DEFAULT_MEMORY
    #: CPU seconds a query may take in the worker process (:data:`DEFAULT_QUERY_CPU`)
    cpu: float = DEFAULT_QUERY_CPU

    def __post_init__(self):
        if self.work < 1:
            raise ValueError(f"the work budget must be at least 1 unit, not {self.work}")
        if not (isinstance(self.cpu, (int, float)) and 0 < self.cpu < 10**7):
            raise ValueError(f"the CPU limit of a query must be a number of seconds above 0 "
                             f"and below 10^7, not {self.cpu!r}")
        if self.memory < MIN_MEMORY:
            raise ValueError(f"the memory budget must be at least {MIN_MEMORY} BDD nodes, "
                             f"not {self.memory}")

    def share(self, fraction: float) -> Budget:
        """This budget with ``fraction`` of its work (at least 1 unit), the same memory and
        CPU limit."""
        return Budget(max(1, int(self.work * fraction)), self.memory, self.cpu)

    def work_spent(self) -> str:
        """The reason of an answer past the work budget."""
        return f"work budget of {self.work} units spent"

    def memory_spent(self, what: str) -> str:
        """The reason of an answer past the memory budget (``what`` needed it)."""
        return f"memory budget of {self.memory} BDD nodes spent ({what})"


#: the smallest memory budget: BuDDy's node table as Spot starts it is about this large
MIN_MEMORY = 1_000_000


def step_cost(nodes: int) -> int:
    """The work units of one fixed-point step through a transition relation of ``nodes``
    BDD nodes: ``nodes`` up to :data:`STEP_KNEE`, then ``nodes * (nodes / STEP_KNEE) **
    1.5``. The relational products of a step grow faster than the relation once it is large
    (measured on this machine: a relation of 3,100 nodes took 0.2 ms a step, the product of
    20 requirements with deadlines near 10^6 ticks, 700,000 nodes, minutes for its first
    step): charged so, a budget ends such a query before its first step, and the same
    budget still lets the small relations take thousands of steps."""
    if nodes <= STEP_KNEE:
        return nodes
    return int(nodes * (nodes / STEP_KNEE) ** 1.5)


class Meter:
    """The work one query has done, against ``budget`` (a :class:`Budget`); ``share``
    (0 < share <= 1): the part of the work budget this meter may spend."""

    def __init__(self, budget: Budget, share: float = 1.0):
        self.budget = budget
        self.limit = max(1, int(budget.work * share))
        self.spent = 0
        #: units every iteration pays besides its sets: the nodes of the relation it
        #: steps through (set by the engine, :meth:`relation`)
        self.base = 0

    def relation(self, b: Any, *bdds: Any) -> None:  # the buddy module, its BDDs
        """Set :attr:`base` to the cost of a step through ``bdds`` (the relation each
        iteration reads: :func:`step_cost` of its nodes); raises :class:`BudgetSpent` when
        one step is past what is left of the budget (the step is not taken: one BDD
        operation cannot be stopped once started)."""
        nodes = sum(b.bdd_nodecount(x) for x in bdds)
        self.base = step_cost(nodes)
        if self.spent + self.base > self.limit:
            raise BudgetSpent(f"{self.budget.work_spent()}: one step of the fixed point over "
                              f"a transition relation of {nodes} BDD nodes costs "
                              f"{self.base} units")

    def charge(self, units: int) -> None:
        """Pay ``units`` (at least one); raises :class:`BudgetSpent` past the limit."""
        self.spent += max(1, units)
        if self.spent > self.limit:
            raise BudgetSpent(self.budget.work_spent())

    def nodes(self, b: Any, *bdds: Any) -> None:
        """Pay one iteration: the BDD nodes of ``bdds`` (``b``: the buddy module) and
        :attr:`base`."""
        self.charge(self.base + sum(b.bdd_nodecount(x) for x in bdds))

    def variables(self, count: int, what: str) -> None:
        """Check before making ``count`` BDD variables; raises :class:`BudgetSpent` when
        they alone pass the memory budget."""
        if count * NODES_PER_VARIABLE > self.budget.memory:
            raise BudgetSpent(self.budget.memory_spent(f"{what}: {count} BDD variables"))
