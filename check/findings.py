"""A finding of ``fretc check`` (:mod:`fretc.check.analysis`, :mod:`fretc.check.realizability`,
:mod:`fretc.check.witness`): what was found, about which requirements, and the witness
trace that shows it."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fretc.check.items import CheckItem

__all__ = ["Finding", "ids", "subsets_text"]


@dataclass
class Finding:
    """One result worth a user's attention.

    ``kind``: ``unsatisfiable`` (one requirement), ``conflict`` (a set), ``vacuous``,
    ``redundant``, ``unrealizable``, ``unknown``. ``severity``: ``error`` (exit 1),
    ``warning`` or ``unknown``. ``requirements``: the ids it is about; ``subsets``: the
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
