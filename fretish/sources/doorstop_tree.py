"""Doorstop trees (folders of documents, each a ``.doorstop.yml`` and one YAML file per item)
as requirement entries, read with the ``doorstop`` library (``doorstop.build``).

One entry per active, normative item, documents in the tree's order (parents first), items
by level:

Design notes: ARCHITECTURE.md, `fretish/sources/doorstop_tree.py`."""

from __future__ import annotations

import logging
import os
import stat
from typing import Any  # doorstop's objects: the library has no types

from fretc.common.errors import FretishFileError

from fretc.fretish.entry import DEFAULT_TEXT_ATTRIBUTE, Origin, RequirementEntry
from fretc.fretish.sources.entries import keep_entry

__all__ = ["load_doorstop", "build_tree", "custom_attributes", "check_tree_files",
           "MAX_YAML_BYTES", "MAX_YAML_NODES"]


def build_tree(path: str) -> Any:
    """The ``doorstop`` tree of the documents under ``path``. Raises
    :class:`FretishFileError` naming ``path`` when Doorstop cannot build it (a document whose
    parent document is missing, two roots, a bad ``.doorstop.yml`` or item file)."""
    import doorstop  # lazy: only for Doorstop trees
    from doorstop.common import DoorstopError

    check_tree_files(path)
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


#: the largest item or document file read (bytes), and the most YAML nodes it may expand to
#: with its aliases resolved: an alias of an alias of ... (a "billion laughs" YAML bomb) is
#: small on disk and exponential once a consumer walks it (doorstop's fingerprint of the
#: ``reviewed`` attributes hung on one)
MAX_YAML_BYTES = 1024 * 1024
MAX_YAML_NODES = 100_000


def check_tree_files(path: str) -> None:
    """Refuse, before doorstop reads anything, the YAML files of the tree under ``path``
    that are not regular files (a FIFO would block the read), lead outside the tree
    (a symbolic link), are larger than :data:`MAX_YAML_BYTES`, nest too deeply for a YAML
    reader, or expand to more than :data:`MAX_YAML_NODES` nodes with their aliases resolved
    (counted on PyYAML's node graph, which shares an alias's node and constructs no
    object: linear in the file); and the files they ``!include`` (doorstop reads the tag in
    a document's ``.doorstop.yml``, relative to it) by the same rules, so an include stays
    inside the tree and reads regular files only. Raises :class:`FretishFileError` naming
    the file."""
    top = os.path.realpath(path)
    for folder, dirs, files in os.walk(path):
        dirs[:] = [d for d in dirs if not d.startswith(".")]
        for name in files:
            if name.endswith((".yml", ".yaml")):
                _check_yaml_file(os.path.join(folder, name), top, path, set())


def _check_yaml_file(f: str, top: str, tree: str, seen: set[str],
                     included_by: str | None = None, chain: tuple[str, ...] = ()) -> None:
    """One YAML file of the tree (:func:`check_tree_files`), then the files it includes
    (``chain``: the real paths of the files including it, a cycle among which is refused:
    doorstop would include them forever)."""
    import yaml

    real = os.path.realpath(f)
    by = f" (included by {included_by})" if included_by else ""
    where = included_by or f
    if os.path.commonpath([top, real]) != top:
        raise FretishFileError(f"{f}{by} leads to {real}, outside the tree {tree}: not read",
                               source=where, line=1)
    if real in chain:
        raise FretishFileError(f"{f}{by} includes itself (an !include cycle): not read",
                               source=where, line=1)
    if real in seen:  # included twice: checked once
        return
    seen.add(real)
    try:
        st = os.stat(real)
    except OSError as e:
        raise FretishFileError(f"{f}{by} cannot be read: {e.strerror or e}", source=where,
                               line=1) from None
    if not stat.S_ISREG(st.st_mode):
        raise FretishFileError(f"{f}{by} is not a regular file: not read", source=where, line=1)
    if st.st_size > MAX_YAML_BYTES:
        raise FretishFileError(f"{f}{by} is {st.st_size} bytes, more than the "
                               f"{MAX_YAML_BYTES} an item file may be", source=where, line=1)
    with open(real, "rb") as fh:
        data = fh.read()
    try:
        root = yaml.compose(data, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return  # doorstop reports the invalid YAML, naming the file
    except RecursionError:
        raise FretishFileError(f"{f}{by} nests its YAML too deeply to be read", source=where,
                               line=1) from None
    nodes = _expanded_nodes(root)
    if nodes > MAX_YAML_NODES:
        raise FretishFileError(f"{f}{by} expands to {nodes} YAML nodes with its aliases "
                               f"resolved, more than {MAX_YAML_NODES} (a YAML bomb?): "
                               "not read", source=where, line=1)
    for target in _includes(root):
        _check_yaml_file(os.path.join(os.path.dirname(f), target), top, tree, seen, f,
                         chain + (real,))


def _includes(root) -> list[str]:
    """The values of the ``!include`` scalars of a composed YAML document."""
    import yaml

    out, stack, seen = [], [root] if root is not None else [], set()
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, yaml.ScalarNode):
            if node.tag == "!include":
                out.append(str(node.value))
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            stack.extend(c for pair in node.value for c in pair)
    return out


def _expanded_nodes(root) -> int:
    """The nodes of a composed YAML document with every alias expanded, computed once per
    shared node (so a bomb's count costs its size on disk, not its expansion)."""
    if root is None:
        return 0
    sizes: dict[int, int] = {}
    stack = [(root, False)]
    while stack:
        node, done = stack.pop()
        if id(node) in sizes:
            continue
        kids = ([c for pair in node.value for c in pair] if isinstance(node.value, list)
                and node.value and isinstance(node.value[0], tuple)
                else node.value if isinstance(node.value, list) else [])
        if done:
            sizes[id(node)] = 1 + sum(sizes.get(id(k), 1) for k in kids)
            continue
        stack.append((node, True))
        stack.extend((k, False) for k in kids if id(k) not in sizes)
    return sizes[id(root)]


