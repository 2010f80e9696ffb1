"""fretc's verdicts where engineers read them: the JUnit properties (read by sphinx-test-reports'
own JUnit parser), ``fretc export --needs`` (checked by sphinx-needs' own needs.json schema),
``--sdoc`` (read by StrictDoc's own reader, its relations resolved by ``strictdoc export``
beside the Safe-ROS StrictDoc document), the Sphinx project of docs/guide/traceability.md built
with sphinx-needs + sphinx-test-reports on the Safe-ROS audit, and the roll-up to parents in
the ReqIF, Doorstop and FRET exports."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from _shared import cli

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "fixtures" / "requirements_tools"
REQIF = FIX / "strictdoc" / "safe_ros.reqif"
SDOC = FIX / "strictdoc" / "safe_ros.sdoc"
DOORSTOP = FIX / "doorstop"
BINDINGS = ROOT / "requirements" / "safe_ros.bindings.toml"
PAGE = ROOT / "docs" / "guide" / "traceability.md"
pytestmark = pytest.mark.skipif(not (ROOT / "traces" / "nominal.mcap").exists(),
                                reason="traces/ is absent")


_run = cli


@pytest.fixture(scope="module")
def audit(tmp_path_factory):
    """The Safe-ROS audit of traces/ from StrictDoc's ReqIF: JSON, JUnit, needs.json, .sdoc."""
    out = tmp_path_factory.mktemp("traceability")
    code, text = _run("audit", "-r", REQIF, "-b", BINDINGS, ROOT / "traces", "--json",
                      out / "audit.json", "--junit", out / "junit.xml", "--no-progress")
    assert code == 1, text                      # traces/ holds violations
    code, text = _run("export", "--from-json", out / "audit.json", "--needs",
                      out / "needs.json", "--sdoc", out / "results.sdoc", "--audit-date",
                      "2026-01-02")
    assert code == 0, text
    return out


def _doc(audit) -> dict:
    return json.loads((audit / "audit.json").read_text())


def test_every_test_case_carries_its_properties(audit):
    doc = _doc(audit)
    tool = {r["id"]: r["origin"]["tool_id"] for r in doc["requirements"]}
    want = {(la["log"], v["requirement"]): v for la in doc["logs"] for v in la["verdicts"]}
    root = ET.parse(audit / "junit.xml").getroot()
    seen = 0
    for suite in root.iter("testsuite"):
        for case in suite.iter("testcase"):
            props = {p.get("name"): p.get("value") for p in case.find("properties")}
            v = want[(props["log"], case.get("name"))]
            assert props["verifies"] == case.get("name") == v["requirement"]
            assert props["tool"] == "reqif" and props["tool_id"] == tool[v["requirement"]]
            assert props["verdict"] == v["verdict"]
            assert props["vacuous"] == str(v["verdict"] == "vacuous").lower()
            rob = v["robustness"]["value"]
            assert float(props["robustness"]) == (float("inf") if rob == "inf" else
                                                  float("-inf") if rob == "-inf" else rob)
            fv = v.get("first_violation")
            if v["verdict"] == "violated":
                assert int(props["first_violation_log_time_ns"]) == fv["log_time_ns"]
                assert float(props["first_violation_s"]) == pytest.approx(fv["tick_time_s"])
            else:
                assert "first_violation_log_time_ns" not in props
            seen += 1
    assert seen == len(want) == 48


def test_sphinx_test_reports_own_parser_reads_the_properties(audit):
    parser = pytest.importorskip("ub_test_reports.junitparser",
                                 reason="sphinx-test-reports is not installed")
    suites = parser.JUnitParser(str(audit / "junit.xml")).parse()
    cases = [c for s in suites for c in s["testcases"]]
    assert len(cases) == 48
    assert all(c["properties"]["verifies"] == c["name"] for c in cases)
    failed = {(c["properties"]["log"].rsplit("/", 1)[-1], c["name"]) for c in cases
              if c["result"] == "failed"}
    assert ("stop_delay.mcap", "R2") in failed


def test_needs_json_passes_sphinx_needs_schema_and_carries_the_verdicts(audit):
    needsfile = pytest.importorskip("sphinx_needs.needsfile",
                                    reason="sphinx-needs is not installed")
    data = json.loads((audit / "needs.json").read_text())
    assert not needsfile.check_needs_data(data).schema
    needs = data["versions"][data["current_version"]]["needs"]
    assert list(needs) == ["R1", "R2", "R3", "R4", "R5", "R6", "SR-0"]
    assert needs["R4"]["status"] == "satisfied" and needs["R2"]["status"] == "violated"
    assert needs["R2"]["links"] == ["R1"] and needs["R1"]["links"] == ["SR-0"]
    assert needs["SR-0"]["fretc_rollup"] == "violated"
    assert needs["SR-0"]["fretc_rollup_path"].startswith("violated via SR-0 > ")
    assert needs["R2"]["fretc_verdicts"].count(": ") == 8
    assert data["created"] == "2026-01-02T00:00:00Z"


