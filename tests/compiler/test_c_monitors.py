"""The C99 monitors (``fretc --emit c``) against the Python monitors, FRET's trace verdicts and
the audit's interval semantics: built in the test with the system C compiler under
``-std=c99 -Wall -Wextra -Werror -pedantic`` (and AddressSanitizer and UBSan where the unit is
small enough to build quickly), stepped by a driver (tests/_c_monitors.py) tick by tick.

Skipped, with the reason, when no C compiler is found; the FRET vectors need ../shared."""

from __future__ import annotations

import math

import random
import re
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler.build import compile_entry
from fretc.compiler.c_codegen import c_units, emit_c
from fretc.compiler.codegen import build_monitor_module
from fretc.fretish import ast as A
from fretc.monitors.interval import verdict_of

from _c_monitors import build, driver_source, needs_cc, run_driver, write
from _monitor_helpers import KEYS, entry, load_source
from _shared import jsonl, needs_shared

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))
import differential  # noqa: E402

VERDICTS = jsonl("fretish/fret_trace_verdicts.jsonl")


class Built:
    """A set of requirements with its Python module and its C driver."""

    def __init__(self, compiled, folder, name, sanitize):
        mm = build_monitor_module(compiled, name)
        self.py = load_source(mm.text)
        automata = {(c.entry.source, c.id): mm.monitors[c.id].automata for c in compiled
                    if c.id in mm.monitors}
        files, self.skipped = emit_c(compiled, automata=automata)
        units = c_units(compiled, automata=automata)
        self.monitors = [m for u in units for m in u.monitors]
        self.index = {m.id: i for i, m in enumerate(self.monitors)}
        self.compiled = {c.id: c for c in compiled}
        write(files, folder)
        (folder / "driver.c").write_text(driver_source(units))
        sources = [f for f in files if f.endswith(".c") and f != "runner.c"] + ["driver.c"]
        self.exe = build(folder, sources, "driver", sanitize=sanitize)

    def run(self, cases):
        """``cases``: (id, trace) -> the C driver's outputs."""
        jobs = [(self.index[rid], self.monitors[self.index[rid]], trace) for rid, trace in cases]
        return run_driver(self.exe, jobs)

    def python(self, rid, trace):
        """Per tick (pt verdict, status, status tick) of the Python monitor, and finish()."""
        m = self.py.MONITORS[rid]()
        ticks = []
        for state in trace:
            v = m.step(state)
            ticks.append((bool(v), m.status, m.status_tick))
        return ticks, m.finish()


def _compile(texts: dict[str, str], tick_period=None):
    return [compile_entry(entry(rid, text, tick_period)) for rid, text in texts.items()]


# --------------------------------------------------------------------------- FRET's vectors
@pytest.fixture(scope="module")
def fret_vectors(tmp_path_factory):
    needs_cc()
    sentences: dict[str, str] = {}
    for case in VERDICTS:
        for c in case["cases"]:
            sentences.setdefault(c["sentence"], f"R{len(sentences)}")
    compiled = _compile({rid: text for text, rid in sentences.items()})
    # 696 monitors: built without the sanitizers (half a minute more); the sanitizers run on
    # the 288 keys and the other sets below
    return sentences, Built(compiled, tmp_path_factory.mktemp("fret"), "verdicts", False)


@needs_shared
@pytest.mark.tor("TOR-GEN-001", "TOR-GEN-003")
def test_fret_trace_verdicts_tick_by_tick(fret_vectors):
    """Every case of fret_trace_verdicts.jsonl: the C monitor's finish() is FRET's verdict,
    and at every tick its pt verdict, LTL3 verdict and LTL3 tick are the Python monitor's."""
    sentences, b = fret_vectors
    cases, expected = [], []
    for case in VERDICTS:
        trace = [{v: any(a <= i <= z for a, z in iv) for v, iv in case["intervals"].items()}
                 for i in range(case["length"])]
        for c in case["cases"]:
            cases.append((sentences[c["sentence"]], trace))
            expected.append(c["expected"])
    assert not b.skipped
    got = b.run(cases)
    ticks = 0
    for (rid, trace), want, out in zip(cases, expected, got):
        py, fin = b.python(rid, trace)
        assert out["ticks"] == py, (rid, b.compiled[rid].text)
        assert out["finish"] == int(want) == int(fin), (rid, b.compiled[rid].text)
        ticks += len(trace)
    assert len(cases) == 2640 and ticks == 2640 * 13


