"""``fretc export`` into a Doorstop tree: a copy of the tree in which each item the audit
judged (or listed as not formalized) carries fretc's results as custom attributes.

Doorstop keeps any key of an item file it does not know as a custom attribute (Doorstop docs,
"Item" reference, extended attributes) and leaves it out of the item's fingerprint unless the
document lists it under ``attributes: reviewed``; so the items' ``reviewed`` stamps stay
valid and the tree passes ``doorstop``'s validation as before. The keys (:data:`KEYS`):
``fretc_verdict``, ``fretc_evidence``, ``fretc_formula_ft``, ``fretc_formula_pt``,
``fretc_rollup`` and ``fretc_rollup_path`` (parent items only: the verdict rolled up over the
items that link to them, :mod:`fretc.reports.rollup`), ``fretc_audit_id``,
``fretc_audit_date``.

Design notes: ARCHITECTURE.md, `reports/export_doorstop.py`."""

from __future__ import annotations

import os
import shutil

from fretc.common.outputs import write_file
from fretc.reports.export_results import RequirementResult, replace_tree

__all__ = ["export_doorstop", "item_block", "MARKER", "KEYS"]

MARKER = "# fretc export: the results of an audit (replaced by the next fretc export)\n"
#: (item file key, field of :class:`RequirementResult`)
KEYS = (("fretc_verdict", "verdict"), ("fretc_evidence", "evidence"),
        ("fretc_formula_ft", "ft"), ("fretc_formula_pt", "pt"),
        ("fretc_rollup", "rollup"), ("fretc_rollup_path", "rollup_path"),
        ("fretc_audit_id", "audit_id"), ("fretc_audit_date", "audit_date"))


def item_block(result: RequirementResult) -> str:
    """The YAML lines fretc appends to an item file (after :data:`MARKER`): each key of
    :data:`KEYS` with a value, as a YAML string on one line (PyYAML's safe dumper, so
    ``doorstop`` reads it back exactly)."""
    import yaml  # lazy: PyYAML, doorstop's own dependency

    data = {key: str(getattr(result, field)) for key, field in KEYS
            if getattr(result, field) is not None}
    return MARKER + yaml.safe_dump(data, default_flow_style=False, sort_keys=False,
                                   allow_unicode=True, width=1 << 30)


_OURS = frozenset(key for key, _field in KEYS)


def _load(raw: bytes):
    """The item file's mapping (PyYAML's safe loader, as doorstop reads it), or None when
    it is not one."""
    import yaml

    try:
        data = yaml.safe_load(raw.decode("utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, RecursionError):
        return None
    return data if isinstance(data, dict) else None


def _without_ours(raw: bytes, want: dict) -> bytes:
    """``raw`` without an earlier export's block: cut at :data:`MARKER` when the marker is a
    line of its own and what follows it holds only fretc's keys (:data:`KEYS`), and
    without top-level keys of :data:`KEYS` (with their indented continuation lines) that
    Doorstop moved when it saved the item (it sorts an item's keys). A user's own
    ``fretc_*`` key, or the marker's text inside a value, stay (each cut is checked on the
    parsed file: only fretc's keys may go). ``want``: the item's own keys, parsed."""
    marker = MARKER.encode()
    at = raw.find(marker)
    while at >= 0:  # the marker as a line of its own, with only fretc's keys after it
        if (at == 0 or raw[at - 1:at] == b"\n") and _load(raw[:at]) == want:
            raw = raw[:at]
            break
        at = raw.find(marker, at + 1)
    out, skipping = [], False
    for line in raw.splitlines(keepends=True):
        key = line.split(b":", 1)[0].decode("utf-8", "replace")
        if key in _OURS and b":" in line:
            skipping = True
            continue
        if skipping and line[:1] in (b" ", b"\t"):
            continue
        skipping = False
        out.append(line)
    cut = b"".join(out)
    return cut if _load(cut) == want else raw


def _with_block(raw: bytes, result: RequirementResult) -> bytes:
    """The item file ``raw`` with fretc's block (an earlier one replaced). The original
    bytes are kept and the block appended when the result reads back as the item's own
    keys and fretc's (checked with PyYAML's safe loader, doorstop's); otherwise (a flow
    mapping, a ``...`` document end, a layout appending cannot extend) the item is
    written again as YAML with its keys in their order and fretc's after them."""
    import yaml

    mine = _load(raw)
    block = item_block(result)
    ours = yaml.safe_load(block) or {}
    if mine is None:  # not a mapping doorstop reads: left as it is
        return raw
    own = {k: v for k, v in mine.items() if k not in _OURS}
    want = {**own, **ours}
    base = _without_ours(raw, own)
    if base and not base.endswith(b"\n"):
        base += b"\n"
    candidate = base + block.encode("utf-8")
    if _load(candidate) == want:
        return candidate
    return (yaml.safe_dump(own, default_flow_style=False, sort_keys=False,
                           allow_unicode=True, width=1 << 30) + block).encode("utf-8")


def export_doorstop(src: str, out: str, results: dict[str, RequirementResult],
                    item_files: dict[str, str]) -> int:
    """Write the Doorstop tree under ``src`` to the new folder ``out`` with the results added
    to the items (``item_files``: UID -> the item's file, inside ``src``); returns how many
    items got them. Atomic: ``out`` appears complete or not at all
    (:func:`~fretc.reports.export_results.replace_tree`); raises :class:`FileExistsError` for a
    non-empty ``out`` and :class:`ValueError` for an item file outside ``src``."""
    root = os.path.realpath(src)
    targets: dict[str, RequirementResult] = {}
    for uid, path in item_files.items():
        result = results.get(uid)
        if result is None:
            continue
        rel = os.path.relpath(os.path.realpath(path), root)
        if rel.startswith(".."):
            raise ValueError(f"{path}: item {uid} lies outside the tree {src}")
        targets[rel] = result

    def build(tmp: str) -> None:
        os.rmdir(tmp)
        shutil.copytree(root, tmp, symlinks=True)
        for rel, result in sorted(targets.items()):
            path = os.path.join(tmp, rel)
            with open(path, "rb") as f:
                raw = f.read()
            write_file(path, _with_block(raw, result))  # (replaces the copy, never a link)

    replace_tree(build, out)
    return len(targets)
