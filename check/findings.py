"""What ``fretc check`` finds (:mod:`fretc.check.analysis`, :mod:`fretc.check.realizability`,
:mod:`fretc.check.witness`): each finding (what was found, about which requirements, and
the witness trace that shows it) and the whole result of a run (:class:`CheckResult`)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fretc.check.items import CheckItem

__all__ = ["Finding", "CheckResult", "ids", "subsets_text"]


@dataclass
class Finding:
    """One result worth a user's attention.

    ``kind``: ``unsatisfiable`` (one requirement), ``conflict`` (a set), ``vacuous``,
    ``redundant``, ``unrealizable``, ``unknown``, ``undeclared`` (a group's
    realizability not decided: a variable declared neither input nor output).
    ``severity``: ``error`` (exit 1), ``warning``, ``unknown`` (exit 1) or ``input`` (an
    input error: exit 2). ``requirements``: the ids it is about; ``subsets``: the
    subsets found (lists of ids, fewest members first); ``standing``: per subset
    ``smallest``, ``minimal`` or ``not shown minimal`` (:class:`fretc.check.checker.Subsets`);
    ``cut``: the subset enumeration ran out of its budget of checks; ``witness``: path of the witness CSV, ``expected`` the verdicts it promises.
    """

    kind: str
    severity: str
    requirements: list[str]
    message: str
    subsets: list[list[str]] = field(default_factory=list)
    standing: list[str] = field(default_factory=list)
    cut: bool = False
    witness: str | None = None
    expected: dict[str, str] = field(default_factory=dict)
    details: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """The finding as a JSON object (every attribute, plain values)."""
        return {"kind": self.kind, "severity": self.severity,
                "requirements": self.requirements, "message": self.message,
                "subsets": self.subsets, "standing": self.standing, "cut": self.cut, "witness": self.witness,
                "expected": self.expected, "details": self.details}


def ids(items: Iterable[CheckItem]) -> list[str]:
    """The requirement ids of check items, in order."""
    return [x.id for x in items]


def subsets_text(names: list[list[str]], standing: list[str], noun: str) -> str:
    """The subsets of a finding in words: ``{A, B}`` with what is shown of each
    (``smallest NOUN``, ``minimal NOUN``, ``a NOUN (not shown minimal)``), ``;`` between."""
    out = []
    for s, st in zip(names, standing):
        text = "{" + ", ".join(s) + "}"
        if st == "not shown minimal":
            out.append(f"a {noun} (not shown minimal) {text}")
        else:
            out.append(f"{st} {noun} {text}")
    return "; ".join(out)


@dataclass
class CheckResult:
    """Everything ``fretc check`` found. ``requirements`` has one JSON-able status dict per
    requirement (``satisfiable``, ``non_vacuous``, ``redundant``: true / false / "unknown"
    / None when not checked); ``groups`` the ids per group; ``abstractions`` the
    uninterpreted atoms; ``queries`` the solver queries, ``smt_queries`` those z3 answered,
    ``monitor_queries`` those the pt monitors' fixed points answered
    (:mod:`fretc.check.smt`), ``unknown_queries`` those past their budget or refused."""

    requirements: list[dict] = field(default_factory=list)
    groups: list[list[str]] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    abstractions: list[dict] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    realizability: dict | None = None
    witnesses: list[dict] = field(default_factory=list)
    input_errors: list[str] = field(default_factory=list)
    queries: int = 0
    unknown_queries: int = 0
    smt_queries: int = 0
    monitor_queries: int = 0
    #: why the set was not checked at all ("" when it was: a FRET component whose
    #: requirements have no tick period for their durations)
    not_checked: str = ""

    @property
    def exit_code(self) -> int:
        """0 no finding, 1 a conflict / vacuity / unrealizability (or an unknown answer:
        nothing is called fine that was not checked), 2 input errors (a requirement that did
        not formalize, a variable of a realizability check declared neither input nor
        output: a finding of severity ``input``)."""
        if self.input_errors or any(f.severity == "input" for f in self.findings):
            return 2
        if self.not_checked or any(f.severity in ("error", "unknown") for f in self.findings):
            return 1
        return 0

    def to_json(self) -> dict:
        """The document of ``fretc check --json`` / ``-o``: tool, semantics, exit code, one status
        per requirement, groups, findings, abstractions, notes, realizability,
        witnesses, input errors and the query counts."""
        return {"tool": "fretc check", "semantics": "ft_inf (infinite traces); witnesses "
                "on finite traces (ft)", "exit_code": self.exit_code,
                "requirements": self.requirements, "groups": self.groups,
                "findings": [f.to_json() for f in self.findings],
                "abstractions": self.abstractions, "realizability": self.realizability,
                "witnesses": self.witnesses,
                "notes": self.notes, "input_errors": self.input_errors,
                "queries": self.queries, "smt_queries": self.smt_queries,
                "monitor_queries": self.monitor_queries,
                "unknown_queries": self.unknown_queries}
