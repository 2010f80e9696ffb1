"""The interval semantics fed a chunk at a time (:class:`fretc.monitors.interval.IntervalStream`)
at every chunk boundary: for every requirement it takes in chunks, every trace and every split
of the trace into chunks (chunks of 0 and 1 tick, uneven ones), its :class:`Evidence` must
equal the one of the whole trace fed as one chunk (:func:`fretc.monitors.interval.
evaluate_requirement`: every field, each listed violation's window, violation tick and reason
included) and the times it gives must be those of the ticks the evidence names, as fed. What
the whole trace's evidence must be is tested against FRET's own verdicts, the generated
monitors and an independent oracle (test_evidence.py, test_evidence_functions.py).

* random sentences of tests/differential.py's generator (the ones the stream refuses must be
  exactly those using one of FRET's temporal functions), on short random traces and on longer
  ones with sparse events and long runs;
* every scope x condition x timing (``within``/``for``/``after`` of 0, 1 and 3 ticks);
* boolean columns fed as ``bool``, ``uint8`` 0/1 or ``float64`` 0/1, the type changing from
  chunk to chunk (the CSV reader decides a column's type at the end of the file);
* ``FTP``, uninterpreted functions, the refusals and the errors;
* memory independent of the trace's length (tracemalloc).

``pytest -m slow`` runs a longer property run (hypothesis) and more of each sample.
"""

from __future__ import annotations

import random
import tracemalloc
from collections.abc import Iterator, Mapping

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.fretish import ast as A
from fretc.fretish import parse
from fretc.monitors.interval import (MAX_LISTED, NOT_POINTWISE, Evidence, EvidenceUnsupported,
                                     IntervalStream, evaluate_requirement, stream_unsupported)

from _monitor_helpers import compiled, requirement
from differential import BOOL_VARS, MODE_VARS, NUM_VARS, random_requirement, random_trace

#: chunk sizes drawn for a split (0 and 1 often)
SIZES = (0, 0, 1, 1, 1, 2, 3, 5, 8, 13, 40, 97)
#: the types a boolean column may arrive in
BOOL_TYPES = (np.bool_, np.uint8, np.float64)


def time_of(tick: int) -> int:
    return 1000 * tick + 7


def named_ticks(ev: Evidence) -> set[int]:
    """The ticks an evidence names (first interval, first trigger, each listed violation)."""
    out: set[int] = set()
    if ev.first_interval is not None:
        out.update(ev.first_interval)
    if ev.first_trigger is not None:
        out.add(ev.first_trigger)
    for v in ev.listed + ([ev.violation] if ev.violation else []):
        out.update((v.trigger_tick, *v.interval, *v.window, v.violation_tick))
    return out


def random_chunks(cols: Mapping[str, np.ndarray], n: int, rnd: random.Random,
                  sizes: tuple[int, ...] = SIZES, retype: bool = True
                  ) -> Iterator[tuple[int, int, dict[str, np.ndarray]]]:
    """``(first tick, ticks, chunk)`` of ``cols`` split at random (``sizes``), each boolean
    column of each chunk in a random type of :data:`BOOL_TYPES` (``retype``)."""
    i = 0
    while i < n:
        k = min(rnd.choice(sizes), n - i)
        chunk = {}
        for name, col in cols.items():
            part = col[i:i + k]
            if retype and part.dtype == np.bool_:
                part = part.astype(rnd.choice(BOOL_TYPES))
            chunk[name] = part
        yield i, k, chunk
        i += k


def streamed(req: A.Requirement, ticks: int | None, cols: Mapping[str, np.ndarray], n: int,
             rnd: random.Random, sizes: tuple[int, ...] = SIZES, retype: bool = True
             ) -> tuple[Evidence, dict[int, int]]:
    """The stream's evidence and times over ``cols`` split at random (``sizes``), each
    boolean column of each chunk in a random type of :data:`BOOL_TYPES` (``retype``)."""
    s = IntervalStream(req, ticks)
    times = time_of(np.arange(n, dtype=np.int64))
    for i, k, chunk in random_chunks(cols, n, rnd, sizes, retype):
        s.feed(chunk, k, times[i:i + k])
    assert s.n == n
    return s.finish()


