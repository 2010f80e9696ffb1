"""ReqIF files (OMG ReqIF 1.2, ``.reqif``; ``.reqifz`` archives of them) as requirement
entries, parsed by the ``reqif`` library (the one StrictDoc uses) once :mod:`.safe_xml`
passed the bytes.

Design notes: ARCHITECTURE.md, `fretish/sources/reqif_file.py`."""

from __future__ import annotations

import os
import re
from typing import Any  # the reqif library's objects: it has no types

from fretc.common.errors import FretishFileError

from fretc.fretish.entry import DEFAULT_TEXT_ATTRIBUTE, Origin, RequirementEntry
from fretc.fretish.sources.entries import keep_entry
from fretc.fretish.sources.safe_xml import MAX_BYTES, checked_text, read_reqif_members

__all__ = ["load_reqif", "parse_reqif_bundles", "attribute_names", "ID_ATTRIBUTES"]

#: Attributes holding the id people use, looked for in this order (names without case).
ID_ATTRIBUTES = ("reqif.foreignid", "uid", "id")
#: The requirement text of a ReqIF file (the ReqIF Implementation Guide's standard name).
REQIF_TEXT = "ReqIF.Text"


def parse_reqif_bundles(path: str) -> list[tuple[str, Any]]:
    """``[(source, ReqIFBundle)]`` of the file at ``path``: one for a ``.reqif``, one per
    ``.reqif`` member of a ``.reqifz`` (source ``archive!member``). Raises
    :class:`FretishFileError` for unreadable, hostile (:func:`.safe_xml.checked_text`) or
    malformed ReqIF, naming the file (and the element the library stopped at)."""
    if path.lower().endswith(".reqifz"):
        members = [(f"{path}!{name}", raw) for name, raw in read_reqif_members(path)]
    else:
        try:
            size = os.path.getsize(path)
            if size > MAX_BYTES:  # refused before a byte is read
                raise FretishFileError(f"ReqIF file of {size} bytes: more than the "
                                       f"{MAX_BYTES // 2**20} MiB fretc reads", source=path)
            with open(path, "rb") as f:
                members = [(path, f.read(MAX_BYTES + 1))]
        except OSError as e:
            raise FretishFileError(f"cannot read: {e.strerror}", source=path) from None
    from reqif.parser import ReqIFParser  # lazy: lxml only for ReqIF

    out = []
    for source, raw in members:
        text = checked_text(raw, source)
        try:
            bundle = ReqIFParser.parse_from_string(text)
        except Exception as e:  # noqa: BLE001 - the library's errors have no common base
            raise FretishFileError(f"not a ReqIF document the reqif library reads: "
                                   f"{type(e).__name__}: {e}".rstrip(": "),
                                   source=source) from None
        if bundle.core_content is None or bundle.core_content.req_if_content is None:
            raise FretishFileError("no CORE-CONTENT/REQ-IF-CONTENT element", source=source)
        out.append((source, bundle))
    return out


def _line(node) -> int:
    """The source line of an lxml element (1 when unknown)."""
    return getattr(node, "sourceline", None) or 1


def attribute_names(content: Any, source: str) -> dict[str, tuple[str, object]]:
    """Attribute definition IDENTIFIER -> (its name, its datatype) over every SPEC-OBJECT-TYPE
    of ``content``. Raises :class:`FretishFileError` at a definition whose datatype is not
    among the DATATYPES (ReqIF 1.2 section 10.8.4: a definition's TYPE references one)."""
    types = {d.identifier: d for d in (content.data_types or [])}
    out = {}
    for spec_type in content.spec_types or []:
        for d in getattr(spec_type, "attribute_definitions", None) or []:
            if d.datatype_definition not in types:
                raise FretishFileError(
                    f"ATTRIBUTE-DEFINITION {d.identifier!r} of {spec_type.identifier!r} "
                    f"refers to datatype {d.datatype_definition!r}, which DATATYPES does not "
                    "define", source=source, line=_line(d.xml_node))
            out[d.identifier] = (d.long_name or d.identifier, types[d.datatype_definition])
    return out


def _value_text(attr, datatype) -> str:
    """An attribute value as text: XHTML without its markup, enumerations as the LONG-NAMEs
    of their values joined by ", "."""
    value = attr.value
    if isinstance(value, list):  # enumeration: ENUM-VALUE refs
        names: dict[str, str] = {v.identifier: (v.long_name or v.key or v.identifier)
                 for v in getattr(datatype, "values", None) or []}
        return ", ".join(str(names.get(v, v)) for v in value)
    if attr.attribute_type.name == "XHTML":
        raw = attr.value_stripped_xhtml if attr.value_stripped_xhtml is not None else value
        return visible_text(raw or "")
    return "" if value is None else str(value)


