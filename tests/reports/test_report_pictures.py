"""The report's pictures a reviewer keeps: every timeline captioned with requirement, run and
verdict inside the SVG; the worst margin drawn on the margin plot at the time the audit gives;
matrix.html with the verdict near the left (a 1,400 px window shows it, checked in headless
Chromium) and each requirement's formula and hash once; the check section (``--check``)
before the footer, linked from the top, with every finding, one that no requirement row
lists by index included."""

from __future__ import annotations

import importlib.util
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]
X = "{http://www.w3.org/1999/xhtml}"
SVG = "{http://www.w3.org/2000/svg}"


def _check_doc() -> dict:
    """A check document whose unrealizable finding is named by no requirement row's
    ``findings`` index (as ``fretc check`` writes R5's), and a vacuity finding that is."""
    reqs = [{"id": f"R{i}", "source": "requirements/safe_ros.fret", "line": i, "text": "",
             "satisfiable": True, "non_vacuous": i != 3, "redundant": False,
             "findings": [1] if i == 3 else []} for i in range(1, 7)]
    return {"tool": "fretc check", "semantics": "ft_inf", "exit_code": 1,
            "requirements": reqs,
            "findings": [
                {"kind": "unrealizable", "severity": "error", "requirements": ["R5"],
                 "message": "no controller meets R5 whatever the inputs (clearance) do",
                 "subsets": [["R5"]], "witness": None,
                 "details": {"environment": {"prefix": [{"clearance": -1.0}],
                                             "cycle": [{"clearance": -1.0}]}}},
                {"kind": "vacuous", "severity": "warning", "requirements": ["R3"],
                 "message": "R3 holds vacuously", "witness": "w/r3.csv", "details": {}}],
            "realizability": {"groups": [{"requirements": ["R5"], "realizable": False,
                                          "method": "safety game"}]},
            "notes": ["a note"], "input_errors": []}


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    if not (ROOT / "traces" / "nominal.mcap").exists():
        pytest.skip("traces/ not recorded")
    tmp = tmp_path_factory.mktemp("pictures")
    check = tmp / "check.json"
    check.write_text(json.dumps(_check_doc()))
    out = tmp / "report"
    res = CliRunner().invoke(main, ["report", "-r", str(ROOT / "requirements"),
                                    str(ROOT / "traces"), "-o", str(out), "--check",
                                    str(check)], catch_exceptions=False)
    assert res.exit_code == 1, res.output
    html = (out / "report.html").read_text(encoding="utf-8")
    return {"out": out, "html": html, "tree": ET.fromstring(html),
            "doc": json.loads((out / "audit.json").read_text())}


def test_every_timeline_is_captioned_inside_its_svg(report):
    doc = report["doc"]
    violated = {(v["requirement"], la["log"]): v for la in doc["logs"]
                for v in la["verdicts"] if v["verdict"] == "violated"}
    files = sorted((report["out"] / "timelines").glob("*.svg"))
    assert len(files) == len(violated) > 0
    seen = set()
    for p in files:
        root = ET.fromstring(p.read_text(encoding="utf-8"))
        req, log = root.get("data-requirement"), root.get("data-log")
        v = violated[(req, log)]
        first = next(root.iter(f"{SVG}text"))
        assert first.get("class") == "caption"
        cap = first.text
        assert cap.startswith(f"{req} violated on run {log}: ")
        assert f"{v['first_violation']['tick_time_s']:.3f} s on the log clock" in cap
        seen.add((req, log))
    assert seen == set(violated)


def test_the_worst_margin_lies_on_the_plotted_line(report):
    doc, html = report["doc"], report["html"]
    marks = re.findall(r'<circle [^>]*data-mark="worst"[^>]*>', html)
    finite = [(la["log"], v["robustness"]) for la in doc["logs"] for v in la["verdicts"]
              if isinstance((v.get("robustness") or {}).get("value"), float)]
    assert finite and len(marks) == len(finite)
    got = {(re.search(r'data-log="([^"]*)"', m).group(1),
            float(re.search(r'data-time-s="([^"]*)"', m).group(1)),
            float(re.search(r'data-value="([^"]*)"', m).group(1))) for m in marks}
    for log, rob in finite:
        assert (Path(log).name, rob["time_s"], rob["value"]) in got
    # and the run's row says it, on the log clock
    for _log, rob in finite:
        assert f"at tick {rob['tick']} ({rob['time_s']:.3f} s)" in html


