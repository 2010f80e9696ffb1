"""The validation suite of ``fretc qualify``: its checks run on the installed fretc, then a
mutation run (each fault of :mod:`fretc.qualification.faults` seeded in turn, the checks run
again until one fails), and the result per tool operational requirement.

A requirement passes when every check that shows it passes, fails when one of them fails,
and is ``not checked here`` when no check of the suite shows it (the project's own tests
show it: the traceability matrix, docs/qualification/). The run writes only inside its
folder: the checks' files in its ``work`` folder, and fretc's disk cache is off while it
runs (``FRETC_CACHE_DIR`` empty), so nothing a previous run cached stands in for the code
under validation.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fretc.qualification import checks as checks_module
from fretc.qualification import (checks_audit, checks_forms, checks_logs, checks_robot,
                                 checks_shield, checks_signals, checks_tools, checks_watch)
from fretc.qualification.catalogue import load_requirements
from fretc.qualification.checks import Check, CheckSkipped, Run
from fretc.qualification.faults import FAULTS

#: every check of the suite, in the order it runs
CHECKS: tuple[Check, ...] = (checks_module.CHECKS + checks_audit.CHECKS + checks_logs.CHECKS
                             + checks_signals.CHECKS + checks_forms.CHECKS
                             + checks_robot.CHECKS + checks_shield.CHECKS
                             + checks_tools.CHECKS + checks_watch.CHECKS)
#: the environment variable that seeds a fault for a whole run (a test's way to stand for a
#: broken installation; its value a name of :data:`fretc.qualification.faults.FAULTS`)
SEED_VARIABLE = "FRETC_QUALIFY_SEED_FAULT"


@dataclass
class CheckResult:
    """One check's outcome: ``passed``, its ``failures`` (sentences), ``seconds``, and
    ``skipped``: why it could not run here (None when it ran; a skipped check has passed
    nothing and failed nothing)."""

    check: Check
    passed: bool
    failures: list[str]
    seconds: float
    skipped: str | None = None

    @property
    def ran(self) -> bool:
        """The check ran (it was not skipped)."""
        return self.skipped is None

    def to_json(self) -> dict[str, Any]:
        """``{"name", "what", "requirements", "result", "passed", "failures", "skipped",
        "seconds"}``; ``result`` one of ``passed``, ``failed``, ``skipped``."""
        result = "skipped" if not self.ran else "passed" if self.passed else "failed"
        return {"name": self.check.name, "what": self.check.what,
                "requirements": list(self.check.tors), "result": result,
                "passed": self.passed, "failures": self.failures, "skipped": self.skipped,
                "seconds": round(self.seconds, 3)}


@dataclass
class Outcome:
    """A validation run: its checks' results, the mutation run's (``mutants``: one dict a
    fault, ``{"fault", "where", "what", "killed", "killed_by"}``) and the fault seeded for
    the whole run, if any."""

    checks: list[CheckResult]
    mutants: list[dict[str, Any]] = field(default_factory=list)
    seeded: str | None = None

    def requirement_results(self) -> list[dict[str, Any]]:
        """Per requirement of ``requirements.toml``, in its order: ``id``, ``area``,
        ``statement``, ``source``, ``result`` (``passed``; ``failed``; ``partly checked
        here``: the checks that ran passed, others were skipped; ``not checked here``: the
        project's tests show it; or ``not verified``: the requirements file says why no test
        does, ``not_verified``), ``checks`` (the names of those that ran), ``skipped`` (of
        those that could not run here) and ``failures``."""
        out = []
        for req in load_requirements():
            mine = [r for r in self.checks if req.id in r.check.tors and r.ran]
            skipped = [r.check.name for r in self.checks
                       if req.id in r.check.tors and not r.ran]
            failed = [r for r in mine if not r.passed]
            result = (("failed" if failed else "partly checked here" if skipped else "passed")
                      if mine else
                      "not verified" if req.not_verified else "not checked here")
            out.append({"id": req.id, "area": req.area, "statement": req.statement,
                        "source": req.source, "result": result,
                        "not_verified": req.not_verified,
                        "checks": [r.check.name for r in mine], "skipped": skipped,
                        "failures": [f"{r.check.name}: {f}" for r in failed
                                     for f in r.failures]})
        return out

    @property
    def failed_requirements(self) -> list[str]:
        """The ids of the requirements a failed check shows, in the file's order."""
        return [r["id"] for r in self.requirement_results() if r["result"] == "failed"]

    @property
    def passed(self) -> bool:
        """Every check passed and every seeded fault of the mutation run was detected."""
        return all(r.passed for r in self.checks) and all(m["killed"] for m in self.mutants)