# --------------------------------------------------------------------------- 288 keys
def _key_requirement(scope, cond, timing, n):
    return A.Requirement(
        f"{scope},{cond},{timing}",
        A.Scope(scope, A.Var("m")) if scope != "null" else A.Scope(),
        A.Condition(cond, A.Var("c")) if cond != "null" else A.Condition(), "sw", None,
        A.Timing(timing, duration=A.Duration(str(n), "ticks")
                 if timing in A.DURATION_TIMINGS else None,
                 stop=A.Var("s") if timing in A.STOP_TIMINGS else None), A.Var("r"))


@pytest.fixture(scope="module")
def keys_at_real_bounds(tmp_path_factory):
    """The 288 template keys with the Safe-ROS bounds: 10 ticks (R2's 1 s at 100 ms) for
    within/for/after (5 for the keys of the scopes "only ..." to vary them)."""
    needs_cc()
    compiled = []
    for s, c, t in KEYS:
        req = _key_requirement(s, c, t, 5 if s.startswith("only") else 10)
        e = SimpleNamespace(id=f"{s},{c},{t}", text=req.key, source="keys.fret", line=1,
                            column=1, rationale=None, parent=None, tick_period=None,
                            requirement=req, error=None, extra={})
        compiled.append(compile_entry(e))
    return Built(compiled, tmp_path_factory.mktemp("keys"), "keys", True)


@pytest.mark.tor("TOR-GEN-003")
def test_every_key_at_real_bounds(keys_at_real_bounds):
    """Each of the 288 keys on 12 random traces of up to 30 ticks: per tick the Python
    monitor's pt verdict and LTL3 verdict; at the end the audit's word (satisfied, vacuous,
    violated) of the interval semantics (monitors/interval.py)."""
    b = keys_at_real_bounds
    assert not b.skipped and len(b.monitors) == 288
    rnd = random.Random(5)
    cases = []
    for s, c, t in KEYS:
        for _ in range(12):
            p = rnd.choice([0.2, 0.5, 0.8])
            trace = [{v: rnd.random() < p for v in "mcrs"} for _ in range(rnd.randint(1, 30))]
            cases.append((f"{s},{c},{t}", trace))
    got = b.run(cases)
    words = {"vacuous": 0, "satisfied": 0, "violated": 0}
    for (rid, trace), out in zip(cases, got):
        py, fin = b.python(rid, trace)
        assert out["ticks"] == py, rid
        cols = {v: np.array([x[v] for x in trace]) for v in "mcrs"}
        comp = b.compiled[rid]
        word = verdict_of(comp.requirement, cols, len(trace), comp.formalization.ticks)
        assert out["verdict"] == word, (rid, trace)
        words[word] += 1
    assert min(words.values()) > 300, words


