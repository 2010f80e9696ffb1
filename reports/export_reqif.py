"""``fretc export`` into ReqIF: the file read back with the ``reqif`` library, fretc's results
added, written again by the library; every original element is kept as it was.

Added (ReqIF 1.2 section 10.8: a DATATYPE-DEFINITION-STRING, ATTRIBUTE-DEFINITION-STRINGs on
a SPEC-OBJECT-TYPE, ATTRIBUTE-VALUE-STRINGs in a SPEC-OBJECT's VALUES):

Design notes: ARCHITECTURE.md, `reports/export_reqif.py`."""

from __future__ import annotations

import io
import zipfile

from fretc.common.errors import FretishFileError
from fretc.fretish.sources.reqif_file import parse_reqif_bundles
from fretc.fretish.sources.safe_xml import read_reqif_members

from fretc.reports.export_results import RequirementResult

__all__ = ["export_reqif", "ATTRIBUTES", "DATATYPE_ID"]

DATATYPE_ID = "FRETC-STRING"
#: (identifier key, LONG-NAME, field of :class:`RequirementResult`)
ATTRIBUTES = (("VERDICT", "fretc verdict", "verdict"),
              ("EVIDENCE", "fretc evidence", "evidence"),
              ("FORMULA-FT", "fretc formula ft", "ft"),
              ("FORMULA-PT", "fretc formula pt", "pt"),
              ("ROLLUP", "fretc rolled-up verdict", "rollup"),
              ("ROLLUP-PATH", "fretc rolled-up path", "rollup_path"),
              ("AUDIT-ID", "fretc audit id", "audit_id"),
              ("AUDIT-DATE", "fretc audit date", "audit_date"))


def _one_line(text: str | None) -> str:
    """A value for an XML attribute: line breaks (which XML would read as spaces) as
    spaces already, so the value reads back as written; characters XML 1.0 does not allow
    (control characters, from a log's name, say) as visible escapes
    (:func:`fretc.common.textsafe.xml_text`), so the file stays well-formed."""
    from fretc.common.textsafe import xml_text

    flat = " ".join((text or "").split("\n")).replace("\r", " ").replace("\t", " ")
    return xml_text(flat, keep="")


def _whitespace_as_references(xml: str) -> str:
    """``xml`` with the tabs, line feeds and carriage returns inside attribute values
    written as character references: the ``reqif`` library reads ``&#9;`` in an
    IDENTIFIER as a tab and writes the tab back, which an XML parser then reads as a space
    (XML 1.0 section 3.3.3, attribute-value normalization): ids changed on export."""
    import re

    refs = {"\t": "&#9;", "\n": "&#10;", "\r": "&#13;"}

    def fix(m):
        value = m.group(2)
        if not any(c in value for c in refs):
            return m.group(0)
        return m.group(1) + "".join(refs.get(c, c) for c in value) + m.group(3)
    return re.sub(r'(\s[\w:.-]+=")([^"<]*)(")', fix, xml)


def _ensure_datatype(content, date: str) -> None:
    from reqif.models.reqif_data_type import ReqIFDataTypeDefinitionString

    if content.data_types is None:
        content.data_types = []
    if not any(d.identifier == DATATYPE_ID for d in content.data_types):
        content.data_types.append(ReqIFDataTypeDefinitionString(
            identifier=DATATYPE_ID, last_change=date, long_name="fretc text",
            max_length="1000000"))


def _ensure_definitions(spec_type, date: str) -> dict[str, str]:
    """The attribute definitions of :data:`ATTRIBUTES` on ``spec_type`` (added when
    missing): LONG-NAME -> identifier."""
    from reqif.models.reqif_spec_object_type import SpecAttributeDefinition
    from reqif.models.reqif_types import SpecObjectAttributeType

    if spec_type.attribute_definitions is None:
        spec_type.attribute_definitions = []
    out = {}
    for key, long_name, _field in ATTRIBUTES:
        ident = f"FRETC-{key}-{spec_type.identifier}"
        if ident not in spec_type.attribute_map:
            d = SpecAttributeDefinition(SpecObjectAttributeType.STRING, ident, DATATYPE_ID,
                                        last_change=date, long_name=long_name)
            spec_type.attribute_definitions.append(d)
            spec_type.attribute_map[ident] = d
        out[long_name] = ident
    return out


def _annotate(content, results: dict[str, RequirementResult], source: str) -> int:
    """Add the results to the SPEC-OBJECTs of ``content``; returns how many got them."""
    from reqif.models.reqif_spec_object import SpecObjectAttribute
    from reqif.models.reqif_types import SpecObjectAttributeType

    by_tool = {r.tool_id: r for r in results.values() if r.tool_id}
    types = {t.identifier: t for t in content.spec_types or []
             if type(t).__name__ == "ReqIFSpecObjectType"}
    date = next(iter(results.values())).audit_date if results else ""
    done = 0
    for so in content.spec_objects or []:
        result = by_tool.get(so.identifier)
        if result is None:
            continue
        spec_type = types.get(so.spec_object_type)
        if spec_type is None:
            raise FretishFileError(f"SPEC-OBJECT {so.identifier!r}: its type "
                                   f"{so.spec_object_type!r} is not among the SPEC-TYPES",
                                   source=source)
        _ensure_datatype(content, date)
        defs = _ensure_definitions(spec_type, date)
        ours = set(defs.values())
        so.attributes = [a for a in so.attributes if a.definition_ref not in ours]
        for _key, long_name, field in ATTRIBUTES:
            value = getattr(result, field)
            if value is None:
                continue
            attr = SpecObjectAttribute(SpecObjectAttributeType.STRING, defs[long_name],
                                       _one_line(str(value)))
            so.attributes.append(attr)
        so.attribute_map = {a.definition_ref: a for a in so.attributes}
        done += 1
    return done


def _exported_text(source: str, bundle, results: dict[str, RequirementResult]
                   ) -> tuple[str, int]:
    from reqif.unparser import ReqIFUnparser

    n = _annotate(bundle.core_content.req_if_content, results, source)
    return _whitespace_as_references(ReqIFUnparser.unparse(bundle)), n


def export_reqif(src: str, results: dict[str, RequirementResult]) -> tuple[bytes, int]:
    """(the bytes of ``src`` with the results added, how many SPEC-OBJECTs got them): a
    ``.reqif`` text or a ``.reqifz`` archive, as ``src`` is. Raises
    :class:`FretishFileError` for a file :mod:`fretc.fretish.sources.reqif_file` refuses. Writes
    nothing."""
    bundles = parse_reqif_bundles(src)
    if not src.lower().endswith(".reqifz"):
        text, n = _exported_text(src, bundles[0][1], results)
        return text.encode("utf-8"), n
    updated = {}
    total = 0
    for source, bundle in bundles:
        text, n = _exported_text(source, bundle, results)
        updated[source.split("!", 1)[1]] = text.encode("utf-8")
        total += n
    buf = io.BytesIO()
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zout:
        raw = dict(read_reqif_members(src))
        for info in zin.infolist():
            if info.is_dir():
                continue
            data = updated.get(info.filename)
            if data is None:
                data = raw.get(info.filename)
            if data is None:
                if info.file_size > 64 * 1024 * 1024:
                    raise FretishFileError(f"member {info.filename!r} is too large to copy",
                                           source=src)
                data = zin.read(info)
            zout.writestr(zipfile.ZipInfo(info.filename, (1980, 1, 1, 0, 0, 0)), data,
                          compress_type=zipfile.ZIP_DEFLATED)
    return buf.getvalue(), total
