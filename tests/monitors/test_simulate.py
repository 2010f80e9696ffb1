"""``fretc simulate``: FRET's simulator without NuSMV. At every tick, ft on the suffix from
that tick and pt on the prefix up to it, checked against an independent oracle read from the
requirement's English meaning (tests/differential.py) and against FRET's own trace verdicts;
the timeline text and the CLI's errors."""

from __future__ import annotations

import json
import random
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from differential import oracle, random_requirement, random_trace  # noqa: E402

from _shared import SHARED, needs_shared  # noqa: E402
from fretc.common.errors import InputError  # noqa: E402
from fretc.compiler.build import compile_entries  # noqa: E402
from fretc.cli import main  # noqa: E402
from fretc.fretish.files import load_requirements  # noqa: E402
from fretc.monitors.simulate import parse_timeline, simulate  # noqa: E402


def _compiled(tmp_path: Path, text: str):
    p = tmp_path / "s.fret"
    p.write_text(text)
    return compile_entries(load_requirements([p]))


@pytest.mark.parametrize("seed", range(6))
def test_every_tick_against_the_oracle_of_the_meaning(tmp_path, seed):
    rnd = random.Random(seed)
    for _k in range(8):
        text, meaning = random_requirement(rnd)
        (c,) = _compiled(tmp_path, f"R: {text}\n")
        for _ in range(4):
            trace = random_trace(rnd, rnd.randint(1, 7))
            cols = {v: [row[v] for row in trace] for v in trace[0]}
            sim = simulate(c, cols)
            n = len(trace)
            assert sim.ft == [oracle(meaning, trace[i:]) for i in range(n)], (text, trace)
            assert sim.pt == [oracle(meaning, trace[:i + 1]) for i in range(n)], (text, trace)


@needs_shared
def test_fret_s_trace_verdicts_at_the_first_and_last_tick(tmp_path):
    cases = [json.loads(x) for x in
             (SHARED / "fretish" / "fret_trace_verdicts.jsonl").read_text().splitlines()]
    rnd = random.Random(1)
    checked = 0
    for c in rnd.sample(cases, 6):  # a bounded sample (the audit's test runs them all)
        cols = {v: [any(a <= i <= b for a, b in iv) for i in range(c["length"])]
                for v, iv in c["intervals"].items()}
        sentences = rnd.sample(c["cases"], 15)
        compiled = _compiled(tmp_path, "".join(f"S{i}: {x['sentence']}\n"
                                               for i, x in enumerate(sentences)))
        for x, comp in zip(sentences, compiled):
            sim = simulate(comp, cols)
            assert sim.ft[0] == x["expected"] == sim.pt[-1], (c["trace"], x)
            checked += 1
    assert checked == 90


def test_the_timeline_text():
    got = parse_timeline("# a trace\np: 0-2, 5\nspeed: 0 0.5 1 1.5 2 2.5\nq:\n")
    assert got == {"p": [True, True, True, False, False, True],
                   "q": [False] * 6, "speed": [0.0, 0.5, 1.0, 1.5, 2.0, 2.5]}
    assert parse_timeline("@ticks 4\np: 1\n") == {"p": [False, True, False, False]}
    for bad, where in [("p 0-2\n", ":1:1"), ("p: 0-2\np: 3\n", ":2:1"),
                       ("p: 3-1\n", ":1:4"), ("v: 1 2 x\n", ":1:4"),
                       ("@ticks 3\nv: 1 2\n", ":2:1"), ("@ticks 2\np: 5\n", ":2:1")]:
        with pytest.raises(InputError, match=where):
            parse_timeline(bad, "t.txt")


def test_the_command_writes_json_svg_and_html_and_exits_1_on_a_violation(tmp_path):
    (tmp_path / "r.fret").write_text(
        "@tick_period 100 ms\n"
        "R2: upon too_close the robot shall within 300 milliseconds satisfy stopped\n")
    (tmp_path / "t.txt").write_text("too_close: 2-3, 8\nstopped: 5-6\n@ticks 12\n")
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"), str(tmp_path / "t.txt"),
                                    "--json", str(tmp_path / "s.json"), "-o", str(tmp_path / "o")])
    assert res.exit_code == 1, res.output
    doc = json.loads((tmp_path / "s.json").read_text())
    assert doc["ticks"] == 12 and doc["requirements"][0]["id"] == "R2"
    r = doc["requirements"][0]
    assert r["pt"][-1] is False and r["ft"][0] is False and r["pt"][7] is True
    assert r["parts"]["condition"][2] is True and r["parts"]["response"][5] is True
    assert (tmp_path / "o" / "R2.svg").read_text().startswith("<svg")
    assert "R2" in (tmp_path / "o" / "simulation.html").read_text()


