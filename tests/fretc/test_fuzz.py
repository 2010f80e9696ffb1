"""Fuzzing, bounded: mutated FRETish sentences from the shared vectors and the
case-study corpus (``bench/fuzz.py``'s mutator, driven by hypothesis) never give a traceback:
each is rejected with a positioned ``FretishError`` or yields a monitor module that passes
``codegen.check_module`` and steps. The long run is ``python bench/fuzz.py`` (docs/contributing.md)."""

from __future__ import annotations

import random
import sys
import time
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.compiler import codegen
from fretc.common.errors import FretishError

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import fuzz  # noqa: E402
from _shared import PRESENT, needs_shared  # noqa: E402

pytestmark = needs_shared  # the seeds are the sentences of ../shared
SEEDS = fuzz.load_seeds() if PRESENT else []


def test_seeds_are_the_shared_sentences():
    assert len(SEEDS) > 400
    assert any("det_3x3" in s for s in SEEDS)  # the case-study corpus is in


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(st.randoms(use_true_random=False))
def test_mutated_sentences_never_crash(rnd):
    rng = random.Random(rnd.random())
    text = fuzz.mutate(rng, rng.choice(SEEDS), SEEDS)
    t0 = time.process_time()
    c, rejected = fuzz.front(text, "F")
    if c is None:
        if rejected != "free-form":
            assert isinstance(rejected, FretishError)
            assert str(rejected).startswith("fuzz.fret:1:")  # positioned
        return
    errors: list = []
    module = codegen.render_module([c], "m", errors)
    assert not errors, errors
    ns: dict = {}
    exec(compile(module, "m", "exec"), ns)
    for cls in ns["MONITORS"].values():
        m = cls()
        for _t in range(5):
            v = m.step({name: rng.choice((True, False, 0, 2.5)) for name in cls.VARIABLES})
            assert type(v) is bool and m.status in ("satisfied", "violated", "unknown")
    assert time.process_time() - t0 < 5 * 3  # generous: the fuzz script's bound is 5 s


def test_fuzz_script_end_to_end(tmp_path):
    """The fuzz script itself, over a few inputs: child ``python -I -S``, audit of a CSV."""
    out = tmp_path / "failures.jsonl"
    code = fuzz.main(["--count", "40", "--seed", "3", "--batch", "10", "--audit-every", "10",
                      "--quiet", "--out", str(out)])
    assert code == 0, out.read_text()