# --------------------------------------------------------------------------- expressions
MIXED = {
    "R1": "whenever too_close agilex_agent shall eventually satisfy stopped",
    "R2": "upon too_close agilex_agent shall within 1 second satisfy stopped",
    "R4": "the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5",
    "N1": "the sw shall always satisfy x + 2 * y ^ 2 <= z mod 3 | x / y > 1",
    "N2": "upon persisted(3, p) the sw shall immediately satisfy absReal(x) < 5",
    "N3": "after m the sw shall always satisfy x > -3.0e2 & y / 0 != 1",
    "N4": "whenever occurred(2, 6, p) the sw shall immediately satisfy minReal(x, y) <= "
          "maxReal(y, z) - 1",
    "N5": "in m the sw shall for 3 ticks satisfy preReal(0, x) < x | persisted(2, 5, q)",
    "N6": "only after q upon p the sw shall within 4 ticks satisfy !r & x >= 1",
    "N7": "when not in m whenever x > 2 the sw shall until q satisfy p",
    "N8": "the sw shall always satisfy x ^ y < 1e300 & (x - y) ^ 0.5 >= 0 | x mod 0 = 0",
    # a number read as a condition (x, a number by its power) where no comparison reads
    # its NaN (NaN ^ 0 is 1), and a NaN given to min/max/preReal/ite, which may hide it
    "N9": "the sw shall always satisfy x ^ 0 >= 1 | x",
    "N10": "the sw shall always satisfy maxReal(y, x) < 5 & preReal(0, z) < 5",
}
_BOOLS = ("too_close", "stopped", "p", "q", "r", "m")
_NUMS = ("linear_speed", "angular_speed", "x", "y", "z")


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    needs_cc()
    from fractions import Fraction

    return Built(_compile(MIXED, Fraction(1, 10)), tmp_path_factory.mktemp("mixed"), "mixed",
                 True)


_numbers = st.one_of(st.integers(-3, 3).map(float),
                     st.sampled_from([0.5, -0.5, 1e308, -0.0, math.nan]),
                     st.floats(-10, 10, allow_nan=False))
_states = st.fixed_dictionaries({**{v: st.booleans() for v in _BOOLS},
                                 **{v: _numbers for v in _NUMS}})


@settings(max_examples=150, deadline=None)
@given(data=st.data())
@pytest.mark.tor("TOR-GEN-003")
def test_hypothesis_traces(mixed, data):
    """Hypothesis-drawn traces over requirements with arithmetic, division and mod by zero,
    powers, min/max, preReal, persisted/occurred windows and numeric conditions: the C
    monitor's ticks are the Python monitor's up to the first tick at which a comparison
    reads NaN, which is where the audit's NaN rule (monitors/nan.py) puts it; there the C
    monitor stops (the Python monitor compares IEEE values on)."""
    from fretc.monitors.judge import nan_ticks

    rid = data.draw(st.sampled_from(sorted(MIXED)))
    trace = data.draw(st.lists(_states, min_size=1, max_size=25))
    (out,) = mixed.run([(rid, trace)])
    py, fin = mixed.python(rid, trace)
    cols = {v: np.array([x[v] for x in trace]) for v in trace[0]}
    nan = np.flatnonzero(nan_ticks(mixed.compiled[rid].requirement, cols, len(trace)))
    first = int(nan[0]) if len(nan) else -1
    assert out["unread"] == first
    if first < 0:
        assert out["ticks"] == py
        assert out["finish"] == int(fin)
    else:
        assert out["ticks"][:first] == py[:first]
        assert out["finish"] == (-1 if first == 0 else int(py[first - 1][0]))


@pytest.mark.tor("TOR-GEN-003")
@pytest.mark.parametrize("rid,var", [("N9", "x"), ("N10", "x"), ("N10", "z")])
def test_a_nan_that_no_comparison_reads_is_an_unread_tick_of_the_c_monitor(mixed, rid, var):
    """A NaN read only as a condition (``x ^ 0 >= 1 | x``: NaN ^ 0 is 1) or given to a
    function that may hide it (``maxReal(y, x)`` is ``y``; ``preReal(0, z)`` is the previous
    z): the C monitor stops at that tick, where the audit's NaN rule puts it."""
    from fretc.monitors.judge import nan_ticks

    base = {**{v: False for v in _BOOLS}, **{v: 0.0 for v in _NUMS}}
    trace = [base, {**base, var: math.nan}, base]
    (out,) = mixed.run([(rid, trace)])
    cols = {v: np.array([x[v] for x in trace]) for v in trace[0]}
    assert np.flatnonzero(nan_ticks(mixed.compiled[rid].requirement, cols, 3))[0] == 1
    assert out["unread"] == 1, out


