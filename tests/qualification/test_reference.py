"""The validation suite's parts in this process: the reference evaluator of FRET's
semantics on worked examples (computed by hand from docs/reference/semantics.md), the
in-process checks passing on this fretc, and each in-process fault detected and undone."""

from __future__ import annotations

from pathlib import Path

import pytest

from fretc.qualification import checks, faults
from fretc.qualification import reference as ref


def _trace(**columns: str) -> list[dict[str, bool]]:
    """A trace from one string of 0/1 a variable (unnamed variables false)."""
    n = len(next(iter(columns.values())))
    return [{v: columns.get(v, "0" * n)[i] == "1" for v in ref.VARIABLES} for i in range(n)]


@pytest.mark.parametrize("key, trace, want", [
    # upon c within 2 ticks r: c rises at 1, r at 3 (= 1 + 2): satisfied
    ("null,regular,within", _trace(c="0110", r="0001"), "satisfied"),
    # ... r at 4 is too late: violated
    ("null,regular,within", _trace(c="01100", r="00001"), "violated"),
    # the window runs past the end of the run: nothing required
    ("null,regular,within", _trace(c="001", r="000"), "satisfied"),
    # never triggered: vacuous
    ("null,regular,within", _trace(c="000", r="000"), "vacuous"),
    # whenever c: every tick of c triggers; the trigger at 2 misses r by 4 (trace ends at 3)
    ("null,holding,within", _trace(c="0110", r="0001", m="0000"), "satisfied"),
    # in m: the stretches [1, 2] and [4, 4]; immediately r at each interval's start
    ("in,null,immediately", _trace(m="01101", r="01001"), "satisfied"),
    ("in,null,immediately", _trace(m="01101", r="01000"), "violated"),
    # before m: [0, first m - 1]; m at 0 leaves no interval
    ("before,null,always", _trace(m="100", r="000"), "vacuous"),
    ("before,null,always", _trace(m="001", r="110"), "satisfied"),
    # only in m: the response is forbidden outside m (notin intervals [0,0] and [3,3])
    ("onlyIn,null,eventually", _trace(m="0110", r="0110"), "satisfied"),
    ("onlyIn,null,eventually", _trace(m="0110", r="0001"), "violated"),
    # after m: from just after the first stretch of m; next: at t+1 unless t is the end
    ("after,null,next", _trace(m="1100", r="0001"), "satisfied"),
    ("after,null,next", _trace(m="1100", r="0000"), "violated"),
    # until s: r from the trigger until s holds
    ("null,null,until", _trace(r="1100", s="0010"), "satisfied"),
    ("null,null,until", _trace(r="1000", s="0010"), "violated"),
    # after 2 ticks: r false at t..t+2 and true at t+3
    ("null,null,after", _trace(r="0001"), "satisfied"),
    ("null,null,after", _trace(r="0010"), "violated"),
])
def test_the_reference_gives_the_worked_verdicts(key, trace, want):
    assert ref.verdict(key, trace) == want


def test_the_key_sentences_cover_every_key_once():
    keys = [k for k, _ in ref.key_sentences()]
    assert len(keys) == len(set(keys)) == 288


@pytest.fixture
def few_traces(monkeypatch):
    """The in-process checks on 2 traces a key (the suite runs 24)."""
    monkeypatch.setattr(checks, "TRACES_PER_KEY", 2)


@pytest.mark.tor("TOR-QUA-001")
def test_the_in_process_checks_pass_on_this_fretc(tmp_path: Path, few_traces):
    run = checks.Run(tmp_path)
    for check in checks.CHECKS:
        assert check.run(run) == [], check.name


@pytest.mark.tor("TOR-QUA-001")
@pytest.mark.parametrize("fault, killer", [("semantics-trigger", "semantics-judge"),
                                           ("semantics-next", "semantics-formulas")])
def test_a_seeded_fault_is_detected_and_undone(tmp_path: Path, few_traces, fault, killer):
    check = next(c for c in checks.CHECKS if c.name == killer)
    with faults.FAULTS[fault].seed():
        assert check.run(checks.Run(tmp_path / "with")) != []
    assert check.run(checks.Run(tmp_path / "after")) == []


def test_a_fault_is_undone_when_the_block_raises():
    from fretc.monitors import interval

    original = interval.trigger_ticks
    with pytest.raises(RuntimeError), faults.FAULTS["semantics-trigger"].seed():
        assert interval.trigger_ticks is not original
        raise RuntimeError("stop")
    assert interval.trigger_ticks is original


def test_a_check_that_fails_raises_or_cannot_run_is_reported_so(tmp_path: Path):
    from fretc.qualification.checks import Check, CheckSkipped
    from fretc.qualification.suite import Outcome, run_checks

    def skip(run):
        raise CheckSkipped("no C compiler (cc, gcc or clang) on the PATH")

    def broken(run):
        raise OverflowError("a broken tool")

    results = run_checks(checks.Run(tmp_path), [
        Check("skip", ("TOR-GEN-003",), "", skip),
        Check("fails", ("TOR-SEM-001",), "", lambda run: ["wrong key"]),
        Check("raises", ("TOR-SEM-002",), "", broken),
        Check("passes", ("TOR-SEM-003",), "", lambda run: [])])
    outcome = Outcome(results)
    got = {r["id"]: (r["result"], r["failures"]) for r in outcome.requirement_results()}
    assert got["TOR-GEN-003"] == ("not checked here", [])
    assert got["TOR-SEM-001"] == ("failed", ["fails: wrong key"])
    assert got["TOR-SEM-002"] == ("failed", ["raises: OverflowError: a broken tool"])
    assert got["TOR-SEM-003"] == ("passed", [])
    assert outcome.failed_requirements == ["TOR-SEM-001", "TOR-SEM-002"]
    assert not outcome.passed
    assert [c.to_json()["result"] for c in results] == ["skipped", "failed", "failed", "passed"]
    assert Outcome(results[:1] + results[3:]).passed


def test_the_c_check_is_skipped_without_a_compiler(tmp_path: Path, monkeypatch):
    import shutil

    from fretc.qualification import checks_forms
    from fretc.qualification.checks import CheckSkipped

    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(CheckSkipped, match="no C compiler"):
        checks_forms.check_c_monitors(checks.Run(tmp_path))
