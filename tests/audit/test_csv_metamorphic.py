"""Metamorphic relation 10 (tests/audit/test_metamorphic.py has 1 to 9): the CSV that
``fretc audit --write-csv`` writes of a log is what the audit judged, so

* the audit of the CSV gives every requirement the log's verdict, LTL3 verdict and tick,
  ticks evaluated and unknown ticks (each requirement on its own clock of the file; an
  ``error`` on the log has no clock and is an error on the file);
* the C monitors' runner (``fretc --emit c``) on the CSV gives each requirement with a C
  monitor the log's verdict, except that it stops at the first unknown tick (a gap's
  ``unknown`` cell, a ``gap`` row, the ``cut`` row, a NaN) where the audit judges on in
  three-valued semantics: there it says ``unknown`` (or the LTL3 verdict decided before),
  never a verdict the audit contradicts, and ``unknown`` wherever the audit does.

On every log the tests have (the cases of tests/audit/_metamorphic.py: the shipped runs,
the real and foreign logs of ../shared/data with generated requirement sets), and on
damaged copies of a shipped run (a chunk failing its CRC, a truncation). The default run
takes the bounded sample of test_metamorphic.py; ``-m slow`` sweeps every log.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner

import _metamorphic as M
from _c_monitors import build, c_compiler
from test_metamorphic import ALL, SAMPLE, _case

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.sampled.csv import write_sampled_csv
from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]
DECIDED = ("satisfied", "vacuous", "violated")


def _seen(v) -> tuple:
    """What a verdict says, whichever file it was read from."""
    return (v.verdict, v.ltl3.status if v.ltl3 else None, v.ltl3.tick if v.ltl3 else None,
            v.ticks_evaluated if v.verdict != "error" else None, v.unknown_ticks)


def _runner(fret: Path, folder: Path) -> Path | None:
    if c_compiler() is None:
        return None
    res = CliRunner().invoke(main, [str(fret), "--emit", "c", "-o", str(folder)])
    assert res.exit_code == 0, res.output
    return build(folder, sorted(p.name for p in folder.glob("*.c")), "runner",
                 sanitize=False)


def check_csv(case: M.Case, tmp: Path) -> None:
    """Relation 10 on one case."""
    fret = M.write(tmp / "r", case)
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    la = audit_log(plan, str(case.log))
    try:
        write_sampled_csv(plan, str(case.log), tmp / "s.csv")
    except ValueError:
        pytest.skip("no bound variable to write")
    csv = audit_log(plan, str(tmp / "s.csv"))
    assert [v.requirement for v in csv.verdicts] == [v.requirement for v in la.verdicts]
    for v, w in zip(la.verdicts, csv.verdicts):
        assert _seen(w) == _seen(v), f"{case.id}: {v.requirement} on its sampled CSV"
    assert csv.partial == la.partial or not any(v.verdict != "error" for v in la.verdicts)
    exe = _runner(fret, tmp / "c")
    if exe is None:
        return
    got = subprocess.run([str(exe), str(tmp / "s.csv")], capture_output=True, text=True)
    assert got.returncode in (0, 1, 2, 3) and not got.stderr, got.stderr
    words = {v.requirement: v.verdict for v in la.verdicts}
    for row in got.stdout.splitlines():
        rid, word, *rest = row.split("\t")
        unread = any(c.startswith("unread=") for c in rest)
        if word in DECIDED or not unread:
            assert word == words[rid], f"{case.id}: {rid}: runner {row!r}, log {words[rid]}"
        else:
            assert word == "unknown", (case.id, row)


@pytest.mark.parametrize("case", SAMPLE)
def test_the_sampled_csv_gives_the_audit(case, tmp_path):
    check_csv(_case(case), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("case", ALL)
def test_the_sampled_csv_gives_the_audit_on_every_log(case, tmp_path):
    check_csv(_case(case), tmp_path)


@pytest.mark.parametrize("damage", ["chunk", "truncated"])
def test_the_sampled_csv_of_a_damaged_log_gives_its_audit(damage, tmp_path):
    """A shipped run with a chunk failing its CRC (a gap: unknown ticks) or cut short."""
    case = next(c for c in M.shipped_cases() if c.log.name == "stop_delay.mcap")
    whole = M.rechunked(case.log, tmp_path / "whole.mcap")
    log = tmp_path / f"{damage}.mcap"
    if damage == "chunk":
        assert M.corrupt_chunk(whole, log, 0.5) is not None
    else:
        data = whole.read_bytes()
        log.write_bytes(data[:int(len(data) * 0.6)])
    check_csv(M.Case(f"{case.id} {damage}", log, case.fret, case.bindings), tmp_path)