def check(req: A.Requirement, ticks: int | None, cols: Mapping[str, np.ndarray], n: int,
          rnd: random.Random, where: str = "", **kw) -> Evidence:
    """Compare the stream with the whole trace on one random split; returns the evidence."""
    want = evaluate_requirement(req, cols, n, ticks)
    got, times = streamed(req, ticks, cols, n, rnd, **kw)
    trace = {k: v.astype(int).tolist() if v.dtype == np.bool_ else v.tolist()
             for k, v in cols.items()}
    assert got == want, f"{where or req.text}\n  trace {trace}\n  stream {got}\n  whole  {want}"
    assert times == {t: time_of(t) for t in named_ticks(want) if t < n}, where or req.text
    return want


def expressions(req: A.Requirement) -> list[A.Expr]:
    return [e for e in (req.scope.mode, req.condition.expr, req.timing.stop, req.response)
            if e is not None]


def uses_temporal_function(req: A.Requirement) -> bool:
    return any(isinstance(x, A.Call) and x.name in NOT_POINTWISE
               for e in expressions(req) for x in A.walk(e))


def trace_columns(trace: list[dict]) -> dict[str, np.ndarray]:
    return {v: np.array([r[v] for r in trace]) for v in BOOL_VARS + MODE_VARS + NUM_VARS}


def sparse_columns(rnd: random.Random, n: int, names: list[str], numbers: list[str]
                   ) -> dict[str, np.ndarray]:
    """Columns of ``n`` ticks whose booleans are rare, frequent or in long runs."""
    cols = {}
    for v in names:
        how = rnd.choice(["rare", "frequent", "runs", "half"])
        if how == "runs":
            flips = np.array([rnd.random() < 0.03 for _ in range(n)])
            cols[v] = (np.cumsum(flips) % 2).astype(np.bool_)
        else:
            p = {"rare": 0.02, "frequent": 0.97, "half": 0.5}[how]
            cols[v] = np.array([rnd.random() < p for _ in range(n)])
    for v in numbers:
        cols[v] = np.array([rnd.randint(-1, 3) for _ in range(n)])
    return cols


# --------------------------------------------------------------------------- random sentences
def run_sentences(seed: int, sentences: int, short: int, long: int) -> tuple[int, int]:
    """Check ``sentences`` random sentences (of expression depth 1 or 2: at depth 2 most use
    a temporal function), each on ``short`` traces of 1..40 ticks and ``long`` of 100..400
    with sparse events; returns (taken, refused)."""
    rnd = random.Random(seed)
    taken = refused = 0
    for i in range(sentences):
        text, _meaning = random_requirement(rnd, depth=rnd.choice([1, 2]))
        why = stream_unsupported(parse(text))
        if why is not None:
            assert uses_temporal_function(parse(text)), f"{text}: refused ({why})"
            assert "temporal function" in why
            two_chunks(parse(text), rnd)
            refused += 1
            continue
        assert not uses_temporal_function(parse(text)), text
        comp = compiled(parse(text), rid=f"S{i}")
        req, ticks = comp.requirement, comp.formalization.ticks
        for _ in range(short):
            n = rnd.randint(1, 40)
            check(req, ticks, trace_columns(random_trace(rnd, n)), n, rnd, text)
        for _ in range(long):
            n = rnd.randint(100, 400)
            cols = sparse_columns(rnd, n, BOOL_VARS + MODE_VARS, NUM_VARS)
            check(req, ticks, cols, n, rnd, text, sizes=SIZES + (150,))
        taken += 1
    return taken, refused


def two_chunks(req: A.Requirement, rnd: random.Random) -> None:
    """A requirement with a temporal function is judged over one chunk, the whole trace,
    and refuses a second chunk."""
    n = rnd.randint(2, 20)
    cols = trace_columns(random_trace(rnd, n))
    s = IntervalStream(req, None)
    s.feed(cols, 1, np.zeros(1, np.int64))
    with pytest.raises(ValueError, match="temporal function"):
        s.feed(cols, 1, np.ones(1, np.int64))
    whole = IntervalStream(req, None)
    whole.feed(cols, n, time_of(np.arange(n, dtype=np.int64)))
    assert whole.finish()[0] == evaluate_requirement(req, cols, n)


