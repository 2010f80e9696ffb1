"""fretc report (reports, reports.timeline, audit.annotate): the traceability report
of the shipped Safe-ROS runs checked cell by cell and witness by witness against the audit's
JSON; requirement -> formulas -> monitor -> AJPF traced against an independent compilation;
determinism; annotated MCAP copies read back with ``mcap``; a synthetic run with a mode scope,
a missing topic and a damaged (truncated) copy; the timeline SVG; headless Chromium (skipped
when absent)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import xml.etree.ElementTree as ET
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner
from mcap.reader import make_reader
from mcap.writer import CompressionType

from fretc.cli import main
from fretc.audit.annotate import FOXGLOVE_LOG_SCHEMA, VERDICT_TOPIC, verdict_events
from fretc.reports.context import GENERATED_PREFIX

from test_report_pictures import _bench
from _logs import MS, SYN_BINDINGS as _SYN_BINDINGS, boolean, float64, scan, twist, write_mcap

ROOT = Path(__file__).resolve().parents[2]
TRACES = ROOT / "traces"
REQS = ROOT / "requirements"
X = "{http://www.w3.org/1999/xhtml}"
SVG = "{http://www.w3.org/2000/svg}"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def _strip_generated(text: str) -> str:
    return "\n".join(l for l in text.splitlines() if GENERATED_PREFIX not in l)


def _by_id(tree):
    return {e.get("id"): e for e in tree.iter() if e.get("id")}


def _text(e) -> str:
    return "".join(e.itertext())


# --------------------------------------------------------------------------- shipped runs
@pytest.fixture(scope="module")
def shipped(tmp_path_factory):
    if not (TRACES / "nominal.mcap").exists():
        pytest.skip("traces/ not recorded")
    tmp = tmp_path_factory.mktemp("report")
    out, ann = tmp / "report", tmp / "annotated"
    res = run("report", "-r", REQS, TRACES, "-o", out, "--annotate", ann)
    doc = json.loads((out / "audit.json").read_text())
    html = (out / "report.html").read_text(encoding="utf-8")
    tree = ET.fromstring(html)          # the page is well-formed XHTML
    return {"res": res, "out": out, "ann": ann, "doc": doc, "html": html, "tree": tree,
            "ids": _by_id(tree), "md": (out / "report.md").read_text(encoding="utf-8")}


def test_report_files_and_exit_code(shipped):
    res, out, doc = shipped["res"], shipped["out"], shipped["doc"]
    assert res.exit_code == doc["summary"]["exit_code"] == 1      # the traces hold violations
    assert doc["schema"] == "fretc-audit/1"
    violated = [(la["log"], v["requirement"]) for la in doc["logs"] for v in la["verdicts"]
                if v["verdict"] == "violated"]
    assert len(violated) == 7
    assert len(list((out / "timelines").glob("*.svg"))) == len(violated)
    # self-contained: no script, no external asset, no link off the page but the annotated logs
    html = shipped["html"]
    assert "<script" not in html and "@import" not in html
    urls = set(re.findall(r'(?:src|href)="([^"#][^"]*)"', html))
    # (and the matrix page written beside it, matrix.html)
    assert all(u == "matrix.html" or (u.startswith("../annotated/") and u.endswith(".mcap"))
               for u in urls), urls
    assert set(re.findall(r"https?://[^\"' )]+", html)) <= {"http://www.w3.org/1999/xhtml",
                                                          "http://www.w3.org/2000/svg"}


def test_matrix_cells_match_the_audit_json(shipped):
    doc, ids = shipped["doc"], shipped["ids"]
    rows = shipped["tree"].find(f".//{X}table[@class='matrix']/{X}tbody").findall(f"{X}tr")
    assert len(rows) == len(doc["requirements"])
    for i, r in enumerate(doc["requirements"]):
        assert rows[i].get("id") == f"row-{i}" and r["id"] in _text(rows[i])
        for j, la in enumerate(doc["logs"]):
            v = la["verdicts"][i]
            assert v["requirement"] == r["id"]
            cell = ids[f"cell-{i}-{j}"]
            assert cell.get("data-verdict") == v["verdict"]
            assert cell.get("data-partial") == ("true" if v["partial"] else "false")
            text = _text(cell)
            assert text.startswith(v["verdict"])
            link = cell.find(f"{X}a").get("href")
            assert link[1:] in ids, link              # every cell links to its detail
            if v["verdict"] == "violated":
                fv = v["first_violation"]
                assert f"@ {fv['tick_time_s']:.3f} s" in text
                assert int(cell.get("data-log-time-ns")) == fv["log_time_ns"]
                assert ids[link[1:]].get("class") == "violation"
            else:
                assert "@" not in text
    # the README's expected verdicts for the shipped runs, as the matrix shows them
    cell = {(la["log"].rsplit("/", 1)[-1], v["requirement"]): ids[f"cell-{i}-{j}"]
            for j, la in enumerate(doc["logs"]) for i, v in enumerate(la["verdicts"])}
    assert cell[("sif_disabled.mcap", "R5")].get("data-log-time-ns") == "1700000015200000000"
    assert cell[("lidar_dropout.mcap", "R6")].get("data-verdict") == "violated"
    assert cell[("nominal.mcap", "R6")].get("data-verdict") == "vacuous"


def test_every_witness_time_matches_the_audit_json(shipped):
    doc, ids = shipped["doc"], shipped["ids"]
    seen = 0
    for j, la in enumerate(doc["logs"]):
        for i, v in enumerate(la["verdicts"]):
            row = ids[ids[f"cell-{i}-{j}"].find(f"{X}a").get("href")[1:]]
            if v["verdict"] != "violated":
                # the per-run row of the requirement: verdict, LTL3, trigger counts
                t = _text(row)
                assert v["verdict"] in t and f"LTL3 (ft_inf): {v['ltl3']['status']}" in t
                if v["triggers"] is not None:
                    assert f"triggers: {v['triggers']} in {v['intervals']} scope" in t
                continue
            seen += 1
            fv, l3 = v["first_violation"], v["ltl3"]
            sec = row
            assert sec.get("data-requirement") == v["requirement"]
            assert sec.get("data-log") == la["log"]
            assert int(sec.get("data-violation-ns")) == fv["log_time_ns"]
            assert int(sec.get("data-trigger-ns")) == fv["trigger"]["time_ns"]
            assert sec.get("data-ltl3-status") == l3["status"]
            if l3["time_ns"] is not None:
                assert int(sec.get("data-ltl3-ns")) == l3["time_ns"]
            t = _text(sec)
            assert (f"tick {fv['tick']} at {fv['tick_time_s']:.3f} s on the "
                    f"{fv['tick_time_base']} clock") in t
            tr = fv["trigger"]
            assert f"tick {tr['tick']} at {tr['time_s']:.3f} s" in t
            # one time base: the witness names no absolute log time (the run does, once)
            facts = _text(sec.find(f"{X}dl"))
            assert str(fv["log_time_ns"]) not in facts and str(tr["time_ns"]) not in facts
            assert f"log time {la['start_time_ns']} ns" in _text(
                ids[sec.find(f"{X}h3").findall(f"{X}a")[1].get("href")[1:]])
            sc, w = fv["scope_interval"], fv["window"]
            assert (f"ticks [{sc['start']['tick']}, {sc['end']['tick']}] = "
                    f"{sc['start']['time_s']:.3f} s .. {sc['end']['time_s']:.3f} s") in t
            assert f"ticks [{w['start_tick']}, {w['end_tick']}] = {w['start_time_s']:.3f} s" in t
            assert fv["reason"] in t and fv["obligation"] in t
            # the timeline: markers at the JSON's times
            svg = sec.find(f".//{SVG}svg")
            marks = {}
            for e in svg.iter():
                if e.get("data-mark") and e.get("data-ns"):
                    marks.setdefault(e.get("data-mark"), set()).add(int(e.get("data-ns")))
            assert marks["violation"] == {fv["tick_time_ns"]}  # the tick's time
            assert marks["trigger"] == {tr["time_ns"]}
            assert marks["scope"] == {sc["start"]["time_ns"]}
            assert marks["window"] == {w["start_time_ns"]}
            if l3["status"] == "violated":
                assert marks["ltl3"] == {l3["time_ns"]}
            held = {r["message_log_time_ns"] for rows in v["sources"].values() for r in rows
                    if r["message_log_time_ns"] is not None}
            assert marks["message"] <= held and marks["message"]
            # the sampled values: every (tick, time, value) of the JSON, in order
            table = sec.find(f".//{X}table[@class='values']")
            heads = [_text(h) for h in table.find(f"{X}thead").iter(f"{X}th")]
            trs = table.find(f"{X}tbody").findall(f"{X}tr")
            for name, vals in v["values"].items():
                col = heads.index(name)
                got = [(int(tr_.get("data-tick")), int(tr_.get("data-time-ns")),
                        json.loads(tr_.findall(f"{X}td")[col].get("data-v"))) for tr_ in trs]
                assert got == [(x["tick"], x["time_ns"], x["value"]) for x in vals]
            for topic, vals in v["sources"].items():
                col = heads.index(f"{topic} @")
                got = [json.loads(tr_.findall(f"{X}td")[col].get("data-v")) for tr_ in trs]
                assert got == [x["message_log_time_ns"] for x in vals]
            marked = {int(tr_.get("data-tick")): _text(tr_.findall(f"{X}td")[-1]) for tr_ in trs}
            assert "violation" in marked[fv["tick"]] and "trigger" in marked[tr["tick"]]
    assert seen == doc["summary"]["violated"]


def test_timeline_files_are_the_inlined_svgs(shipped):
    html = shipped["html"]
    for p in sorted((shipped["out"] / "timelines").glob("*.svg")):
        svg = p.read_text(encoding="utf-8")
        ET.fromstring(svg)
        assert svg.strip() in html
        assert f'id="{p.stem}"' in html


def test_requirements_are_traced_to_formulas_monitor_and_ajpf(shipped):
    """Against an independent compilation of the requirement files."""
    from fretc.compiler.ajpf import psl_label_and_formula
    from fretc.compiler.build import compile_entries
    from fretc.compiler.codegen import emit_monitors
    from fretc.fretish.files import load_requirements

    doc, ids = shipped["doc"], shipped["ids"]
    # the bindings tick every 100 ms: the period of a file that declares none (r1.fret)
    compiled = {c.id: c for c in compile_entries(
        [e if e.tick_period is not None else dataclasses.replace(e, tick_period=Fraction(1, 10))
         for e in load_requirements([REQS])])}
    modules = emit_monitors(list(compiled.values()))
    for r in doc["requirements"]:
        c = compiled[r["id"]]
        sec = next(e for e in shipped["tree"].iter(f"{X}section")
                   if e.get("data-requirement") == r["id"] and e.get("class") == "req")
        # the FRETish text with its fields marked from the AST spans
        box = sec.find(f"{X}div[@class='fretish']")
        assert "".join(t for t in box.itertext() if t not in
                       ("scope", "condition", "component", "timing", "response")) == c.text
        fields = {m.get("data-field"): "".join(m.text or "") for m in box.iter(f"{X}mark")}
        req = c.requirement
        assert fields["component"] == c.text[req.component_span.start:req.component_span.end]
        assert fields["response"] == c.text[req.response_span.start:req.response_span.end]
        assert fields.get("timing") == c.text[req.timing.span.start:req.timing.span.end]
        t = _text(sec)
        assert c.formalization.key in t
        for which in ("ft", "ft_inf", "pt"):
            pre = sec.find(f".//{X}pre[@data-formula='{which}']")
            assert pre.text == c.smv_text[which]
        hashes = {e.get("data-hash"): e.text for e in sec.iter(f"{X}code") if e.get("data-hash")}
        assert hashes["source"] == c.source_hash
        stem = "r1_monitors" if r["id"] == "R1" else "safe_ros_monitors"
        assert hashes["module"] == hashlib.sha256(modules[stem].encode()).hexdigest()
        assert f"class Monitor_{r['id']}_" in t
        label, formula = psl_label_and_formula(c)
        if label is not None:
            assert sec.find(f".//{X}pre[@class='ajpf']").text == f"{label}: {formula}"
        else:
            assert formula in t
        if c.entry.rationale:
            assert c.entry.rationale in t
        if c.entry.parent:
            assert ids[f"req-{c.entry.parent.lower()}"] is not None
    r1 = next(e for e in shipped["tree"].iter(f"{X}pre") if e.get("class") == "ajpf")
    assert r1.text == "R1: [] (B(agilex_agent,too_close) -> <> B(agilex_agent,stopped))"
    r2 = ids["req-r2"]
    assert "child of R1" in _text(r2.find(f"{X}h3"))
    assert "next operator" in _text(r2)                  # why R2 has no AJPF property
    # the module section holds the exact module text the audit ran
    for stem, text in modules.items():
        mod = ids[f"mod-{stem}"]
        assert mod.find(f".//{X}pre").text == text


def test_every_requirement_card_shows_fret_semantics_diagram(shipped):
    """FRET's semantics diagram of each requirement, inline in its card: its key, its
    windows and the same bytes as ``fretc explain --semantics`` writes."""
    for r in shipped["doc"]["requirements"]:
        sec = next(e for e in shipped["tree"].iter(f"{X}section")
                   if e.get("data-requirement") == r["id"] and e.get("class") == "req")
        fig = sec.find(f"{X}figure[@class='semantics']")
        assert fig is not None, r["id"]
        diagram = fig.find(f"{SVG}svg")
        assert diagram.get("data-key") == r["key"]
        assert r["id"] in _text(fig.find(f"{X}figcaption"))
        windows = [e for e in diagram.iter(f"{SVG}rect") if e.get("class") == "window"]
        assert windows, r["id"]


def test_coverage_of_the_shipped_runs(shipped):
    doc, tree = shipped["doc"], shipped["tree"]
    cov = _by_id(tree)["coverage"]
    assert not [e for e in cov.iter() if e.get("data-never")]   # every requirement fired
    counts = {e.get("data-triggers"): [_text(td) for td in e.findall(f"{X}td")]
              for e in cov.iter(f"{X}tr") if e.get("data-triggers")}
    for i, r in enumerate(doc["requirements"]):
        assert counts[r["id"]] == [str(la["verdicts"][i]["triggers"]) for la in doc["logs"]]
    assert "Every run has a message on every bound topic." in _text(cov)


def test_markdown_has_the_same_content(shipped):
    doc, md = shipped["doc"], shipped["md"]
    lines = md.splitlines()
    for i, r in enumerate(doc["requirements"]):
        row = next(l for l in lines if l.startswith(f"| [{r['id']}](#req-"))
        cells = [c.strip() for c in row.strip().strip("|").split(" | ")][1:]
        assert len(cells) == len(doc["logs"])
        for cell, la in zip(cells, doc["logs"]):
            v = la["verdicts"][i]
            assert v["verdict"] in cell
            if v["verdict"] == "violated":
                assert f"@ {v['first_violation']['tick_time_s']:.3f} s" in cell
    for la in doc["logs"]:
        for v in la["verdicts"]:
            if v["verdict"] != "violated":
                continue
            fv = v["first_violation"]
            assert f"{fv['tick_time_s']:.3f} s on the {fv['tick_time_base']} clock" in md
            assert f"log time {fv['log_time_ns']} ns" not in md
            for rows in v["values"].values():
                for x in rows:
                    assert f"| {x['tick']} | {x['time_s']:.3f} s |" in md
    for p in (shipped["out"] / "timelines").glob("*.svg"):
        assert f"](timelines/{p.name})" in md
    assert "R1: [] (B(agilex_agent,too_close) -> <> B(agilex_agent,stopped))" in md


@pytest.mark.tor("TOR-OUT-002")
def test_same_inputs_same_report_and_from_json_equals_live(shipped, tmp_path):
    out = shipped["out"]
    again = tmp_path / "report"          # the same layout as the fixture's: ../annotated
    res = run("report", "--from-json", out / "audit.json", "-o", again,
              "--annotate", tmp_path / "annotated")
    assert res.exit_code == 1
    for name in ("report.html", "report.md", "audit.json"):
        a = (out / name).read_text(encoding="utf-8")
        b = (again / name).read_text(encoding="utf-8")
        assert _strip_generated(a) == _strip_generated(b), name
        assert sum(GENERATED_PREFIX in l for l in a.splitlines()) == (
            0 if name == "audit.json" else 1)
    for p in (out / "timelines").glob("*.svg"):
        assert p.read_bytes() == (again / "timelines" / p.name).read_bytes()
    for p in shipped["ann"].glob("*.mcap"):
        assert p.read_bytes() == (tmp_path / "annotated" / p.name).read_bytes()


def test_annotated_mcaps_read_back_with_the_verdicts(shipped):
    doc, ann = shipped["doc"], shipped["ann"]
    for la in doc["logs"]:
        src = Path(la["log"])
        dst = ann / src.name
        with open(src, "rb") as f1, open(dst, "rb") as f2:
            r1, r2 = make_reader(f1), make_reader(f2)
            s1, s2 = r1.get_summary(), r2.get_summary()
            assert r2.get_header().profile == r1.get_header().profile
            assert {c.compression for c in s2.chunk_indexes} == \
                {c.compression for c in s1.chunk_indexes} == {"zstd"}
            topics1 = {c.id: c.topic for c in s1.channels.values()}
            topics2 = {c.id: c.topic for c in s2.channels.values()}
            assert set(topics2.values()) == set(topics1.values()) | {VERDICT_TOPIC}
            n1 = {topics1[k]: n for k, n in s1.statistics.channel_message_counts.items()}
            n2 = {topics2[k]: n for k, n in s2.statistics.channel_message_counts.items()}
            events = n2.pop(VERDICT_TOPIC)
            assert n2 == n1
            ch = next(c for c in s2.channels.values() if c.topic == VERDICT_TOPIC)
            sch = s2.schemas[ch.schema_id]
            assert (sch.name, sch.encoding, ch.message_encoding) == \
                ("foxglove.Log", "jsonschema", "json")
            assert json.loads(sch.data) == FOXGLOVE_LOG_SCHEMA
            msgs = [(m.log_time, json.loads(m.data))
                    for _, _, m in r2.iter_messages(topics=[VERDICT_TOPIC])]
            assert len(msgs) == events == len(verdict_events(la))
            for t, m in msgs:
                assert m["timestamp"]["sec"] * 10**9 + m["timestamp"]["nsec"] == t
                assert set(m) == {"timestamp", "level", "message", "name", "file", "line"}
            errors = {(m["name"], t) for t, m in msgs if m["level"] == 4}
            for v in la["verdicts"]:
                name = f"fretc/{v['requirement']}"
                if v["verdict"] == "violated":
                    assert (name, v["first_violation"]["log_time_ns"]) in errors
                    assert any(t == v["first_violation"]["log_time_ns"] and "VIOLATED" in
                               m["message"] for t, m in msgs)
                if v["ltl3"]["status"] == "violated":
                    assert any(t == v["ltl3"]["time_ns"] and "LTL3 verdict violated" in
                               m["message"] and m["name"] == name for t, m in msgs)
                assert any(t == la["end_time_ns"] and m["name"] == name and
                           f"finite-trace verdict: {v['verdict']}" in m["message"]
                           for t, m in msgs)
            meta = {m.name: m.metadata for m in r2.iter_metadata()}
            assert meta["fretc.verdicts"] == {v["requirement"]: v["verdict"]
                                              for v in la["verdicts"]}
    # one log in full: every original message byte-for-byte, in the same order
    src = TRACES / "sif_disabled.mcap"
    with open(src, "rb") as f1, open(ann / src.name, "rb") as f2:
        a = [(c.topic, m.log_time, m.publish_time, m.sequence, m.data)
             for _, c, m in make_reader(f1).iter_messages()]
        b = [(c.topic, m.log_time, m.publish_time, m.sequence, m.data)
             for _, c, m in make_reader(f2).iter_messages() if c.topic != VERDICT_TOPIC]
        assert a == b


def test_annotated_copy_is_deterministic(shipped, tmp_path):
    from fretc.audit.annotate import annotate_mcap

    la = next(l for l in shipped["doc"]["logs"] if l["log"].endswith("sif_disabled.mcap"))
    annotate_mcap(la["log"], str(tmp_path / "a.mcap"), la)
    assert (tmp_path / "a.mcap").read_bytes() == \
        (shipped["ann"] / "sif_disabled.mcap").read_bytes()


# --------------------------------------------------------------------------- synthetic run
SYN_FRET = """@tick_period 100 ms
S0: the bot shall always satisfy speed <= 1
    rationale: Speed limit.
