"""Running generated requirements-based tests (``fretc testgen``) against a system
(``fretc testrun DIR --command CMD``, and the pytest file ``fretc testgen --pytest`` writes):
each test's trace is turned into a log of the system by a command (``CMD TRACE.csv LOG``: a
simulator driven by the trace's inputs, a test bench), and the log is audited with the
test set's requirements (and binding file) with coverage.

Design notes: ARCHITECTURE.md, `testing/testrun.py`."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fretc.common.outputs import output_folder
from fretc.testing.tests_json import file_name

__all__ = ["OUTCOMES", "Outcome", "judge", "run_test", "audit_log", "missing_traces"]

#: the outcomes of a test against a system, worst first
OUTCOMES = ("fail", "unknown", "not exercised", "pass")

_DECIDED = ("satisfied", "vacuous", "violated")


@dataclass
class Outcome:
    """One test against a system: ``outcome`` (one of :data:`OUTCOMES`), the ``verdicts`` of
    the system's log (requirement id -> verdict), ``violated``/``undecided`` requirement ids,
    ``not_exercised`` (``(requirement id, obligation id)`` the test covers that the log does
    not exercise), ``exercised`` (how many of the test's obligations it does), ``log`` and
    ``error`` (the command's or the audit's failure, or None), ``target`` (the obligation the
    test was generated for, as text)."""

    test: str
    outcome: str
    verdicts: dict[str, str] = field(default_factory=dict)
    violated: list[str] = field(default_factory=list)
    undecided: list[str] = field(default_factory=list)
    not_exercised: list[tuple[str, str]] = field(default_factory=list)
    exercised: int = 0
    log: str = ""
    error: str | None = None
    target: str = ""

    def text(self) -> str:
        """One line: the outcome and why."""
        if self.error:
            return f"{self.test}: {self.outcome}: {self.error}"
        why = {"fail": "violated: " + ", ".join(self.violated),
               "unknown": "undecided: " + ", ".join(f"{r} ({self.verdicts.get(r)})"
                                                     for r in self.undecided),
               "not exercised": f"{self.target} not exercised on the system's log",
               "pass": f"no requirement violated, {self.target} exercised"}[self.outcome]
        if self.not_exercised:
            why += "; also not exercised: " + ", ".join(f"{r} {o}" for r, o in
                                                        self.not_exercised
                                                        if f"{r} {o}" != self.target)
        total = self.exercised + len(self.not_exercised)
        return f"{self.test}: {self.outcome}: {why} ({self.exercised} of {total} " \
               "obligations exercised)"


def judge(test: dict[str, Any], doc: dict[str, Any], require: str = "target") -> Outcome:
    """The outcome (module docstring) of ``test`` (an entry of ``tests.json``) on the
    system's log audited as ``doc`` (``fretc audit --coverage --json``'s document);
    ``require``: ``"target"`` (the obligation it was generated for must be exercised) or
    ``"all"`` (every obligation it covers).

    Raises:
        ValueError: another ``require``."""
    if require not in ("target", "all"):
        raise ValueError(f"require must be 'target' or 'all', not {require!r}")
    logs = doc.get("logs") or []
    verdicts = {v["requirement"]: v["verdict"] for lg in logs for v in lg["verdicts"]}
    covered = {(r["requirement"], o["obligation"])
               for r in (doc.get("coverage") or {}).get("requirements", [])
               for o in r["obligations"] if o["status"] == "covered"}
    g = test.get("generated_for") or {}
    target = (g.get("requirement"), g.get("obligation"))
    wanted = list(dict.fromkeys([(c["requirement"], c["obligation"]) for c in test["covers"]]
                                + ([target] if g else [])))
    out = Outcome(test["id"], "pass", verdicts,
                  violated=[r for r, v in verdicts.items() if v == "violated"],
                  undecided=[r for r, v in verdicts.items() if v not in _DECIDED],
                  not_exercised=[w for w in wanted if w not in covered],
                  exercised=sum(w in covered for w in wanted),
                  log=logs[0]["log"] if logs else "",
                  target=" ".join(str(x) for x in g.values()) or "no obligation")
    if logs and logs[0].get("error"):
        out.undecided = out.undecided or ["(log)"]
        out.error = f"the audit could not read the log: {logs[0]['error']}"
    if out.violated:
        out.outcome = "fail"
    elif out.undecided or not verdicts:
        out.outcome = "unknown"
    elif not wanted or (out.not_exercised if require == "all" or not g
                        else target in out.not_exercised):
        out.outcome = "not exercised"  # a test without an obligation shows nothing
    return out


def audit_log(requirements: list[str], bindings: str | None, log: Path, out: Path) -> dict[str, Any]:
    """``fretc audit -r REQ... [--bindings B] LOG --coverage --json OUT`` in a fresh process;
    its JSON document.

    Raises:
        RuntimeError: the audit wrote no document (its exit code and last error line)."""
    cmd = [sys.executable, "-m", "fretc", "audit", *[x for r in requirements for x in ("-r", r)],
           *(["--bindings", bindings] if bindings else []), str(log), "--coverage",
           "--json", str(out), "--no-progress"]
    out.unlink(missing_ok=True)  # an earlier run's document is never this run's
    res = subprocess.run(cmd, capture_output=True, text=True)
    if not out.exists():
        last = (res.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"fretc audit exited {res.returncode}: {last}")
    doc: dict[str, Any] = json.loads(out.read_text(encoding="utf-8"))
    return doc


def missing_traces(tests: list[dict[str, Any]], folder: Path) -> list[str]:
    """``FOLDER/TRACE: why`` for each test of ``tests`` (``tests.json``'s, as
    :func:`fretc.testing.tests_json.load_tests` read them) whose trace is not a file in the
    test folder ``folder``: no such file, or a folder there. A test without its trace cannot
    be run (its command would be given a path to nothing and might still write a log)."""
    out = []
    for t in tests:
        trace = folder / t["trace"]
        if not trace.is_file():
            why = "a folder, not a trace file" if trace.is_dir() else "no such file"
            out.append(f"{trace}: {why} (test {t['id']}'s trace, named in "
                       f"{folder / 'tests.json'})")
    return out


def run_test(test: dict[str, Any], doc: dict[str, Any], folder: Path, command: str, work: Path,
             bindings: str | None = None, require: str = "target",
             log_name: str | None = None) -> Outcome:
    """Run ``command`` (split as a shell would, then ``TRACE LOG`` appended) on ``test``'s
    trace in ``folder`` (the test folder; ``doc``: its ``tests.json``), audit the log it
    writes in ``work`` and judge it (module docstring). ``bindings``: the binding file
    (default: ``doc``'s ``"bindings"``, else the audit's own search beside the
    requirements); ``require``: as :func:`judge`'s; ``log_name``: the log's file name in
    ``work`` (default ``<test id>.mcap``; its suffix tells the audit the format). A command
    that fails or writes no log gives ``unknown`` with its error. Files are named by
    :func:`fretc.testing.tests_json.file_name` only (``test['id']`` as read by
    :func:`fretc.testing.tests_json.load_tests`).

    Raises:
        ValueError: a test id or ``log_name`` that is not a file name, or a trace that is
            not a file in ``folder`` (:func:`missing_traces`): never run without it."""
    missing = missing_traces([test], folder)
    if missing:
        raise ValueError(missing[0])
    log = work / file_name(log_name or test["id"], "" if log_name else ".mcap")
    report = work / file_name(test["id"], ".audit.json")
    output_folder(work)  # (the caller's folder: fretc testrun checks its default runs/)
    trace = folder / test["trace"]
    log.unlink(missing_ok=True)  # an earlier run's log is never judged as this run's
    res = subprocess.run(shlex.split(command) + [str(trace), str(log)], capture_output=True,
                         text=True)
    if res.returncode != 0 or not log.exists():
        last = (res.stderr.strip().splitlines() or ["no output"])[-1]
        error = f"the command exited {res.returncode}: {last}"
        if not log.exists():
            error = f"the command exited {res.returncode} without a log: {last}"
        return Outcome(test["id"], "unknown", error=error, log=str(log))
    try:
        audited = audit_log(doc["requirements"], bindings or doc.get("bindings"), log, report)
    except RuntimeError as exc:
        return Outcome(test["id"], "unknown", error=str(exc), log=str(log))
    return judge(test, audited, require)