def test_random_sentences(tmp_path):
    """100 random sentences over the whole grammar (tests/differential.py: every scope,
    condition, timing and temporal function, quoted and dotted names, numbers): the C
    monitors that exist are the Python monitors' tick by tick, and the same ones are
    skipped (a future-time function in pt)."""
    needs_cc()
    rnd = random.Random(11)
    texts = {}
    while len(texts) < 100:
        text, _ = differential.random_requirement(rnd)
        texts[f"S{len(texts)}"] = text
    compiled = [c for c in _compile(texts) if c.error is None]
    b = Built(compiled, tmp_path, "random_sentences", True)
    assert {i for _, i, _ in b.skipped} == set(b.compiled) - set(b.py.MONITORS)
    cases = []
    for m in b.monitors:
        for _ in range(6):
            cases.append((m.id, differential.random_trace(rnd, rnd.randint(1, 14))))
    for (rid, trace), out in zip(cases, b.run(cases)):
        assert out["ticks"] == b.python(rid, trace)[0], b.compiled[rid].text
    assert len(b.monitors) > 40


def test_an_uninterpreted_function_of_terms_builds_under_werror(tmp_path):
    """A function fretc does not compute (``det(a*a + b, a - 1.0)``, as LMCPS's EB-001's
    ``det_3x3`` of sums of products) is an input named by its printed call: its arguments'
    terms are not computed (before: unused ``const double`` locals, an error under
    ``-Wall -Werror``), and the C monitor steps as the Python one."""
    needs_cc()
    compiled = _compile({"U": "the sw shall always satisfy det(a*a + b, a - 1.0) <= 2.0 | "
                              "absReal(a - b) < 1.0"})
    b = Built(compiled, tmp_path, "opaque", False)
    name = "det(((a * a) + b),(a - 1.0))"
    rnd = random.Random(3)
    trace = [{"a": rnd.uniform(-2, 2), "b": rnd.uniform(-2, 2), name: rnd.uniform(0, 4)}
             for _ in range(12)]
    [out] = b.run([("U", trace)])
    assert out["ticks"] == b.python("U", trace)[0]



@pytest.mark.tor("TOR-GEN-003")
def test_eleven_atoms_and_a_ring_of_bytes_build_and_step_as_python(tmp_path):
    """A requirement over 11 atoms (no LTL3 automaton: its status stays unknown) and one
    whose window keeps a ring of several bytes in its state: both C monitors build (the
    state's size checked at compile time against the fields laid out largest element
    first) and step as the Python monitors."""
    needs_cc()
    atoms = [f"a{i}" for i in range(11)]
    b = Built(_compile({"A": "the sw shall always satisfy " + " | ".join(atoms),
                        "W": "the sw shall always satisfy occurred(30, 40, q) | p"}),
              tmp_path, "wide", False)
    assert not b.skipped and [m.id for m in b.monitors] == ["A", "W"]
    assert max(f.length for f in b.monitors[1].fields) >= 4  # a ring of 4 bytes
    rnd = random.Random(4)
    cases = [(rid, [{v: rnd.random() < 0.1 for v in [*atoms, "p", "q"]} for _ in range(60)])
             for rid in ("A", "W") for _ in range(3)]
    for (rid, trace), out in zip(cases, b.run(cases)):
        assert out["ticks"] == b.python(rid, trace)[0], rid


@pytest.mark.tor("TOR-GEN-003")
def test_three_ids_of_one_c_identifier_get_their_own_monitors(tmp_path):
    """Three ids that make one C identifier (``a.b``, ``a b``, ``a-b``: ``a_b``) get three
    monitors (``_2``, ``_3``), which build together, and the runner gives each its own
    verdict."""
    import subprocess

    needs_cc()
    files, skipped = emit_c(_compile({"a.b": "the sw shall always satisfy p",
                                      "a b": "the sw shall always satisfy q",
                                      "a-b": "the sw shall always satisfy r"}))
    assert not skipped
    write(files, tmp_path)
    exe = build(tmp_path, ["test_monitors.c", "runner.c"], "runner")
    (tmp_path / "t.csv").write_text("p,q,r\ntrue,false,true\n")
    got = subprocess.run([str(exe), str(tmp_path / "t.csv")], capture_output=True, text=True)
    assert [line.split("\t")[:2] for line in got.stdout.splitlines()] == [
        ["a.b", "satisfied"], ["a b", "violated"], ["a-b", "satisfied"]], got