@pytest.mark.parametrize("trace, args, msg", [
    ("p: 1\n", [], "the trace has no 'q'"),
    ("p: 1\nq: 2\n", ["--id", "R9"], "no requirement 'R9'"),
    ("p,q\ntrue,false\ntrue\n", [], "t.csv:3"),
])
def test_bad_traces_and_ids_are_input_errors(tmp_path, trace, args, msg):
    (tmp_path / "r.fret").write_text("R1: the sw shall always satisfy p & q\n")
    name = "t.csv" if "," in trace else "t.txt"
    (tmp_path / name).write_text(trace)
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"),
                                    str(tmp_path / name), *args])
    assert res.exit_code == 2, res.output
    assert msg in res.output and "Traceback" not in res.output


def _vector_cases():
    if not (SHARED / "fretish" / "fret_trace_verdicts.jsonl").exists():
        return []
    return [json.loads(x) for x in
            (SHARED / "fretish" / "fret_trace_verdicts.jsonl").read_text().splitlines()]


@pytest.mark.slow
@pytest.mark.parametrize("case", _vector_cases(), ids=lambda c: f"trace{c['trace']}")
def test_every_fret_trace_vector_through_the_command(tmp_path, case):
    """``fretc simulate FILE T.csv --json OUT`` on each FRET trace vector: FRET's verdict at
    the last tick (pt) and from the first (ft), for every sentence of the vector."""
    names = sorted(case["intervals"])
    rows = [",".join(names)] + [",".join("true" if any(a <= i <= b for a, b in
                                                       case["intervals"][v]) else "false"
                                         for v in names) for i in range(case["length"])]
    (tmp_path / "t.csv").write_text("\n".join(rows) + "\n")
    (tmp_path / "r.fret").write_text("".join(f"S{i}: {x['sentence']}\n"
                                             for i, x in enumerate(case["cases"])))
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"),
                                    str(tmp_path / "t.csv"), "--json", str(tmp_path / "o.json")])
    assert res.exit_code in (0, 1), res.output
    got = {r["id"]: r for r in json.loads((tmp_path / "o.json").read_text())["requirements"]}
    for i, x in enumerate(case["cases"]):
        r = got[f"S{i}"]
        assert r["pt"][-1] == x["expected"] == r["ft"][0], (case["trace"], x)


@pytest.mark.parametrize("seed", range(4))
def test_a_nan_is_unknown_and_every_known_tick_holds_for_every_value_it_could_be(tmp_path,
                                                                                seed):
    """NaN in a numeric variable: wherever simulate says True or False (ft and pt), every
    value the NaN could stand for (a value on each side of and at every constant the
    generator compares with) gives that answer by the oracle; was: NaN read as a value
    (every comparison false), so `never x >= 5` over NaNs was satisfied."""
    import itertools

    from differential import NUM_VARS

    domain = [c / 2 for c in range(-3, 8)]  # -1.5 .. 3.5: each side of -1 .. 3
    rnd = random.Random(seed)
    decided = unknown = 0
    for _ in range(12):
        text, meaning = random_requirement(rnd)
        (c,) = _compiled(tmp_path, f"R: {text}\n")
        used = [v for v in NUM_VARS if v in c.formalization.variables]
        if not used:
            continue
        trace = random_trace(rnd, rnd.randint(1, 6))
        holes = rnd.sample([(i, v) for i in range(len(trace)) for v in used],
                           min(2, len(trace) * len(used)))
        for i, v in holes:
            trace[i][v] = float("nan")
        sim = simulate(c, {v: [row[v] for row in trace] for v in trace[0]})
        n = len(trace)
        for fill in itertools.product(domain, repeat=len(holes)):
            t = [dict(row) for row in trace]
            for (i, v), x in zip(holes, fill):
                t[i][v] = x
            for k in range(n):
                if sim.ft[k] is not None:
                    assert sim.ft[k] == oracle(meaning, t[k:]), (text, trace, fill, k)
                if sim.pt[k] is not None:
                    assert sim.pt[k] == oracle(meaning, t[:k + 1]), (text, trace, fill, k)
        decided += sum(x is not None for x in sim.ft + sim.pt)
        unknown += sum(x is None for x in sim.ft + sim.pt)
    assert decided and unknown


