"""fretc export and the traceability matrix, on the Safe-ROS requirements as StrictDoc's ReqIF
and as a Doorstop tree (tests/fixtures/requirements_tools): their audits of traces/ equal the
audit of requirements/, and the exports keep every original byte and re-import."""

from __future__ import annotations

import csv
import difflib
import io
import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.fretish.files import load_requirements
from test_traceability_tools import BINDINGS, DOORSTOP, REQIF, ROOT, _run, pytestmark  # noqa: F401


@pytest.fixture(scope="module")
def audits(tmp_path_factory):
    """The audit JSON of traces/ for requirements/, the ReqIF and the Doorstop tree."""
    out = tmp_path_factory.mktemp("audits")
    docs = {}
    for name, src in (("fret", ROOT / "requirements"), ("reqif", REQIF),
                      ("doorstop", DOORSTOP)):
        path = out / f"{name}.json"
        code, _ = _run("audit", "-r", src, "-b", BINDINGS, ROOT / "traces", "--json", path,
                       "--no-progress")
        assert code == 1, name                      # traces/ holds violations
        docs[name] = path
    return docs


def _verdicts(path) -> dict:
    doc = json.loads(Path(path).read_text())
    return {(la["log"], v["requirement"]): (v["verdict"], v["robustness"]["value"],
                                            v.get("tool_id"))
            for la in doc["logs"] for v in la["verdicts"]}


def test_tool_sources_audit_like_requirements_and_name_their_tool_ids(audits):
    fret = _verdicts(audits["fret"])
    tool_ids = {e.id: e.origin.tool_id for e in load_requirements(REQIF)}
    for name in ("reqif", "doorstop"):
        got = _verdicts(audits[name])
        assert {k: v[:2] for k, v in got.items()} == {k: v[:2] for k, v in fret.items()}
        for (_log, rid), (_v, _r, tool_id) in got.items():
            assert tool_id == (tool_ids[rid] if name == "reqif" else rid)
    doc = json.loads(audits["reqif"].read_text())
    assert [x["id"] for x in doc["not_formalized"]] == ["SR-0"]
    assert all(r["origin"]["format"] == "reqif" for r in doc["requirements"])


def _only_insertions(before: list[str], after: list[str]) -> bool:
    ops = difflib.SequenceMatcher(None, before, after, autojunk=False).get_opcodes()
    return all(op in ("equal", "insert") for op, *_ in ops)


def test_reqif_export_keeps_the_file_adds_one_verdict_each_and_reimports(audits, tmp_path):
    from reqif.parser import ReqIFParser
    from reqif.unparser import ReqIFUnparser

    out = tmp_path / "out.reqif"
    code, text = _run("export", "-r", REQIF, "--from-json", audits["reqif"], "-o", out,
                      "--audit-date", "2026-01-02")
    assert code == 0, text
    data = out.read_text(encoding="utf-8")
    assert _only_insertions(REQIF.read_text(encoding="utf-8").splitlines(),
                            data.splitlines())
    assert ReqIFUnparser.unparse(ReqIFParser.parse_from_string(data)) == data  # lossless
    entries = load_requirements(out, text_attribute="fretc verdict")
    unformalized: list = []
    again = load_requirements(out, not_formalized=unformalized)
    assert [(e.id, e.text) for e in again] == [(e.id, e.text) for e in
                                               load_requirements(REQIF)]
    fret = _verdicts(audits["fret"])
    for e in entries:                               # one verdict per requirement
        runs = {v for (_log, rid), (v, _r, _t) in fret.items() if rid == e.id}
        assert e.text == ("not formalized" if e.id == "SR-0" else
                          "violated" if "violated" in runs else "satisfied")
    assert len(entries) == 7 and data.count('LONG-NAME="fretc verdict"') == 1
    assert data.count("2026-01-02T00:00:00Z") >= 7
    out2 = tmp_path / "again.reqif"                 # deterministic, and idempotent
    assert _run("export", "-r", out, "--from-json", audits["reqif"], "-o", out2,
                "--audit-date", "2026-01-02")[0] == 0
    assert out2.read_bytes() == out.read_bytes()


