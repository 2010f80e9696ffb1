"""The audit of a CSV trace judged as its rows are read (audit/streamed.py: FRET's interval
semantics, the robustness and the LTL3 automata fed a chunk of rows at a time, nothing of a
chunk kept) against the same audit with the whole-trace judge (``streamed.ENABLED`` off: the
columns of every tick kept and judged at once): the audit JSON is the same bytes

* on random traces (hypothesis), read a few rows at a time and the robustness evaluated a
  few ticks at a time, so that the chunks' edges fall everywhere, with every scope,
  condition and timing, and with what sends a requirement back to the whole-trace judge
  (NaN, ``unknown`` cells, ``gap`` and ``cut`` rows, temporal functions, a probability);
* on plain CSV traces of every log the tests have: each clock of the trace ``fretc audit
  --write-csv`` writes of it (tests/audit/_metamorphic.py's cases), as a plain trace (the
  default run takes test_metamorphic.py's sample, ``-m slow`` every log);

and the streams do judge (not the whole-trace judge behind them): their results are
counted, and the fallback to the whole-trace judge happens only where the module says.
"""

from __future__ import annotations

import json
import random
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import _metamorphic as M
from test_metamorphic import ALL, SAMPLE, _case
from test_csv_chunks import REQUIREMENTS as CHUNKS_REQUIREMENTS

import fretc.audit.log as audit_log_module
import fretc.audit.streamed as streamed
import fretc.audit.streamed_three as streamed_three
import fretc.logs.csv.read as csv_read
import fretc.monitors.robustness as robustness
from _logs import written_plan
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.sampled.csv import write_sampled_csv
from fretc.audit.verdict import audit_json
from fretc.logs.csv.source import CLOCK_COLUMN, CsvSource

#: test_csv_chunks' seven requirements (R1 .. R7), then more of every kind
REQUIREMENTS = "@tick_period 100 ms\n" + CHUNKS_REQUIREMENTS + """\
R8: in m mode whenever p the sw shall at the next timepoint satisfy q
R9: only in m mode upon p the sw shall within 2 ticks satisfy !q
R10: before p the sw shall never satisfy x > 3
R11: only after q upon p the sw shall eventually satisfy m
R12: whenever p the sw shall until q satisfy x >= 0
R13: unless m upon p the sw shall before q satisfy x > 1
R14: upon p the sw shall after 2 ticks satisfy q
R15: in m mode the sw shall finally satisfy q
R16: only before m the sw shall always satisfy p | q
R17: whenever x > 1 the sw shall within 200 milliseconds satisfy !p
R18: upon persisted(2, p) the sw shall immediately satisfy q
R19: upon p the sw shall with probability > 0.5 within 2 ticks satisfy q
"""
#: what the streams never take (the whole-trace judge's): a temporal function, a probability
WHOLE = {"R18", "R19"}
XS = ["0.0", "0.5", "1.0", "1.5", "2.25", "-1", "3.5", "4", "0", "1"]


def _plan(folder: str):
    return written_plan(folder, "streamed.fret", REQUIREMENTS)


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    return _plan(str(tmp_path_factory.mktemp("streamed")))


def _trace(rnd: random.Random, n: int, timed: bool, marks: str) -> str:
    """A CSV trace of ``n`` rows of ``x, p, q, m`` (``marks``: "" for a clean trace, or
    what makes some ticks unknown: ``nan``, ``unknown`` cells, ``both``, ``gap`` rows, a
    ``cut`` row; two of them joined by ``+``)."""
    kinds = set(marks.split("+"))
    lines = ["time,x,p,q,m" if timed else "x,p,q,m"]
    t = 0.0
    sticky = [rnd.choice("01") for _ in range(3)]
    for _ in range(n):
        t += rnd.choice([0.1, 0.1, 0.2, 0.0])
        if "gap" in kinds and rnd.random() < 0.05:
            cells = ["gap"] * 4
        else:
            for j in range(3):  # (runs of the booleans, so that scopes and triggers last)
                if rnd.random() < 0.3:
                    sticky[j] = rnd.choice("01")
            cells = [rnd.choice(XS)] + sticky
            if kinds & {"nan", "both"} and rnd.random() < 0.05:
                cells[0] = "nan"
            if kinds & {"unknown", "both"} and rnd.random() < 0.05:
                cells[rnd.randrange(4)] = "unknown"
        lines.append(",".join(([f"{t:.1f}"] if timed else []) + cells))
    if "cut" in kinds:
        lines.append(",".join(([f"{t + 0.1:.1f}"] if timed else []) + ["cut"] * 4))
    return "\n".join(lines) + "\n"


