"""``fretc testgen``: the generated tests' expected verdicts are what ``fretc audit`` gives on
their traces; every obligation they list is exercised by their trace (checked again by the
reference ft evaluator where the verdicts differ in holding); every obligation is covered or
listed as unmeetable with a reason."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from fretc.testing.generate import generate
from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.compiler.coverage import obligations
from fretc.compiler.evaluate import ft_at
from fretc.compiler.semantics import formalize
from fretc.fretish.files import load_requirements
from fretc.monitors.coverage import exercised
from tests.check._replay import audit_verdicts

ROOT = Path(__file__).resolve().parents[2]
REQS = ROOT / "requirements"


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """``fretc testgen requirements/ -o DIR``: (DIR, tests.json, exit code)."""
    out = tmp_path_factory.mktemp("tests")
    res = CliRunner().invoke(main, ["testgen", str(REQS), "-o", str(out)])
    return out, json.loads((out / "tests.json").read_text()), res


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], int]:
    lines = [x for x in path.read_text().splitlines() if not x.startswith("#")]
    names = lines[0].split(",")
    rows = [x.split(",") for x in lines[1:]]
    cols = {}
    for i, name in enumerate(names):
        vals = [r[i] for r in rows]
        if vals[0] in ("true", "false"):
            cols[name] = np.array([v == "true" for v in vals])
        else:
            cols[name] = np.array([float(v) for v in vals])
    return cols, len(rows)


def test_expected_verdicts_are_the_audits(generated, tmp_path):
    out, doc, res = generated
    assert res.exit_code == 0, res.output
    assert doc["tests"]
    for t in doc["tests"]:
        got = {}
        for src in doc["requirements"]:
            got.update(audit_verdicts(Path(src), out / t["trace"], tmp_path))
        assert got == t["expected"], t["id"]
        assert set(t["expected"]) == {"R1", "R2", "R3", "R4", "R5", "R6"}


def test_every_obligation_covered_or_unmeetable(generated):
    _, doc, _ = generated
    every = {(o["requirement"], o["obligation"]) for o in doc["obligations"]}
    covered = {(c["requirement"], c["obligation"]) for t in doc["tests"] for c in t["covers"]}
    unmeetable = {(o["requirement"], o["obligation"]) for o in doc["unmeetable"]}
    assert not doc["unknown"]
    assert covered | unmeetable == every
    assert all(o["reason"] for o in doc["unmeetable"])
    # the deadline's boundary tests and each atom's two effects are among them
    assert ("R2", "deadline-reached") in covered and ("R2", "deadline-missed") in covered
    assert ("R2", "condition:too_close+") in covered
    assert ("R4", "response:linear_speed <= 0.5:false") in covered


def test_listed_coverage_is_exercised(generated):
    """Every (requirement, obligation) a test lists is met on its trace by the interval
    semantics, and where the two verdicts differ in holding, FRET's ft of the requirement
    and of the variant differ by the reference evaluator too (an independent engine)."""
    out, doc, _ = generated
    compiled = {c.id: c for c in compile_entries(load_requirements([REQS]))}
    for t in doc["tests"]:
        cols, n = _read_csv(out / t["trace"])
        rows = [{k: (bool(v[i]) if v.dtype == bool else float(v[i]))
                 for k, v in cols.items()} for i in range(n)]
        for cov in t["covers"]:
            c = compiled[cov["requirement"]]
            obs = obligations(c.id, c.requirement, c.formalization.ticks)
            ob = next(o for o in obs if o.id == cov["obligation"])
            ex = exercised([ob], c.requirement, cols, n, c.formalization.ticks)[0]
            assert ex.met, (t["id"], cov)
            if ex.verdicts and ("violated" in ex.verdicts):
                mine = ft_at(c.formalization.ft, rows)
                variant = formalize(ob.variant, c.entry.tick_period).ft
                assert mine != ft_at(variant, rows), (t["id"], cov)


def test_unmeetable_obligation_has_its_reason(tmp_path):
    """A requirement whose response is a tautology: its atom's effects cannot be shown."""
    p = tmp_path / "taut.fret"
    p.write_text("A: upon p the sw shall within 3 ticks satisfy q | !q\n")
    c = compile_entries(load_requirements([p]))
    gen = generate(c, fork=False)
    names = {o.id: why for o, why in gen.unmeetable}
    assert "response:q+" in names and "response:q-" in names
    assert "no finite trace" in names["response:q+"]
    met = {o for t in gen.tests for _, o, _ in t.covers}
    assert "trigger" in met and "condition:p+" in met


