"""Full collections made rarer while a log is audited, and Python's thresholds given back."""

from __future__ import annotations

import gc
from pathlib import Path

import pytest

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.common.collections_gc import FULL_EVERY, fewer_full_collections

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def thresholds():
    before = gc.get_threshold()
    gc.set_threshold(700, 10, 10)
    yield
    gc.set_threshold(*before)


def test_the_audit_of_a_log_runs_with_rare_full_collections_and_restores_them(
        thresholds, monkeypatch):
    from fretc.audit import log as audit_log_module

    seen = []
    real = audit_log_module._LogRun.run

    def run(self, progress):
        seen.append(gc.get_threshold())
        return real(self, progress)

    monkeypatch.setattr(audit_log_module._LogRun, "run", run)
    plan = load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))
    la = audit_log(plan, str(ROOT / "traces" / "stop_delay.mcap"))
    assert la.verdicts and seen == [(700, 10, FULL_EVERY)]
    assert gc.get_threshold() == (700, 10, 10)


def test_nested_blocks_and_thresholds_changed_inside_are_kept(thresholds):
    with fewer_full_collections():
        with fewer_full_collections():
            assert gc.get_threshold() == (700, 10, FULL_EVERY)
        assert gc.get_threshold() == (700, 10, FULL_EVERY)
    assert gc.get_threshold() == (700, 10, 10)
    with fewer_full_collections():
        gc.set_threshold(500, 5, 5)  # the program's own choice, made meanwhile
    assert gc.get_threshold() == (500, 5, 5)


def test_a_failed_audit_gives_the_thresholds_back(thresholds):
    with pytest.raises(RuntimeError):
        with fewer_full_collections():
            raise RuntimeError("boom")
    assert gc.get_threshold() == (700, 10, 10)


def test_the_audit_command_prints_its_verdicts_with_rare_full_collections(
        thresholds, monkeypatch):
    """``fretc audit`` keeps the full collections rare while it prints the verdicts too (a
    full collection walks every verdict kept for the report), and gives them back after."""
    from click.testing import CliRunner

    from fretc.cli import main
    from fretc.reports import terminal

    seen = []
    real = terminal.print_summary

    def print_summary(*args, **kwargs):
        seen.append(gc.get_threshold())
        return real(*args, **kwargs)

    monkeypatch.setattr(terminal, "print_summary", print_summary)
    res = CliRunner().invoke(main, ["audit", "-r", str(ROOT / "requirements"),
                                    str(ROOT / "traces" / "stop_delay.mcap"), "--no-progress"])
    assert res.exit_code in (0, 1, 3), res.output
    assert seen == [(700, 10, FULL_EVERY)]
    assert gc.get_threshold() == (700, 10, 10)
