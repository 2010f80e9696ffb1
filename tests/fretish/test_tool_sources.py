"""Requirements read from tools (fretish/sources): the ReqIF StrictDoc wrote and the Doorstop
tree the doorstop command made (tests/fixtures/requirements_tools/README.md), ReqIF files of
real tools (../shared/data/reqif, SOURCES.md there), and hostile or broken inputs."""

from __future__ import annotations

import os
import shutil
import sys
import time
import zipfile
from pathlib import Path

import pytest

from _shared import SHARED, needs_shared
from fretc.common.errors import FretishFileError
from fretc.fretish.files import load_requirements

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "fixtures" / "requirements_tools"
REQIF = FIX / "strictdoc" / "safe_ros.reqif"
DOORSTOP = FIX / "doorstop"
SAFE_ROS = [ROOT / "requirements" / "r1.fret", ROOT / "requirements" / "safe_ros.fret"]


def _load(path, **kw):
    unformalized: list = []
    return load_requirements(path, not_formalized=unformalized, **kw), unformalized


def test_strictdoc_reqif_holds_the_safe_ros_requirements_with_their_identity():
    entries, unformalized = _load(REQIF)
    fret = {e.id: e for e in load_requirements(SAFE_ROS)}
    assert [e.id for e in entries] == ["R1", "R2", "R3", "R4", "R5", "R6"]
    for e in entries:
        assert e.error is None and e.requirement is not None
        assert e.text == fret[e.id].text                      # the FRETish attribute
        assert e.rationale == fret[e.id].rationale
        o = e.origin
        assert o.format == "reqif" and o.tool_id.startswith("REQUIREMENT-")
        assert o.version and o.container == "Safe-ROS requirements"
        assert o.text_attribute == "FRETish" and o.long_name     # ReqIF.Name: the title
    by = {e.id: e for e in entries}
    assert by["R2"].origin.parents == ("R1",) and by["R2"].parent == "R1"
    assert by["R4"].origin.parents == ("SR-0",)
    assert len({e.origin.tool_id for e in entries}) == 6
    assert [(u.id, u.text) for u in unformalized] == [("SR-0", "")]


def test_text_attribute_picks_another_field_and_bad_sentences_stay_per_requirement():
    entries, _ = _load(REQIF, text_attribute="ReqIF.Text")
    assert len(entries) == 7                       # every item has a statement
    assert all(e.origin.text_attribute == "ReqIF.Text" for e in entries)
    assert sum(e.error is not None for e in entries) == 7   # prose is not FRETish: no raise


def test_doorstop_tree_made_by_doorstop():
    entries, unformalized = _load(DOORSTOP)
    fret = {e.id: e for e in load_requirements(SAFE_ROS)}
    assert [e.id for e in entries] == ["R1", "R2", "R3", "R4", "R5", "R6"]
    for e in entries:
        assert e.text == fret[e.id].text and e.rationale == fret[e.id].rationale
        assert e.origin.format == "doorstop" and e.origin.tool_id == e.id
        assert e.origin.file.endswith(f"{e.id}.yml") and e.origin.container == "R"
        assert e.source == str(DOORSTOP)           # the tree: an audit can read it again
        assert e.origin.version and e.origin.level
    by = {e.id: e for e in entries}
    assert by["R2"].origin.parents == ("R1",) and by["R1"].origin.parents == ("SYS1",)
    assert [u.id for u in unformalized] == ["SYS1"]


def _tree_copy(tmp_path) -> Path:
    out = tmp_path / "tree"
    shutil.copytree(DOORSTOP, out)
    return out


def test_doorstop_link_cycle_is_an_error_naming_the_item(tmp_path):
    tree = _tree_copy(tmp_path)
    r1 = tree / "r" / "R1.yml"
    r1.write_text(r1.read_text().replace("links:\n", "links:\n- R2: null\n"))
    with pytest.raises(FretishFileError) as err:
        load_requirements(tree)
    assert "cycle" in str(err.value) and "R1 -> R2 -> R1" in err.value.message
    assert err.value.source.endswith(("R1.yml", "R2.yml"))  # the item file


