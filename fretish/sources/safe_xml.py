"""The checks a ReqIF file passes before any XML parser builds it: size caps, UTF-8, no DTD
(so no entity of any kind: the billion laughs and external entities are refused before they
are read, and no file or URL is ever opened for them), well-formed XML by defusedxml's
parser; and for ``.reqifz`` (a zip archive of ``.reqif`` files, ReqIF 1.2 section 11: the
exchange archive) caps on members, sizes and compression ratio, and names that stay inside
the archive.

The ``reqif`` library parses with lxml's default parser, which would expand internal
entities; it is only given text that passed :func:`checked_text`.
"""

from __future__ import annotations

import zipfile

from fretc.common.errors import FretishFileError

__all__ = ["checked_text", "read_reqif_members", "MAX_BYTES", "MAX_MEMBERS", "MAX_RATIO"]

#: Largest ReqIF text read (a file, or one member of a .reqifz, and all members together).
MAX_BYTES = 64 * 1024 * 1024
#: Most members of a .reqifz archive.
MAX_MEMBERS = 1000
#: Largest uncompressed / compressed size of a .reqifz member (a zip bomb has thousands).
MAX_RATIO = 200


def _position(raw: bytes, offset: int) -> tuple[int, int]:
    """1-based (line, column) of byte ``offset``."""
    line = raw.count(b"\n", 0, offset) + 1
    return line, offset - (raw.rfind(b"\n", 0, offset) + 1) + 1


def checked_text(raw: bytes, source: str) -> str:
    """The XML text of ``raw`` once it is known safe to hand to an XML parser.

    Raises :class:`FretishFileError` at the offending place: more than :data:`MAX_BYTES`; not
    UTF-8 (ReqIF files are UTF-8, ReqIF 1.2 section 10.2); a document type declaration
    (``<!DOCTYPE``) or an entity declaration (``<!ENTITY``), which ReqIF never needs (its
    grammar is an XML schema) and which carry the entity attacks; XML that is not
    well-formed (by :mod:`defusedxml`, entities forbidden)."""
    if len(raw) > MAX_BYTES:
        raise FretishFileError(f"ReqIF file of {len(raw)} bytes: more than the "
                               f"{MAX_BYTES // 2**20} MiB fretc reads", source=source)
    for marker in (b"<!DOCTYPE", b"<!ENTITY"):
        at = raw.find(marker)
        if at >= 0:
            line, col = _position(raw, at)
            raise FretishFileError(
                f"{marker.decode()[1:]} declaration refused: a ReqIF file needs no DTD, and its "
                "entities could expand without bound or read local files; nothing was "
                "expanded or read", source=source, line=line, column=col,
                hint="export the file again from the requirements tool, without a DTD")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line, col = _position(raw, e.start)
        raise FretishFileError(f"not UTF-8: byte 0x{raw[e.start]:02x} ({e.reason})",
                               source=source, line=line, column=col) from None
    _well_formed(raw, source)
    return text


def _well_formed(raw: bytes, source: str) -> None:
    """Parse ``raw`` with defusedxml (DTDs, entities and external references forbidden);
    raises :class:`FretishFileError` at the parser's position when it is not XML."""
    import defusedxml.ElementTree as DET  # lazy: only for ReqIF files
    from defusedxml import DefusedXmlException
    from xml.etree.ElementTree import ParseError

    try:
        DET.fromstring(raw, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    except ParseError as e:
        line, col = getattr(e, "position", (1, 0))
        raise FretishFileError(f"not well-formed XML: {e}", source=source, line=line,
                               column=col + 1) from None
    except DefusedXmlException as e:
        raise FretishFileError(f"refused XML construct: {e}", source=source) from None


def read_reqif_members(path: str) -> list[tuple[str, bytes]]:
    """The ``.reqif`` members of the ``.reqifz`` archive at ``path`` as ``(name, bytes)``,
    sorted by name.

    Raises :class:`FretishFileError` naming the archive and member: not a zip file; more than
    :data:`MAX_MEMBERS` members; a member name that is absolute or climbs out (``..``); a
    member larger than :data:`MAX_BYTES`, all of them together larger, or compressed more
    than :data:`MAX_RATIO` times (a zip bomb); no ``.reqif`` member. Nothing is extracted
    to disk."""
    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError) as e:
        raise FretishFileError(f"not a .reqifz (zip) archive: {e}", source=path) from None
    with zf:
        infos = zf.infolist()
        if len(infos) > MAX_MEMBERS:
            raise FretishFileError(f"{len(infos)} members: more than {MAX_MEMBERS}",
                                   source=path)
        total = 0
        out = []
        for info in sorted(infos, key=lambda i: i.filename):
            name = info.filename
            parts = name.replace("\\", "/").split("/")
            if name.startswith(("/", "\\")) or ".." in parts or ":" in parts[0]:
                raise FretishFileError(f"member {name!r} points outside the archive",
                                       source=path)
            if info.is_dir() or not name.lower().endswith(".reqif"):
                continue
            total += info.file_size
            ratio = info.file_size / max(info.compress_size, 1)
            if info.file_size > MAX_BYTES or total > MAX_BYTES or ratio > MAX_RATIO:
                raise FretishFileError(
                    f"member {name!r}: {info.file_size} bytes from {info.compress_size} "
                    f"(a zip bomb? fretc reads at most {MAX_BYTES // 2**20} MiB, compressed "
                    f"at most {MAX_RATIO} times)", source=path)
            try:
                with zf.open(info) as f:
                    data = f.read(MAX_BYTES + 1)
            except (zipfile.BadZipFile, OSError, NotImplementedError) as e:
                raise FretishFileError(f"member {name!r} cannot be read: {e}",
                                       source=path) from None
            if len(data) > info.file_size:
                raise FretishFileError(f"member {name!r} is larger than its header says",
                                       source=path)
            out.append((name, data))
    if not out:
        raise FretishFileError("no .reqif file in the archive", source=path)
    return out