def _json(plan, path: str) -> str:
    la = audit_log(plan, path)
    return audit_json([la], plan.requirements_json(), plan.bindings_json())


def _both(plan, path: str, patches: dict | None = None) -> tuple[str, str, dict]:
    """The audit JSON of ``path`` streamed and judged whole (with ``patches`` of module
    constants in both), and what the streams decided in the streamed one."""
    decided: dict = {}
    original = streamed.CsvStreams.close
    then = audit_log_module.judged_three

    def spy(self, source):
        original(self, source)
        decided.update(results=set(self.results), whole=dict(self.whole), three=set())

    def spy_three(plan, streams, source):
        before = set(streams.results)
        then(plan, streams, source)
        decided.update(results=set(streams.results), whole=dict(streams.whole),
                       three=set(streams.results) - before)

    mp = pytest.MonkeyPatch()
    try:
        for (module, name), value in (patches or {}).items():
            mp.setattr(module, name, value)
        mp.setattr(streamed.CsvStreams, "close", spy)
        mp.setattr(audit_log_module, "judged_three", spy_three)
        got = _json(plan, path)
        mp.setattr(streamed, "ENABLED", False)
        whole = _json(plan, path)
    finally:
        mp.undo()
    return got, whole, decided


def _ids(plan, indexes) -> set[str]:
    return {r.id for r in plan.requirements if r.index in indexes}


_TRACES = (st.integers(1, 60), st.booleans(),
           st.sampled_from(["", "", "", "nan", "unknown", "both", "gap", "cut", "gap+cut",
                            "both+cut"]),
           st.integers(1, 7), st.integers(1, 9), st.randoms(use_true_random=False))


@settings(max_examples=25, deadline=None)
@given(*_TRACES)
@pytest.mark.tor("TOR-LOG-003")
def test_the_streamed_audit_is_the_whole_trace_audit(tmp_path_factory, n, timed, marks, rows,
                                                     chunk, rnd):
    check_trace(tmp_path_factory, n, timed, marks, rows, chunk, rnd)


@pytest.mark.slow
@settings(max_examples=400, deadline=None)
@given(*_TRACES)
def test_the_streamed_audit_is_the_whole_trace_audit_long(tmp_path_factory, n, timed, marks,
                                                          rows, chunk, rnd):
    check_trace(tmp_path_factory, n, timed, marks, rows, chunk, rnd)


@settings(max_examples=8, deadline=None)
@given(st.integers(1, 60), st.booleans(), st.sampled_from(["nan", "unknown", "both"]),
       st.integers(1, 7), st.integers(3, 9), st.randoms(use_true_random=False))
def test_completions_followed_in_a_read_of_their_own(tmp_path_factory, n, timed, marks, rows,
                                                     chunk, rnd):
    """Where the completions are not followed beside the three-valued streams (more states
    than CONCURRENT_STATES: here every time), one more read follows them: the same JSON."""
    check_trace(tmp_path_factory, n, timed, marks, rows, chunk, rnd,
                {(streamed_three, "CONCURRENT_STATES"): 0})


def check_trace(tmp_path_factory, n: int, timed: bool, marks: str, rows: int, chunk: int,
                rnd: random.Random, more: dict | None = None) -> None:
    """The relation on one random trace, read ``rows`` rows and its robustness evaluated
    ``chunk`` ticks at a time (``more``: other module constants patched)."""
    folder = tmp_path_factory.getbasetemp() / "streamed_plan"
    folder.mkdir(exist_ok=True)
    plan = _plan(str(folder))
    path = tmp_path_factory.mktemp("t") / "trace.csv"
    path.write_text(_trace(rnd, n, timed, marks), encoding="utf-8")
    got, whole, decided = _both(plan, str(path), {(csv_read, "CHUNK_ROWS"): rows,
                                                  (robustness, "ROBUSTNESS_CHUNK"): chunk,
                                                  **(more or {})})
    assert got == whole
    streamed_ids = _ids(plan, decided["results"])
    assert not streamed_ids & WHOLE
    if chunk >= 3:
        # a clean trace, or one whose NaN, unknown cells and gap rows the three-valued
        # streams take (a gap row as a gap tick, one tick or more), cut at its end or not:
        # every requirement but
        # WHOLE streamed (a robustness chunk shorter than a bounded window, R14's 3 ticks,
        # is refused)
        assert streamed_ids == {r.id for r in plan.requirements} - WHOLE, decided["whole"]