def test_doorstop_export_keeps_every_byte_validates_and_carries_verdicts(audits, tmp_path):
    import doorstop

    out = tmp_path / "tree"
    code, text = _run("export", "-r", DOORSTOP, "--from-json", audits["doorstop"], "-o", out)
    assert code == 0, text
    for f in DOORSTOP.rglob("*"):
        if f.is_file():
            assert (out / f.relative_to(DOORSTOP)).read_bytes().startswith(f.read_bytes())
    again = tmp_path / "again"                      # an export of an export: one block
    assert _run("export", "-r", out, "--from-json", audits["doorstop"], "-o", again)[0] == 0
    assert (again / "r" / "R2.yml").read_bytes() == (out / "r" / "R2.yml").read_bytes()
    before = doorstop.build(cwd=str(DOORSTOP), root=str(DOORSTOP))
    tree = doorstop.build(cwd=str(out), root=str(out))
    assert tree.validate()
    for uid in ("R1", "R2", "R3", "R4", "R5", "R6", "SYS1"):
        item = tree.find_item(uid)
        assert item.get("fretc_verdict") in ("satisfied", "violated", "not formalized")
        assert item.get("fretc_audit_id").startswith("sha256:")
        assert item.stamp() == before.find_item(uid).stamp()   # reviews stay valid
    assert tree.find_item("R4").get("fretc_verdict") == "satisfied"
    assert tree.find_item("R2").get("fretc_formula_pt").startswith("(H ")
    # doorstop's validation saved the items in its layout (keys sorted): exported again,
    # each item still holds one set of fretc's keys
    third = tmp_path / "third"
    assert _run("export", "-r", out, "--from-json", audits["doorstop"], "-o", third)[0] == 0
    r2 = (third / "r" / "R2.yml").read_text()
    assert r2.count("fretc_verdict:") == 1 and r2.count("fretc_formula_ft:") == 1
    assert doorstop.build(cwd=str(third), root=str(third)).validate()


def test_fret_export_gains_a_fretc_member_and_keeps_the_rest(audits, tmp_path):
    src = tmp_path / "fret.json"
    objs = [{"reqid": e.id, "project": "Safe-ROS", "fulltext": e.text,
             "semantics": {"ft": "kept"}} for e in load_requirements(
        [ROOT / "requirements" / "r1.fret", ROOT / "requirements" / "safe_ros.fret"])]
    src.write_text(json.dumps(objs, indent=4))
    out = tmp_path / "out.json"
    code, text = _run("export", "-r", src, "--from-json", audits["fret"], "-o", out)
    assert code == 0, text
    got = json.loads(out.read_text())
    assert [{k: v for k, v in o.items() if k != "fretc"} for o in got] == objs
    assert {o["reqid"]: o["fretc"]["verdict"] for o in got}["R4"] == "satisfied"
    assert out.read_text().startswith("[\n    {")


def test_matrix_lists_every_requirement_with_its_tool_id_and_flags_stale(audits, tmp_path):
    tree = tmp_path / "tree"
    shutil.copytree(DOORSTOP, tree)
    r4 = tree / "r" / "R4.yml"
    r4.write_text(r4.read_text().replace("linear_speed <= 0.5", "linear_speed <= 0.6"))
    matrix, page = tmp_path / "m.csv", tmp_path / "m.html"
    code, text = _run("export", "-r", tree, "--from-json", audits["doorstop"], "-o",
                      tmp_path / "out", "--matrix", matrix, "--matrix-html", page)
    assert code == 0 and "R4: stale evidence" in text
    rows = list(csv.DictReader(io.StringIO(matrix.read_text())))
    assert {r["requirement"] for r in rows} == {"R1", "R2", "R3", "R4", "R5", "R6", "SYS1"}
    assert len([r for r in rows if r["requirement"] == "R1"]) == 8   # one per run
    assert {r["requirement"] for r in rows if r["stale"] == "stale evidence"} == {"R4"}
    assert all(r["tool_id"] and r["monitor_hash"] for r in rows if r["requirement"] != "SYS1")
    html = page.read_text()
    assert "<script" not in html and html.count('<section class="order"') == 5
    assert 'href="#by-verdict"' in html