def custom_attributes(item: Any) -> dict[str, object]:
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


#: what reading an item can raise besides Doorstop's own error: attributes of the wrong
#: type (``level: {a: 1}``, ``links: 5``, ``text: [1, 2]``) fail inside doorstop
_ITEM_ERRORS = (ValueError, TypeError, AttributeError, KeyError, OSError, RecursionError)


def _item_error(item_path: str, exc: BaseException) -> FretishFileError:
    """An error reading one item file, naming it (its first line: doorstop does not say
    where in the file)."""
    import re

    text = " ".join(str(exc).split()) or type(exc).__name__
    named = re.search(r"(\S+\.ya?ml)\b", text)  # doorstop's messages name the file
    where = named.group(1).strip("'\"") if named else item_path
    return FretishFileError(f"Doorstop item cannot be read: {text[:300]}", source=where,
                            line=1)


def _culprit(doc, root: str) -> str | None:
    """The first item file of ``doc`` (in name order) that doorstop cannot load on its own
    with its level and links read (what listing a document's items reads), or None."""
    from doorstop.core.item import Item

    folder = str(doc.path)
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".yml") or name.startswith("."):
            continue
        path = os.path.join(folder, name)
        try:
            item = Item(doc, path, root=root)
            item.load()
            str(item.level), [str(u) for u in item.links], item.text
        except Exception:  # noqa: BLE001 - any failure names this file
            return path
    return None


def _one_per_folder(tree) -> set[int]:
    """The ids of the documents of ``tree`` to read: one per real folder. A document whose
    folder is also reached through a symbolic link inside the tree (``tree/r_link -> r``)
    is one document, read once, by its own path (the link's when every path to it is one)."""
    def linked(doc) -> bool:
        return os.path.realpath(doc.path) != os.path.abspath(doc.path)

    chosen: dict[str, Any] = {}
    for doc in tree:
        real = os.path.realpath(doc.path)
        other = chosen.get(real)
        if other is None or (linked(other) and not linked(doc)):
            chosen[real] = doc
    return {id(doc) for doc in chosen.values()}


def _items(tree, root: str) -> list:
    """Active, normative items: documents in tree order (each folder once:
    :func:`_one_per_folder`), items by level. Raises
    :class:`FretishFileError` naming the item file for one doorstop cannot read (invalid
    YAML, a YAML tag such as ``!!python/object`` or ``!include``, not UTF-8, an attribute of
    the wrong type) and for an item file that is a link to outside the tree (``root``)."""
    from doorstop.common import DoorstopError

    top = os.path.realpath(root)
    out = []
    kept = _one_per_folder(tree)
    for doc in tree:
        if id(doc) not in kept:  # (a document reached again through a link to its folder)
            continue
        try:
            listed = list(doc.items)
        except (DoorstopError, *_ITEM_ERRORS) as e:
            raise _item_error(_culprit(doc, root) or str(doc.path), e) from None
        for i in listed:
            real = os.path.realpath(i.path)
            if os.path.commonpath([top, real]) != top:
                raise FretishFileError(f"item {i.path} is a link to {real}, outside the tree "
                                       f"{root}: not read", source=str(i.path), line=1)
            try:
                keep = bool(i.active and i.normative)
                if keep:  # every attribute the entry reads, read here where it is named
                    str(i.uid), i.text, i.header, str(i.level), [str(u) for u in i.links]
                    i.stamp()
            except (DoorstopError, *_ITEM_ERRORS) as e:
                raise _item_error(str(i.path), e) from None
            if keep:
                out.append(i)
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


def load_doorstop(path: str, text_attribute: str | None = None
                  ) -> tuple[list[RequirementEntry], list[RequirementEntry]]:
    """(entries, not formalized) of the Doorstop tree under ``path`` (module docstring; both
    lists of :class:`fretc.fretish.files.RequirementEntry`, ``source`` the tree ``path``, the item
    file in ``origin.file``; ``line`` the line of the text attribute in it). Raises
    :class:`FretishFileError`: a tree Doorstop cannot build, an item it cannot read or one
    outside the tree (:func:`_items`), a missing parent, a cycle, a text attribute that is
    not text."""
    tree = build_tree(path)
    items = _items(tree, path)
    all_uids = {str(i.uid) for doc in tree for i in doc.items}
    _check_links(items, all_uids)
    wanted = text_attribute or _default_attribute(items)
    entries: list[RequirementEntry] = []
    unformalized: list[RequirementEntry] = []
    for item in items:
        custom = {k.lower(): (k, v) for k, v in custom_attributes(item).items()}
        if wanted == "text":
            key, value = "text", item.text
        else:
            key, value = custom.get(wanted.lower(), (wanted, None))
        if value is not None and not isinstance(value, str):
            raise FretishFileError(f"item {item.uid}: its {key} attribute is a "
                                   f"{type(value).__name__}, not text", source=item.path,
                                   line=_line_of(item.path, key))
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
        keep_entry(str(item.uid), text, path, source, line, origin, entries, unformalized)
    return entries, unformalized


def _default_attribute(items: list) -> str:
    """``FRETish`` when an item has that custom attribute (any case), else ``text``."""
    for item in items:
        if any(k.lower() == DEFAULT_TEXT_ATTRIBUTE.lower() for k in custom_attributes(item)):
            return DEFAULT_TEXT_ATTRIBUTE
    return "text"