@pytest.mark.tor("TOR-LOG-003")
def test_what_sends_a_requirement_back_to_the_whole_trace_judge(plan, tmp_path):
    """A NaN read by a comparison sends the requirements comparing ``x`` (only them) to the
    three-valued streams (audit/streamed_three.py), which decide them here, an ``unknown``
    cell those reading its column, and a ``gap`` row (one tick or more) every one; a ``cut``
    row none: the streams decide every one, an obligation still open at the cut read from
    the interval stream's waiting triggers (R2, R6, R12 and R17 held, their LTL3 verdict
    not definite: unknown), and with a ``gap`` row too the three-valued streams decide every
    one at the cut. The JSON is the whole-trace judge's in each case."""
    rows = ["time,x,p,q,m"] + [f"{i / 10:.1f},1.5,{i % 3 == 0:d},{i % 4 == 0:d},{i % 7 < 3:d}"
                               for i in range(30)]

    three: dict[str, set[str]] = {}

    def run(name: str, edit) -> tuple[set[str], set[str]]:
        lines = list(rows)
        edit(lines)
        path = tmp_path / f"{name}.csv"
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        got, whole, decided = _both(plan, str(path))
        assert got == whole, name
        three[name] = _ids(plan, decided["three"])
        return _ids(plan, decided["results"]), _ids(plan, decided["whole"])

    def nan(lines):
        lines[10] = lines[10].replace(",1.5,", ",nan,")

    def unknown_q(lines):
        cells = lines[10].split(",")
        cells[3] = "unknown"
        lines[10] = ",".join(cells)

    reading_x = {"R1", "R3", "R4", "R6", "R7", "R10", "R12", "R13", "R17"}
    ok, back = run("nan", nan)
    assert not back and ok == set(_ids(plan, range(99))) - WHOLE
    assert three["nan"] == reading_x
    ok, back = run("unknown", unknown_q)
    reading_q = {"R2", "R3", "R4", "R5", "R7", "R8", "R9", "R11", "R12", "R13", "R14",
                 "R15", "R16"}
    assert not back and ok == set(_ids(plan, range(99))) - WHOLE
    assert three["unknown"] == reading_q
    ok, back = run("gap", lambda lines: lines.insert(12, "1.05,gap,gap,gap,gap"))
    assert not back and ok == set(_ids(plan, range(99))) - WHOLE
    assert three["gap"] == ok
    ok, back = run("cut", lambda lines: lines.append("3.0,cut,cut,cut,cut"))
    # every one decided by the streams, those whose obligation is open at the cut included
    assert not back and ok == set(_ids(plan, range(99))) - WHOLE
    assert not three.get("cut")
    path = tmp_path / "cut.csv"
    verdicts = {v["requirement"]: v for v in json.loads(_json(plan, str(path)))["logs"][0][
        "verdicts"]}
    undecided = {i for i, v in verdicts.items() if v["verdict"] == "unknown"} - WHOLE
    assert undecided >= {"R2", "R6", "R12", "R17"}, undecided

    def gap_and_cut(lines):
        lines.insert(12, "1.05,gap,gap,gap,gap")
        lines.append("3.0,cut,cut,cut,cut")

    ok, back = run("gap and cut", gap_and_cut)  # (the three-valued streams at the cut)
    assert not back and ok == set(_ids(plan, range(99))) - WHOLE
    assert three["gap and cut"] == ok


def _plain_clocks(sampled: Path, folder: Path) -> list[Path]:
    """Each clock of the sampled trace ``sampled`` as a plain CSV trace: its rows and its
    columns (the time and the variables its first row fills)."""
    head = CsvSource(sampled)
    out = []
    for label in head.clocks:
        src = CsvSource(sampled, clock=label)
        if not src.row_count:
            continue
        times = src.row_times()
        names = [c for c in src.columns if c != CLOCK_COLUMN]
        cols = [src.column_values(c) for c in names]
        lines = [",".join(["time"] + names)]
        for i in range(src.row_count):
            cells = [f"{int(times[i]) / 1e9:.9f}"]
            for c, col in zip(names, cols):
                x = col[i]
                bad = i in set(src.unknown_rows.get(c, ()))
                cells.append("unknown" if bad else (str(int(x)) if src.types[c] == "bool"
                                                    else repr(float(x))))
            lines.append(",".join(cells))
        path = folder / f"clock_{label}.csv"
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        out.append(path)
    return out