def test_export_of_a_hostile_source_writes_nothing(audits, tmp_path):
    bad = tmp_path / "bad.reqif"
    bad.write_text('<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "b">]>\n<REQ-IF/>\n')
    out = tmp_path / "out.reqif"
    code, text = _run("export", "-r", bad, "--from-json", audits["reqif"], "-o", out,
                      "--matrix", tmp_path / "m.csv")
    assert code == 2 and "DOCTYPE declaration refused" in text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.reqif"]
    full = tmp_path / "full"
    (full / "x").mkdir(parents=True)
    code, text = _run("export", "-r", DOORSTOP, "--from-json", audits["doorstop"], "-o", full)
    assert code == 2 and "not empty" in text and [p.name for p in full.iterdir()] == ["x"]


def test_report_has_the_matrix_page_with_every_tool_id(audits, tmp_path):
    out = tmp_path / "report"
    code, text = _run("report", "--from-json", audits["reqif"], "-o", out, "--base", ROOT)
    assert code == 1, text
    page = (out / "matrix.html").read_text()
    for e in load_requirements(REQIF):
        assert e.origin.tool_id in page
    assert 'href="matrix.html"' in (out / "report.html").read_text()
    rows = list(csv.DictReader(io.StringIO((out / "matrix.csv").read_text())))
    assert {r["stale"] for r in rows} == {""}       # the sources are as audited
    assert [r["verdict"] for r in rows if r["requirement"] == "SR-0"] == ["not formalized"]


