"""``fretc audit --write-csv`` writes what the audit judged: each requirement's own clock
(its ticks only, never another requirement's), and what the log's damage left unknown
(``unknown`` cells, ``gap`` rows, the ``cut`` row), so that the audit of the CSV and the C
monitors' runner on it give ``unknown`` where the audit of the log does, and the log's
verdict where it decides. The CSV format's marks are checked on their own too."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.sampled.csv import write_sampled_csv
from fretc.cli import main
from fretc.common.problems import CsvError
from fretc.logs.csv.source import CsvSource, clock_lines, escape_id, unescape_id

from _c_monitors import build, needs_cc
from _logs import float64, write_mcap

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "logs"))
S = 1_000_000_000
T0 = 1_700_000_000 * S


def _plan(folder: Path, fret: str, bindings: str):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "r.fret").write_text(fret)
    (folder / "r.bindings.toml").write_text(bindings)
    return load_plan(AuditConfig(requirements=(str(folder / "r.fret"),)))


def _words(la) -> dict[str, str]:
    return {v.requirement: v.verdict for v in la.verdicts}


def _runner(folder: Path, fret: Path) -> Path:
    needs_cc()
    out = folder / "c"
    res = CliRunner().invoke(main, [str(fret), "--emit", "c", "-o", str(out)])
    assert res.exit_code == 0, res.output
    return build(out, sorted(p.name for p in out.glob("*.c")), "runner", sanitize=False)


def _run(exe: Path, csv: Path) -> tuple[int, dict[str, list[str]]]:
    got = subprocess.run([str(exe), str(csv)], capture_output=True, text=True)
    return got.returncode, {r.split("\t")[0]: r.split("\t")[1:]
                            for r in got.stdout.splitlines()}


DF_FRET = """@tick_period 100 ms
B0: the copter shall always satisfy volt_ok
B1: the copter shall always satisfy volt1_ok
"""
DF_BINDINGS = """[tick]
period = "100 ms"
[variables]
volt_ok = '"BAT".Volt > 10.0'
volt1_ok = '"BAT/1".Volt > 10.0'
"""


def test_a_truncated_flight_log_writes_its_cut(tmp_path):
    """A DataFlash log cut short: instance 1 held its voltage so far (``unknown``: the rest
    of the flight was not read), instance 0 dropped below 10 V before the cut
    (``violated``). The CSV's last row of each clock is its ``cut``: the audit of the CSV
    and the runner give ``unknown`` and ``violated`` too (they gave ``satisfied`` and
    ``violated`` on a CSV that carried no mark of the cut)."""
    from _dataflash import write_dataflash

    rows = []
    for i in range(50):
        t = 1_000_000 + i * 100_000
        rows.append(("BAT", [t, 0, 12.0 - i * 0.05, 5.0, 90.0 - i]))
        rows.append(("BAT", [t + 10, 1, 11.0, 1.0, 50.0]))
    log = write_dataflash(tmp_path / "flight.bin", rows)
    cut = tmp_path / "cut.bin"
    cut.write_bytes(log.read_bytes()[:-40])
    plan = _plan(tmp_path / "r", DF_FRET, DF_BINDINGS)
    la = audit_log(plan, str(cut))
    assert _words(la) == {"B0": "violated", "B1": "unknown"}
    write_sampled_csv(plan, str(cut), tmp_path / "cut.csv")
    text = (tmp_path / "cut.csv").read_text()
    assert text.splitlines()[-1].endswith(",cut")
    csv = audit_log(plan, str(tmp_path / "cut.csv"))
    assert _words(csv) == _words(la) and csv.partial
    code, got = _run(_runner(tmp_path, tmp_path / "r" / "r.fret"), tmp_path / "cut.csv")
    assert {k: v[0] for k, v in got.items()} == _words(la) and code == 1


def test_each_requirement_keeps_its_own_clock(tmp_path):
    """/cmd stops at 5 s (moving from 2 s on), /scan goes on to 8.5 s. ``count_ticks(moving,
    4 s) <= 35`` reads /cmd alone: its clock ends at 5 s (31 ticks moving in the last 4 s:
    satisfied). A CSV of one clock over both topics held the last command to 8.5 s and
    counted 41 (violated on the CSV, satisfied on the log); each clock of its own, the CSV
    gives the log's verdicts."""
    msgs = [("/cmd", "std_msgs/msg/Float64", T0 + k * S // 10, float64(float(k >= 20)))
            for k in range(51)]
    msgs += [("/scan", "std_msgs/msg/Float64", T0 + k * S // 10, float64(2.0)) for k in range(86)]
    log = write_mcap(tmp_path / "run.mcap", sorted(msgs, key=lambda m: m[2]))
    fret = ("@tick_period 100 ms\nC: the robot shall always satisfy busy <= 35\n"
            "F: the robot shall always satisfy free\n")
    binds = ('[tick]\nperiod = "100 ms"\n[variables]\nbusy = "count_ticks(/cmd.data > 0.5, '
             '4 s)"\nfree = "/scan.data > 1.0"\n')
    plan = _plan(tmp_path / "r", fret, binds)
    la = audit_log(plan, str(log))
    assert _words(la) == {"C": "satisfied", "F": "satisfied"}
    _la, clocks = write_sampled_csv(plan, str(log), tmp_path / "run.csv")
    assert [c.ids for c in clocks] == [["C"], ["F"]]
    assert [len(c.times) for c in clocks] == [v.ticks_evaluated for v in la.verdicts]
    csv = audit_log(plan, str(tmp_path / "run.csv"))
    assert _words(csv) == _words(la)
    assert [v.ticks_evaluated for v in csv.verdicts] == [v.ticks_evaluated for v in la.verdicts]
    code, got = _run(_runner(tmp_path, tmp_path / "r" / "r.fret"), tmp_path / "run.csv")
    assert code == 0 and {k: v[0] for k, v in got.items()} == _words(la)
    assert got["C"][2] == f"ticks={la.verdicts[0].ticks_evaluated}"


def test_a_gap_is_unknown_on_the_csv_as_on_the_log(tmp_path):
    """A chunk of the log failing its CRC: the ticks it leaves unknown are ``unknown``
    cells; the audit of the CSV judges them three-valued as the log's audit does (a
    violation after the gap stands, an invariant that held is unknown); the runner stops at
    the first unknown tick (``unknown``, never a verdict the audit contradicts)."""
    import _metamorphic as M

    msgs = [("/v", "std_msgs/msg/Float64", T0 + k * S // 10,
             float64(5.0 if k < 150 else 12.0)) for k in range(200)]
    whole = write_mcap(tmp_path / "whole.mcap", msgs, chunk_size=400)
    got = M.corrupt_chunk(whole, tmp_path / "gap.mcap", 0.3)
    assert got is not None
    fret = "@tick_period 100 ms\nV: the robot shall always satisfy v < 10\nW: the robot shall always satisfy v < 20\n"
    plan = _plan(tmp_path / "r", fret, '[tick]\nperiod = "100 ms"\n[variables]\nv = "/v.data"\n')
    la = audit_log(plan, str(tmp_path / "gap.mcap"))
    assert _words(la) == {"V": "violated", "W": "unknown"}
    write_sampled_csv(plan, str(tmp_path / "gap.mcap"), tmp_path / "gap.csv")
    assert "unknown" in (tmp_path / "gap.csv").read_text()
    csv = audit_log(plan, str(tmp_path / "gap.csv"))
    assert _words(csv) == _words(la)
    assert [v.unknown_ticks for v in csv.verdicts] == [v.unknown_ticks for v in la.verdicts]
    code, ran = _run(_runner(tmp_path, tmp_path / "r" / "r.fret"), tmp_path / "gap.csv")
    assert {k: v[0] for k, v in ran.items()} == {"V": "unknown", "W": "unknown"}
    assert all(any(c.startswith("unread=") for c in v) for v in ran.values()) and code == 3


def test_a_requirement_no_clock_names_is_an_error(tmp_path):
    """A sampled trace carries the clocks of the requirements it was written for: another
    requirement is an error on it (its ticks are not there), in the audit and the runner."""
    path = tmp_path / "t.csv"
    path.write_text("# fretc sampled trace of x.mcap: ...\n# fretc clock 1: A\n"
                    "time,p\n0,true\n0.1,true\n")
    fret = tmp_path / "r.fret"
    fret.write_text("A: the sw shall always satisfy p\nB: the sw shall always satisfy p\n")
    la = audit_log(load_plan(AuditConfig(requirements=(str(fret),))), str(path))
    assert _words(la) == {"A": "satisfied", "B": "error"}
    assert "carries no clock of B" in la.verdicts[1].error
    code, got = _run(_runner(tmp_path, fret), path)
    assert code == 2 and got["A"][0] == "satisfied" and got["B"][:2] == [
        "error", "no clock of this trace names it"]


def test_clocks_marks_and_their_errors(tmp_path):
    """Two clocks in one file: each read alone (its rows, its columns); the marks; what is
    refused, naming the line."""
    text = ("# fretc sampled trace of x.mcap: ...\n# fretc clock 1: A B\n# fretc clock 2: C\n"
            "time,tick,p,x\n0,1,true,\n0,2,,1.5\n0.1,1,unknown,\n0.1,2,,gap\n0.2,1,false,\n"
            "0.3,2,,cut\n")
    path = tmp_path / "t.csv"
    path.write_text(text)
    assert clock_lines(path) == {"1": ["A", "B"], "2": ["C"]}
    one, two = CsvSource(path, clock="1"), CsvSource(path, clock="2")
    assert (one.columns, one.types, one.row_count, one.unknown_rows) == (
        ["p"], {"p": "bool"}, 3, {"p": [1]})
    assert (two.columns, two.row_count, two.gap_rows, two.cut_time) == (["x"], 2, [1], 3 * S // 10)
    rows = list(two.rows())
    assert [r.gap for r in rows] == [False, True] and two.cut_start == 3 * S // 10
    assert list(CsvSource(path).rows()) == []  # several clocks read whole: no rows
    bad = {"after the cut": text + "0.4,2,,1\n",
           "every cell": text.replace("0.1,2,,gap", "0.1,2,,gap").replace(
               "time,tick,p,x", "time,tick,p,x,y").replace(",\n", ",,\n").replace(
               "gap\n", "gap,1\n").replace("cut\n", "cut,cut\n").replace("1.5\n", "1.5,1\n"),
           "not named": text.replace("0.2,1,", "0.2,3,"),
           "fill": text.replace("0.2,1,false,", "0.2,1,false,2")}
    for why, t in bad.items():
        path.write_text(t)
        with pytest.raises(CsvError) as e:
            CsvSource(path, clock="2" if why != "fill" else "1")
        assert why in str(e.value) or why == "every cell" and "every cell" in str(e.value), (
            why, str(e.value))


def test_a_log_name_with_quotes_and_commas_is_written_visibly(tmp_path):
    """The log's name in the first line is escaped as ids are: no comma or quote reaches the
    CSV readers (a quote at a cell's start would open a quoted cell over the lines after)."""
    log = tmp_path / 'a,"b.csv'
    log.write_text("time,p\n0,true\n1,false\n")
    fret = tmp_path / "r.fret"
    fret.write_text("A: the sw shall always satisfy p\n")
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    write_sampled_csv(plan, str(log), tmp_path / "s.csv")
    first = (tmp_path / "s.csv").read_text().splitlines()[0]
    assert '"' not in first and "a\\x2c\\x22b.csv" in first
    assert [v.verdict for v in audit_log(plan, str(tmp_path / "s.csv")).verdicts] == ["violated"]


@pytest.mark.parametrize("rid", ["R1", "a b", "x,y", 'q"', "é\\", "\t"])
def test_ids_escape_and_come_back(rid):
    word = escape_id(rid)
    assert " " not in word and "," not in word and '"' not in word
    assert unescape_id(word) == rid
