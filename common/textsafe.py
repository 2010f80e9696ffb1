"""Text from the inputs made safe for each output format.

Requirement ids, texts, file names, topic names and binding expressions come from files a
user did not necessarily write (a FRET JSON export, a log's channel records). Every output
shows them so that they cannot change the output's structure or the reader's screen
(:func:`visible`, the base of every other function: control, format and separator
characters written as Python-style escapes; :func:`terminal_text`, :func:`xml_text`,
:func:`md_code`, :func:`one_line`), and generated code embeds them so that the text cannot
become code: one function per target language (:func:`java_string`, :func:`java_comment`,
:func:`c_comment`, :func:`python_doc`, :func:`properties_key`, :func:`properties_value`,
:func:`properties_comment`, :func:`gwendolen_comment`, :func:`xml_content`). Each function's
rule and its source (Unicode categories, XML 1.0, CommonMark, JLS 17 section 3.3,
``java.util.Properties``): ARCHITECTURE.md ("Text made safe").
"""

from __future__ import annotations

import re
from typing import Any

__all__ = ["csv_line", "visible", "terminal_text", "xml_text", "md_code", "one_line", "is_unsafe",
           "file_stems", "no_surrogates", "java_string", "java_comment", "c_comment",
           "python_doc", "properties_key", "properties_value", "properties_comment",
           "gwendolen_comment", "xml_content"]

_UNSAFE_CATEGORIES = frozenset({"Cc", "Cf", "Zl", "Zp", "Cs", "Co", "Cn"})


def _unsafe(ch: str, keep: str) -> bool:
    if ch in keep:
        return False
    o = ord(ch)
    if 0x20 <= o < 0x7F:
        return False
    if o in (0xFFFE, 0xFFFF):
        return True
    import unicodedata  # lazy: only text beyond printable ASCII needs it (start-up time)

    cat = unicodedata.category(ch)
    if cat == "Cn":  # unassigned: unknown to this Python; only noncharacters are unsafe
        return (o & 0xFFFE) == 0xFFFE or 0xFDD0 <= o <= 0xFDEF
    return cat in _UNSAFE_CATEGORIES and cat != "Co"


def _escape(ch: str) -> str:
    o = ord(ch)
    if o <= 0xFF:
        return f"\\x{o:02x}"
    if o <= 0xFFFF:
        return f"\\u{o:04x}"
    return f"\\U{o:08x}"


def is_unsafe(text: str, keep: str = "") -> bool:
    """True when :func:`visible` would change ``text``."""
    return any(_unsafe(ch, keep) for ch in text)


def visible(text: Any, keep: str = "") -> str:
    """``text`` (``str()`` of it; None gives ``""``) with every unsafe character (module
    docstring) written as a visible escape; characters in ``keep`` are left alone."""
    s = "" if text is None else str(text)
    if s.isascii() and s.isprintable():
        return s
    return "".join(_escape(ch) if _unsafe(ch, keep) else ch for ch in s)


_SURROGATE = re.compile("[\ud800-\udfff]")


def no_surrogates(value: Any) -> Any:
    """``value`` (JSON data: dicts, lists, strings, numbers) with every lone surrogate of
    its strings and keys written as a visible escape: ``\\xfe`` for the byte a file name
    that is not UTF-8 had (Python's ``surrogateescape``, PEP 383: U+DC80-U+DCFF), else
    ``\\udXXX``. Such text cannot be encoded as UTF-8, so every output written from it
    (JSON, CSV, HTML, needs.json, .sdoc) would fail; other characters are left as they are."""
    if isinstance(value, str):
        if not _SURROGATE.search(value):
            return value
        return _SURROGATE.sub(lambda m: (f"\\x{ord(m.group()) - 0xDC00:02x}"
                                         if 0xDC80 <= ord(m.group()) <= 0xDCFF
                                         else f"\\u{ord(m.group()):04x}"), value)
    if isinstance(value, dict):
        return {no_surrogates(k): no_surrogates(v) for k, v in value.items()}
    if isinstance(value, list):
        return [no_surrogates(v) for v in value]
    return value


def terminal_text(text: Any, keep: str = "") -> str:
    """Text for the terminal (module docstring), newlines escaped too (a newline in a log's
    topic, frame id or joint name cannot forge a line); pass ``keep="\n"`` only for our own
    multi-line messages (a parse error's source line and caret) whose parts from the inputs
    were escaped where they were written."""
    return visible(text, keep)


def xml_text(text: Any, keep: str = "\n\t") -> str:
    """Text for XML 1.0 content or attributes (module docstring); newlines and tabs are kept
    by default (element content), pass ``keep=""`` for one-line fields."""
    return visible(text, keep)


_BACKTICKS = r"`+"  # compiled on first use (re's cache): start-up time


