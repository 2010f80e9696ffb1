"""A finding of ``fretc check`` (:mod:`check.analysis`, :mod:`check.realizability`,
:mod:`check.witness`): what was found, about which requirements, and the witness
trace that shows it."""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Finding", "ids"]


@dataclass
class Finding:
    """One result worth a user's attention.

    ``kind``: ``unsatisfiable`` (one requirement), ``conflict`` (a set), ``vacuous``,
    ``redundant``, ``unrealizable``, ``unknown``. ``severity``: ``error`` (exit 1),
    ``warning`` or ``unknown``. ``requirements``: the ids it is about; ``subsets``: minimal
    subsets (lists of ids, smallest first); ``cut``: the subset enumeration ran out of
    budget; ``witness``: path of the witness CSV, ``expected`` the verdicts it promises.
    """

    kind: str
    severity: str
    requirements: list[str]
    message: str
    subsets: list[list[str]] = field(default_factory=list)
    cut: bool = False
    witness: str | None = None
    expected: dict[str, str] = field(default_factory=dict)
    details: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """The finding as a JSON object (every attribute, plain values)."""
        return {"kind": self.kind, "severity": self.severity,
                "requirements": self.requirements, "message": self.message,
                "subsets": self.subsets, "cut": self.cut, "witness": self.witness,
                "expected": self.expected, "details": self.details}


def ids(items) -> list[str]:
    """The requirement ids of check items, in order."""
    return [x.id for x in items]