def test_doorstop_missing_parent_is_an_error_naming_the_item(tmp_path):
    tree = _tree_copy(tmp_path)
    r4 = tree / "r" / "R4.yml"
    r4.write_text(r4.read_text().replace("links:\n", "links:\n- R99: null\n"))
    with pytest.raises(FretishFileError) as err:
        load_requirements(tree)
    assert "R99" in err.value.message and "missing parent" in err.value.message
    assert err.value.source.endswith("R4.yml") and err.value.line > 1


def test_duplicate_ids_across_sources_name_both_files():
    with pytest.raises(FretishFileError) as err:
        load_requirements([REQIF, DOORSTOP])
    assert "R1" in str(err.value) and "safe_ros.reqif" in str(err.value)


LAUGHS = ('<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
          + "".join(f'<!ENTITY lol{i} "{("&lol%s;" % (i - 1 if i > 1 else "")) * 10}">'
                    for i in range(1, 10))
          + ']>\n<REQ-IF>&lol9;</REQ-IF>\n')


def test_billion_laughs_is_refused_fast(tmp_path):
    p = tmp_path / "laughs.reqif"
    p.write_text(LAUGHS)
    t0 = time.perf_counter()
    with pytest.raises(FretishFileError) as err:
        load_requirements(p)
    assert time.perf_counter() - t0 < 1.0
    assert "DOCTYPE declaration refused" in err.value.message and err.value.line == 2


