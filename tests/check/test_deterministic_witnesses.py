"""Same input, same output: the traces Spot finds (``fretc testgen``'s tests, ``fretc
check``'s witnesses) do not depend on the Spot work the process did before.

Spot numbers the BDD variables of a dictionary's atoms in the order they are first
registered, and the accepting word Spot finds depends on that numbering. The queries used to
translate with Spot's process-wide default dictionary, which a forked query worker inherits
from its parent: a parent that held automata over the same atom names, registered in another
order (an LSP server, a library user running several commands, a test worker that ran other
tests), got other traces than ``fretc testgen`` run as a command. Each query worker now makes
its automata in a dictionary of its own (``fretc.check.solver``).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]
REQS = ROOT / "requirements"
BINDINGS = REQS / "safe_ros.bindings.toml"

#: the atoms of the Safe-ROS queries (requirements/) and some others, in orders unlike the
#: ones the queries register them in
_ORDERS = [
    ['zz', 'xx', '"LAST"', 'forwarded_zero', 'stopped', 'stop_requested', 'too_close',
     '"(linear_speed <= 0.5)"', 'scan_stale', 'yy', '"(clearance > 0)"',
     '"(angular_speed <= 0.5)"'],
    ['too_close', 'stopped', 'stop_requested', 'scan_stale', 'forwarded_zero',
     '"(linear_speed <= 0.5)"', '"(clearance > 0)"', '"(angular_speed <= 0.5)"', '"LAST"',
     'ww'],
]


def _testgen_in_process(out: Path) -> dict[str, bytes]:
    """``fretc testgen requirements/ -b ... -o out`` run the way the testgen tests run it
    (in this process, its query worker forked from it): every file written, by name."""
    shutil.rmtree(out, ignore_errors=True)
    res = CliRunner().invoke(main, ["testgen", str(REQS), "-b", str(BINDINGS), "-o", str(out)])
    assert res.exit_code == 0, res.output
    return _files(out)


def _files(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if p.is_file()}


def _differing(a: dict[str, bytes], b: dict[str, bytes]) -> list[str]:
    return sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))


def _unrelated_spot_work(order: list[str]) -> list:
    """Automata of formulas over ``order``'s atoms, translated with Spot's default BDD
    dictionary and kept (the caller holds them while it runs testgen again)."""
    import spot

    kept = []
    for a, b in zip(order, order[1:]):
        kept.append(spot.translate(f"G({a} -> F {b})"))
        kept.append(spot.translate(f"{b} U ({a} & X !{b})", "det"))
    return kept


def test_testgen_traces_do_not_depend_on_earlier_spot_work(tmp_path):
    """testgen in this process, then again while automata of other formulas (the same atoms
    and others, registered in other orders in Spot's default dictionary) are alive, then as
    a command in a new process: byte-identical files (the CSV traces name their folder, so
    every run writes to the same one)."""
    out = tmp_path / "tests"
    first = _testgen_in_process(out)
    assert json.loads(first["tests.json"])["tests"]
    for order in _ORDERS:
        kept = _unrelated_spot_work(order)
        again = _testgen_in_process(out)
        assert not _differing(first, again), (order, _differing(first, again))
        del kept
    shutil.rmtree(out)
    res = subprocess.run([sys.executable, "-m", "fretc", "testgen", str(REQS), "-b",
                          str(BINDINGS), "-o", str(out)], capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    command = _files(out)
    assert not _differing(first, command), _differing(first, command)


def _formulas_of_queries_shuffled(seed: int) -> list:
    """Spot formulas of every sub-formula of the Safe-ROS requirements' ft formulas and their
    negations, made in a shuffled order (Spot numbers a formula when it is first made and
    orders the operands of ``&`` and ``|`` by that number)."""
    import random

    import spot

    from fretc.compiler.build import compile_entries
    from fretc.compiler.printers import to_spot
    from fretc.fretish.files import load_requirements

    subs: set[str] = set()

    def walk(f) -> None:
        subs.add(str(f))
        for g in f:
            walk(g)

    for c in compile_entries(load_requirements([REQS / "safe_ros.fret"])):
        if c.formalization is not None:
            walk(spot.formula(f"!({to_spot(c.formalization.ft)})"))
    order = sorted(subs)
    random.Random(seed).shuffle(order)
    return [spot.formula(s) for s in order]


def _bdd_nodes_alive(seed: int, count: int) -> list:
    """``count`` BDDs over 60 atoms of an automaton in a dictionary of its own (the
    automaton last in the list, so the BDDs are freed before it), kept alive: the BuDDy node
    table the query worker inherits is fuller, and its nodes numbered otherwise."""
    import random

    import spot
    import buddy  # (importable once Spot is)

    rnd = random.Random(seed)
    owner = spot.make_twa_graph(spot.make_bdd_dict())
    var = [owner.register_ap(f"held{k}") for k in range(60)]
    kept: list = []
    for _ in range(count):
        b = buddy.bddtrue
        for _k in range(rnd.randint(2, 8)):
            v = buddy.bdd_ithvar(var[rnd.randrange(60)])
            b = (b & v) if rnd.random() < 0.5 else (b | buddy.bdd_not(v))
        kept.append(b)
    return [owner] + kept  # (a list frees its items from the last)


def test_testgen_traces_do_not_depend_on_what_the_parent_holds(tmp_path):
    """What a CI test worker may hold when testgen's query worker forks from it: the same
    requirements' formulas made in other orders, a fuller BuDDy node table, an in-process
    testgen of a subset (Spot, BuDDy and z3 used in this process, ``fork=False``). Each
    time the files testgen writes are byte-identical to a first run. (A CI worker once got
    other Safe-ROS tests than the command gives; none of these reproduced it.)"""
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.testing.generate import generate

    out = tmp_path / "tests"
    first = _testgen_in_process(out)
    held: list = []
    for seed in (1, 2):
        held.append(_formulas_of_queries_shuffled(seed))
        assert not _differing(first, _testgen_in_process(out)), ("formulas", seed)
    held.append(_bdd_nodes_alive(3, 100_000))
    assert not _differing(first, _testgen_in_process(out)), "BuDDy nodes"
    compiled = compile_entries(load_requirements([REQS / "safe_ros.fret"]))
    generate([c for c in compiled if c.id in ("R6", "R3")], fork=False)
    assert not _differing(first, _testgen_in_process(out)), "in-process testgen"
    del held
