"""``fretc audit --write-csv``: the shipped runs' CSV traces (traces/*.csv) are what the
command writes; the audit of each CSV gives the verdicts of its MCAP (each requirement on
its own clock of the file: the same ticks and LTL3 verdicts), and so does the C monitors'
runner (``fretc --emit c``), built here with the system C compiler; on random CSV traces
with NaN and numbers read as conditions the runner's words are the audit's. Relation 10 of
the metamorphic tests (tests/audit/test_csv_metamorphic.py) checks it on every log."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.audit import AuditConfig, audit_log, find_logs, load_plan
from fretc.cli import main

from _c_monitors import build, needs_cc

ROOT = Path(__file__).resolve().parents[2]
TRACES = ROOT / "traces"
LOGS = sorted(TRACES.glob("*.mcap"))
REQS = (ROOT / "requirements" / "r1.fret", ROOT / "requirements" / "safe_ros.fret")
#: the command that writes traces/*.csv (traces/README.md)
COMMAND = ["audit", "-r", "requirements/r1.fret", "-r", "requirements/safe_ros.fret",
           "traces/*.mcap", "--write-csv", "traces"]


def _plan(*reqs):
    return load_plan(AuditConfig(requirements=tuple(str(r) for r in reqs)))


@pytest.fixture(scope="module")
def plan():
    return _plan(*REQS)


@pytest.fixture(scope="module")
def mcap_audits(plan):
    return {p.stem: audit_log(plan, str(p)) for p in LOGS}


def _words(la):
    return {v.requirement: v.verdict for v in la.verdicts}


def test_shipped_csvs_are_what_the_command_writes(tmp_path, monkeypatch):
    """traces/*.csv byte for byte as ``fretc audit ... --write-csv`` writes them now; the
    command names each file's clocks (R5 and R6 read a topic whose first message comes a
    tick before the others': a clock of their own; R6 reads age(/scan), so its clock ends at
    the log's end, as R5's does)."""
    monkeypatch.chdir(ROOT)
    args = COMMAND[:5] + [str(p.relative_to(ROOT)) for p in LOGS] + ["--write-csv",
                                                                      str(tmp_path)]
    res = CliRunner().invoke(main, args + ["--no-progress"])
    assert res.exit_code == 1, res.output  # some runs violate a requirement
    assert sorted(p.name for p in tmp_path.glob("*.csv")) == sorted(
        p.stem + ".csv" for p in LOGS)
    for p in LOGS:
        assert (tmp_path / (p.stem + ".csv")).read_bytes() == \
            (TRACES / (p.stem + ".csv")).read_bytes(), p.name
    assert "nominal.csv (2 clocks, 1755 ticks: R1, R2, R3, R4 877; R5, R6 878)" in res.output


def test_csv_audit_gives_the_verdicts_of_the_mcap(plan, mcap_audits):
    """Every requirement on every run: the CSV's verdict, ticks, first tick and LTL3
    verdict are the MCAP's (each requirement on its own clock; one file of one clock gave
    R5 and R6 another first tick, and R3 and R4 on sif_disabled another last)."""
    for stem, la in mcap_audits.items():
        csv = audit_log(plan, str(TRACES / f"{stem}.csv"))
        assert _words(csv) == _words(la), stem
        for v, w in zip(la.verdicts, csv.verdicts):
            assert (v.first_tick_ns, v.ticks_evaluated, v.ltl3.status, v.ltl3.tick) == (
                w.first_tick_ns, w.ticks_evaluated, w.ltl3.status, w.ltl3.tick), (stem, v.requirement)


def test_folder_audit_skips_the_csv_of_a_log():
    """A folder search does not count a run twice (X.csv beside X.mcap); named, the CSV
    is audited."""
    found = find_logs([str(TRACES)])
    assert found == [str(p) for p in LOGS]
    assert find_logs([str(TRACES / "nominal.csv")]) == [str(TRACES / "nominal.csv")]


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    """``fretc requirements/r1.fret requirements/safe_ros.fret --emit c -o DIR``, built
    with every .c file of DIR under the strict flags and the sanitizers."""
    needs_cc()
    out = tmp_path_factory.mktemp("c")
    res = CliRunner().invoke(main, [str(r) for r in REQS] + ["--emit", "c", "-o", str(out)])
    assert res.exit_code == 0, res.output
    return build(out, sorted(p.name for p in out.glob("*.c")), "runner")


def _run(exe, *csvs):
    got = subprocess.run([str(exe), *map(str, csvs)], capture_output=True, text=True)
    rows = [line.split("\t") for line in got.stdout.splitlines() if not line.startswith("==")]
    return got.returncode, rows


def test_runner_on_the_shipped_csvs(runner, mcap_audits):
    """The runner on traces/*.csv: one line per requirement, the audit's verdict of the
    MCAP, its LTL3 verdict and tick and its ticks (each requirement stepped on its own
    clock's rows)."""
    for stem, la in mcap_audits.items():
        code, rows = _run(runner, TRACES / f"{stem}.csv")
        assert {r[0]: r[1] for r in rows} == _words(la), stem
        for row, v in zip(rows, la.verdicts):
            assert row[2] == "ltl3=" + v.ltl3.status + (
                f"@{v.ltl3.tick}" if v.ltl3.tick is not None else "")
            assert row[3] == f"ticks={v.ticks_evaluated}"
        assert code == (1 if "violated" in _words(la).values() else 0)
    code, rows = _run(runner, *(TRACES / f"{s}.csv" for s in mcap_audits))
    assert code == 1 and len(rows) == 6 * len(mcap_audits)


RANDOM_REQS = """\
@tick_period 1 s
A1: whenever p the sw shall within 2 ticks satisfy x > 1
A2: in m the sw shall always satisfy y
A3: upon q the sw shall eventually satisfy x / y >= 0.5
A4: only after p the sw shall never satisfy x <= 0
A5: the sw shall always satisfy y | persisted(2, p)
"""

_cell = st.one_of(st.sampled_from(["0", "1", "2", "-1", "0.5", "nan", "inf", "-inf"]),
                  st.integers(-2, 3).map(str))


@pytest.fixture(scope="module")
def random_runner(tmp_path_factory):
    needs_cc()
    folder = tmp_path_factory.mktemp("random")
    fret = folder / "rnd.fret"
    fret.write_text(RANDOM_REQS)
    out = folder / "c"
    res = CliRunner().invoke(main, [str(fret), "--emit", "c", "-o", str(out)])
    assert res.exit_code == 0, res.output
    return folder, _plan(fret), build(out, sorted(p.name for p in out.glob("*.c")), "runner")


@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.tuples(st.booleans(), st.booleans(), st.booleans(), _cell, _cell),
                     min_size=0, max_size=12),
       y_numeric=st.booleans())
def test_runner_words_are_the_audits_on_random_csvs(random_runner, rows, y_numeric):
    """Random CSV traces (NaN and infinities in the numbers; y a boolean column or a
    number read as a condition): per requirement the runner's word is the audit's
    (satisfied, vacuous, violated, error without a tick). After a tick a NaN leaves unread
    the monitor stops (it steps known inputs only): the runner then says unknown unless it
    decided before, where the audit judges the ticks after it three-valued; a word the
    runner gives is never one the audit contradicts. The exit status follows the words."""
    folder, plan, exe = random_runner
    path = folder / "t.csv"
    lines = ["m,p,q,x,y"]
    for m, p, q, x, y in rows:
        yv = y if y_numeric else ("true" if y not in ("0", "-1", "nan") else "false")
        lines.append(f"{str(m).lower()},{str(p).lower()},{str(q).lower()},{x},{yv}")
    path.write_text("\n".join(lines) + "\n")
    la = audit_log(plan, str(path))
    code, got = _run(exe, path)
    runner, audit = {r[0]: r[1] for r in got}, _words(la)
    unread = {r[0] for r in got if any(c.startswith("unread=") for c in r)}
    for rid, word in runner.items():
        if rid in unread and word == "unknown":
            continue
        assert word == audit[rid], (rid, path.read_text(), got)
    want = 2 if "error" in runner.values() else 1 if "violated" in runner.values() \
        else 3 if (la.problems or unread or "unknown" in runner.values()) else 0
    assert code == want, (path.read_text(), got, la.problems)


def test_runner_input_errors(runner, tmp_path):
    """A CSV the audit refuses, the runner refuses: file:line, the column, exit 2."""
    bad = {"mix.csv": "too_close,stopped\ntrue,1\n2,false\n",
           "cells.csv": "too_close,stopped\ntrue\n",
           "name.csv": "too close,stopped\ntrue,true\n",
           "time.csv": "time,too_close\n1,true\n0.5,false\n"}
    for name, text in bad.items():
        (tmp_path / name).write_text(text)
        got = subprocess.run([str(runner), str(tmp_path / name)], capture_output=True,
                             text=True)
        assert got.returncode == 2 and f"{tmp_path / name}:" in got.stderr, (name, got)
    (tmp_path / "missing.csv").write_text("too_close\ntrue\n")
    code, rows = _run(runner, tmp_path / "missing.csv")
    assert code == 2 and rows[0][:3] == ["R1", "error", "no column stopped"]


@pytest.mark.parametrize("byte", [b"\x00", b"\x00\x00\x00", b"\xff\x00"])
def test_runner_refuses_a_nul_byte_and_never_stops_at_it(random_runner, tmp_path, byte):
    """A NUL byte in a trace is an error naming its line, exit 2, as fretc audit refuses the
    file: the runner used to read it as the end of the file and judge the rows before it
    (``satisfied``, exit 0, on rows that violate after it)."""
    _folder, plan, exe = random_runner
    path = tmp_path / "nul.csv"
    path.write_bytes(b"m,p,q,x,y\nfalse,false,false,2,true\nfalse,false,false,2,true" + byte
                     + b"\ntrue,false,false,2,false\ntrue,false,false,2,false\n")
    la = audit_log(plan, str(path))
    assert la.error is not None and re.match(rf"{re.escape(str(path))}:3\D", la.error), la.error
    got = subprocess.run([str(exe), str(path)], capture_output=True, text=True)
    assert got.returncode == 2 and f"{path}:3:" in got.stderr and "NUL" in got.stderr, got
    assert got.stdout == ""


def test_runner_reads_a_lone_carriage_return_as_the_audit_does(random_runner, tmp_path):
    """A lone CR ends a line for the audit (Python's csv: ``m\\r,p,...`` is a header ``m``
    and a row of five cells, refused); the runner read it as a space in the cell and judged
    the trace (found by bench/fuzz_hostile.py --classes crunner)."""
    _folder, plan, exe = random_runner
    path = tmp_path / "cr.csv"
    path.write_bytes(b"m\r,p,q,x,y\nfalse,false,false,2,true\n")
    la = audit_log(plan, str(path))
    assert la.error is not None and re.match(rf"{re.escape(str(path))}:2\D", la.error)
    got = subprocess.run([str(exe), str(path)], capture_output=True, text=True)
    assert got.returncode == 2 and f"{path}:2:" in got.stderr and got.stdout == "", got
    path.write_bytes(b"m,p,q,x,y\rfalse,false,false,2,true\r")  # old Mac line ends: read
    code, rows = _run(exe, path)
    assert [r[:2] for r in rows] == [[v.requirement, v.verdict]
                                     for v in audit_log(plan, str(path)).verdicts]