#: elements whose content a reader does not see as the text: deleted text (``del``: a
#: tracked change), scripts, styles, the document head
_HIDDEN_TAGS = frozenset({"del", "script", "style", "head", "template"})
_VOID = frozenset({"br", "hr", "img", "input", "meta", "link", "area", "base", "col",
                   "embed", "param", "source", "track", "wbr"})
_HIDDEN_STYLE = re.compile(r"(?:^|;)\s*(?:display\s*:\s*none|visibility\s*:\s*hidden)",
                           re.IGNORECASE)


def visible_text(markup: str) -> str:
    """The text of an XHTML value as a reader sees it: the markup dropped (an element
    boundary is a space), character references resolved, and the content of elements a
    reader does not see left out: ``del``, ``script``, ``style``, ``head``, ``template``,
    and elements with the ``hidden`` attribute or a ``display: none`` or ``visibility:
    hidden`` style (HTML Living Standard, "The hidden attribute"; CSS 2.1 "display").
    Whitespace runs become one space."""
    from html.parser import HTMLParser

    parts: list[str] = []
    stack: list[bool] = []  # per open element: hidden

    class _Reader(HTMLParser):
        def handle_starttag(self, tag, attrs):
            a = dict(attrs)
            local = tag.rsplit(":", 1)[-1].lower()
            if local in _VOID:  # no content, no end tag
                parts.append(" ")
                return
            hide = (local in _HIDDEN_TAGS or "hidden" in a
                    or bool(_HIDDEN_STYLE.search(a.get("style") or "")))
            stack.append(hide or (bool(stack) and stack[-1]))
            parts.append(" ")

        def handle_startendtag(self, tag, attrs):
            parts.append(" ")

        def handle_endtag(self, tag):
            if stack:
                stack.pop()
            parts.append(" ")

        def handle_data(self, data):
            if not (stack and stack[-1]):
                parts.append(data)

    reader = _Reader(convert_charrefs=True)
    reader.feed(markup)
    reader.close()
    return " ".join("".join(parts).split())


def load_reqif(path: str, text_attribute: str | None = None
               ) -> tuple[list[RequirementEntry], list[RequirementEntry]]:
    """(entries, not formalized) of the ReqIF file at ``path`` (module docstring; both lists of
    :class:`fretc.fretish.files.RequirementEntry`). Raises :class:`FretishFileError` (file, line of
    the element): hostile or malformed XML, a SPEC-OBJECT whose type or attribute definition
    is missing, a missing datatype, two SPEC-OBJECTs with one id or one IDENTIFIER."""
    entries: list[RequirementEntry] = []
    unformalized: list[RequirementEntry] = []
    for source, bundle in parse_reqif_bundles(path):
        got, skipped = _read_bundle(source, bundle.core_content.req_if_content,
                                    text_attribute)
        entries.extend(got)
        unformalized.extend(skipped)
    return entries, unformalized


def _containers(content) -> dict[str, str]:
    """SPEC-OBJECT IDENTIFIER -> the LONG-NAME (else IDENTIFIER) of the SPECIFICATION that
    holds it (the first one, in document order)."""
    out: dict[str, str] = {}
    for spec in content.specifications or []:
        name = spec.long_name or spec.identifier
        stack = list(reversed(spec.children or []))
        while stack:
            h = stack.pop()
            out.setdefault(h.spec_object, name)
            stack.extend(reversed(h.children or []))
    return out