def run_checks(run: Run, checks: Sequence[Check] = CHECKS, stop_at_failure: bool = False
               ) -> list[CheckResult]:
    """Run ``checks`` in order; an exception escaping a check is that check's failure
    (named with its type), never the end of the run. ``stop_at_failure``: stop after the
    first check that fails (the mutation run's question is only whether one does)."""
    out = []
    for check in checks:
        start = time.perf_counter()
        skipped = None
        try:
            failures = check.run(run)
        except CheckSkipped as exc:
            failures, skipped = [], str(exc)
        except Exception as exc:  # noqa: BLE001 - a broken tool may fail in any way
            failures = [f"{type(exc).__name__}: {exc}"]
        out.append(CheckResult(check, not failures, failures, time.perf_counter() - start,
                               skipped))
        if failures and stop_at_failure:
            break
    return out


@contextlib.contextmanager
def _no_cache() -> Iterator[None]:
    """fretc's disk cache off inside the block (``FRETC_CACHE_DIR`` empty), as before
    after it."""
    old = os.environ.get("FRETC_CACHE_DIR")
    os.environ["FRETC_CACHE_DIR"] = ""
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("FRETC_CACHE_DIR", None)
        else:
            os.environ["FRETC_CACHE_DIR"] = old


def _fresh(work: Path, name: str, command: Any) -> Run:
    """A run whose files go in the new folder ``work/name`` (made as an output folder of
    fretc's own: a link or a file there is refused) and whose end-to-end checks run
    ``command``."""
    from fretc.common.outputs import sub_folder

    return Run(Path(sub_folder(work, name)), command)


def mutation_run(work: Path, command: Any) -> list[dict[str, Any]]:
    """Seed each fault of :data:`FAULTS` in turn and run the checks (the end-to-end ones
    with ``command``, the ``fretc`` click group), those of its ``first`` first, until one
    fails: a fault is killed when a check fails under it (``killed_by`` names it)."""
    out = []
    for name, fault in sorted(FAULTS.items()):
        order = ([c for c in CHECKS if c.name in fault.first]
                 + [c for c in CHECKS if c.name not in fault.first])
        with fault.seed():
            results = run_checks(_fresh(work, f"mutant-{name}", command), order,
                                 stop_at_failure=True)
        killers = [r.check.name for r in results if not r.passed]
        out.append({"fault": name, "where": fault.where, "what": fault.what,
                    "killed": bool(killers), "killed_by": killers})
    return out


def validate(work: Path, command: Any, seeded: str | None = None, mutation: bool = True
             ) -> Outcome:
    """The suite on this installation: every check (the end-to-end ones running
    ``command``, the ``fretc`` click group, which the command line passes in), then
    (``mutation``) the mutation run, with fretc's disk cache off; ``seeded`` (a name of
    :data:`FAULTS`) holds that fault for the whole run. Files go under ``work`` (which must
    exist). Raises ``KeyError`` for an unknown fault name."""
    seed = FAULTS[seeded].seed() if seeded else contextlib.nullcontext()
    with _no_cache(), seed:
        outcome = Outcome(run_checks(_fresh(work, "checks", command)), seeded=seeded)
        if mutation:
            outcome.mutants = mutation_run(work, command)
    return outcome