@pytest.mark.parametrize("seed", range(3))
def test_random_sentences_equal_the_whole_trace(seed):
    taken, refused = run_sentences(900 + seed, sentences=100, short=5, long=2)
    assert taken >= 15 and refused >= 15, (taken, refused)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(20))
def test_random_sentences_long_run(seed):
    taken, refused = run_sentences(1900 + seed, sentences=100, short=10, long=3)
    assert taken >= 12, (taken, refused)


# --------------------------------------------------------------------------- every template
TIMINGS = [(t, n) for t in A.TIMING_KINDS
           for n in ((0, 1, 3) if t in A.DURATION_TIMINGS else (2,))]
RESPONSES = ("r", "!r", "r | s", "x > 2")


def run_templates(scope: str, seed: int, traces: int) -> int:
    """Every condition x timing of ``scope`` on ``traces`` random traces each (short and
    long ones, dense and sparse); returns how many had more violations than are listed."""
    rnd = random.Random(f"{scope}{seed}")
    over = 0
    for cond in A.CONDITION_KINDS:
        for timing, n in TIMINGS:
            req = requirement(scope, cond, timing, response=rnd.choice(RESPONSES), n=n)
            for _ in range(traces):
                length = rnd.choice([rnd.randint(1, 12), rnd.randint(1, 60),
                                     rnd.randint(150, 400)])
                cols = sparse_columns(rnd, length, ["m", "c", "r", "s"], ["x"])
                ev = check(req, None, cols, length, rnd)
                over += ev.violations > MAX_LISTED
    return over


@pytest.mark.parametrize("scope", A.SCOPE_KINDS)
def test_every_scope_condition_and_timing(scope):
    run_templates(scope, 0, traces=3)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(1, 6))
@pytest.mark.parametrize("scope", A.SCOPE_KINDS)
def test_every_template_long_run(scope, seed):
    run_templates(scope, seed, traces=8)


