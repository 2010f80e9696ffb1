"""The audit of a CSV trace read and judged in small chunks equals the audit of the same
trace read and judged whole (differential, on random traces): the file read 1 to 5 rows at a
time (:data:`fretc.logs.csv.read.CHUNK_ROWS`), rows as blocks of 1 to 5 ticks where blocks
are used (the columns kept a block at a time, a topic's log times shared with the ticks'
times while they are equal) and the robustness a chunk of 1 to 5 ticks at a time, so that the
chunks' edges fall everywhere, inside runs of ``unknown`` cells and ``gap`` rows and just
before a ``cut`` row. Verdicts, evidence, LTL3 verdicts, robustness, margins, problems and
the whole audit JSON must be the same bytes. The requirements are judged over the whole
trace's columns here (``streamed.ENABLED`` off): the judge fed the rows as they are read is
tests/audit/test_streamed.py's."""

from __future__ import annotations

import functools
import json
import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fretc.audit.passes as passes
import fretc.audit.streamed as streamed
import fretc.logs.csv.read as csv_read
import fretc.monitors.robustness as robustness
import fretc.signals.blocks as blocks
from _logs import written_plan
from fretc.audit import audit_log

REQUIREMENTS = """\
R1: the sw shall always satisfy x < 2
R2: upon p the sw shall within 3 ticks satisfy q
R3: whenever p the sw shall immediately satisfy x >= 0.5 | q
R4: in q mode the sw shall always satisfy x <= 3
R5: after p the sw shall eventually satisfy q
R6: upon p the sw shall for 2 ticks satisfy x > 0
R7: the sw shall always satisfy x < 2.5 & !(p & q)
"""
XS = ["0.0", "0.5", "1.0", "1.5", "2.25", "-1", "3.5", "nan"]


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    return written_plan(str(tmp_path_factory.mktemp("chunks")), "chunks.fret", REQUIREMENTS)


@pytest.fixture(autouse=True)
def whole_trace_judge(monkeypatch):
    """The columns of every tick kept and judged at once (not streamed)."""
    monkeypatch.setattr(streamed, "ENABLED", False)


def _trace(rnd: random.Random, n: int, timed: bool, unknown: float, gaps: float,
           cut: bool, nan: bool = True) -> str:
    """A CSV trace of ``n`` rows (``unknown``: the chance of an ``unknown`` cell, ``gaps`` of a
    ``gap`` row; ``cut``: a last ``cut`` row; ``nan``: x may be NaN, an unknown tick)."""
    xs = XS if nan else XS[:-1]
    lines = ["time,x,p,q" if timed else "x,p,q"]
    t = 0.0
    for _ in range(n):
        t += rnd.choice([0.1, 0.1, 0.2, 0.0])
        if rnd.random() < gaps:
            cells = ["gap"] * 3
        else:
            cells = [rnd.choice(xs), rnd.choice("01"), rnd.choice("01")]
            cells = [c if rnd.random() >= unknown else "unknown" for c in cells]
        lines.append(",".join(([f"{t:.1f}"] if timed else []) + cells))
    if cut:
        t += 0.1
        lines.append(",".join(([f"{t:.1f}"] if timed else []) + ["cut"] * 3))
    return "\n".join(lines) + "\n"


def _audit_json(plan, path: str) -> str:
    la = audit_log(plan, path)
    return json.dumps(la.to_json(), sort_keys=True, default=str)


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40), st.booleans(), st.sampled_from([0.0, 0.0, 0.05, 0.2]),
       st.sampled_from([0.0, 0.0, 0.1]), st.booleans(), st.booleans(), st.integers(1, 5),
       st.integers(1, 5), st.randoms(use_true_random=False))
def test_chunked_audit_equals_the_whole_file_audit(plan, tmp_path_factory, n, timed, unknown,
                                                   gaps, cut, nan, block, chunk, rnd):
    path = tmp_path_factory.mktemp("t") / "trace.csv"
    path.write_text(_trace(rnd, n, timed, unknown, gaps, cut, nan), encoding="utf-8")
    whole = _audit_json(plan, str(path))
    small = functools.partial(blocks.blocks_of_ticks, size=block)
    mp = pytest.MonkeyPatch()
    try:
        mp.setattr(passes, "blocks_of_ticks", small)
        mp.setattr(blocks, "blocks_of_ticks", small)
        mp.setattr(csv_read, "CHUNK_ROWS", block)
        mp.setattr(robustness, "ROBUSTNESS_CHUNK", chunk)
        chunked = _audit_json(plan, str(path))
    finally:
        mp.undo()
    assert chunked == whole


def test_the_chunks_are_exercised(plan, tmp_path):
    """The relation above is not vacuous: on a plain trace of 40 rows every requirement is
    judged with a robustness (evaluated in chunks of 3 ticks), and one verdict is violated
    (its evidence compared too)."""
    path = tmp_path / "plain.csv"
    path.write_text(_trace(random.Random(5), 40, True, 0.0, 0.0, False, nan=False), encoding="utf-8")
    calls = []
    original = robustness.RobustnessStream._evaluate

    def spy(self, columns, k, times):
        calls.append((self.start, self.start + k))
        original(self, columns, k, times)

    mp = pytest.MonkeyPatch()
    try:
        mp.setattr(robustness, "ROBUSTNESS_CHUNK", 3)
        mp.setattr(robustness.RobustnessStream, "_evaluate", spy)
        la = audit_log(plan, str(path))
    finally:
        mp.undo()
    assert calls and (0, 3) in calls and (39, 40) in calls
    assert "violated" in [v.verdict for v in la.verdicts]
    assert all(v.robustness is not None for v in la.verdicts if v.verdict != "error")
