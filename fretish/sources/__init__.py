"""Requirements kept in engineers' tools: ReqIF files (``.reqif``, ``.reqifz``) and Doorstop
trees, read into :class:`fretc.fretish.files.RequirementEntry` objects that remember where each
requirement came from (:class:`Origin`).

May import: ``fretc.common`` and the FRETish layer's entries and parser
(:mod:`fretc.fretish.entry`, :mod:`fretc.fretish.parser`); :mod:`fretc.fretish.files` calls
it, never the other way.

Design notes: ARCHITECTURE.md, `fretish/sources/__init__.py`."""

from __future__ import annotations

import os

from fretc.fretish.entry import DEFAULT_TEXT_ATTRIBUTE, Origin, RequirementEntry

__all__ = ["Origin", "tool_source_kind", "load_tool_source", "fret_origin",
           "DEFAULT_TEXT_ATTRIBUTE", "REQIF_SUFFIXES"]

REQIF_SUFFIXES = (".reqif", ".reqifz")


def tool_source_kind(path: str) -> str | None:
    """``"reqif"`` for a ``.reqif``/``.reqifz`` file, ``"doorstop"`` for a folder that is a
    Doorstop document or holds one (a ``.doorstop.yml`` in it or in a sub-folder, at most
    four levels down, hidden folders skipped), None for anything else."""
    if os.path.isfile(path):
        return "reqif" if path.lower().endswith(REQIF_SUFFIXES) else None
    if not os.path.isdir(path):
        return None
    for depth, (_folder, _dirs, files) in enumerate(_walk(path)):
        if ".doorstop.yml" in files:
            return "doorstop"
        if depth > 200:  # a very wide tree is not worth searching for one
            break
    return None


def _walk(path: str):
    """``os.walk`` down to four levels below ``path``, sorted, hidden folders skipped."""
    base = path.rstrip(os.sep).count(os.sep)
    for folder, dirs, files in os.walk(path):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        if folder.count(os.sep) - base >= 4:
            dirs[:] = []
        yield folder, dirs, files


def load_tool_source(path: str, kind: str, text_attribute: str | None = None
                     ) -> tuple[list[RequirementEntry], list[RequirementEntry]]:
    """(entries, not formalized) of the ReqIF file or Doorstop tree at ``path`` (``kind`` from
    :func:`tool_source_kind`): two lists of :class:`fretc.fretish.files.RequirementEntry`, the
    second of the items without FRETish text (their ``text`` empty, ``requirement`` and
    ``error`` None). Raises :class:`fretc.common.errors.FretishFileError` naming the file and
    element of a structural problem (bad or hostile XML, a missing datatype, a Doorstop
    link to nothing, a cycle, a duplicate id)."""
    if kind == "reqif":
        from fretc.fretish.sources.reqif_file import load_reqif  # lazy: lxml and reqif only for ReqIF
        return load_reqif(path, text_attribute)
    from fretc.fretish.sources.doorstop_tree import load_doorstop  # lazy: doorstop only for its trees
    return load_doorstop(path, text_attribute)


def fret_origin(source: str, obj: dict) -> Origin:
    """The origin of one requirement object of a FRET export (FRET's fields ``reqid``,
    ``project``, ``parent_reqid``, ``rationale``, ``_rev``)."""
    parent = obj.get("parent_reqid")
    rev = obj.get("_rev")
    return Origin("fret", source, str(obj.get("reqid")),
                  version=rev if isinstance(rev, str) and rev else None,
                  parents=(parent,) if isinstance(parent, str) and parent else (),
                  rationale=obj.get("rationale") if isinstance(obj.get("rationale"), str)
                  else None,
                  container=obj.get("project") if isinstance(obj.get("project"), str)
                  else None,
                  text_attribute="fulltext", text=obj.get("fulltext"))