def test_check_section_before_the_footer_with_every_finding(report):
    html, tree = report["html"], report["tree"]
    sec = next(e for e in tree.iter(f"{X}section") if e.get("id") == "check-findings")
    assert html.index('id="check-findings"') < html.index("<footer")
    toc = next(e for e in tree.iter(f"{X}nav"))
    assert any(a.get("href") == "#check-findings" for a in toc.iter(f"{X}a"))
    kinds = {tr.get("data-kind"): "".join(tr.itertext()) for tr in sec.iter(f"{X}tr")
             if tr.get("data-kind")}
    assert set(kinds) == {"unrealizable", "vacuous"}
    assert "R5" in kinds["unrealizable"] and '[{"clearance": -1.0}]' in kinds["unrealizable"]
    rows = {tr.get("data-requirement"): "".join(tr.itertext()) for tr in sec.iter(f"{X}tr")
            if tr.get("data-requirement")}
    assert "unrealizable #0" in rows["R5"] and "vacuous #1" in rows["R3"]
    assert "unrealizable" not in rows["R1"]
    md = (report["out"] / "report.md").read_text(encoding="utf-8")
    assert md.index("## Check findings") > md.index("## Generated monitor modules")
    assert "| 0 | unrealizable | error | R5 |" in md
    matrix = (report["out"] / "matrix.csv").read_text()
    assert "unrealizable: no controller meets R5" in matrix


def test_matrix_puts_the_verdict_left_and_each_formula_once(report):
    page = (report["out"] / "matrix.html").read_text(encoding="utf-8")
    doc = report["doc"]
    first = page.split('<section class="order"', 1)[1].split("</section>", 1)[0]
    heads = re.findall(r"<th>(?:<a [^>]*>)?([^<]*)", first)
    assert heads.index("verdict") <= 2
    assert "monitor hash" not in heads and "formalization" not in heads
    for r in doc["requirements"]:
        assert page.count(r["ft"].replace("&", "&amp;").replace("<", "&lt;")
                          .replace(">", "&gt;")) == 1
        assert page.count(r["source_hash"]) == 1


def _bench():
    spec = importlib.util.spec_from_file_location("screenshot_report",
                                                  ROOT / "bench" / "screenshot_report.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


MEASURE = """<script>//<![CDATA[
window.addEventListener('load', function () {
  var W = document.documentElement.clientWidth, out = {width: W,
      scroll: document.documentElement.scrollWidth, verdicts: []};
  document.querySelectorAll('td.verdict').forEach(function (e) {
    var r = e.getBoundingClientRect(); if (r.width) out.verdicts.push(r.right); });
  var p = document.createElement('pre'); p.id = 'm'; p.textContent = JSON.stringify(out);
  document.body.appendChild(p); });
//]]></script>"""


def test_matrix_verdicts_visible_at_1400_px_in_chromium(report, tmp_path):
    bench = _bench()
    if bench.chromium() is None:
        pytest.skip("chromium not installed (apt-get install -y chromium)")
    page = (report["out"] / "matrix.html").read_text(encoding="utf-8")
    copy = tmp_path / "matrix.html"
    copy.write_text(page.replace("</body>", MEASURE + "</body>"), encoding="utf-8")
    dom, console = bench.dump_dom(copy, 1400, 900)
    assert not console, console
    m = json.loads(re.search(r'<pre id="m">(.*?)</pre>', dom, re.S).group(1)
                   .replace("&quot;", '"'))
    assert m["verdicts"], "no verdict cell laid out"
    assert m["scroll"] <= m["width"], m          # no horizontal scrolling
    assert max(m["verdicts"]) <= m["width"], m


def test_a_check_file_that_is_not_one_exits_2_naming_it(report, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"tool": "something else"}')
    res = CliRunner().invoke(main, ["report", "--from-json", str(report["out"] / "audit.json"),
                                    "-o", str(tmp_path / "r"), "--base", str(ROOT),
                                    "--check", str(bad)])
    assert res.exit_code == 2 and f"--check {bad}" in res.output