S1: in moving mode, upon near the bot shall within 300 milliseconds satisfy halted
    rationale: Stop <quickly> & "safely" | when moving.
    parent: S0
S3: whenever flag the bot shall immediately satisfy halted
S4: the bot shall always satisfy battery > 0.2
"""
# the audit tests' bindings (tests/_logs.py; same layout as BINDINGS in bench/bench_audit.py)
# and two more variables
SYN_BINDINGS = _SYN_BINDINGS + 'moving = "/mode.data"\nbattery = "/battery.data"\n'


def _synthetic_run(folder: Path) -> Path:
    """20 s at 10 Hz: moving mode 2..15 s, an obstacle near 8..9 s, the bot halts only at
    8.6 s (S1 violated: 300 ms); /flag never true (S3 vacuous); no /battery (S4 error); LZ4
    chunks of 2 kB."""
    msgs = []
    for k in range(200):
        t = k * 100 * MS
        msgs.append(("/scan", "sensor_msgs/msg/LaserScan", t,
                     scan([0.3 if 80 <= k < 90 else 2.0, float("nan"), float("inf")], t)))
        msgs.append(("/cmd", "geometry_msgs/msg/Twist", t + 10 * MS,
                     twist(0.0 if 86 <= k < 100 else 0.5)))
        msgs.append(("/flag", "std_msgs/msg/Bool", t + 20 * MS, boolean(False)))
        msgs.append(("/mode", "std_msgs/msg/Bool", t + 30 * MS, boolean(20 <= k < 150)))
        msgs.append(("/other", "std_msgs/msg/Float64", t + 40 * MS, float64(k / 10)))
    (folder / "syn.fret").write_text(SYN_FRET)
    (folder / "syn.bindings.toml").write_text(SYN_BINDINGS)
    return write_mcap(folder / "syn_run.mcap", msgs, chunk_size=2048,
                      compression=CompressionType.LZ4)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("syn")
    path = _synthetic_run(tmp)
    cut = tmp / "syn_cut.mcap"
    data = path.read_bytes()
    cut.write_bytes(data[: int(len(data) * 0.6)])
    out, ann = tmp / "out", tmp / "ann"
    res = run("report", "-r", tmp / "syn.fret", path, cut, "-o", out, "--annotate", ann,
              "--title", "Synthetic <run> & checks")
    html = (out / "report.html").read_text(encoding="utf-8")
    return {"tmp": tmp, "res": res, "out": out, "ann": ann, "tree": ET.fromstring(html),
            "html": html, "doc": json.loads((out / "audit.json").read_text()),
            "md": (out / "report.md").read_text(encoding="utf-8")}


def test_synthetic_report_scope_missing_topic_and_partial_log(synthetic):
    doc, tree, ids = synthetic["doc"], synthetic["tree"], _by_id(synthetic["tree"])
    assert synthetic["res"].exit_code == 2          # S4 cannot be audited: no /battery
    verdicts = {(la["log"].rsplit("/", 1)[-1], v["requirement"]): v
                for la in doc["logs"] for v in la["verdicts"]}
    assert verdicts[("syn_run.mcap", "S1")]["verdict"] == "violated"
    assert verdicts[("syn_run.mcap", "S3")]["verdict"] == "vacuous"
    assert verdicts[("syn_run.mcap", "S4")]["verdict"] == "error"
    cut = next(la for la in doc["logs"] if la["log"].endswith("syn_cut.mcap"))
    assert cut["partial"]
    j = doc["logs"].index(cut)
    for i in range(len(doc["requirements"])):
        cell = ids[f"cell-{i}-{j}"]
        assert cell.get("data-partial") == "true" and "partial log" in _text(cell)
    # the title is escaped, the mode scope marked
    assert "Synthetic &lt;run&gt; &amp; checks" in synthetic["html"]
    s1 = ids["req-s1"]
    marks = {m.get("data-field"): m.text for m in s1.iter(f"{X}mark")}
    assert marks["scope"] == "in moving mode" and marks["condition"] == "upon near"
    assert 'Stop <quickly> & "safely" | when moving.' in _text(s1)
    # the violation's timeline shows the scope interval of the mode
    v = verdicts[("syn_run.mcap", "S1")]
    sec = next(e for e in tree.iter(f"{X}section") if e.get("class") == "violation"
               and e.get("data-log", "").endswith("syn_run.mcap"))
    scope_ns = {int(e.get("data-ns")) for e in sec.iter() if e.get("data-mark") == "scope"}
    assert scope_ns == {v["first_violation"]["scope_interval"]["start"]["time_ns"]}
    # coverage: S3 never triggered, /battery missing in both runs, the damaged run listed
    cov = ids["coverage"]
    assert {e.get("data-never") for e in cov.iter() if e.get("data-never")} == {"S3"}
    missing = [e for e in cov.iter(f"{X}tr") if e.get("data-missing")]
    assert {e.get("data-missing") for e in missing} == {"/battery"}
    assert len(missing) == 2 and all("S4" in _text(e) and "not in the log" in _text(e)
                                     for e in missing)
    assert "/battery" in _text(cov.find(f".//{X}p[@class='err']"))   # in no run at all
    assert "partial log: the log is damaged (truncated" in _text(cov)
    assert "/battery" in _text(ids["coverage"]) and "S4 on syn_run.mcap" in _text(cov)
    md = synthetic["md"]
    assert "[in moving mode]<sub>scope</sub>" in md
    assert "*partial log*" in md


def test_synthetic_annotation_keeps_lz4_and_copies_up_to_the_damage(synthetic):
    ann, doc = synthetic["ann"], synthetic["doc"]
    with open(ann / "syn_run.mcap", "rb") as f:
        r = make_reader(f)
        s = r.get_summary()
        assert {c.compression for c in s.chunk_indexes} == {"lz4"}
        assert len(s.chunk_indexes) > 10
        la = next(l for l in doc["logs"] if l["log"].endswith("syn_run.mcap"))
        v = next(x for x in la["verdicts"] if x["requirement"] == "S1")
        got = [(m.log_time, json.loads(m.data)) for _, _, m in
               r.iter_messages(topics=[VERDICT_TOPIC])]
        assert (v["first_violation"]["log_time_ns"], 4) in {(t, m["level"]) for t, m in got}
        assert any("S4 finite-trace verdict: error" in m["message"] for _, m in got)
    with open(ann / "syn_cut.mcap", "rb") as f:
        r = make_reader(f)
        msgs = list(r.iter_messages())
        topics = {c.topic for _, c, _ in msgs}
        assert VERDICT_TOPIC in topics and "/scan" in topics
        cut = next(l for l in doc["logs"] if l["log"].endswith("syn_cut.mcap"))
        n_orig = sum(1 for _ in msgs if _[1].topic != VERDICT_TOPIC)
        assert 0 < n_orig < 1000
        assert sum(1 for _, c, _m in msgs if c.topic == VERDICT_TOPIC) == \
            len(verdict_events(cut))
    text = _text(_by_id(synthetic["tree"])["runs"])
    assert "copied up to the damage" in text


def test_from_json_without_the_requirement_files(synthetic, tmp_path):
    doc = json.loads((synthetic["out"] / "audit.json").read_text())
    for r in doc["requirements"]:       # the requirement file is gone
        r["source"] = "gone/syn.fret:" + r["source"].rsplit(":", 1)[1]
    doc_path = tmp_path / "audit.json"
    doc_path.write_text(json.dumps(doc))
    res = run("report", "--from-json", doc_path, "-o", tmp_path / "r", "--base", tmp_path)
    assert res.exit_code == 2
    assert "not found" in res.output
    html = (tmp_path / "r" / "report.html").read_text(encoding="utf-8")
    tree = ET.fromstring(html)
    assert "shown from the audit JSON only" in html
    assert _by_id(tree)["cell-1-0"].get("data-verdict") == "violated"


def test_bad_input_exits_2(tmp_path):
    p = tmp_path / "x.json"
    p.write_text('{"schema": "something-else"}')
    res = run("report", "--from-json", p, "-o", tmp_path / "o")
    assert res.exit_code == 2 and "fretc-audit/1" in res.output
    res = CliRunner().invoke(main, ["report", "-o", str(tmp_path / "o")])
    assert res.exit_code == 2


@pytest.mark.tor("TOR-VER-008")
def test_a_refused_document_names_its_first_break_and_how_many_more(tmp_path):
    """fretc report refuses an audit document that breaks the schema naming the first break
    in document order, its value cut to 80 characters, and how many others there are."""
    (tmp_path / "r.fret").write_text("R: the robot shall always satisfy ok\n")
    (tmp_path / "run.csv").write_text("ok\n1\n1\n")
    good = tmp_path / "a.json"
    res = run("audit", "-r", tmp_path / "r.fret", tmp_path / "run.csv", "--no-progress",
              "--json", good)
    assert res.exit_code == 0, res.output
    long = ["x" * 100]
    cut = repr(long)[:77] + "..."
    for extra, more in (({}, ""), ({"requirements": "x"}, " (and 1 more)")):
        doc = json.loads(good.read_text())
        doc["logs"][0]["log"] = long
        doc.update(extra)
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps(doc))
        res = run("report", "--from-json", bad, "-o", tmp_path / "o")
        want = f"$.logs[0].log: {cut} is not of type 'string'{more}\n"
        assert res.exit_code == 2 and want in res.output, res.output


# --------------------------------------------------------------------------- Chromium
def test_report_opens_in_headless_chromium(shipped, tmp_path):
    bench = _bench()
    if bench.chromium() is None:
        pytest.skip("chromium not installed (apt-get install -y chromium)")
    html = shipped["out"] / "report.html"
    dom, console = bench.dump_dom(html)
    assert not console, console
    assert 'id="matrix"' in dom and 'class="timeline"' in dom
    png = tmp_path / "top.png"
    bench.screenshot(html, png, 1400, 2000)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_psl_map_gives_comparisons_an_ajpf_property(shipped, tmp_path):
    mapping = tmp_path / "map.toml"
    mapping.write_text('agent = "agilex_agent"\n[comparisons]\n"(clearance > 0)" = "clear"\n')
    res = run("report", "--from-json", shipped["out"] / "audit.json", "-o", tmp_path / "r",
              "--psl-map", mapping)
    assert res.exit_code == 1
    tree = ET.parse(tmp_path / "r" / "report.html").getroot()
    r5 = _by_id(tree)["req-r5"]
    assert r5.find(f".//{X}pre[@class='ajpf']").text == "R5: [] B(agilex_agent,clear)"
    bad = tmp_path / "bad.toml"
    bad.write_text("[variables]\nx = 3\n")
    res = run("report", "--from-json", shipped["out"] / "audit.json", "-o", tmp_path / "r2",
              "--psl-map", bad)
    assert res.exit_code == 2 and "must be a table" in res.output