def test_nan_is_unknown_in_the_command_and_an_empty_trace_is_an_error(tmp_path):
    (tmp_path / "r.fret").write_text("S1: the robot shall never satisfy speed >= 5\n")
    (tmp_path / "t.txt").write_text("speed: nan nan nan\n")
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"), str(tmp_path / "t.txt"),
                                    "--json", str(tmp_path / "s.json")])
    assert res.exit_code == 3, res.output
    assert "S1: unknown" in res.output
    r = json.loads((tmp_path / "s.json").read_text())["requirements"][0]
    assert r["ft"] == r["pt"] == [None, None, None]
    (tmp_path / "t.txt").write_text("speed: 1 nan 7\n")  # the 7 violates whatever the NaN
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"), str(tmp_path / "t.txt")])
    assert res.exit_code == 1 and "S1: violated" in res.output, res.output
    for empty in ("", "# nothing\n", "@ticks 0\n"):
        (tmp_path / "e.txt").write_text(empty)
        res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"),
                                        str(tmp_path / "e.txt")])
        assert res.exit_code == 2 and "tick" in res.output, (empty, res.output)


@pytest.mark.parametrize("text", ["@ticks 100000000\nspeed: 1\n",
                                  "@ticks 10000000000\n",
                                  "@ticks " + "9" * 20 + "\n",
                                  "p: 0-99999999\n",
                                  "p: " + "9" * 30 + "\n"])
def test_a_huge_timeline_is_refused_before_it_is_built(tmp_path, text):
    """@ticks 10^8 took 2.4 GB, 10^10 a MemoryError, 10^20 grew without end: refused at
    the line, named file:line:col, before any list is built."""
    import resource

    (tmp_path / "r.fret").write_text("S1: the robot shall never satisfy speed >= 5\n")
    (tmp_path / "t.txt").write_text(text)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.fret"), str(tmp_path / "t.txt")])
    assert res.exit_code == 2, res.output
    assert "t.txt:1:" in res.output and "Traceback" not in res.output
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000  # KB


def test_ids_that_map_to_one_file_name_keep_their_own_svgs(tmp_path):
    """Ids from FRET's JSON export may hold any character: 'a/b' and 'a_b' (and 'A_B' on a
    case-insensitive file system) once wrote one SVG over another."""
    reqs = [{"reqid": i, "fulltext": f"the robot shall {t} satisfy p"}
            for i, t in (("a/b", "always"), ("a_b", "never"), ("A_B", "eventually"))]
    (tmp_path / "r.json").write_text(json.dumps(reqs))
    (tmp_path / "t.txt").write_text("p: 0-1\n@ticks 3\n")
    res = CliRunner().invoke(main, ["simulate", str(tmp_path / "r.json"), str(tmp_path / "t.txt"),
                                    "-o", str(tmp_path / "o")])
    assert res.exit_code == 1, res.output
    svgs = sorted((tmp_path / "o").glob("*.svg"))
    assert len(svgs) == 3
    titles = sorted(p.read_text().split("<title>")[1].split(":")[0] for p in svgs)
    assert titles == ["A_B", "a/b", "a_b"]


def test_a_long_csv_is_refused_after_its_first_rows(tmp_path):
    """A CSV of 10^6 rows was read whole (644 MB) before the 2,000-tick refusal: it is
    refused once its rows pass 2,000 (exit 2, naming the file), in a process whose peak
    stays near its start-up's (the rows past the bound are never read)."""
    import subprocess

    (tmp_path / "r.fret").write_text("S1: the robot shall never satisfy speed >= 5\n")
    with open(tmp_path / "t.csv", "w") as f:
        f.write("time,speed\n")
        f.writelines(f"{i / 10:.1f},{i % 7}\n" for i in range(1_000_000))
    from _peak import PEAK_KB

    code = (PEAK_KB + "from click.testing import CliRunner\nfrom fretc.cli import main\n"
            f"res = CliRunner().invoke(main, ['simulate', {str(tmp_path / 'r.fret')!r}, "
            f"{str(tmp_path / 't.csv')!r}])\n"
            "print(res.exit_code, _peak_kb())\n"
            "print(res.output)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=600).stdout
    code_and_peak, message = out.split("\n", 1)
    exit_code, peak_kb = map(int, code_and_peak.split())
    assert exit_code == 2 and "t.csv" in message and "more than 2000 ticks" in message, out
    assert peak_kb < 250_000, peak_kb  # (the whole file read: 700,000 KB)
