"""The symbolic Büchi game of fretc check (check/buchi_game.py): realizability of sets with
``eventually`` responses. Agreement with Spot's synthesis game on random sets with small
bounds; defeating input lassos checked by Spot (no output sequence along them meets the
set) and replayed through fretc audit; the Safe-ROS R1 with R2 at 50 Hz."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.check.analysis import Checker, make_item
from fretc.check.buchi_game import _automaton
from fretc.check.pt_monitor import Outside
from fretc.check.realizability import _Decider
from fretc.check.solver import UNKNOWN, SpotWorker
from fretc.compiler import ir
from fretc.compiler.build import compile_entries
from fretc.compiler.printers import to_spot
from fretc.fretish.files import load_requirements
from tests.check._replay import replayed_unrealizable
from tests.check.test_safety_game import realizability_of

_LIVENESS = [
    "whenever {a} the sw shall eventually satisfy {b}",
    "upon {a} the sw shall eventually satisfy {b}",
    "the sw shall eventually satisfy {b}",
    "in m mode the sw shall eventually satisfy {b}",
    "after m the sw shall eventually satisfy {b}",
    "whenever {a} the sw shall until {c} satisfy {b}",
    "whenever {a} the sw shall eventually satisfy s > 0.6",
]
_SAFETY = [
    "whenever {a} the sw shall within {k} ticks satisfy {b}",
    "upon {a} the sw shall for {k} ticks satisfy {b}",
    "the sw shall always satisfy {a} -> {b}",
    "whenever {a} the sw shall immediately satisfy {b}",
    "in m mode upon {a} the sw shall within {k} ticks satisfy {b}",
    "the sw shall always satisfy s <= 0.5 | {a}",
]
_LITERALS = ["i", "!i", "j", "o", "!o", "p", "!p", "o | p", "i & o"]
_INPUTS = ["i", "j", "m"]


def _items(path: Path):
    return [make_item(k, c) for k, c in enumerate(compile_entries(load_requirements([path])))]


def _lasso_defeats(items, prefix: list[dict], cycle: list[dict]) -> bool:
    """Spot's own answer: along the input word ``prefix cycle^w``, does no output sequence
    meet every requirement's ft_inf? (The product of the set's automaton with the word's
    is empty; the word constrains the inputs only.)"""
    import spot

    spec = spot.translate(to_spot(ir.and_all(*(x.phi for x in items))))

    def letter(row: dict) -> str:
        return "&".join(str(spot.formula.ap(k)) if v else "!" + str(spot.formula.ap(k))
                        for k, v in sorted(row.items())) or "1"

    text = ";".join([letter(r) for r in prefix] + ["cycle{" + ";".join(map(letter, cycle))
                                                   + "}"])
    word = spot.parse_word(text, spec.get_dict()).as_automaton()
    return spot.product(spec, word).is_empty()


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(_SAFETY), st.sampled_from(_LITERALS),
                          st.sampled_from(_LITERALS), st.sampled_from(["i", "o", "j"]),
                          st.integers(1, 8)), max_size=2),
       st.lists(st.tuples(st.sampled_from(_LIVENESS), st.sampled_from(_LITERALS),
                          st.sampled_from(_LITERALS), st.sampled_from(["i", "o", "j"])),
                min_size=1, max_size=2))
@pytest.mark.tor("TOR-CHK-003")
def test_buchi_game_agrees_with_spot(tmp_path, safety, liveness):
    """Random sets with an ``eventually`` or ``until`` (inputs i, j, m; outputs o, p;
    bounds up to 8 ticks): the Büchi game (engine auto) and Spot's game (engine spot) give
    the same answer; a lost game's input lasso defeats every controller by Spot's check."""
    lines = [t.format(a=a, b=b, c=c, k=k) for t, a, b, c, k in safety]
    lines += [t.format(a=a, b=b, c=c) for t, a, b, c in liveness]
    text = "".join(f"R{n}: {line}\n" for n, line in enumerate(lines))
    path = tmp_path / "r.fret"
    path.write_text(text, encoding="utf-8")
    items = _items(path)
    with SpotWorker() as worker:
        decide = _Decider(Checker(items, worker, engine="auto"), _INPUTS)
        game = decide(items)
        spot = _Decider(Checker(items, worker, engine="spot"), _INPUTS)(items)
        if UNKNOWN in (game, spot):
            return
        assert game["realizable"] == spot["realizable"], (text, game, spot)
        # every set here is the games': Spot's only when the Büchi game failed
        assert game["method"] in ("safety game", "Büchi game"), (text, game)
        if game["method"] != "Büchi game" or game["realizable"]:
            return
        found = decide.witness(items, game)
    if found["counter"] is not None:
        assert _lasso_defeats(items, *found["counter"]), (text, found["counter"])
    else:
        assert "react" in found["note"], found


def test_safe_ros_at_50_hz(tmp_path):
    """R1 (whenever too_close eventually stopped) with R2 (upon too_close within 1 second
    stopped) at a 20 ms tick: 50 ticks, past Spot's game, decided realizable by the Büchi
    game over R2's deadline counter and R1's two-state automaton."""
    comp = realizability_of(
        tmp_path, "@tick_period 20 ms\n"
        "R1: whenever too_close agilex_agent shall eventually satisfy stopped\n"
        "R2: upon too_close agilex_agent shall within 1 second satisfy stopped\n",
        ["too_close"])
    assert comp["realizable"] is True and comp["method"] == "Büchi game", comp
    assert comp["strategy"]["automaton_states"] == [2]
    assert comp["strategy"]["state_bits"] < 16


def test_a_recurrence_spot_translates_nondeterministically(tmp_path):
    """``upon o | p ... eventually o`` (outputs only): Spot's translation preferring
    determinism gives a nondeterministic automaton, but the formula has a deterministic Büchi
    one (found by determinizing): the Büchi game decides it, not Spot's game (a case
    hypothesis found)."""
    comp = realizability_of(tmp_path, "R0: upon o | p the sw shall eventually satisfy o\n",
                            ["i", "j", "m"])
    assert comp["realizable"] is True and comp["method"] == "Büchi game", comp


@pytest.mark.tor("TOR-CHK-001", "TOR-CHK-003")
def test_lost_game_lasso_replays_through_the_audit(tmp_path):
    """``eventually`` against a 50-tick hold the environment re-triggers every other tick:
    unrealizable; the input lasso (Spot's check: it defeats every controller) with a
    controller's best effort, written as a witness CSV, makes fretc audit find the
    ``eventually`` violated, as the witness header promises."""
    req = tmp_path / "set.fret"
    req.write_text("A: whenever p the sw shall eventually satisfy q\n"
                   "B: upon r the sw shall for 50 ticks satisfy !q\n", encoding="utf-8")
    comp = replayed_unrealizable(req, ["p", "r"], "Büchi game", tmp_path)
    assert comp["minimal_unrealizable"] == [["A", "B"]]
    env = comp["environment"]
    assert len(env["prefix"]) + len(env["cycle"]) <= 2
    assert any(row["r"] for row in env["cycle"]) and not all(row["r"] for row in env["cycle"])


def test_no_deterministic_buchi_automaton():
    """A persistence property (``F G``) has no deterministic Büchi automaton: the game
    refuses it (the caller goes to Spot's game) instead of answering on a wrong one."""
    with pytest.raises(Outside, match="no deterministic Büchi automaton"):
        _automaton(ir.F(ir.G(ir.ap("p"))))
    assert _automaton(ir.G(ir.implies(ir.ap("p"), ir.F(ir.ap("q"))))).num_states() == 2
