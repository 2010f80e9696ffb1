"""The LTL3 tables fretc embeds are exactly Spot's LTL3 monitors of ft_inf.

Differential, per requirement shape and polarity (``bad`` = monitor of ft_inf, ``good`` = of
its negation; Bauer, Leucker & Schallhart, TOSEM 2011): the tables of
``compiler.spot_monitors.spot_automata`` (what the disk cache stores: for a safety or guarantee
shape one monitor from Spot's terminal automaton of the guarantee side and the other derived
from it; otherwise Spot's ``low`` translation with ``spot_monitors.LOW_XARGS``, then
:mod:`fretc.compiler.dfa`'s subset construction pruned by simulation and its minimization) equal the table of Spot's own construction from its default ``low``
translation (``tgba_powerset`` + ``minimize_monitor``; Moore's refinement instead of
``minimize_monitor`` on powersets of more than 3000 states), both renamed breadth-first.

The default run checks a fixed random sample of FRET's trace-vector sentences and of the 288
template keys at small bounds; ``-m slow`` checks all 696 sentences of
``fret_trace_verdicts.jsonl`` and all 288 template keys with every bound at 12 ticks
(minutes).
"""

from __future__ import annotations

import random
import sys
from pathlib import Path

import pytest

spot = pytest.importorskip("spot")

from fretc.compiler import automata, dfa, ir, spot_monitors  # noqa: E402
from fretc.compiler.printers import to_spot  # noqa: E402
from fretc.compiler.semantics import formalize  # noqa: E402
from fretc.fretish import parse  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from bench_codegen import template_sentences  # noqa: E402
from _shared import jsonl, params  # noqa: E402


def _verdict_sentences() -> list[str]:
    """The sentences of FRET's trace vectors (none without ../shared)."""
    texts: dict[str, None] = {}
    for row in jsonl("fretish/fret_trace_verdicts.jsonl"):
        texts.update((c["sentence"], None) for c in row["cases"])
    return list(texts)


#: Above this many states Spot's powerset is minimized by Moore's refinement
#: (``compiler.dfa.minimize``) instead of Spot's ``minimize_monitor`` (which takes minutes on
#: a 40,000-state powerset).
REFERENCE_MINIMIZE_MAX = 3000


def _table(aut, n_atoms: int) -> tuple[int, list[list[int]]]:
    return aut.get_init_state_number(), spot_monitors.letter_rows(aut, n_atoms)


def _spot_reference(text: str, negate: bool, n_atoms: int):
    """Spot's minimal LTL3 monitor of ``text`` (or its negation) as (table, empty): Spot's
    default ``low`` translation, its ``tgba_powerset``, then ``minimize_monitor`` (or Moore's
    refinement beyond :data:`REFERENCE_MINIMIZE_MAX` states)."""
    f = spot.formula(text)
    aut = spot.translate(spot.formula.Not(f) if negate else f, "monitor", "low")
    empty = bool(aut.is_empty())
    det = aut if aut.is_deterministic() else spot.tgba_powerset(aut)
    if det.num_states() <= REFERENCE_MINIMIZE_MAX:
        init, rows = _table(spot.minimize_monitor(det), n_atoms)
    else:
        init, rows = _table(det, n_atoms)
        init, rows = spot_monitors._bfs_tables(init, rows)
        init, rows = dfa.minimize(rows)
    return spot_monitors._bfs_tables(init, rows)[1], empty


def check_exact(sentence: str) -> bool:
    """Assert that both LTL3 tables of ``sentence``'s ft_inf equal Spot's; False when the
    sentence is outside Spot's construction (bounds, atoms: formula progression or none)."""
    shape, atoms = automata.canonical_shape(formalize(parse(sentence)).ft_inf)
    bounds = [n.hi for n in ir.walk(shape) if n.hi is not None]
    if len(atoms) > automata.MAX_LTL3_ATOMS or (bounds and (
            max(bounds) > automata.MAX_LTL3_BOUND
            or sum(bounds) > automata.MAX_LTL3_BOUND_SUM)):
        return False
    text = to_spot(shape)
    got = spot_monitors.spot_automata(text, len(atoms), automata.MAX_AUTOMATON_STATES,
                                      automata.TABLE_MAX_APS)
    for negate in (False, True):
        ours = got["good" if negate else "bad"]
        assert ours is not None, (sentence, negate)
        assert (ours["table"], ours["empty"]) == _spot_reference(text, negate, len(atoms)), \
            (sentence, negate)
    return True


SAMPLE = params(lambda: random.Random(11).sample(_verdict_sentences(), 40)) + \
    random.Random(11).sample(template_sentences(3), 20) + [
    # a 40,000-subset powerset (15 pruned by simulation)
    "only in mm whenever cc the sw shall after 8 ticks satisfy rr"]


@pytest.mark.parametrize("sentence", SAMPLE)
@pytest.mark.tor("TOR-VER-009", "TOR-GEN-002")
def test_ltl3_tables_equal_spots(sentence):
    assert check_exact(sentence)


@pytest.mark.slow
@pytest.mark.parametrize("sentence", params(_verdict_sentences) + template_sentences(12))
def test_ltl3_tables_equal_spots_full_sweep(sentence):
    check_exact(sentence)
