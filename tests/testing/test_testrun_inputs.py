"""``fretc testrun`` of a test folder whose tests.json names a trace that is not there: an
input error naming the file (exit 2), before any test runs, never a test run and judged on a
log its command made without its trace."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
R1 = ROOT / "requirements" / "r1.fret"


def _fretc(args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fretc", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, env=dict(os.environ), timeout=600)


def test_a_missing_trace_is_an_error_naming_it_before_any_test_runs(tmp_path):
    tests = tmp_path / "tests"
    assert _fretc(["testgen", R1, "-o", tests]).returncode == 0
    (tests / "T02.csv").unlink()
    ran = tmp_path / "ran"
    # a system that writes a log whatever it is given (the log of the nominal run)
    command = (f"{sys.executable} -c \"import shutil, sys; open({str(ran)!r}, 'a').write('x');"
               f" shutil.copy({str(ROOT / 'traces' / 'nominal.mcap')!r}, sys.argv[2])\"")
    got = _fretc(["testrun", tests, "--command", command])
    assert got.returncode == 2, got.stdout + got.stderr
    assert "T02.csv" in got.stderr and "no such file" in got.stderr, got.stderr
    assert not ran.exists()  # (no test ran)
    assert not (tests / "runs").exists() or not list((tests / "runs").iterdir())
    (tests / "T02.csv").mkdir()  # a folder where the trace goes: the same
    got = _fretc(["testrun", tests, "--command", command, "--test", "T02"])
    assert got.returncode == 2 and "T02.csv" in got.stderr, got.stderr
    assert not ran.exists()