def _read_bundle(source: str, content, text_attribute: str | None):

    names = attribute_names(content, source)
    types = {t.identifier for t in content.spec_types or []}
    wanted = _text_attribute(names, text_attribute)
    objects = content.spec_objects or []
    ids: dict[str, tuple[str, dict[str, str], Any]] = {}  # IDENTIFIER -> (id, values, node)
    first: dict[str, tuple[str, int]] = {}  # id -> (IDENTIFIER, line)
    for so in objects:
        if so.identifier in ids:  # IDENTIFIERs are unique in a ReqIF document (ReqIF 1.2)
            raise FretishFileError(
                f"two SPEC-OBJECTs have the IDENTIFIER {so.identifier!r} (lines "
                f"{_line(ids[so.identifier][2])} and {_line(so.xml_node)}); a ReqIF "
                "IDENTIFIER must be unique", source=source, line=_line(so.xml_node))
        values = _values(so, names, source, types)
        rid = next((values[k] for k in ID_ATTRIBUTES if values.get(k)), so.identifier)
        if rid in first:
            raise FretishFileError(
                f"SPEC-OBJECT {so.identifier!r} has the id {rid!r} of SPEC-OBJECT "
                f"{first[rid][0]!r} (line {first[rid][1]}); ids must be unique",
                source=source, line=_line(so.xml_node))
        first[rid] = (so.identifier, _line(so.xml_node))
        ids[so.identifier] = (rid, values, so.xml_node)
    parents: dict[str, list[str]] = {}
    for rel in content.spec_relations or []:
        target = ids.get(rel.target)
        parents.setdefault(rel.source, []).append(target[0] if target else rel.target)
    holder = _containers(content)
    entries: list[RequirementEntry] = []
    unformalized: list[RequirementEntry] = []
    for so in objects:
        rid, values, _node = ids[so.identifier]
        text = values.get(wanted.lower(), "").strip()
        rationale = next((v for k, v in sorted(values.items()) if "rationale" in k and v),
                         None)
        origin = Origin("reqif", source, so.identifier,
                        long_name=so.long_name or values.get("reqif.name") or None,
                        version=so.last_change, parents=tuple(sorted(parents.get(
                            so.identifier, []))), rationale=rationale,
                        container=holder.get(so.identifier), text_attribute=wanted,
                        text=text)
        line = _line(so.xml_node)
        keep_entry(rid, text, source, source, line, origin, entries, unformalized)
    return entries, unformalized


def _text_attribute(names: dict, asked: str | None) -> str:
    """The attribute name the FRETish text is read from (module docstring)."""
    if asked:
        return asked
    known = {n.lower() for n, _dt in names.values()}
    return DEFAULT_TEXT_ATTRIBUTE if DEFAULT_TEXT_ATTRIBUTE.lower() in known else REQIF_TEXT


def _values(so, names: dict, source: str, types: set[str]) -> dict[str, str]:
    """A SPEC-OBJECT's attribute values by lower-case attribute name. Raises
    :class:`FretishFileError` at a SPEC-OBJECT whose type ``types`` (the SPEC-OBJECT-TYPE
    identifiers) does not hold, and at a value whose definition is not defined or that its
    datatype does not take (:func:`_value_problem`)."""
    if so.spec_object_type not in types:
        raise FretishFileError(
            f"SPEC-OBJECT {so.identifier!r} is of SPEC-OBJECT-TYPE {so.spec_object_type!r}, "
            "which SPEC-TYPES does not define", source=source, line=_line(so.xml_node))
    out = {}
    for attr in so.attributes:
        got = names.get(attr.definition_ref)
        line = _line(attr.xml_node if attr.xml_node is not None else so.xml_node)
        if got is None:
            raise FretishFileError(
                f"SPEC-OBJECT {so.identifier!r}: its value refers to attribute definition "
                f"{attr.definition_ref!r}, which no SPEC-OBJECT-TYPE defines", source=source,
                line=line)
        why = _value_problem(attr, got[1])
        if why is not None:
            raise FretishFileError(f"SPEC-OBJECT {so.identifier!r}: its value of {got[0]!r} "
                                   f"{why}", source=source, line=line)
        out[got[0].lower()] = _value_text(attr, got[1])
    return out


def _value_problem(attr, datatype) -> str | None:
    """Why ``attr``'s value is not one of its datatype (ReqIF 1.2 section 10.8: an INTEGER
    value a whole number within the datatype's MIN and MAX, a REAL a number, a BOOLEAN
    ``true``/``false``, an enumeration's values among the datatype's ENUM-VALUEs), or None."""
    kind, value = attr.attribute_type.name, attr.value
    if kind == "ENUMERATION":
        known = {v.identifier for v in getattr(datatype, "values", None) or []}
        bad = [v for v in value or [] if v not in known]
        return (f"is ENUM-VALUE {bad[0]!r}, which its datatype "
                f"{datatype.identifier!r} does not define") if bad else None
    if kind == "INTEGER":
        try:
            n = int(str(value).strip())
        except ValueError:
            return f"{value!r} is not an integer"
        lo, hi = (getattr(datatype, "min_value", None), getattr(datatype, "max_value", None))
        try:
            lo, hi = int(lo) if lo is not None else None, int(hi) if hi is not None else None
        except ValueError:
            return None
        if (lo is not None and n < lo) or (hi is not None and n > hi):
            return f"{n} is outside [{lo}, {hi}], its datatype's MIN and MAX"
    if kind == "REAL":
        try:
            float(str(value).strip())
        except ValueError:
            return f"{value!r} is not a number"
    if kind == "BOOLEAN" and str(value).strip().lower() not in ("true", "false", "1", "0"):
        return f"{value!r} is not true or false"
    return None
