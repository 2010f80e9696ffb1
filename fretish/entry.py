"""A requirement as read from a file or a requirements tool (:class:`RequirementEntry`), and
where a requirement kept in a tool came from (:class:`Origin`): the data
:mod:`fretc.fretish.files` and :mod:`fretc.fretish.sources` give the compiler."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from fretc.common.errors import FretishError

from fretc.fretish.ast import Requirement

__all__ = ["RequirementEntry", "Origin", "DEFAULT_TEXT_ATTRIBUTE"]

#: The attribute name looked for first (compared without case).
DEFAULT_TEXT_ATTRIBUTE = "FRETish"


@dataclass(frozen=True)
class Origin:
    """Where a requirement came from, in its tool's own terms.

    Attributes:
        format: ``"reqif"``, ``"doorstop"`` or ``"fret"``.
        file: the file read (for Doorstop, the item's ``.yml`` file).
        tool_id: the tool's identifier: the ReqIF SPEC-OBJECT ``IDENTIFIER`` (ReqIF 1.2,
            section 10.8.20, Identifiable), the Doorstop UID, FRET's ``reqid``.
        long_name: ReqIF ``LONG-NAME`` (else its ``ReqIF.Name`` attribute); Doorstop
            ``header``; None in FRET.
        version: the last change the format records: ReqIF ``LAST-CHANGE``, Doorstop's
            fingerprint of the item (``Item.stamp()``, what ``reviewed`` is compared with),
            FRET's ``_rev`` when the export has one; else None.
        parents: the tool ids (fretc ids where known) of the requirements it refines:
            ReqIF SPEC-RELATIONs with it as SOURCE, Doorstop ``links``, FRET
            ``parent_reqid``; sorted.
        rationale: the rationale as the tool holds it, or None.
        container: the ReqIF SPECIFICATION's LONG-NAME, the Doorstop document prefix, the
            FRET project.
        level: Doorstop's ``level`` (``"1.2"``); None elsewhere.
        text_attribute: the attribute the FRETish text was read from.
        text: the FRETish text as read (the audit compares it to spot stale evidence).
    """

    format: str
    file: str
    tool_id: str
    long_name: str | None = None
    version: str | None = None
    parents: tuple[str, ...] = ()
    rationale: str | None = None
    container: str | None = None
    level: str | None = None
    text_attribute: str | None = None
    text: str | None = None
    extra: dict = field(default_factory=dict, compare=False)

    def to_json(self) -> dict:
        """The origin as the audit JSON's ``requirements[].origin`` gives it (keys sorted by
        the writer; ``parents`` a list)."""
        return {"format": self.format, "file": self.file, "tool_id": self.tool_id,
                "long_name": self.long_name, "version": self.version,
                "parents": list(self.parents), "rationale": self.rationale,
                "container": self.container, "level": self.level,
                "text_attribute": self.text_attribute, "text": self.text}


@dataclass
class RequirementEntry:
    """One requirement read from a file.

    ``text`` is the sentence exactly as parsed; ``source``/``line``/``column`` give where
    it starts (1-based). ``tick_period`` is in seconds (None: not declared). Exactly one
    of ``requirement`` (the parsed AST) and ``error`` (why it does not parse) is set.
    ``extra`` holds the other members of a FRET JSON object. ``inputs``/``outputs`` are
    the file's ``@inputs``/``@outputs`` variable names (for ``fretc check``'s
    realizability), the same for every requirement of the file (of a FRET export: the Input and Output
    variables FRET declares for the requirement's component, ``variables``). ``origin`` says where
    a requirement kept in a tool came from (:class:`fretc.fretish.sources.Origin`: ReqIF, Doorstop,
    FRET export; None for ``.fret`` files).
    """

    id: str
    text: str
    source: str
    line: int
    column: int
    rationale: str | None = None
    parent: str | None = None
    tick_period: Fraction | None = None
    requirement: Requirement | None = None
    error: FretishError | None = None
    extra: dict = field(default_factory=dict)
    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    origin: Origin | None = None
    #: a FRET export's variables of the requirement's component
    #: (:class:`fretc.fretish.fret_variables.FretVariable`; ``inputs``/``outputs`` are its
    #: Input and Output ones); empty for other files
    variables: tuple = ()
    #: the stream variables of its FRET export it reads, computed tick by tick from the
    #: variables they read (:class:`fretc.fretish.fret_streams.StreamSystem`; set by
    #: :func:`fretc.fretish.fret_variables.with_fret_definitions` with ``streams``), or None
    streams: Any = None