@pytest.mark.slow
def test_long_deadline_boundaries(tmp_path):
    """A 300-tick deadline (past Spot's 16): its boundary tests through check's other
    engines, each confirmed by the judge. Slow: about 3 minutes of CPU (its queries spend
    their budgets), most of the default suite's time on one worker."""
    p = tmp_path / "long.fret"
    p.write_text("L: upon p the sw shall within 300 ticks satisfy q\n")
    c = compile_entries(load_requirements([p]))
    gen = generate(c, fork=False)
    met = {o: tick for t in gen.tests for _, o, tick in t.covers}
    assert {"deadline-reached", "deadline-missed"} <= set(met), (gen.unknown, gen.unmeetable)
    assert max(len(t.rows) for t in gen.tests) > 300


def test_bad_input_exit_2(tmp_path):
    p = tmp_path / "bad.fret"
    p.write_text("B: upon p the sw shall within satisfy q\n")
    res = CliRunner().invoke(main, ["testgen", str(p), "-o", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "bad.fret" in res.output


def test_variables_compared_with_each_other(tmp_path):
    """An enumeration written as variables compared with each other (the case studies'
    ``state = ap_standby_state``): every obligation gets a test the judge confirms."""
    p = tmp_path / "enum.fret"
    p.write_text("E: whenever state = standby_state & go the fsm shall at the next timepoint "
                 "satisfy state = nominal_state\n")
    c = compile_entries(load_requirements([p]))
    gen = generate(c, fork=False)
    assert not gen.unknown, gen.unknown
    met = {o for t in gen.tests for _, o, _ in t.covers}
    assert "condition:state = standby_state+" in met and "timing:immediately" in met


def test_generated_pytest_file_compares_the_selected_requirements(tmp_path):
    """Tests generated with ``--only A`` from a file that also holds B: the generated pytest
    file audits the trace with the whole file and compares A's verdict, the one the tests
    list (before: every verdict, B's too, so every test failed)."""
    import os
    import subprocess
    import sys

    p = tmp_path / "two.fret"
    p.write_text("A: upon p the sw shall within 2 ticks satisfy q\n"
                 "B: the sw shall always satisfy r\n")
    res = CliRunner().invoke(main, ["testgen", str(p), "-o", str(tmp_path / "t"), "--pytest",
                                    "--only", "A"])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "t" / "tests.json").read_text(encoding="utf-8"))
    assert doc["tests"] and all(set(t["expected"]) == {"A"} for t in doc["tests"])
    cmd = [sys.executable, "-m", "pytest", str(tmp_path / "t" / "test_fretc_generated.py"),
           "-q", "-p", "no:cacheprovider", "-p", "no:randomly"]
    env = {k: v for k, v in os.environ.items() if k != "FRETC_RUN_TRACE"}
    ok = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True)
    assert ok.returncode == 0, ok.stdout + ok.stderr


