"""A project checked one FRET component at a time (``fretc check EXPORT -o FILE``) in the
report's check section (``fretc report --check FILE``): FRET's table, every component's
findings numbered through the project, each group named with its component."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main
from fretc.reports.check_section import check_context

from _fret_export import fret_export


def _export(tmp_path: Path) -> str:
    return fret_export(tmp_path / "p.json", {
        "C1": "whenever a ctrl shall immediately satisfy o",
        "C2": "whenever a ctrl shall immediately satisfy !o",
        "M1": "whenever o mon shall immediately satisfy w",
        "M2": "whenever o mon shall immediately satisfy !w"},
        [("ctrl", "a", "Input"), ("ctrl", "o", "Output"), ("mon", "o", "Input"),
         ("mon", "w", "Output")])


def test_the_report_shows_fret_s_table_and_every_component_s_findings(tmp_path):
    out = tmp_path / "check.json"
    got = CliRunner().invoke(main, ["check", _export(tmp_path), "--no-redundancy",
                                    "-o", str(out)])
    assert got.exit_code == 1, got.output
    doc = json.loads(out.read_text(encoding="utf-8"))
    ctx = check_context(doc)
    assert [(c["component"], c["realizability"], c["conflicts"])
            for c in ctx["fret_components"]] == [("ctrl", "unrealizable", ["C1, C2"]),
                                                 ("mon", "unrealizable", ["M1, M2"])]
    per_component = [len(c["check"]["findings"]) for c in doc["fret_components"]]
    assert len(ctx["findings"]) == sum(per_component) >= 2
    assert [f["index"] for f in ctx["findings"]] == list(range(len(ctx["findings"])))
    assert len({f["anchor"] for f in ctx["findings"]}) == len(ctx["findings"])
    assert [r["id"] for r in ctx["rows"]] == ["C1", "C2", "M1", "M2"]
    m1 = next(r for r in ctx["rows"] if r["id"] == "M1")
    assert m1["findings"] and all("M1" in f["requirements"] for f in m1["findings"])
    assert {g["requirements"][0] for g in ctx["components"]} == {"ctrl:", "mon:"}