# --------------------------------------------------------------------------- the C text
def _code(text: str) -> str:
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


@pytest.mark.tor("TOR-GEN-003")
def test_constant_memory_and_no_floating_point_without_numbers():
    """No allocation, recursion or loop in a monitor's code; no floating point in a file
    whose requirements compare no number; the state's size stated in the header."""
    files, _ = emit_c(_compile({k: MIXED[k] for k in ("R1", "R2")}))
    src, hdr = _code(files["test_monitors.c"]), _code(files["test_monitors.h"])
    assert not re.search(r"\b(malloc|calloc|realloc|free|for|while|goto|double|float)\b",
                         src + hdr)
    assert "#include <math.h>" not in src
    assert re.search(r"#define TEST_R2_STATE_BYTES \d+", hdr)
    steps = re.findall(r"bool (\w+_step)\(.*?\n}\n", src, flags=re.S)
    assert steps == ["test_R1_step", "test_R2_step"]
    for name in steps:
        body = src[src.index(f"bool {name}("):]
        body = body[:body.index("\n}\n")]
        assert body.count(f"{name}(") == 1  # its definition only: no recursion
    files, _ = emit_c(_compile({"N1": MIXED["N1"]}))
    assert "double" in files["test_monitors.h"] and "#include <math.h>" in files[
        "test_monitors.c"]


def test_deterministic_and_split(tmp_path):
    needs_cc()
    compiled = _compile(MIXED)
    assert emit_c(compiled)[0] == emit_c(_compile(MIXED))[0]
    files, skipped = emit_c(compiled, split=True)
    assert not skipped
    assert sorted(files) == sorted([f"test_{rid}.{x}" for rid in MIXED for x in "ch"]
                                   + ["runner.c"])
    write(files, tmp_path)
    build(tmp_path, sorted(f for f in files if f.endswith(".c")), "runner")


@pytest.mark.tor("TOR-GEN-005")
def test_hostile_names_and_texts(tmp_path):
    """Ids, texts and variable names that are not C: quotes, comment ends, trigraphs,
    backslashes, line breaks and non-ASCII reach the C text escaped; it builds and the
    runner prints the id with its control characters escaped."""
    needs_cc()
    texts = {'R"*/??/\\\nÄ': 'the sw shall always satisfy "we?ird */ var" & "x??/"'}
    compiled = _compile(texts)
    files, skipped = emit_c(compiled)
    assert not skipped
    write(files, tmp_path)
    exe = build(tmp_path, ["test_monitors.c", "runner.c"], "runner")
    (tmp_path / "t.csv").write_text("a\ntrue\n")
    import subprocess

    got = subprocess.run([str(exe), str(tmp_path / "t.csv")], capture_output=True, text=True)
    assert got.returncode == 2
    assert got.stdout.startswith('R"*/??/\\x5c\\x0a\u00c4\terror\tno column we?ird */ var')


def test_command_needs_a_folder_and_reports_skipped(tmp_path):
    """``--emit c`` without ``-o DIR``: exit 2 with the reason; a requirement without an
    online monitor is named on stderr and in the header."""
    from click.testing import CliRunner

    from fretc.cli import main

    fret = tmp_path / "f.fret"
    fret.write_text("A: the sw shall always satisfy p\n"
                    "B: the sw shall always satisfy persists(2, p)\n")
    res = CliRunner().invoke(main, [str(fret), "--emit", "c"])
    assert res.exit_code == 2 and "give the folder with -o DIR" in res.output
    res = CliRunner().invoke(main, [str(fret), "--emit", "c", "-o", str(tmp_path / "c")])
    assert res.exit_code == 0
    assert "skipped B (f_monitors): the pt formula needs the future-time function" in res.output
    assert " *   B: the pt formula needs" in (tmp_path / "c" / "f_monitors.h").read_text()