def test_more_violations_than_listed():
    """Past :data:`MAX_LISTED` violations the stream counts them all and lists the first."""
    rnd = random.Random(5)
    n = 1000
    cols = {"m": (np.arange(n) // 37) % 3 != 0, "c": np.ones(n, np.bool_),
            "r": np.arange(n) % 7 == 0, "s": np.arange(n) % 11 == 0,
            "x": np.zeros(n)}
    over = 0
    for scope in ("null", "in", "onlyIn", "onlyAfter"):
        for timing, k in TIMINGS:
            req = requirement(scope, "holding", timing, n=k)
            ev = check(req, None, cols, n, rnd, sizes=(1, 64, 300, 4096))
            if ev.violations > MAX_LISTED:
                assert len(ev.listed) == MAX_LISTED
                over += 1
    assert over >= 20


# --------------------------------------------------------------------------- column types
@pytest.mark.parametrize("text", [
    "whenever c the sw shall within 3 ticks satisfy r",
    "in m mode upon c the sw shall always satisfy r xor m",
    "only after m, when c the sw shall until s satisfy !r",
    "before m the sw shall eventually satisfy (x > 1) & r",
    "when not in m mode, whenever c = r the sw shall for 2 ticks satisfy r",
])
def test_boolean_column_types_do_not_change_the_evidence(text):
    rnd = random.Random(text)
    req = parse(text)
    for _ in range(20):
        n = rnd.randint(1, 120)
        cols = sparse_columns(rnd, n, ["m", "c", "r", "s"], ["x"])
        want = evaluate_requirement(req, cols, n)
        for kind in BOOL_TYPES:   # one type throughout, then mixed chunk by chunk
            as_kind = {v: c.astype(kind) if c.dtype == np.bool_ else c
                       for v, c in cols.items()}
            assert streamed(req, None, as_kind, n, rnd, retype=False)[0] == want
        assert streamed(req, None, cols, n, rnd, retype=True)[0] == want


# --------------------------------------------------------------------------- expressions
def test_ftp_is_true_at_the_first_tick_of_the_trace_only():
    rnd = random.Random(1)
    for text in ["whenever FTP the sw shall immediately satisfy r",
                 "upon FTP | c the sw shall within 2 ticks satisfy r",
                 "in m mode the sw shall always satisfy FTP | r",
                 "only in m mode the sw shall eventually satisfy !FTP & r",
                 "after m the sw shall until FTP | s satisfy r"]:
        req = parse(text)
        assert stream_unsupported(req) is None, text
        for _ in range(40):
            n = rnd.randint(1, 30)
            check(req, None, sparse_columns(rnd, n, ["m", "c", "r", "s"], []), n, rnd)


def test_uninterpreted_functions_read_their_column_as_the_whole_trace_does():
    rnd = random.Random(2)
    req = parse("whenever c the sw shall always satisfy sqrt(x) > 1 | foo(r, x)")
    assert stream_unsupported(req) is None
    for _ in range(30):
        n = rnd.randint(1, 40)
        cols = sparse_columns(rnd, n, ["c", "r", "foo(r,x)"], ["x"])
        cols["sqrt(x)"] = np.sqrt(np.abs(cols["x"]))
        check(req, None, cols, n, rnd)
    # without the column: EvidenceUnsupported, as the whole-trace function, at the feed
    cols = {"c": np.ones(3, np.bool_), "r": np.ones(3, np.bool_), "x": np.ones(3)}
    with pytest.raises(EvidenceUnsupported) as whole:
        evaluate_requirement(req, cols, 3)
    s = IntervalStream(req, None)
    with pytest.raises(EvidenceUnsupported) as chunk:
        s.feed(cols, 3, np.arange(3))
    assert str(chunk.value) == str(whole.value)


@pytest.mark.parametrize("response", [
    "persisted(2, r)", "occurred(1, 3, r)", "persists(2, r)", "occurs(2, r)",
    "prevOcc(p, q)", "nextOcc(p, q)", "(at the previous occurrence of p, q)",
    "(at the next occurrence of p, q)", "preBool(false, r)", "preInt(0, x) > 1",
    "preReal(0.0, x) > 1"])
def test_temporal_functions_are_judged_in_one_chunk(response):
    for text in (f"the sw shall always satisfy {response}",
                 f"in m mode upon {response} the sw shall within 2 ticks satisfy r",
                 f"while {response} the sw shall always satisfy r",
                 f"whenever c the sw shall until {response} satisfy r"):
        req = parse(text)
        why = stream_unsupported(req)
        assert why is not None and "temporal function" in why, text
        cols = {v: np.ones(3, np.bool_) for v in ("m", "c", "r", "p", "q")}
        cols["x"] = np.ones(3)
        s = IntervalStream(req, None)
        s.feed(cols, 2, np.arange(2))
        with pytest.raises(ValueError, match="temporal function"):
            s.feed(cols, 1, np.arange(1))


def test_other_refusals_and_errors():
    free = parse('"the robot shall be nice"')
    assert stream_unsupported(free) == "a free-form requirement has no semantics"
    with pytest.raises(EvidenceUnsupported):
        IntervalStream(free, None)
    minus = parse("the sw shall always satisfy -r")   # refused whatever the data
    assert stream_unsupported(minus) == "arithmetic minus where a condition is expected"
    with pytest.raises(EvidenceUnsupported, match="fractional"):
        IntervalStream(parse("the sw shall within 2.5 ticks satisfy r"), None)
    s = IntervalStream(parse("the sw shall always satisfy r"), None)
    s.feed({}, 0, np.zeros(0, np.int64))
    with pytest.raises(ValueError):
        s.finish()   # no tick, as evaluate_requirement with n < 1
    with pytest.raises(KeyError):
        s.feed({"q": np.ones(2, np.bool_)}, 2, np.arange(2))
    s = IntervalStream(parse("the sw shall always satisfy r"), None)
    s.feed({"r": np.array([True, False])}, 2, np.array([5, 9]))
    first = s.finish()
    assert first == s.finish() and first[0].violation is not None
    assert first[1] == {0: 5, 1: 9}
    with pytest.raises(ValueError):
        s.feed({"r": np.ones(1, np.bool_)}, 1, np.zeros(1, np.int64))


def test_duration_ticks_from_the_compiler():
    rnd = random.Random(3)
    req = parse("whenever c the sw shall within 2 seconds satisfy r")
    for k in (0, 1, 4):
        for _ in range(20):
            n = rnd.randint(1, 60)
            check(req, k, sparse_columns(rnd, n, ["c", "r"], []), n, rnd)


# --------------------------------------------------------------------------- property run
@st.composite
def _cases(draw):
    scope = draw(st.sampled_from(A.SCOPE_KINDS))
    cond = draw(st.sampled_from(A.CONDITION_KINDS))
    timing, k = draw(st.sampled_from(TIMINGS))
    req = requirement(scope, cond, timing, response=draw(st.sampled_from(RESPONSES)), n=k)
    n = draw(st.integers(1, 80))
    bits = st.lists(st.booleans(), min_size=n, max_size=n)
    cols = {v: np.array(draw(bits)) for v in "mcrs"}
    cols["x"] = np.array(draw(st.lists(st.integers(0, 3), min_size=n, max_size=n)))
    return req, cols, n, draw(st.integers(0, 2 ** 32))


@pytest.mark.slow
@settings(max_examples=3000, deadline=None)
@given(_cases())
def test_property_any_split_any_template(case):
    req, cols, n, seed = case
    check(req, None, cols, n, random.Random(seed))


# --------------------------------------------------------------------------- memory
CHUNK = 4096


class _Concatenating:
    """What a stream that keeps its chunks would hold: copies of every chunk, concatenated
    at the end into the whole-trace columns :func:`evaluate_requirement` needs (not
    evaluated here: the measure is about what is held)."""

    def __init__(self, req: A.Requirement, duration_ticks: int | None) -> None:
        self.parts: list[tuple[dict[str, np.ndarray], np.ndarray]] = []

    def feed(self, columns, k, times):
        self.parts.append(({v: c[:k].copy() for v, c in columns.items()}, times[:k].copy()))

    def finish(self):
        return {v: np.concatenate([p[v] for p, _ in self.parts]) for v in self.parts[0][0]}


def fed_peak(cls, text: str, ticks: int) -> int:
    """The peak of traced memory (bytes) while ``cls`` is made, fed ``ticks`` ticks (a
    holding condition always true, :data:`CHUNK` at a time) and finished."""
    i = np.arange(CHUNK)
    cols = {"c": np.ones(CHUNK, np.bool_), "r": i % 50 != 49 if "always" in text else
            i % 50 == 0}
    warm = cls(parse(text), None)   # (first calls import and cache what they need)
    warm.feed(cols, CHUNK, i)
    warm.finish()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        s = cls(parse(text), None)
        for n0 in range(0, ticks, CHUNK):
            s.feed(cols, CHUNK, (n0 + np.arange(CHUNK, dtype=np.int64)) * 1000)
        s.finish()
        return tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("text", ["whenever c the sw shall always satisfy r",
                                  "whenever c the sw shall within 10 ticks satisfy r"])
def test_memory_does_not_grow_with_the_trace(text):
    """4 times the ticks (2*10^5 -> 8*10^5, a trigger at every tick, violations past
    MAX_LISTED) may not cost 1 MB more at the peak. The same measure of a stream that keeps
    its chunks (:class:`_Concatenating`: 10 bytes a tick, two boolean columns and the times,
    then the columns concatenated) grows by about 7 MB: the measure can fail."""
    small = fed_peak(IntervalStream, text, 200_000)
    large = fed_peak(IntervalStream, text, 800_000)
    assert large - small < 1_000_000, (small, large)
    naive_small = fed_peak(_Concatenating, text, 200_000)
    naive_large = fed_peak(_Concatenating, text, 800_000)
    assert naive_large - naive_small > 5_000_000, (naive_small, naive_large)