def test_generated_pytest_file_runs(tmp_path):
    """``--pytest``: the generated file, run by pytest, passes on the generated traces and
    fails when FRETC_RUN_TRACE's command makes a log with other verdicts."""
    import os
    import subprocess
    import sys

    p = tmp_path / "one.fret"
    p.write_text("A: upon p the sw shall within 2 ticks satisfy q\n")
    res = CliRunner().invoke(main, ["testgen", str(p), "-o", str(tmp_path / "t"), "--pytest"])
    assert res.exit_code == 0, res.output
    gen = tmp_path / "t" / "test_fretc_generated.py"
    cmd = [sys.executable, "-m", "pytest", str(gen), "-q", "-p", "no:cacheprovider",
           "-p", "no:randomly"]
    env = {k: v for k, v in os.environ.items() if k != "FRETC_RUN_TRACE"}
    ok = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    # a "system" that never responds (q false throughout) and one that always does
    def system(value: str) -> str:
        fake = tmp_path / f"q_{value}.py"
        fake.write_text("import sys\nrows = open(sys.argv[1]).read().splitlines()\n"
                        "head = [i for i, r in enumerate(rows) if not r.startswith('#')][0]\n"
                        "names = rows[head].split(',')\nq = names.index('q')\n"
                        f"out = rows[:head + 1] + [','.join('{value}' if i == q else c for i, "
                        "c in enumerate(r.split(','))) for r in rows[head + 1:]]\n"
                        "open(sys.argv[2], 'w').write('\\n'.join(out) + '\\n')\n")
        return f"{sys.executable} {fake}"

    env["FRETC_RUN_LOG"] = "run.csv"
    env["FRETC_RUN_TRACE"] = system("false")
    bad = subprocess.run(cmd + ["-rs"], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert bad.returncode == 1, bad.stdout + bad.stderr
    assert "fail: violated: A" in bad.stdout, bad.stdout
    # the pass rule: a correct system fails no test; a test whose obligation its log does
    # not exercise (deadline missed, trigger absent...) is skipped as not exercised
    env["FRETC_RUN_TRACE"] = system("true")
    good = subprocess.run(cmd + ["-rs"], cwd=tmp_path, env=env, capture_output=True,
                          text=True)
    assert good.returncode == 0, good.stdout + good.stderr
    assert "failed" not in good.stdout and "not exercised" in good.stdout, good.stdout


def test_arithmetic_and_uninterpreted_functions_replay(tmp_path):
    """Requirements in the case studies' style: an arithmetic identity, an uninterpreted
    function of a number (``sqrt(weight)``) and one read as a condition (``det_3x3(a,b,c)``,
    a quoted CSV column): every obligation gets a test and ``fretc audit`` of each trace
    gives the expected verdicts."""
    p = tmp_path / "lm.fret"
    p.write_text("S: SWIM shall always satisfy (storeCat = CAT3) => "
                 "(CalAirspeedMin = 1.33694 * sqrt(weight) + 10.0)\n"
                 "E: Euler shall always satisfy det_3x3(a, b, c)\n"
                 "T: Tustin shall always satisfy normal => yout = 0.5 * (xin + xinpv) + ypv\n")
    out = tmp_path / "tests"
    res = CliRunner().invoke(main, ["testgen", str(p), "-o", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "tests.json").read_text())
    assert not doc.get("unknown"), doc.get("unknown")
    assert '"det_3x3(a,b,c)"' in (out / doc["tests"][0]["trace"]).read_text()
    for t in doc["tests"]:
        assert audit_verdicts(p, out / t["trace"], tmp_path) == t["expected"], t["id"]


def test_a_literal_past_the_largest_float_is_no_internal_error(tmp_path):
    """``1e999`` (inf) in a requirement: testgen used to stop with an OverflowError."""
    f = tmp_path / "a.fret"
    f.write_text("A: the sw shall always satisfy x < 1e999\n"
                 "B: upon x > -1e999 the sw shall immediately satisfy y\n")
    res = CliRunner().invoke(main, ["testgen", str(f), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0 and "internal error" not in res.output, res.output
    doc = json.loads((tmp_path / "out" / "tests.json").read_text())
    assert doc["tests"]


@pytest.mark.parametrize("text,name", [
    ("A: the sw shall always satisfy time > 1\n", "time"),
    ('A: the sw shall always satisfy "#x" > 1\n', "#x"),
    ('A: upon p the sw shall immediately satisfy "a,b"\n', "a,b"),
])
def test_a_variable_no_csv_trace_can_carry_is_refused(tmp_path, text, name):
    """testgen wrote traces its own audit cannot read (a header whose first cell ``#x``
    reads as a comment, a variable ``time`` read as the rows' time), exit 0: refused, naming
    the variable, nothing written."""
    f = tmp_path / "a.fret"
    f.write_text(text)
    res = CliRunner().invoke(main, ["testgen", str(f), "-o", str(tmp_path / "out")])
    assert res.exit_code == 2 and repr(name) in res.output, res.output
    assert not (tmp_path / "out").exists()


def test_an_id_with_a_line_break_stays_in_its_comment_line(tmp_path):
    """A requirement id with a line break (a FRET export's ``reqid``) ended the
    ``# expected:`` comment, the rest a row the audit could not read."""
    f = tmp_path / "r.json"
    f.write_text(json.dumps([{"reqid": "R1\nx,y", "fulltext": "the sw shall always satisfy p"},
                             {"reqid": "R2", "fulltext": "upon q the sw shall immediately "
                                                         "satisfy p"}]))
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["testgen", str(f), "-o", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "tests.json").read_text())
    for t in doc["tests"]:
        text = (out / t["trace"]).read_text()
        assert "# expected: R1\\x0ax,y=" in text
        a = CliRunner().invoke(main, ["audit", "-r", str(f), str(out / t["trace"]), "--json",
                                      str(tmp_path / "a.json"), "--no-progress"])
        assert a.exit_code in (0, 1), a.output
        got = json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"]
        assert {v["requirement"]: v["verdict"] for v in got} == t["expected"]


def test_generated_pytest_file_runs_inside_a_project_with_its_own_pytest_options(tmp_path):
    """Generated into a project whose pytest options ask for a plugin the environment lacks
    (``addopts = -n auto``: pytest-xdist), the file runs with pytest's defaults (its folder's
    pytest.ini): the project's options used to make every run an error."""
    import subprocess
    import sys

    (tmp_path / "pyproject.toml").write_text('[tool.pytest.ini_options]\naddopts = "-n auto '
                                             '--dist loadgroup"\n')
    p = tmp_path / "one.fret"
    p.write_text("A: upon p the sw shall within 2 ticks satisfy q\n")
    res = CliRunner().invoke(main, ["testgen", str(p), "-o", str(tmp_path / "gen"), "--pytest"])
    assert res.exit_code == 0, res.output
    cmd = [sys.executable, "-m", "pytest", "-p", "no:xdist", "-p", "no:cacheprovider"]
    ran = subprocess.run(cmd + ["gen/test_fretc_generated.py"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert ran.returncode == 0 and " passed" in ran.stdout, ran.stdout + ran.stderr
    (tmp_path / "gen" / "pytest.ini").unlink()  # the project's options: the error it was
    ran = subprocess.run(cmd + ["gen/test_fretc_generated.py"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert ran.returncode != 0


def test_the_replay_line_of_a_per_entity_requirement_gives_its_expected_verdicts(tmp_path):
    """Bindings with [entities] beside the requirements: each test's ``# replay:`` command
    audits the trace's columns as the variables (the per-entity ones too) and gives the
    expected verdicts (the entities' key was looked for in the CSV: an error)."""
    import json
    import shlex

    (tmp_path / "e.fret").write_text("@tick_period 100 ms\nM: in present mode the robot "
                                     "shall always satisfy motor_level < 2\n")
    (tmp_path / "e.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[entities]\nmotor = { key = "/diagnostics.status[:].name",'
        ' matching = "motor*" }\n[variables]\n'
        "motor_level = 'max(/diagnostics.status[:]{name==$motor}.level)'\n"
        "present = 'count(/diagnostics.status[:]{name==$motor}.level >= 0) = 1'\n")
    out = tmp_path / "gen"
    res = CliRunner().invoke(main, ["testgen", str(tmp_path / "e.fret"), "-o", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "tests.json").read_text())
    assert doc["tests"]
    for t in doc["tests"]:
        line = next(x for x in (out / t["trace"]).read_text().splitlines()
                    if x.startswith("# replay: "))
        args = shlex.split(line[len("# replay: fretc "):])
        got = CliRunner().invoke(main, args + ["--json", "-", "--no-progress"])
        verdicts = json.loads(got.output[got.output.index("{"):])["logs"][0]["verdicts"]
        assert {v["requirement"]: v["verdict"] for v in verdicts} == t["expected"], t["id"]


def test_the_generated_tests_kill_every_condition_kind_and_reviewer_mutant_of_safe_ros():
    """A reviewer's mutants of the Safe-ROS set (upon/whenever swapped, a bound +-1, the
    response negated, always/eventually) are each killed by some generated test, unless
    check's engines show the mutant equivalent: ``upon too_close`` read as ``whenever``
    is told apart only by a test whose condition stays true past its response."""
    from fretc.compiler.mutants import mutants
    from fretc.monitors.interval import verdict_of
    from fretc.testing.generate import Finder, column_kinds, separating_trace
    from fretc.check.budget import Budget
    from fretc.check.solver import SpotWorker

    c = compile_entries(load_requirements([REQS / "safe_ros.fret"]))
    gen = generate(c, fork=False)
    kinds = column_kinds(c)
    reviewer = ("condition ", "timing n-1", "timing n+1", "response: negate",
                "timing always", "timing eventually")
    survivors, checked = [], 0
    with SpotWorker(Budget(), fork=False) as worker:
        finder = Finder(worker, kinds)
        for comp in c:
            if comp.formalization is None:
                continue
            ticks = comp.formalization.ticks
            for op, m in mutants(comp.requirement, ticks):
                if not op.startswith(reviewer):
                    continue
                mf = formalize(m, comp.entry.tick_period)
                killed = any(verdict_of(m, {k: np.array([r[k] for r in t.rows],
                                                        dtype=bool if kinds[k] == "bool"
                                                        else float) for k in kinds},
                                        len(t.rows), mf.ticks) != t.expected[comp.id]
                             for t in gen.tests)
                checked += 1
                if not killed and separating_trace(finder, comp, m)[0] is not None:
                    survivors.append((comp.id, op))
    assert checked >= 20 and not survivors, survivors
    persists = {cid for t in gen.tests for cid, o, _ in t.covers if o == "trigger-persists"}
    assert {"R2", "R3", "R6"} <= persists, persists
