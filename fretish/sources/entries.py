"""One requirement of a requirements tool (ReqIF, Doorstop) as a :class:`RequirementEntry`:
parsed when it has text, kept aside as not formalized when it has none."""

from __future__ import annotations

from fretc.fretish.entry import Origin, RequirementEntry


def keep_entry(rid: str, text: str, path: str, source: str, line: int, origin: Origin,
               entries: list[RequirementEntry], unformalized: list[RequirementEntry]) -> None:
    """One tool requirement as an entry at ``path`` (its ``source`` names syntax errors,
    line ``line``, column 1): in ``unformalized`` when its text is empty, else parsed into
    ``entries`` (a syntax error kept on the entry, never raised)."""
    from fretc.common.errors import FretishSyntaxError
    from fretc.fretish.parser import parse

    entry = RequirementEntry(rid, text, path, line, 1, rationale=origin.rationale,
                             parent=origin.parents[0] if origin.parents else None,
                             origin=origin)
    if not text:
        unformalized.append(entry)
        return
    try:
        entry.requirement = parse(text, source=source, line=line, column=1)
    except FretishSyntaxError as e:
        entry.error = e
    entries.append(entry)
