"""The symbolic safety game of fretc check (check/safety_game.py): agreement with Spot's
synthesis game on random sets with small bounds, defeating inputs replayed through fretc
audit, the reactive environment, and bounds of hundreds of ticks."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.check.analysis import Checker, check_requirements, make_item
from fretc.check.realizability import _Decider
from fretc.check.safety_game import is_safety
from fretc.check.solver import UNKNOWN, SpotWorker
from fretc.compiler import ir
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from tests.check._replay import replayed_unrealizable
from tests.check._roles import rest_as_outputs

_TEMPLATES = [
    "whenever {a} the sw shall within {k} ticks satisfy {b}",
    "upon {a} the sw shall for {k} ticks satisfy {b}",
    "the sw shall always satisfy {a} -> {b}",
    "whenever {a} the sw shall immediately satisfy {b}",
    "upon {a} the sw shall at the next timepoint satisfy {b}",
    "in m mode the sw shall always satisfy {b}",
    "in m mode upon {a} the sw shall within {k} ticks satisfy {b}",
    "whenever {a} the sw shall until {c} satisfy {b}",
    "upon {a} the sw shall after {k} ticks satisfy {b}",
    "whenever {a} the sw shall before {c} satisfy {b}",
    "the sw shall eventually satisfy {b}",
]
_LITERALS = ["i", "!i", "j", "o", "!o", "p", "!p", "o | p", "i & o"]


def _items(path: Path):
    return [make_item(k, c) for k, c in enumerate(compile_entries(load_requirements([path])))]


def realizability_of(tmp_path: Path, text: str, inputs: list[str]) -> dict:
    """The realizability entry of the first component of the set ``text`` (satisfiability
    checks only, no vacuity or redundancy; the variables other than ``inputs`` outputs)."""
    p = tmp_path / "r.fret"
    p.write_text(text, encoding="utf-8")
    compiled = compile_entries(load_requirements([p]))
    r = check_requirements(compiled, inputs=inputs, outputs=rest_as_outputs(compiled, inputs),
                           vacuity=False, redundancy=False)
    return r.realizability["groups"][0]


def _decide(items, engine: str, worker):
    checker = Checker(items, worker, engine=engine)
    return _Decider(checker, ["i", "j", "m"])(items)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(_TEMPLATES), st.sampled_from(_LITERALS),
                          st.sampled_from(_LITERALS), st.sampled_from(["i", "o", "j"]),
                          st.integers(1, 10)), min_size=1, max_size=3))
def test_game_agrees_with_spot(tmp_path, parts):
    """Random sets (inputs i, j, m; outputs o, p; bounds up to 10 ticks): the safety game
    (engine auto) and Spot's game (engine spot) give the same answer when both decide."""
    text = "".join(f"R{n}: " + t.format(a=a, b=b, c=c, k=k) + "\n"
                   for n, (t, a, b, c, k) in enumerate(parts))
    path = tmp_path / "r.fret"
    path.write_text(text, encoding="utf-8")
    items = _items(path)
    with SpotWorker() as worker:
        game = _decide(items, "auto", worker)
        spot = _decide(items, "spot", worker)
    if UNKNOWN in (game, spot):
        return
    assert game["realizable"] == spot["realizable"], (text, game, spot)
    if all(is_safety(x.phi) for x in items):
        assert game["method"] == "safety game"


@pytest.mark.parametrize("text, inputs", [
    ("A: the r shall always satisfy s <= 0.5\n"
     "B: whenever p the r shall immediately satisfy s > 0.6\n", ["p"]),
    ("A: whenever p the sw shall within 6 ticks satisfy q\n"
     "B: upon p the sw shall for 4 ticks satisfy !q\n", ["p"]),
    ("U1: upon too_close the robot shall within 3 ticks satisfy stopped\n"
     "U2: the robot shall always satisfy too_close\n", ["too_close"]),
    ("C: in m mode upon p the sw shall within 5 ticks satisfy speed > 0.6\n"
     "D: in m mode the sw shall always satisfy speed <= 0.5\n", ["p", "m"]),
])
def test_defeating_inputs_replay_through_the_audit(tmp_path, text, inputs):
    """Unrealizable sets: the defeating inputs with the best effort of a controller, written
    as a witness CSV, make fretc audit find a requirement of the set violated, as the
    witness header promises."""
    req = tmp_path / "set.fret"
    req.write_text(text, encoding="utf-8")
    comp = replayed_unrealizable(req, inputs, "safety game", tmp_path)
    assert comp["environment"]["prefix"], comp


def test_reactive_environment(tmp_path):
    """The controller must guess the next input: unrealizable, yet every fixed input
    sequence has matching outputs (the search exhausts the sets of monitor states)."""
    text = ("R1: the sw shall always satisfy o | q\n"
            "R2: whenever o the sw shall at the next timepoint satisfy i\n"
            "R3: whenever q the sw shall at the next timepoint satisfy !i\n")
    comp = realizability_of(tmp_path, text, ["i"])
    assert comp["realizable"] is False and "prefix" not in comp["environment"]
    assert "must react" in comp["environment"]["note"]
    p = tmp_path / "r.fret"
    with SpotWorker() as worker:
        assert _decide(_items(p), "spot", worker)["realizable"] is False


def test_hundreds_of_ticks(tmp_path):
    """A 200-tick deadline against a 197-tick hold: the environment re-triggers the hold
    before the deadline (a fixed input sequence of 201 ticks); a lone 200-tick deadline is
    realizable. Spot's game cannot take these bounds in time."""
    p = tmp_path / "r.fret"
    p.write_text("A: whenever p the sw shall within 200 ticks satisfy q\n"
                 "B: upon p the sw shall for 197 ticks satisfy !q\n", encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([p])), inputs=["p"],
                           outputs=["q"], vacuity=False, redundancy=False)
    comp = r.realizability["groups"][0]
    assert comp["realizable"] is False and comp["minimal_unrealizable"] == [["A", "B"]]
    prefix = comp["environment"]["prefix"]
    assert prefix[0]["p"] is True and sum(row["p"] for row in prefix) == 2
    p.write_text("A: whenever p the sw shall within 200 ticks satisfy q\n", encoding="utf-8")
    r = check_requirements(compile_entries(load_requirements([p])), inputs=["p"],
                           outputs=["q"], vacuity=False, redundancy=False)
    comp = r.realizability["groups"][0]
    # the deadline is one counter of the oldest pending trigger's age (9 bits for 0..201),
    # not a delay line of 200 bits
    assert comp["realizable"] is True and comp["strategy"]["state_bits"] < 16


def test_syntactic_safety():
    """Sistla's fragment: bounded operators, G and release positive; F and U negative."""
    p, q = ir.ap("p"), ir.ap("q")
    assert is_safety(ir.G(ir.implies(p, ir.F(q, 0, 300))))
    assert is_safety(ir.V(p, q)) and is_safety(ir.not_(ir.F(p)))
    assert not is_safety(ir.F(p)) and not is_safety(ir.G(ir.implies(p, ir.F(q))))
    assert not is_safety(ir.U(p, q)) and not is_safety(ir.not_(ir.G(p)))
    assert not is_safety(ir.iff(p, ir.G(q)))