def test_external_entity_is_refused_without_reading_the_file(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOP-SECRET-CONTENT")
    p = tmp_path / "xxe.reqif"
    p.write_text(f'<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY x SYSTEM "file://{secret}">]>'
                 "\n<REQ-IF>&x;</REQ-IF>\n")
    opened: list[str] = []

    def hook(event, args):
        if event == "open" and args and str(args[0]) == str(secret):
            opened.append(event)

    sys.addaudithook(hook)  # stays for the session: cheap, it compares one path
    t0 = time.perf_counter()
    with pytest.raises(FretishFileError) as err:
        load_requirements(p)
    assert time.perf_counter() - t0 < 1.0
    assert opened == [] and "TOP-SECRET" not in str(err.value)


def test_malformed_xml_names_the_line(tmp_path):
    p = tmp_path / "broken.reqif"
    p.write_text('<?xml version="1.0"?>\n<REQ-IF>\n  <THE-HEADER>\n</REQ-IF>\n')
    with pytest.raises(FretishFileError) as err:
        load_requirements(p)
    assert "not well-formed" in err.value.message and err.value.line == 4


def test_missing_datatype_names_the_definition(tmp_path):
    text = REQIF.read_text()
    p = tmp_path / "nodt.reqif"
    p.write_text(text.replace('<DATATYPE-DEFINITION-STRING IDENTIFIER='
                              '"SDOC_DATATYPE_MULTI_LINE_STRING"',
                              '<DATATYPE-DEFINITION-STRING IDENTIFIER="RENAMED"'))
    with pytest.raises(FretishFileError) as err:
        load_requirements(p)
    assert "SDOC_DATATYPE_MULTI_LINE_STRING" in err.value.message
    assert "ATTRIBUTE-DEFINITION" in err.value.message and err.value.line > 1


def test_reqifz_reads_like_its_reqif_and_refuses_bombs_and_escapes(tmp_path):
    good = tmp_path / "good.reqifz"
    with zipfile.ZipFile(good, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(REQIF, "safe_ros.reqif")
    assert [e.text for e in load_requirements(good)] == [e.text for e in _load(REQIF)[0]]
    bomb = tmp_path / "bomb.reqifz"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("a.reqif", b" " * (8 * 1024 * 1024))
    with pytest.raises(FretishFileError, match="zip bomb"):
        load_requirements(bomb)
    escape = tmp_path / "escape.reqifz"
    with zipfile.ZipFile(escape, "w") as z:
        z.writestr("../../evil.reqif", REQIF.read_bytes())
    with pytest.raises(FretishFileError, match="outside the archive"):
        load_requirements(escape)


@needs_shared
@pytest.mark.parametrize("name, ids, tool_ids", [
    ("polarion_sample1.reqif", ["rmf-bd312f1z-fa7c-4de3-b8f3-ab105179fccc", "LOREM-818"],
     ["rmf-bd312f1z-fa7c-4de3-b8f3-ab105179fccc", "rmf-1d312f18-fa7c-4de3-b8f3-ab105179fddf"]),
    ("capella_requirements_vp.reqif", ["_xen_QMkhEee8KsfWrp9EJQ"],
     ["_xen_QMkhEee8KsfWrp9EJQ"]),
])
def test_real_tool_exports_read_with_their_identifiers(name, ids, tool_ids):
    entries, _ = _load(SHARED / "data" / "reqif" / name)
    assert [e.id for e in entries] == ids                # ReqIF.ForeignID where it is set
    assert [e.origin.tool_id for e in entries] == tool_ids
    assert all(e.origin.version for e in entries)   # LAST-CHANGE


@needs_shared
@pytest.mark.parametrize("name", ["enterprise_architect_8.reqif",
                                  "reqif_testcase_TC1100.reqif", "eclipse_rmf_sample.reqif"])
def test_real_tool_exports_without_text_list_items_as_not_formalized(name):
    entries, unformalized = _load(SHARED / "data" / "reqif" / name)
    assert entries == [] and unformalized and all(u.origin.tool_id for u in unformalized)


@needs_shared
def test_real_doors_excerpt_with_a_missing_datatype_is_a_clear_error():
    with pytest.raises(FretishFileError) as err:
        load_requirements(SHARED / "data" / "reqif" / "doors_user_06.reqif")
    assert "DATATYPES does not define" in err.value.message and err.value.line == 29


def test_a_huge_reqif_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from fretc.fretish.sources import reqif_file

    p = tmp_path / "huge.reqif"
    p.write_bytes(b"<REQ-IF>" + b" " * 2048 + b"</REQ-IF>")
    monkeypatch.setattr(reqif_file, "MAX_BYTES", 1024)
    with pytest.raises(FretishFileError, match="more than the"):
        load_requirements(p)


def test_two_spec_objects_with_one_identifier_are_refused_naming_both(tmp_path):
    """Both had their own ids (ReqIF.ForeignID): one requirement was lost and the other
    read twice."""
    text = REQIF.read_text()
    first = "REQUIREMENT-464b68b1-fa31-442f-9b42-981f70179f22"
    second = "REQUIREMENT-714dc3bf-6b7d-45bb-a560-764bfcd1a314"
    p = tmp_path / "dup.reqif"
    p.write_text(text.replace(f'<SPEC-OBJECT IDENTIFIER="{second}"',
                              f'<SPEC-OBJECT IDENTIFIER="{first}"'))
    with pytest.raises(FretishFileError) as err:
        load_requirements(p)
    assert first in err.value.message and "lines 66 and 93" in err.value.message
    assert err.value.line == 93


_XHTML_REQIF = """<?xml version="1.0" encoding="UTF-8"?>
<REQ-IF xmlns="http://www.omg.org/spec/ReqIF/20110401/reqif.xsd"
        xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <THE-HEADER><REQ-IF-HEADER IDENTIFIER="h"><TITLE>t</TITLE></REQ-IF-HEADER></THE-HEADER>
  <CORE-CONTENT><REQ-IF-CONTENT>
    <DATATYPES>
      <DATATYPE-DEFINITION-XHTML IDENTIFIER="DT-X" LAST-CHANGE="2026-01-01T00:00:00Z"/>
      <DATATYPE-DEFINITION-STRING IDENTIFIER="DT-S" LAST-CHANGE="2026-01-01T00:00:00Z"
                                  MAX-LENGTH="100"/>
    </DATATYPES>
    <SPEC-TYPES>
      <SPEC-OBJECT-TYPE IDENTIFIER="T" LAST-CHANGE="2026-01-01T00:00:00Z">
        <SPEC-ATTRIBUTES>
          <ATTRIBUTE-DEFINITION-STRING IDENTIFIER="A-ID" LONG-NAME="ReqIF.ForeignID"
              LAST-CHANGE="2026-01-01T00:00:00Z">
            <TYPE><DATATYPE-DEFINITION-STRING-REF>DT-S</DATATYPE-DEFINITION-STRING-REF></TYPE>
          </ATTRIBUTE-DEFINITION-STRING>
          <ATTRIBUTE-DEFINITION-XHTML IDENTIFIER="A-F" LONG-NAME="FRETish"
              LAST-CHANGE="2026-01-01T00:00:00Z">
            <TYPE><DATATYPE-DEFINITION-XHTML-REF>DT-X</DATATYPE-DEFINITION-XHTML-REF></TYPE>
          </ATTRIBUTE-DEFINITION-XHTML>
        </SPEC-ATTRIBUTES>
      </SPEC-OBJECT-TYPE>
    </SPEC-TYPES>
    <SPEC-OBJECTS>
      <SPEC-OBJECT IDENTIFIER="O1" LAST-CHANGE="2026-01-01T00:00:00Z">
        <TYPE><SPEC-OBJECT-TYPE-REF>T</SPEC-OBJECT-TYPE-REF></TYPE>
        <VALUES>
          <ATTRIBUTE-VALUE-STRING THE-VALUE="X1">
            <DEFINITION><ATTRIBUTE-DEFINITION-STRING-REF>A-ID</ATTRIBUTE-DEFINITION-STRING-REF></DEFINITION>
          </ATTRIBUTE-VALUE-STRING>
          <ATTRIBUTE-VALUE-XHTML>
            <DEFINITION><ATTRIBUTE-DEFINITION-XHTML-REF>A-F</ATTRIBUTE-DEFINITION-XHTML-REF></DEFINITION>
            <THE-VALUE><xhtml:div>the robot shall <xhtml:del>never</xhtml:del> always satisfy
              <xhtml:span style="display: none">!</xhtml:span>ok<xhtml:span hidden="hidden">
              &amp; broken</xhtml:span></xhtml:div></THE-VALUE>
          </ATTRIBUTE-VALUE-XHTML>
        </VALUES>
      </SPEC-OBJECT>
    </SPEC-OBJECTS>
  </REQ-IF-CONTENT></CORE-CONTENT>
</REQ-IF>
"""


def test_only_the_visible_text_of_an_xhtml_value_is_formalized(tmp_path):
    """Deleted text (``del``, a tracked change) and hidden spans (``display: none``, the
    ``hidden`` attribute) were formalized into the sentence."""
    p = tmp_path / "x.reqif"
    p.write_text(_XHTML_REQIF, encoding="utf-8")
    (e,) = load_requirements(p)
    assert e.id == "X1" and e.error is None
    assert e.text == "the robot shall always satisfy ok"


_BOMB = "".join(f"{a}: &{a} [{', '.join([f'*{p}'] * 9) if p else ', '.join(['x'] * 9)}]\n"
                for p, a in zip([None, "a", "b", "c", "d", "e", "f", "g"], "abcdefgh"))


def _hostile_item(tree: Path, how: str) -> str:
    """Damage the tree's item R1 (or add a file) as ``how`` says; the file the error names."""
    r1 = tree / "r" / "R1.yml"
    text = r1.read_text()
    if how == "invalid_yaml":
        r1.write_text("text: [unclosed\n")
    elif how == "python_tag":
        r1.write_text("text: !!python/object/apply:os.system ['echo hi']\nactive: true\n")
    elif how == "non_utf8":
        r1.write_bytes(b"text: \xff\xfe\nactive: true\n")
    elif how == "level_mapping":
        r1.write_text(text.replace("level:", "level: {a: 1}\nold_level:"))
    elif how == "links_number":
        r1.write_text(text.replace("links:", "links: 5\nold_links:"))
    elif how == "fretish_mapping":
        r1.write_text(text + "\nFRETish: {a: 1}\n")
    elif how == "yaml_bomb":
        (tree / "r" / ".doorstop.yml").write_text(
            (tree / "r" / ".doorstop.yml").read_text() + "\nattributes:\n  reviewed: [h]\n")
        r1.write_text(text + "\n" + _BOMB)
    elif how == "fifo":
        os.mkfifo(tree / "r" / "R9.yml")
        return str(tree / "r" / "R9.yml")
    elif how == "link_outside":
        outside = tree.parent / "outside.yml"
        outside.write_text("active: true\nlevel: 9\nnormative: true\ntext: outside\n")
        os.symlink(outside, tree / "r" / "R9.yml")
        return str(tree / "r" / "R9.yml")
    elif how.startswith("include_"):  # doorstop reads !include in a document's config
        doc = tree / "r" / ".doorstop.yml"
        target = {"include_passwd": "/etc/passwd",
                  "include_outside": "../../outside.yml",
                  "include_fifo": "pipe.txt",
                  "include_nested": "inner.yml", "include_cycle": "loop.yml"}[how]
        (tree.parent / "outside.yml").write_text("prefix: X\n")
        if how == "include_fifo":
            os.mkfifo(tree / "r" / "pipe.txt")
        if how == "include_cycle":  # two files that include each other
            (tree / "r" / "loop.yml").write_text("a: !include loop2.yml\n")
            (tree / "r" / "loop2.yml").write_text("b: !include loop.yml\n")
        if how == "include_nested":  # an included file inside the tree that includes out
            (tree / "r" / "inner.yml").write_text("a: !include ../../outside.yml\n")
        doc.write_text(doc.read_text() + f"\nextra: !include {target}\n")
        return {"include_nested": str(tree / "r" / "inner.yml"),
                "include_cycle": "includes itself"}.get(how, str(doc))
    elif how == "deep_doc_yaml":
        doc = tree / "r" / ".doorstop.yml"
        doc.write_text(doc.read_text() + "\ndeep: " + "[" * 5000 + "]" * 5000 + "\n")
        return str(doc)
    return str(r1)


@pytest.mark.parametrize("how", ["invalid_yaml", "python_tag", "non_utf8", "level_mapping",
                                 "links_number", "fretish_mapping", "yaml_bomb", "fifo",
                                 "link_outside", "include_passwd", "include_outside",
                                 "include_fifo", "include_nested", "include_cycle",
                                 "deep_doc_yaml"])
def test_a_hostile_doorstop_item_is_an_input_error_naming_its_file(tmp_path, how):
    """Each was an internal error (exit 4), a hang (a FIFO, a YAML bomb under ``reviewed``)
    or a file read from outside the tree; the entry point must answer within seconds."""
    tree = _tree_copy(tmp_path)
    named = _hostile_item(tree, how)
    t0 = time.monotonic()
    with pytest.raises(FretishFileError) as err:
        load_requirements(tree)
    assert time.monotonic() - t0 < 20
    assert err.value.source == named or named in err.value.message, (how, str(err.value))


_TYPED_REQIF = """<?xml version="1.0" encoding="UTF-8"?>
<REQ-IF xmlns="http://www.omg.org/spec/ReqIF/20110401/reqif.xsd" xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <THE-HEADER><REQ-IF-HEADER IDENTIFIER="h"><TITLE>t</TITLE></REQ-IF-HEADER></THE-HEADER>
  <CORE-CONTENT><REQ-IF-CONTENT>
    <DATATYPES>
      <DATATYPE-DEFINITION-STRING IDENTIFIER="DT-S" LAST-CHANGE="2026-01-01T00:00:00Z" MAX-LENGTH="100"/>
      <DATATYPE-DEFINITION-INTEGER IDENTIFIER="DT-I" LAST-CHANGE="2026-01-01T00:00:00Z" MAX="100" MIN="0"/>
      <DATATYPE-DEFINITION-ENUMERATION IDENTIFIER="DT-E" LAST-CHANGE="2026-01-01T00:00:00Z">
        <SPECIFIED-VALUES>
          <ENUM-VALUE IDENTIFIER="E-HIGH" LONG-NAME="high" LAST-CHANGE="2026-01-01T00:00:00Z"><PROPERTIES><EMBEDDED-VALUE KEY="1" OTHER-CONTENT=""/></PROPERTIES></ENUM-VALUE>
        </SPECIFIED-VALUES>
      </DATATYPE-DEFINITION-ENUMERATION>
    </DATATYPES>
    <SPEC-TYPES>
      <SPEC-OBJECT-TYPE IDENTIFIER="T" LAST-CHANGE="2026-01-01T00:00:00Z">
        <SPEC-ATTRIBUTES>
          <ATTRIBUTE-DEFINITION-STRING IDENTIFIER="A-ID" LONG-NAME="ReqIF.ForeignID" LAST-CHANGE="2026-01-01T00:00:00Z">
            <TYPE><DATATYPE-DEFINITION-STRING-REF>DT-S</DATATYPE-DEFINITION-STRING-REF></TYPE>
          </ATTRIBUTE-DEFINITION-STRING>
          <ATTRIBUTE-DEFINITION-STRING IDENTIFIER="A-F" LONG-NAME="FRETish" LAST-CHANGE="2026-01-01T00:00:00Z">
            <TYPE><DATATYPE-DEFINITION-STRING-REF>DT-S</DATATYPE-DEFINITION-STRING-REF></TYPE>
          </ATTRIBUTE-DEFINITION-STRING>
          <ATTRIBUTE-DEFINITION-INTEGER IDENTIFIER="A-P" LONG-NAME="Priority" LAST-CHANGE="2026-01-01T00:00:00Z">
            <TYPE><DATATYPE-DEFINITION-INTEGER-REF>DT-I</DATATYPE-DEFINITION-INTEGER-REF></TYPE>
          </ATTRIBUTE-DEFINITION-INTEGER>
          <ATTRIBUTE-DEFINITION-ENUMERATION IDENTIFIER="A-E" LONG-NAME="Level" LAST-CHANGE="2026-01-01T00:00:00Z" MULTI-VALUED="false">
            <TYPE><DATATYPE-DEFINITION-ENUMERATION-REF>DT-E</DATATYPE-DEFINITION-ENUMERATION-REF></TYPE>
          </ATTRIBUTE-DEFINITION-ENUMERATION>
        </SPEC-ATTRIBUTES>
      </SPEC-OBJECT-TYPE>
    </SPEC-TYPES>
    <SPEC-OBJECTS>
      <SPEC-OBJECT IDENTIFIER="O1" LAST-CHANGE="2026-01-01T00:00:00Z">
        <TYPE><SPEC-OBJECT-TYPE-REF>TYPEREF</SPEC-OBJECT-TYPE-REF></TYPE>
        <VALUES>
          <ATTRIBUTE-VALUE-STRING THE-VALUE="X1"><DEFINITION><ATTRIBUTE-DEFINITION-STRING-REF>A-ID</ATTRIBUTE-DEFINITION-STRING-REF></DEFINITION></ATTRIBUTE-VALUE-STRING>
          <ATTRIBUTE-VALUE-STRING THE-VALUE="the robot shall always satisfy ok"><DEFINITION><ATTRIBUTE-DEFINITION-STRING-REF>A-F</ATTRIBUTE-DEFINITION-STRING-REF></DEFINITION></ATTRIBUTE-VALUE-STRING>
          <ATTRIBUTE-VALUE-INTEGER THE-VALUE="INTVAL"><DEFINITION><ATTRIBUTE-DEFINITION-INTEGER-REF>A-P</ATTRIBUTE-DEFINITION-INTEGER-REF></DEFINITION></ATTRIBUTE-VALUE-INTEGER>
          <ATTRIBUTE-VALUE-ENUMERATION><DEFINITION><ATTRIBUTE-DEFINITION-ENUMERATION-REF>A-E</ATTRIBUTE-DEFINITION-ENUMERATION-REF></DEFINITION><VALUES><ENUM-VALUE-REF>ENUMREF</ENUM-VALUE-REF></VALUES></ATTRIBUTE-VALUE-ENUMERATION>
        </VALUES>
      </SPEC-OBJECT>
    </SPEC-OBJECTS>
  </REQ-IF-CONTENT></CORE-CONTENT>
</REQ-IF>
"""


@pytest.mark.parametrize("case,swap,what", [
    ("type", ("TYPEREF", "NOPE"), "SPEC-OBJECT-TYPE 'NOPE'"),
    ("integer", ("INTVAL", "abc"), "'abc' is not an integer"),
    ("range", ("INTVAL", "500"), "outside [0, 100]"),
    ("enum", ("ENUMREF", "E-NOPE"), "ENUM-VALUE 'E-NOPE'"),
])
def test_a_reqif_value_its_datatype_refuses_is_an_error_naming_it(tmp_path, case, swap, what):
    """A SPEC-OBJECT of an undefined type, an INTEGER ``abc`` (or outside its datatype's
    MIN/MAX) and an enumeration value its datatype does not define were accepted as text
    (ReqIF 1.2, sections 10.8.x: a value is of its definition's datatype)."""
    good = {"TYPEREF": "T", "INTVAL": "5", "ENUMREF": "E-HIGH"}
    text = _TYPED_REQIF
    for k, v in good.items():
        text = text.replace(k, swap[1] if k == swap[0] else v)
    p = tmp_path / "t.reqif"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(FretishFileError) as err:
        load_requirements(p)
    assert what in str(err.value) and err.value.line > 1, str(err.value)
    ok = _TYPED_REQIF
    for k, v in good.items():
        ok = ok.replace(k, v)
    p.write_text(ok, encoding="utf-8")
    (e,) = load_requirements(p)
    assert e.id == "X1" and e.error is None
