"""fretc's ft, pt and ft_inf against an independent interval-semantics oracle on random
sentences over the whole grammar (tests/differential.py). A bounded sample here; the long
run is ``python bench/differential_long.py --sentences 5000``."""

from __future__ import annotations

import random

import pytest

from differential import (_World, check_requirement, oracle, random_requirement, value)

SENTENCES = 150


@pytest.mark.parametrize("chunk", range(5))
@pytest.mark.tor("TOR-SEM-002", "TOR-SEM-003", "TOR-SEM-004", "TOR-SEM-008")
def test_random_sentences_agree_with_the_oracle(chunk):
    rnd = random.Random(1000 + chunk)
    for _ in range(SENTENCES // 5):
        text, meaning = random_requirement(rnd)
        problem = check_requirement(text, meaning, rnd, traces=20)
        assert problem is None, f"{text}\n{problem}"


def test_generator_covers_the_grammar():
    rnd = random.Random(7)
    texts = [random_requirement(rnd)[0] for _ in range(400)]
    joined = "\n".join(texts)
    for needle in ("persisted(", "occurred(", "prevOcc(", "persists(", "occurs(", "nextOcc(",
                   "preBool(", "at the previous occurrence of", "at the next occurrence of",
                   " then ", "if (", '"weird var"', "a.b", "x%", "only before", "only after",
                   "only in", "except while", "when not in", "whenever", "upon", "is false",
                   "until", "before (", "within", "for ", "after 0", "at the next timepoint"):
        assert needle in joined, needle
    meanings = [random_requirement(rnd)[1] for _ in range(400)]
    assert {m["scope"] for m in meanings} == {"null", "in", "notin", "onlyIn", "after",
                                              "before", "onlyAfter", "onlyBefore"}
    assert len({m["timing"] for m in meanings}) == 12


def test_oracle_function_meanings():
    """The oracle's functions on hand-checked cases (section 6b's meaning column)."""
    tr = [{"p": False}, {"p": True}, {"p": True, "q": True}, {"p": False}]
    w = _World(tr, "null", None, False)
    at = lambda e, t: value(w, e, t)  # noqa: E731
    p, q = ("var", "p"), ("var", "q")
    assert [at(("persisted", (1,), p), t) for t in range(4)] == [False, False, True, False]
    assert [at(("occurred", (1, 2), p), t) for t in range(4)] == [False, False, True, True]
    assert [at(("prevOcc", p, q), t) for t in range(4)] == [True, True, False, True]
    assert [at(("nextOcc", p, q), t) for t in range(4)] == [False, True, True, True]
    assert [at(("occurs", (1, 2), p), t) for t in range(4)] == [True, True, False, False]
    assert [at(("persists", (1,), p), t) for t in range(4)] == [False, True, False, False]


def test_oracle_requirement_truth():
    meaning = {"scope": "in", "mode": ("var", "m"), "cond_kind": "null", "cond": None,
               "timing": "immediately", "n": 0, "stop": None,
               "response": ("prevOcc", ("var", "p"), ("var", "q"))}
    trace = [{"m": False, "p": True}, {"m": True}]
    assert oracle(meaning, trace)        # true at the interval's first position
    meaning["response"] = ("occurred", (1, 2), ("var", "p"))
    assert not oracle(meaning, [{"m": False, "p": True}, {"m": True}, {"m": True}])


@pytest.mark.parametrize("sentence", [
    "in m upon occurred(1, 2, p) the sw shall immediately satisfy q",
    "while persisted(2, p) the sw shall always satisfy q",
    "after occurred(1, 3, p) the sw shall eventually satisfy q",
    "only before persisted(1, 2, p) the sw shall always satisfy !q",
    "in m the sw shall always satisfy occurred(2, 3, p) | q",
])
@pytest.mark.tor("TOR-SEM-005", "TOR-SEM-006", "TOR-SEM-007")
def test_interval_evidence_follows_the_formulas(sentence):
    """monitors/interval.py's direct interval semantics gives the ft verdict for bounded
    occurred/persisted and for functions inside scope conditions (endpoint-free)."""
    from fretc.compiler.evaluate import ft_at
    from fretc.compiler.semantics import formalize
    from fretc.fretish import parse
    from fretc.monitors.interval import evaluate_requirement
    from _monitor_helpers import random_trace, samples

    req = parse(sentence)
    f = formalize(req)
    rnd = random.Random(3)
    for _ in range(300):
        n = rnd.randint(1, 10)
        cols = random_trace(rnd, n, variables=("m", "p", "q"), numeric=())
        ev = evaluate_requirement(req, cols, n, f.ticks)
        assert ev.holds == ft_at(f.ft, samples(cols, n)), {k: v.tolist()
                                                          for k, v in cols.items()}