def test_reqifz_export_rewrites_its_reqif_member_and_copies_the_others(audits, tmp_path):
    import zipfile

    src = tmp_path / "safe_ros.reqifz"
    with zipfile.ZipFile(src, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(REQIF, "safe_ros.reqif")
        z.writestr("attachments/readme.txt", b"kept as it is\n")
    out = tmp_path / "out.reqifz"
    code, text = _run("export", "-r", src, "--from-json", audits["reqif"], "-o", out)
    assert code == 0, text
    with zipfile.ZipFile(out) as z:
        assert z.namelist() == ["safe_ros.reqif", "attachments/readme.txt"]
        assert z.read("attachments/readme.txt") == b"kept as it is\n"
        assert _only_insertions(REQIF.read_text().splitlines(),
                                z.read("safe_ros.reqif").decode().splitlines())
    verdicts = load_requirements(out, text_attribute="fretc verdict")
    assert {e.id: e.text for e in verdicts}["R4"] == "satisfied"


def test_audit_of_a_hostile_reqif_is_an_input_error(tmp_path):
    bad = tmp_path / "laughs.reqif"
    bad.write_text('<?xml version="1.0"?>\n<!DOCTYPE l [<!ENTITY a "aaaa">'
                   '<!ENTITY b "&a;&a;&a;&a;">]>\n<REQ-IF>&b;</REQ-IF>\n')
    code, text = _run("audit", "-r", bad, "-b", BINDINGS, ROOT / "traces" / "nominal.mcap",
                      "--no-progress")
    assert code == 2 and "laughs.reqif:2:" in text and "DOCTYPE declaration refused" in text


def test_written_files_have_the_permissions_of_any_new_file(tmp_path):
    """Atomic writes go through mkstemp (0600): the result is made as open() would make it."""
    import os
    from fretc.reports.export_results import write_atomic

    old = os.umask(0o022)
    try:
        write_atomic(str(tmp_path / "out.txt"), b"x")
    finally:
        os.umask(old)
    assert (tmp_path / "out.txt").stat().st_mode & 0o777 == 0o644


MARKER_TEXT = "# fretc export: the results of an audit (replaced by the next fretc export)\n"
_VALID_ITEMS = {
    "user_fretc_key": "active: true\ntext: t\nfretc_notes: mine, not fretc's\n",
    "document_end": "active: true\ntext: t\n...\n",
    "flow_mapping": "{active: true, text: t, level: 1.1}\n",
    "marker_in_text": ("active: true\ntext: |\n  see\n  " + MARKER_TEXT + "  more\nlevel: 1\n"),
    "quoted_scalar": "active: true\ntext: \"a long\n  fretc_verdict: inside the quote\"\n",
    "no_final_newline": "active: true\ntext: t",
    "comments": "# a comment\nactive: true  # inline\ntext: t\n",
    "ours_moved": "active: true\nfretc_verdict: violated\ntext: t\n",
}


@pytest.mark.parametrize("name", sorted(_VALID_ITEMS))
def test_doorstop_export_of_any_valid_item_reads_back_as_its_keys_and_ours(name):
    """Five of eleven valid items were broken by the export: a user's own fretc_* key
    deleted, a '...' end and a flow mapping made unreadable, an item cut at the marker's
    text, a quoted scalar broken. Now each exported file reads back (PyYAML's safe loader,
    doorstop's) as the item's own keys and fretc's, exported twice the same."""
    import yaml

    from fretc.reports.export_doorstop import KEYS, _with_block
    from fretc.reports.export_results import RequirementResult

    raw = _VALID_ITEMS[name].encode()
    mine = yaml.safe_load(raw)
    result = RequirementResult(id="R1", tool_id="R1", verdict="satisfied",
                               evidence="e: 'x'\nline", ft="G p", pt="H p",
                               audit_id="sha256:1", audit_date="2026-11-24", runs=1)
    once = _with_block(raw, result)
    back = yaml.safe_load(once)
    ours = {k: str(getattr(result, f)) for k, f in KEYS if getattr(result, f) is not None}
    assert back == {**{k: v for k, v in mine.items() if k not in ours}, **ours}
    assert _with_block(once, result) == once


def test_reqif_export_stays_well_formed_keeps_id_references_and_is_idempotent(tmp_path):
    """Control characters in a value (a log's name in the evidence) made ill-formed XML;
    an IDENTIFIER written with ``&#9;`` came back with a space; exporting an export changed
    its bytes."""
    import defusedxml.ElementTree as ET

    from fretc.reports.export_reqif import export_reqif
    from fretc.reports.export_results import RequirementResult

    src = tmp_path / "tab.reqif"
    src.write_text(REQIF.read_text().replace("REQUIREMENT-714dc3bf",
                                             "REQ&#9;UIREMENT-714dc3bf"))

    def results(path):
        return {e.id: RequirementResult(
            id=e.id, tool_id=e.origin.tool_id, verdict="violated",
            evidence="log\x01name\x7f\x1b[31m\there\nnext", ft="G p", pt="H p",
            audit_id="sha256:1", audit_date="2026-11-24T00:00:00Z", runs=1)
            for e in load_requirements(path)}

    ids = sorted(e.origin.tool_id for e in load_requirements(src))
    assert any("\t" in i for i in ids)
    once, n = export_reqif(str(src), results(src))
    assert n == 6
    ET.fromstring(once)  # well-formed
    out = tmp_path / "once.reqif"
    out.write_bytes(once)
    assert sorted(e.origin.tool_id for e in load_requirements(out)) == ids
    twice, _ = export_reqif(str(out), results(out))
    assert twice == once


@pytest.mark.parametrize("mutate", ["logs_str", "verdict_list", "log_none", "ticks_str",
                                    "reqs_str", "deep"])
@pytest.mark.tor("TOR-VER-008")
def test_a_from_json_document_that_breaks_the_schema_is_an_input_error(audits, tmp_path,
                                                                        mutate):
    """18 internal errors (exit 4) of export and report on audit documents of the right
    schema name and the wrong shape; each is now an input error naming where it breaks."""
    doc = json.loads(Path(audits["reqif"]).read_text())
    bad = tmp_path / "bad.json"
    if mutate == "deep":
        bad.write_text("[" * 100_000 + "]" * 100_000)
    else:
        if mutate == "logs_str":
            doc["logs"] = "x"
        elif mutate == "verdict_list":
            doc["logs"][0]["verdicts"][0]["verdict"] = ["x"]
        elif mutate == "log_none":
            doc["logs"][0]["log"] = None
        elif mutate == "ticks_str":
            doc["logs"][0]["verdicts"][0]["ticks_evaluated"] = "many"
        else:
            doc["requirements"] = "x"
        bad.write_text(json.dumps(doc))
    for args in (["report", "--from-json", bad, "-o", tmp_path / "rep"],
                 ["export", "-r", REQIF, "--from-json", bad, "-o", tmp_path / "x.reqif"]):
        code, text = _run(*args)
        assert code == 2 and "internal error" not in text, (args[0], text)
        assert "bad.json" in text and ("$." in text or "nested too deeply" in text), text


@pytest.mark.parametrize("case", ["deep", "overflow", "surrogate"])
def test_fret_export_of_hostile_json(audits, tmp_path, case):
    """A FRET export nested 100,000 deep was an internal error; 1e999 was written back as
    Infinity (not JSON); a lone surrogate (\\ud800) was an internal error on writing."""
    src = tmp_path / "fret.json"
    obj = {"reqid": "R1", "project": "P", "fulltext": "the sw shall always satisfy p"}
    if case == "deep":
        src.write_text("[" * 100_000 + "]" * 100_000)
    elif case == "overflow":
        src.write_text(json.dumps([dict(obj, n=1)]).replace('"n": 1', '"n": 1e999'))
    else:
        src.write_text(json.dumps([dict(obj, note="\ud800")]))
    out = tmp_path / "out.json"
    code, text = _run("export", "-r", src, "--from-json", audits["fret"], "-o", out)
    assert "internal error" not in text
    if case == "surrogate":
        assert code == 0, text
        back = json.loads(out.read_text())
        assert back[0]["note"] == "\ud800" and back[0]["fretc"]["verdict"]
    else:
        assert code == 2 and not out.exists(), text
        assert case == "deep" or "1e999" in text


def test_a_log_name_that_is_not_utf8_is_written_escaped_in_every_output(tmp_path):
    """A log named with a byte that is not UTF-8 (``run\\xff.mcap``, and one that cannot be
    read, ``bad\\xfe.mcap``): its name reaches the audit JSON as a lone surrogate, and every
    export but ReqIF (needs.json, .sdoc, the matrix CSV and HTML) and the report stopped on
    it (UnicodeEncodeError, an internal error); each writes it as a visible escape."""
    import os
    import shutil

    logs = tmp_path / "logs"
    logs.mkdir()
    try:
        shutil.copy(ROOT / "traces" / "stop_delay.mcap",
                    os.fsdecode(bytes(logs) + b"/run\xff.mcap"))
        (logs / os.fsdecode(b"bad\xfe.mcap")).write_bytes(b"junk")
    except (OSError, UnicodeError):
        pytest.skip("the file system does not take names that are not UTF-8")
    doc = tmp_path / "a.json"
    code, _ = _run("audit", "-r", REQIF, "-b", BINDINGS, logs, "--json", doc, "--no-progress")
    assert code == 2
    outs = {"--needs": "n.json", "--sdoc": "r.sdoc", "--matrix": "m.csv",
            "--matrix-html": "m.html", "-o": "out.reqif"}
    for flag, name in outs.items():
        code, text = _run("export", "-r", REQIF, "--from-json", doc, flag, tmp_path / name)
        assert code == 0 and "internal error" not in text, (flag, text)
        data = (tmp_path / name).read_bytes().decode("utf-8")  # valid UTF-8
        if flag.startswith("--matrix"):  # the matrix names every log
            assert "bad\\xfe.mcap" in data, flag
    code, text = _run("report", "-r", REQIF, "--from-json", doc, "-o", tmp_path / "rep")
    assert "internal error" not in text and (tmp_path / "rep" / "report.html").exists(), text
    assert "bad\\xfe.mcap" in (tmp_path / "rep" / "matrix.csv").read_text(encoding="utf-8")


HOSTILE_IDS = ["R1", "R1-1", "R#2", "R$2", "A\u202eB", "L\u2028M", "C\x07D", "[[copy('id')]]"]


def test_hostile_ids_keep_their_links_in_junit_needs_and_sdoc(tmp_path):
    """StrictDoc: ``R1``'s first run and ``R1-1``'s verification got one UID, ``R#2`` and
    ``R$2`` collided, an id outside StrictDoc's UID pattern lost its Parent silently;
    needs.json kept raw the ids JUnit's ``verifies`` escapes (the link broke), and ``[[``
    went unescaped into sphinx-needs (a dynamic function call)."""
    import re
    import xml.etree.ElementTree as ET

    reqs = tmp_path / "r.json"
    reqs.write_text(json.dumps([{"reqid": i, "fulltext": f"the sw shall always satisfy p{k}"}
                                for k, i in enumerate(HOSTILE_IDS)]))
    trace = tmp_path / "t.csv"
    trace.write_text(",".join(f"p{k}" for k in range(len(HOSTILE_IDS))) + "\n"
                     + ",".join("true" for _ in HOSTILE_IDS) + "\n")
    doc, junit = tmp_path / "a.json", tmp_path / "j.xml"
    code, out = _run("audit", "-r", reqs, trace, "--json", doc, "--junit", junit,
                     "--no-progress")
    assert code == 0, out
    code, out = _run("export", "--from-json", doc, "--needs", tmp_path / "n.json", "--sdoc",
                     tmp_path / "r.sdoc")
    assert code == 0, out
    for rid in ("A\u202eB", "L\u2028M", "C\x07D", "[[copy('id')]]"):
        assert f"note: {tmp_path / 'r.sdoc'}: {rid!r}".encode("unicode_escape").decode() \
            in out.encode("unicode_escape").decode(), out
    verifies = {p.get("value") for p in ET.parse(junit).iter("property")
                if p.get("name") == "verifies"}
    needs = json.loads((tmp_path / "n.json").read_text())["versions"]["1.0"]["needs"]
    assert set(needs) == verifies and len(verifies) == len(HOSTILE_IDS)
    assert all("[[" not in str(v) for n in needs.values() for k, v in n.items() if k != "id")
    uids = re.findall(r"^UID: (.*)$", (tmp_path / "r.sdoc").read_text(), re.M)
    assert len(uids) == len(set(uids)) == 2 * len(HOSTILE_IDS)  # a verification, a run


def test_a_carriage_return_in_an_id_stays_in_its_matrix_row(tmp_path):
    """A CR in a requirement id (a FRET export's reqid) split its row of the matrix CSV."""
    reqs = tmp_path / "r.json"
    reqs.write_text(json.dumps([{"reqid": "A\rB", "fulltext": "the sw shall always satisfy p"},
                                {"reqid": "C", "fulltext": "the sw shall always satisfy p"}]))
    (tmp_path / "t.csv").write_text("p\ntrue\n")
    doc = tmp_path / "a.json"
    assert _run("audit", "-r", reqs, tmp_path / "t.csv", "--json", doc, "--no-progress")[0] == 0
    assert _run("export", "--from-json", doc, "--matrix", tmp_path / "m.csv")[0] == 0
    with open(tmp_path / "m.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    assert [r[0] for r in rows[1:]] == ["A\rB", "C"], rows


def test_the_audit_json_of_a_csv_without_bindings_reads_back(tmp_path):
    """fretc's own audit JSON of a CSV trace judged without bindings (``tick_time_base``
    ``"csv"``) with a violation: ``report`` and ``export --from-json`` read it; a document
    that does break the schema is refused naming the failing member and value, not the
    whole instance around it."""
    (tmp_path / "r.fret").write_text("@tick_period 1 s\nA2: in m the sw shall always satisfy y\n")
    (tmp_path / "t.csv").write_text("m,y\ntrue,true\ntrue,false\n")
    out = tmp_path / "a.json"
    res = CliRunner().invoke(main, ["audit", "-r", str(tmp_path / "r.fret"), str(tmp_path / "t.csv"),
                                    "--json", str(out), "--no-progress"])
    assert res.exit_code == 1, res.output
    doc = json.loads(out.read_text())
    assert doc["logs"][0]["verdicts"][0]["first_violation"]["tick_time_base"] == "csv"
    res = CliRunner().invoke(main, ["report", "-r", str(tmp_path / "r.fret"), "--from-json",
                                    str(out), "-o", str(tmp_path / "rep")])
    assert res.exit_code == 1 and (tmp_path / "rep" / "report.html").exists(), res.output
    doc["logs"][0]["verdicts"][0]["first_violation"]["tick_time_base"] = "sideways"
    out.write_text(json.dumps(doc))
    res = CliRunner().invoke(main, ["report", "-r", str(tmp_path / "r.fret"), "--from-json",
                                    str(out), "-o", str(tmp_path / "rep2")])
    assert res.exit_code == 2
    assert "$.logs[0].verdicts[0].first_violation.tick_time_base: 'sideways' is not one of" \
        in res.output, res.output
    assert "scope_interval" not in res.output  # the instance around it is not dumped