def _emit_files(tmp_path, files: dict[str, str], *args):
    from click.testing import CliRunner

    from fretc.cli import main

    paths = []
    for name, text in files.items():
        p = tmp_path / "in" / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
        paths.append(str(p))
    out = tmp_path / "c"
    res = CliRunner().invoke(main, paths + ["--emit", "c", "-o", str(out), *args])
    assert res.exit_code == 0, res.output
    return out


@pytest.mark.tor("TOR-GEN-003")
@pytest.mark.parametrize("split", [False, True])
@pytest.mark.parametrize("files", [
    {"a.fret": "b_c: the sw shall always satisfy p\n",
     "a_b.fret": "c: the sw shall always satisfy q\n"},
    {"one/Safe.fret": "R: the sw shall always satisfy p\n",
     "two/safe.fret": "r: the sw shall always satisfy q\n"},
    {"x.fret": "A: the sw shall always satisfy p\nB: the sw shall always satisfy q\n",
     "x_A.fret": "h: the sw shall always satisfy q\n"},
], ids=["a_b_c", "case", "x_A_h"])
def test_names_are_unique_across_the_files_of_one_emission(tmp_path, files, split):
    """Two requirements never share a file name (whatever the case) or an identifier, in
    one emission of several files with or without ``--split``: ``a.fret``'s ``b_c`` and
    ``a_b.fret``'s ``c`` both became ``a_b_c.h`` (the second overwrote the first and the
    runner fed b_c's column to c's monitor), ``one/Safe.fret`` and ``two/safe.fret`` did not
    compile. Each requirement's monitor reads its own column: the runner's verdicts are
    each requirement's own."""
    import subprocess

    out = _emit_files(tmp_path, files, *(["--split"] if split else []))
    names = sorted(p.name for p in out.iterdir())
    assert len({n.lower() for n in names}) == len(names), names
    runner_c = (out / "runner.c").read_text()
    includes = re.findall(r'#include "([^"]+)"', runner_c)
    assert len(includes) == len(set(includes)) and all((out / i).exists() for i in includes)
    ids = [line.split(":")[0] for text in files.values() for line in text.splitlines()]
    exe = build(out, sorted(p.name for p in out.glob("*.c")), "runner")
    (tmp_path / "t.csv").write_text("p,q\ntrue,false\n")
    got = subprocess.run([str(exe), str(tmp_path / "t.csv")], capture_output=True, text=True)
    words = [line.split("\t")[:2] for line in got.stdout.splitlines()]
    want = [[rid, "satisfied" if "satisfy p" in line else "violated"]
            for text in files.values() for line in text.splitlines() for rid in [line.split(":")[0]]]
    assert sorted(words) == sorted(want) and len(words) == len(ids), got


def test_an_id_over_c99s_string_limit_builds_pedantic(tmp_path):
    """C99 promises string literals of 4,095 bytes (after concatenation); an id (or text)
    longer than that was one literal and broke ``-pedantic``. It builds, and the runner
    prints the id in full."""
    import subprocess

    rid = "R" + "-x." * 1700
    out = _emit_files(tmp_path, {"a.fret": f"{rid}: the sw shall always satisfy p\n"})
    exe = build(out, sorted(p.name for p in out.glob("*.c")), "runner")
    (tmp_path / "t.csv").write_text("p\ntrue\n")
    got = subprocess.run([str(exe), str(tmp_path / "t.csv")], capture_output=True)
    assert got.returncode == 0 and got.stdout.decode() == f"{rid}\tsatisfied\tltl3=unknown\tticks=1\n"
