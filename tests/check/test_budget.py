"""``fretc check``'s budgets are counted in work, not seconds, and its memory is
bounded: the same input gives byte-identical JSON with and without a CPU hog
beside it, a query past a budget is unknown with the reason, subsets say what is shown of
them, and a lost game's fixed defeating input is found at any bound."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from fretc.check.analysis import check_requirements
from fretc.check.budget import Budget, BudgetSpent, Meter
from fretc.check.checker import MINIMAL, NOT_SHOWN_MINIMAL, SMALLEST, Checker
from fretc.check.solver import UNKNOWN
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements

ROOT = Path(__file__).resolve().parents[2]

#: a set decided by the monitors (past Spot's 16 ticks), with a conflict, and realizability
SET = ("A1: whenever p the sw shall within 40 ticks satisfy q\n"
       "A2: upon p the sw shall for 43 ticks satisfy !q\n"
       "A3: the sw shall eventually satisfy p\n"
       "A4: in m mode the sw shall always satisfy speed <= 0.5\n"
       "A5: in m mode upon p the sw shall within 40 ticks satisfy speed > 0.4\n")


def _command(path: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "fretc", "check", str(path), "--json",
                           *args], cwd=ROOT, env=env, capture_output=True, timeout=600)


@pytest.mark.parametrize("budget", ["20000000", "3000"])
def test_same_json_with_and_without_a_cpu_hog(tmp_path, budget):
    """The same check set run twice, once with busy-looping processes on every core beside
    it: byte-identical JSON. With a small budget some answers are unknown: the same ones
    (they depend on the work counted, not on the time it took)."""
    path = tmp_path / "set.fret"
    path.write_text(SET, encoding="utf-8")
    args = ("--budget", budget, "--inputs", "p,m", "--outputs", "q,speed")
    idle = _command(path, *args)
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
            for _ in range(os.cpu_count() or 2)]
    try:
        loaded = _command(path, *args)
    finally:
        for h in hogs:
            h.kill()
            h.wait()
    assert idle.returncode == loaded.returncode == 1
    assert idle.stdout == loaded.stdout
    doc = json.loads(idle.stdout)
    states = [r["satisfiable"] for r in doc["requirements"]]
    if budget == "3000":
        assert doc["unknown_queries"] > 0
        assert any(f["kind"] == "unknown" for f in doc["findings"])
        assert any("work budget of 3000 units spent" in n for n in doc["notes"]), doc["notes"]
    else:
        assert "unknown" not in states and doc["unknown_queries"] == 0
        (conflict,) = [f for f in doc["findings"] if f["kind"] == "conflict"]
        assert conflict["subsets"] == [["A1", "A2", "A3"]]
        assert conflict["standing"] == ["smallest"]


def test_meter_counts_nodes_and_stops_past_the_budget():
    meter = Meter(Budget(work=10))
    meter.charge(0)  # an iteration costs at least one unit
    meter.charge(9)
    assert meter.spent == 10
    with pytest.raises(BudgetSpent, match="work budget of 10 units spent"):
        meter.charge(1)
    with pytest.raises(BudgetSpent, match="memory budget of 1000000 BDD nodes"):
        Meter(Budget(memory=1_000_000)).variables(1_000_000, "a delay line")
    with pytest.raises(ValueError):
        Budget(work=0)


def test_deadlines_near_a_million_ticks_take_counters_not_delay_lines(tmp_path):
    """Deadlines near 10^6 ticks, 3 of them: the monitors allot a counter per
    deadline (not a million bits of delay line), so satisfiability of each is decided and
    the rest is unknown past the work budget, with the reason, in little memory."""
    path = tmp_path / "big.fret"
    path.write_text("H1: whenever p0 the sw shall within 1000000 ticks satisfy q1\n"
                    "H2: upon p1 the sw shall for 999993 ticks satisfy !q2\n"
                    "H3: in m2 mode the sw shall within 999986 ticks satisfy q3\n",
                    encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([path])),
                           budget=Budget(work=200_000), redundancy=False)
    assert [s["satisfiable"] for s in r.requirements] == [True, True, True]


def test_z3_lassos_past_the_memory_budget_are_skipped():
    from fretc.compiler import ir
    from fretc.check.smt import SmtSolver

    s = SmtSolver(Budget(work=100_000, memory=1_000_000))
    p, q = ir.ap("p"), ir.ap("q")
    # satisfiable by a lasso of 400 001 ticks only: past the memory budget, so not built
    got = s.sat([ir.G(p), ir.G(ir.implies(p, ir.F(q, 0, 400_000))),
                 ir.G(ir.implies(q, ir.G(ir.not_(q), 1, 400_000)))])
    assert got == UNKNOWN
    assert "skipped, past the memory budget of 1000000 BDD nodes" in s.failures[-1]


def test_z3_past_its_memory_budget_is_unknown_and_the_next_query_answers():
    """z3 runs in the worker process with what it allocates capped at the memory budget
    (z3's own count of bytes, so the cap falls at the same point on every machine): a query
    that needs more answers unknown with the reason, twice alike, and the next query gets a
    new worker and its answer. (Before, z3 had no cap: one query of a random set reached
    4.2 GB.)"""
    from fretc.compiler import ir
    from fretc.check.smt import SmtSolver
    from fretc.check.solver import SpotWorker

    p, q, r = ir.ap("p"), ir.ap("q"), ir.ap("r")
    hard = [ir.G(ir.implies(p, ir.F(q, 0, 300))), ir.G(ir.implies(q, ir.G(ir.not_(r), 1, 290))),
            ir.G(ir.implies(r, ir.F(p, 0, 170))), ir.G(ir.F(r, 0, 5000)), ir.F(p, 0, 3)]
    with SpotWorker(Budget(work=100_000_000, memory=1_000_000)) as w:
        s = SmtSolver(w.budget, worker=w)
        for _ in range(2):
            assert s.sat(hard) == UNKNOWN
            assert s.failures[-1] == ("z3: memory budget of 1000000 BDD nodes spent (z3 "
                                      "allocated more than its 24 MB)")
        assert s.spent == 2
        got = s.sat([ir.F(p, 0, 3)])
        assert got != UNKNOWN and got[0] is True


def test_a_worker_that_ends_without_an_answer_is_unknown_with_the_reason(monkeypatch):
    """The worker process ending mid-query: BuDDy's abort (SIGABRT, its node table full) is
    the memory budget, any other end says its exit code; a z3 query says z3's worker ended;
    the next query gets a new worker and its answer."""
    import signal

    from fretc.compiler import ir
    from fretc.check import solver
    from fretc.check.smt import SmtSolver
    from fretc.check.solver import SpotWorker

    real = solver.run_query

    def run_query(query, budget=None):  # runs in the forked worker
        if query[0] == "smt" or query == ("sat", "abort"):
            os.kill(os.getpid(), signal.SIGABRT)
        if query == ("sat", "exit"):
            os._exit(3)
        return real(query, budget)

    monkeypatch.setattr(solver, "run_query", run_query)
    with SpotWorker(Budget(memory=1_000_000)) as w:
        assert w.ask(("sat", "abort")) == UNKNOWN
        assert w.failures[-1] == ("memory budget of 1000000 BDD nodes spent (BuDDy's node "
                                  "table is full)")
        assert w.ask(("sat", "exit")) == UNKNOWN
        assert w.failures[-1] == "the query's worker process ended (exit code 3)"
        s = SmtSolver(w.budget, worker=w)
        assert s.sat([ir.ap("p")]) == UNKNOWN
        assert s.failures == [f"z3's worker process ended without an answer (exit code "
                              f"{-signal.SIGABRT})"]
        assert w.ask(("sat", "G p")) == (True, ([], [{"p": True}]))
        assert w.spent == 2 and s.spent == 1


# --------------------------------------------------------------------------- subsets
def _items(n: int):
    return [SimpleNamespace(index=k, id=f"H{k + 1}", variables=["x"]) for k in range(n)]


def _subsets(pool, bad, budget: int):
    fake = SimpleNamespace(mus_budget=budget)
    got = Checker.minimal_subsets(fake, pool, [], bad)
    return [[x.id for x in s] for s in got.subsets], got.standing, got.cut


@pytest.mark.tor("TOR-CHK-002")
def test_subsets_say_smallest_only_when_every_smaller_subset_was_checked():
    """{H1, H2} and {H3, H4, H5} conflict; deletion from the whole set finds
    {H3, H4, H5} first. With no budget for more checks it is minimal, not smallest; with
    the budget, {H1, H2} is the smallest."""
    pool = _items(5)

    def bad(s):
        ids = {x.index for x in s}
        return {0, 1} <= ids or {2, 3, 4} <= ids

    assert _subsets(pool, bad, 0) == ([["H3", "H4", "H5"]], [MINIMAL], True)
    assert _subsets(pool, bad, 1000) == ([["H1", "H2"], ["H3", "H4", "H5"]],
                                         [SMALLEST, MINIMAL], False)


@pytest.mark.tor("TOR-CHK-002")
def test_a_subset_with_an_unknown_check_is_not_shown_minimal():
    pool = _items(3)

    def bad(s):
        ids = {x.index for x in s}
        if ids == {1, 2}:
            return UNKNOWN  # the check that would shrink {H1, H2, H3}
        return {0, 1} <= ids and 2 in ids or {1, 2} <= ids

    names, standing, _cut = _subsets(pool, bad, 0)
    assert names == [["H1", "H2", "H3"]] and standing == [NOT_SHOWN_MINIMAL]


def test_the_command_shows_the_standing_of_a_conflicting_subset(tmp_path):
    path = tmp_path / "c.fret"
    path.write_text("C1: the sw shall always satisfy s <= 0.5\n"
                    "C2: the sw shall always satisfy s > 1.0\n", encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([path])), mus_budget=0)
    (f,) = [f for f in r.findings if f.kind == "conflict"]
    assert "minimal conflicting subset {C1, C2}" in f.message and f.cut
    assert "smallest" not in f.message


# --------------------------------------------------------------------------- lost games
def test_lost_game_at_a_thousand_ticks_has_its_fixed_defeating_input(tmp_path):
    """A fixed input that defeats every controller (request and halt, then halt forever)
    is found by one fixed point per input letter, at 1000 ticks as at 10."""
    path = tmp_path / "lost.fret"
    path.write_text("L1: whenever req the sw shall eventually satisfy done\n"
                    "L2: whenever halt the sw shall for 1000 ticks satisfy !done\n",
                    encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([path])), redundancy=False,
                           vacuity=False, inputs=["req", "halt"], outputs=["done"])
    (comp,) = r.realizability["groups"]
    assert comp["realizable"] is False and comp["method"] == "Büchi game"
    env = comp["environment"]
    assert "prefix" in env, env
    assert all(row["halt"] for row in env["cycle"])
    assert any(row["req"] for row in env["prefix"] + env["cycle"])


# --------------------------------------------------------------------------- bounded runs
#: the first 8 of the 20 (bench/bench_check.py part 7)
_H20 = Path(__file__).resolve().parents[1] / "fixtures" / "check" / "deadlines_near_1e6.fret"
_H8 = "".join(line for line in _H20.read_text(encoding="utf-8").splitlines(keepends=True)
              if line.startswith("@") or line.startswith(tuple(f"H{k}:" for k in range(8))))


def test_a_set_past_the_monitors_budget_is_answered_by_z3_and_the_run_is_bounded(tmp_path):
    """Deadlines near 10^6 ticks in a set of 8 (the shape that ran for an hour): each alone
    is decided by its monitor; the set's monitors run past the budget and z3's lasso answers
    it; after MAX_SPENT_QUERIES queries spent their whole budget, the later ones on these
    requirements are unknown without being tried, saying so. The same answers twice."""
    from fretc.check.budget import MAX_SPENT_QUERIES

    path = tmp_path / "h8.fret"
    path.write_text(_H8, encoding="utf-8")
    runs = []
    for _ in range(2):
        r = check_requirements(compile_entries(load_requirements([path])),
                               budget=Budget(work=300_000))
        runs.append(json.dumps(r.to_json(), sort_keys=True))
    assert runs[0] == runs[1]
    doc = json.loads(runs[0])
    assert all(s["satisfiable"] is True for s in doc["requirements"])
    assert any("z3 answered 1 of them" in n for n in doc["notes"]), doc["notes"]
    spent = next(n for n in doc["notes"] if "were not tried" in n)
    assert spent.startswith(f"{MAX_SPENT_QUERIES} queries spent their whole work budget")
    assert doc["monitor_queries"] <= 8 + MAX_SPENT_QUERIES + 1
    assert "unknown" in {s["non_vacuous"] for s in doc["requirements"]}


@pytest.mark.parametrize("option", ["--query-cpu", "--timeout"])
@pytest.mark.parametrize("value", ["nan", "inf", "-1", "0"])
def test_check_time_options_refuse_nan_infinities_and_non_positive(tmp_path, option, value):
    from click.testing import CliRunner

    from fretc.cli import main

    (tmp_path / "a.fret").write_text("R: the sw shall always satisfy p\n", encoding="utf-8")
    res = CliRunner().invoke(main, ["check", str(tmp_path / "a.fret"), option, value])
    # fretc's refusal naming the option, not click's wording around it
    assert res.exit_code == 2 and f"'{option}'" in res.output, res.output


@pytest.mark.tor("TOR-CHK-002")
def test_a_minimal_conflict_of_four_of_five_is_found_beside_the_pair_deletion_finds():
    """{H1, H5} and {H1, H2, H3, H4} conflict; deletion from the whole set finds
    {H1, H5}; the enumeration goes on to every size, so the conflict of four of the five is
    found too (minimal, not smallest)."""
    pool = _items(5)

    def bad(s):
        ids = {x.index for x in s}
        return {0, 4} <= ids or {0, 1, 2, 3} <= ids

    assert _subsets(pool, bad, 1000) == ([["H1", "H5"], ["H1", "H2", "H3", "H4"]],
                                         [SMALLEST, MINIMAL], False)