def md_code(text: Any) -> str:
    """A Markdown code span holding ``text`` literally (module docstring)."""
    s = visible(text).replace("|", "\\|")
    longest = max((len(m) for m in re.findall(_BACKTICKS, s)), default=0)
    fence = "`" * (longest + 1)
    if longest or s.startswith(" ") or s.endswith(" ") or not s:
        return f"{fence} {s} {fence}"
    return f"{fence}{s}{fence}"


def one_line(text: Any) -> str:
    """One line of a comment (``.psl`` ``//`` lines): white space runs folded to one space,
    then :func:`visible`."""
    return visible(" ".join(str(text).split()))


def file_stems(ids: Any) -> dict[str, str]:
    """A file name stem for each of ``ids`` (requirement ids), distinct in one folder.

    A stem keeps letters, digits, ``-``, ``_`` and ``.`` of the id and turns every other
    character into ``_``, at most 80 characters, never starting with ``.``; where two ids
    would share a stem (case-insensitively, as on macOS and Windows file systems) every
    one of them whose stem is not the id itself, or every one when all are, gets ``~`` and
    the first 10 hex digits of the id's SHA-256 (and ``~2``, ``~3`` ... in the ids' sorted
    order should that still meet another id's stem). The same ids give the same stems in
    any order.

    Returns:
        id -> stem (without extension).
    """
    import hashlib
    import re

    def plain(i: str) -> str:
        stem = re.sub(r"[^A-Za-z0-9_.-]", "_", i)[:80] or "_"
        return "_" + stem[1:] if stem.startswith(".") else stem

    def tagged(i: str) -> str:
        return plain(i)[:69] + "~" + hashlib.sha256(i.encode("utf-8", "surrogatepass"))\
            .hexdigest()[:10]

    ids = sorted(set(ids))
    plains = {i: plain(i) for i in ids}
    groups: dict[str, list[str]] = {}
    for i in ids:
        groups.setdefault(plains[i].casefold(), []).append(i)
    stems = dict(plains)
    for rivals in groups.values():
        if len(rivals) < 2:
            continue
        keep = [j for j in rivals if plains[j] == j]
        for j in rivals:
            if j not in keep or len(keep) > 1:
                stems[j] = tagged(j)
    taken = {stems[i].casefold() for i in ids if stems[i] == plains[i]}
    for i in ids:  # an id spelled like another's tagged stem: numbered, in sorted order
        if stems[i] == plains[i]:
            continue
        stem, n = stems[i], 1
        while stem.casefold() in taken:
            n += 1
            stem = f"{stems[i]}~{n}"
        stems[i] = stem
        taken.add(stem.casefold())
    return stems


def csv_line(cells: list[str]) -> str:
    """One CSV row of ``cells`` without its line end, each quoted where RFC 4180 requires it
    (a comma, a double quote or a line break in it: a printed call ``det_3x3(a,b,c)`` as a
    column name), quotes doubled."""
    return ",".join('"' + c.replace('"', '""') + '"' if any(x in c for x in ',"\r\n') else c
                    for c in cells)


def _utf16_units(ch: str) -> list[int]:
    """The UTF-16 code units of one character (a lone surrogate: itself)."""
    o = ord(ch)
    if o <= 0xFFFF:
        return [o]
    o -= 0x10000
    return [0xD800 + (o >> 10), 0xDC00 + (o & 0x3FF)]


def java_string(text: Any) -> str:
    """A Java string literal (with its quotes) whose value is ``text`` (``str()`` of it), in
    printable ASCII: ``"`` and ``\\`` escaped, line break, carriage return and tab as
    ``\\n``, ``\\r``, ``\\t``, every other character below U+0100 as a three-digit
    octal escape, every one above as ``\\uXXXX`` per UTF-16 code unit (translated by the
    compiler into a character that is neither a quote, a backslash nor a line terminator:
    JLS 17, sections 3.3 and 3.10.7). A backslash of the text is doubled, so the text's own
    ``\\u000a`` stays six characters."""
    out = ['"']
    for ch in str(text):
        o = ord(ch)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 0x20 <= o < 0x7F:
            out.append(ch)
        elif ch in "\n\r\t":
            out.append({"\n": "\\n", "\r": "\\r", "\t": "\\t"}[ch])
        elif o < 0x100:
            out.append(f"\\{o:03o}")
        else:
            out.extend(f"\\u{u:04x}" for u in _utf16_units(ch))
    out.append('"')
    return "".join(out)