def test_sdoc_reads_back_with_strictdoc_and_its_relations_resolve(audit, tmp_path):
    pytest.importorskip("strictdoc", reason="strictdoc is not installed")
    from strictdoc.backend.sdoc.reader import SDReader

    text = (audit / "results.sdoc").read_text()
    document = SDReader.read(text, str(audit / "results.sdoc"))
    nodes = list(document.section_contents)
    assert [n.node_type for n in nodes].count("VERIFICATION") == 7
    assert [n.node_type for n in nodes].count("TEST_RESULT") == 48
    parents = {r.ref_uid for n in nodes for r in n.relations}
    assert parents == {"R1", "R2", "R3", "R4", "R5", "R6", "SR-0"}
    # beside the requirements' own StrictDoc document, strictdoc resolves every relation
    project = tmp_path / "docs"
    project.mkdir()
    shutil.copy(SDOC, project / "safe_ros.sdoc")
    shutil.copy(audit / "results.sdoc", project / "results.sdoc")
    exported = _strictdoc_json(project, tmp_path / "out")
    results = next(d for d in exported["DOCUMENTS"] if d["TITLE"] == "fretc audit results")
    failed = {n["TITLE"] for n in results["NODES"] if n.get("STATUS") == "FAILED"
              and n["_NODE_TYPE"] == "TEST_RESULT"}
    assert any(t.startswith("R2 on ") and t.endswith("stop_delay.mcap") for t in failed)
    # and a result whose requirement is not in the project is refused by StrictDoc
    (project / "results.sdoc").write_text(text.replace("VALUE: R4", "VALUE: NOT-THERE", 1))
    with pytest.raises(AssertionError, match="NOT-THERE"):
        _strictdoc_json(project, tmp_path / "out2")


def _strictdoc_json(project: Path, out: Path) -> dict:
    exe = shutil.which("strictdoc", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("the strictdoc command is not installed")
    r = subprocess.run([exe, "export", str(project), "--formats", "json", "--output-dir",
                        str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return json.loads((out / "json" / "index.json").read_text())


def _page_blocks() -> tuple[str, str]:
    """The conf.py and the page of docs/guide/traceability.md."""
    page = PAGE.read_text()
    conf = re.search(r"```python\n(# conf\.py: fretc.*?)```", page, re.S).group(1)
    rst = re.search(r"```rst\n(.*?)```", page, re.S).group(1)
    return conf, rst


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # Sphinx 9's, in sphinx-needs
@pytest.mark.filterwarnings("ignore::PendingDeprecationWarning")
def test_the_documented_sphinx_project_shows_each_requirement_with_its_verdicts(audit,
                                                                               tmp_path):
    pytest.importorskip("sphinx_needs", reason="sphinx-needs is not installed")
    pytest.importorskip("sphinx_test_reports", reason="sphinx-test-reports is not installed")
    from sphinx.cmd.build import build_main

    conf, rst = _page_blocks()
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text('project = "Safe-ROS"\nneeds_build_json = True\n' + conf)
    (src / "index.rst").write_text(rst)
    shutil.copy(audit / "needs.json", src / "needs.json")
    shutil.copy(audit / "junit.xml", src / "junit.xml")
    out = tmp_path / "html"
    assert build_main(["-b", "html", "-q", "-W", "--keep-going", str(src), str(out)]) == 0
    built = json.loads((out / "needs.json").read_text())
    needs = built["versions"][built["current_version"]]["needs"]
    doc = _doc(audit)
    want = {(la["log"], v["requirement"]): v["verdict"] for la in doc["logs"]
            for v in la["verdicts"]}
    for rid in ("R1", "R2", "R3", "R4", "R5", "R6"):
        cases = [needs[c] for c in needs[rid]["verifies_back"]]
        assert len(cases) == 8                        # one per run, each linked
        assert {(c["log"], rid): c["verdict"] for c in cases} == \
            {k: v for k, v in want.items() if k[1] == rid}
        assert needs[rid]["fretc_verdict"] == needs[rid]["status"]
    assert needs["SR-0"]["fretc_rollup"] == "violated"
    html = (out / "index.html").read_text()
    assert "SR-0" in html and "violated via SR-0" in html


def test_parents_get_the_rolled_up_verdict_in_every_export(audit, tmp_path):
    from fretc.fretish.files import load_requirements

    out = tmp_path / "out.reqif"
    assert _run("export", "-r", REQIF, "--from-json", audit / "audit.json", "-o", out)[0] == 0
    rolled = {e.id: e.text for e in load_requirements(out,
                                                      text_attribute="fretc rolled-up verdict")}
    assert rolled == {"R1": "violated", "SR-0": "violated"}    # the parents only
    data = out.read_text()
    assert "violated via SR-0 &gt; R1 (R1 violated)" in data
    code, _ = _run("audit", "-r", DOORSTOP, "-b", BINDINGS, ROOT / "traces" / "stop_delay.mcap",
                   "--json", tmp_path / "d.json", "--no-progress")
    assert code == 1
    tree = tmp_path / "tree"
    assert _run("export", "-r", DOORSTOP, "--from-json", tmp_path / "d.json", "-o", tree)[0] == 0
    import doorstop

    t = doorstop.build(cwd=str(tree), root=str(tree))
    assert t.find_item("SYS1").get("fretc_rollup") == "violated"
    assert t.find_item("SYS1").get("fretc_rollup_path").startswith("violated via SYS1 > R")
    assert t.find_item("R2").get("fretc_rollup") is None