def check_log(case: M.Case, tmp: Path) -> int:
    """The relation on each clock of ``case``'s sampled trace as a plain trace; returns how
    many requirements the streams decided."""
    fret = M.write(tmp / "r", case)
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    try:
        write_sampled_csv(plan, str(case.log), tmp / "s.csv")
    except ValueError:
        pytest.skip("no bound variable to write")
    bare = load_plan(AuditConfig(requirements=(str(fret),), bindings=()))
    count = 0
    for path in _plain_clocks(tmp / "s.csv", tmp):
        got, whole, decided = _both(bare, str(path), {(csv_read, "CHUNK_ROWS"): 97,
                                                      (robustness, "ROBUSTNESS_CHUNK"): 61})
        assert got == whole, f"{case.id}: {path.name}"
        count += len(decided.get("results", ()))
    return count


@pytest.mark.parametrize("case", SAMPLE)
def test_the_streamed_audit_of_every_log(case, tmp_path):
    check_log(_case(case), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("case", ALL)
def test_the_streamed_audit_of_every_log_sweep(case, tmp_path):
    check_log(_case(case), tmp_path)


def test_the_shipped_runs_are_streamed(tmp_path):
    """The relation above is not vacuous: on the clocks of a shipped run, the streams
    decide the Safe-ROS requirements (one of them violated)."""
    case = next(c for c in M.shipped_cases() if c.log.name == "sif_disabled.mcap")
    assert check_log(case, tmp_path) >= 5


def test_long_ticks_and_listed_violations(plan, tmp_path):
    """More rows than a chunk of the reader and of the robustness, and more violations than
    the evidence lists: the same JSON, every requirement but WHOLE streamed."""
    rnd = random.Random(3)
    path = tmp_path / "long.csv"
    path.write_text(_trace(rnd, 3000, True, ""), encoding="utf-8")
    got, whole, decided = _both(plan, str(path), {(csv_read, "CHUNK_ROWS"): 256,
                                                  (robustness, "ROBUSTNESS_CHUNK"): 1000})
    assert got == whole
    assert _ids(plan, decided["results"]) == {r.id for r in plan.requirements} - WHOLE
    violations = [v["violations"] for v in json.loads(got)["logs"][0]["verdicts"]
                  if v.get("violations")]
    assert max(violations) > 100


@pytest.mark.parametrize("marks", ["", "nan", "unknown"])
def test_a_requirement_alone_is_judged_as_in_the_set(plan, tmp_path, marks):
    """Each requirement audited alone gets the verdict it gets among the others, whichever
    judge takes it (the streams, or the columns after a NaN or an ``unknown`` cell sent the
    others back): one requirement's result never depends on another's presence."""
    from dataclasses import replace

    path = tmp_path / "trace.csv"
    path.write_text(_trace(random.Random(11), 200, True, marks), encoding="utf-8")
    together = audit_log(plan, str(path)).to_json()["verdicts"]
    for r, whole in zip(plan.requirements, together):
        alone = audit_log(replace(plan, requirements=[r]), str(path)).to_json()["verdicts"]
        assert alone == [whole], r.id


def test_more_runs_of_unknown_ticks_than_kept_go_back_to_the_whole_trace_judge(plan, tmp_path):
    """Past MAX_RUNS runs of unknown ticks in a part, the three-valued streams give the
    requirement up, and the judge holding its columns decides it: the same JSON."""
    import fretc.monitors.definite as definite

    rows = ["time,x,p,q,m"] + [f"{i / 10:.1f},{'nan' if i % 4 == 1 else '1.5'},{i % 3 == 0:d},"
                               f"{i % 4 == 0:d},{i % 7 < 3:d}" for i in range(40)]
    path = tmp_path / "runs.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    got, whole, decided = _both(plan, str(path), {(definite, "MAX_RUNS"): 3})
    assert got == whole
    back = {rid for rid, why in ((r.id, decided["whole"].get(r.index))
                                 for r in plan.requirements) if why}
    assert {"R1", "R4", "R7"} <= back - WHOLE
    assert all(decided["whole"][r.index].endswith("; more runs of unknown ticks than the "
                                                  "streams keep")
               for r in plan.requirements if r.id in back - WHOLE)
