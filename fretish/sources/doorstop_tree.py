"""Doorstop trees (folders of documents, each a ``.doorstop.yml`` and one YAML file per item)
as requirement entries, read with the ``doorstop`` library (``doorstop.build``).

One entry per active, normative item, documents in the tree's order (parents first), items
by level:

* id: the item's UID (``R1``, ``SRD-004``);
* text: the custom attribute named ``text_attribute`` (compared without case); by default
  ``FRETish``, or the item's ``text`` when no item of the tree has a ``FRETish`` attribute
  (Doorstop docs, "Item" reference: custom attributes are any other key of the item file);
* origin: the UID, ``header`` (its long name), ``level``, the item's fingerprint
  (``Item.stamp()``, the value Doorstop stores in ``reviewed``) as its version, its
  ``links`` as parents, a ``rationale`` attribute, the document prefix.

A link to a UID that is in no document, or links that go round in a cycle, are errors naming
the item file: the traceability they break is what the audit reports on.
"""

from __future__ import annotations

import logging
import os

from fretc.common.errors import FretishFileError, FretishSyntaxError

from fretc.fretish.entry import DEFAULT_TEXT_ATTRIBUTE, Origin, RequirementEntry

__all__ = ["load_doorstop", "build_tree", "custom_attributes"]


def build_tree(path: str):
    """The ``doorstop`` tree of the documents under ``path``. Raises
    :class:`FretishFileError` naming ``path`` when Doorstop cannot build it (a document whose
    parent document is missing, two roots, a bad ``.doorstop.yml`` or item file)."""
    import doorstop  # lazy: only for Doorstop trees
    from doorstop.common import DoorstopError

    quiet = logging.getLogger("doorstop")
    level = quiet.level
    quiet.setLevel(logging.ERROR)
    try:
        return doorstop.build(cwd=path, root=path)
    except DoorstopError as e:
        raise FretishFileError(f"not a Doorstop tree doorstop can build: {e}",
                               source=path) from None
    except (OSError, ValueError, TypeError, AttributeError) as e:
        raise FretishFileError(f"Doorstop tree cannot be read: {type(e).__name__}: {e}",
                               source=path) from None
    finally:
        quiet.setLevel(level)


def custom_attributes(item) -> dict[str, object]:
    """The item's attributes outside Doorstop's own (its custom attributes), by name."""
    data = getattr(item, "_data", {}) or {}
    own = {"active", "derived", "header", "level", "links", "normative", "ref", "references",
           "reviewed", "text"}
    return {k: v for k, v in data.items() if k not in own}


def _line_of(path: str, key: str) -> int:
    """The line of ``key:`` (or ``- key``) in the item file (1 when not found)."""
    try:
        with open(path, encoding="utf-8") as f:
            for n, line in enumerate(f, 1):
                s = line.strip()
                if s.startswith((f"{key}:", f"- {key}:", f"- {key}")):
                    return n
    except OSError:
        pass
    return 1


def _items(tree) -> list:
    """Active, normative items: documents in tree order, items by level."""
    out = []
    for doc in tree:
        out.extend(i for i in doc.items if i.active and i.normative)
    return out


def _check_links(items: list, all_uids: set[str]) -> None:
    """Raise :class:`FretishFileError` at the first link to a UID in no document, and at a
    cycle of links (found by depth-first search, in item order)."""
    links = {str(i.uid): [str(u) for u in i.links] for i in items}
    files = {str(i.uid): i.path for i in items}
    for uid, targets in links.items():
        for t in targets:
            if t not in all_uids:
                raise FretishFileError(f"item {uid} links to {t}, which is in no document "
                                       "of the tree (a missing parent)", source=files[uid],
                                       line=_line_of(files[uid], t))
    state: dict[str, int] = {}
    for start in links:
        stack = [(start, iter(links[start]))]
        path = [start]
        state[start] = state.get(start, 0) or 1
        while stack:
            node, it = stack[-1]
            nxt = next(it, None)
            if nxt is None:
                state[node] = 2
                stack.pop()
                path.pop()
                continue
            if state.get(nxt) == 1:
                cycle = path[path.index(nxt):] + [nxt]
                raise FretishFileError("links go round in a cycle: " + " -> ".join(cycle),
                                       source=files[node], line=_line_of(files[node], nxt))
            if state.get(nxt) != 2 and nxt in links:
                state[nxt] = 1
                stack.append((nxt, iter(links[nxt])))
                path.append(nxt)


def load_doorstop(path: str, text_attribute: str | None = None):
    """(entries, not formalized) of the Doorstop tree under ``path`` (module docstring; both
    lists of :class:`fretc.fretish.files.RequirementEntry`, ``source`` the tree ``path``, the item
    file in ``origin.file``; ``line`` the line of the text attribute in it). Raises
    :class:`FretishFileError`: a tree Doorstop cannot build, a missing parent, a cycle."""
    from fretc.fretish.parser import parse

    tree = build_tree(path)
    items = _items(tree)
    all_uids = {str(i.uid) for doc in tree for i in doc.items}
    _check_links(items, all_uids)
    wanted = text_attribute or _default_attribute(items)
    entries, unformalized = [], []
    for item in items:
        custom = {k.lower(): (k, v) for k, v in custom_attributes(item).items()}
        if wanted == "text":
            key, value = "text", item.text
        else:
            key, value = custom.get(wanted.lower(), (wanted, None))
        text = value.strip() if isinstance(value, str) else ""
        rationale = custom.get("rationale", (None, None))[1]
        rationale = rationale.strip() if isinstance(rationale, str) and rationale else None
        source = os.path.relpath(item.path) if not os.path.isabs(path) else item.path
        origin = Origin("doorstop", source, str(item.uid),
                        long_name=item.header or None, version=str(item.stamp()),
                        parents=tuple(sorted(str(u) for u in item.links)),
                        rationale=rationale, container=str(item.document.prefix),
                        level=str(item.level), text_attribute=key, text=text)
        line = _line_of(item.path, key)
        # the entry's source is the tree (what the audit is given again to rebuild it; the
        # item file is the origin's), its syntax errors name the item file
        entry = RequirementEntry(str(item.uid), text, path, line, 1, rationale=rationale,
                                 parent=origin.parents[0] if origin.parents else None,
                                 origin=origin)
        if not text:
            unformalized.append(entry)
            continue
        try:
            entry.requirement = parse(text, source=source, line=line, column=1)
        except FretishSyntaxError as e:
            entry.error = e
        entries.append(entry)
    return entries, unformalized


def _default_attribute(items: list) -> str:
    """``FRETish`` when an item has that custom attribute (any case), else ``text``."""
    for item in items:
        if any(k.lower() == DEFAULT_TEXT_ATTRIBUTE.lower() for k in custom_attributes(item)):
            return DEFAULT_TEXT_ATTRIBUTE
    return "text"