def _ascii_escaped(text: Any) -> str:
    """``text`` in printable ASCII with Python's escapes, read back by the
    ``unicode_escape`` codec: ``\\`` doubled, every other character outside printable
    ASCII as ``\\xHH`` (below U+0100) or ``\\UHHHHHHHH`` (a capital ``U``: no Java unicode
    escape)."""
    out = []
    for ch in str(text):
        o = ord(ch)
        if ch == "\\":
            out.append("\\\\")
        elif 0x20 <= o < 0x7F:
            out.append(ch)
        elif o < 0x100:
            out.append(f"\\x{o:02x}")
        else:
            out.append(f"\\U{o:08x}")
    return "".join(out)


def java_comment(text: Any) -> str:
    """The text of one ``//`` comment line of Java source showing ``text``: printable ASCII,
    no line terminator, and no backslash that can begin a unicode escape (each of the text's
    is doubled; others are written ``\\xHH`` or ``\\UHHHHHHHH``, capital ``U``, which Java
    does not translate: JLS 17, section 3.3). It reads back as ``text`` with Python's
    ``unicode_escape`` codec."""
    return _ascii_escaped(text)


def c_comment(text: Any) -> str:
    """The text of a C ``/* */`` comment showing ``text``: printable ASCII (every other
    character, line breaks included, written ``?``), never ``*/`` or ``/*`` (a space put in
    them) nor a trigraph (``??`` split: C99, section 5.2.1.1)."""
    t = "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in str(text))
    t = t.replace("*/", "* /").replace("/*", "/ *")
    while "??" in t:  # no trigraph
        t = t.replace("??", "? ?")
    return t


def python_doc(text: Any) -> str:
    """The text of a Python docstring (between ``\"\"\"`` quotes, not raw) that reads back
    as ``text``: ``\\`` escaped, a ``"`` escaped where another follows it or it ends the
    text (so no three quotes close the docstring, nor does a last quote meet the closing
    ones), line breaks and tabs kept, and every other character :func:`visible` escapes
    (controls, NUL, carriage returns, bidirectional controls, lone surrogates, which no UTF-8
    file holds) as a Python escape of the same character."""
    s = str(text)
    out = []
    for i, ch in enumerate(s):
        if ch == "\\" or (ch == '"' and (i + 1 == len(s) or s[i + 1] == '"')):
            out.append("\\" + ch)
        elif ch in "\n\t" or not _unsafe(ch, ""):
            out.append(ch)
        else:
            out.append(_escape(ch))
    return "".join(out)


def _properties(text: Any, key: bool) -> str:
    """``java.util.Properties.store``'s escapes (its ``saveConvert``, with ``escapeUnicode``)."""
    out = []
    for i, ch in enumerate(str(text)):
        o = ord(ch)
        if ch == " ":
            out.append("\\ " if key or i == 0 else " ")
        elif ch in "\\=:#!":
            out.append("\\" + ch)
        elif ch in "\t\n\r\f":
            out.append({"\t": "\\t", "\n": "\\n", "\r": "\\r", "\f": "\\f"}[ch])
        elif 0x20 < o < 0x7F:
            out.append(ch)
        else:
            out.extend(f"\\u{u:04X}" for u in _utf16_units(ch))
    return "".join(out)


def properties_key(text: Any) -> str:
    """A key of a Java properties file (JPF's ``.jpf``, AIL's ``.ail``) that
    ``java.util.Properties.load`` reads back as ``text``: as ``Properties.store`` writes it
    (every space, ``\\``, ``=``, ``:``, ``#``, ``!`` escaped, controls as ``\\t``
    ``\\n`` ``\\r`` ``\\f``, other characters outside printable ASCII as ``\\uXXXX``),
    so that no character of it ends the key, the line or the file's structure."""
    return _properties(text, True)


def properties_value(text: Any) -> str:
    """A value of a Java properties file read back as ``text`` by
    ``java.util.Properties.load``: :func:`properties_key`'s escapes but a space only where it
    leads (``Properties.store``); a trailing ``\\`` is doubled, so it continues no line."""
    return _properties(text, False)


def properties_comment(text: Any) -> str:
    """The text of one ``#`` comment line of a Java properties file: printable ASCII, no line
    break (:func:`java_comment`'s escapes: ``Properties.load`` ends a comment at a line
    terminator, and reads no escape in it)."""
    return _ascii_escaped(text)


def gwendolen_comment(text: Any) -> str:
    """The text of one ``//`` comment line of a Gwendolen agent: :func:`one_line` (no line
    break, no control or bidirectional character)."""
    return one_line(text)


def xml_content(text: Any) -> str:
    """``text`` as the content of an XML 1.0 element (or an attribute in double quotes): one
    line (:func:`xml_text` with no character kept), then ``&``, ``<``, ``>`` and ``"`` as
    entities, so no text closes the element or adds one."""
    return (xml_text(text, keep="").replace("&", "&amp;").replace("<", "&lt;")
            .replace(">", "&gt;").replace('"', "&quot;"))
