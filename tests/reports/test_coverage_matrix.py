"""``fretc report`` of an audit run with ``--coverage`` writes the coverage matrix: one row
per obligation, coloured by the runs covering it, each run's tick."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_report_writes_coverage_matrix(tmp_path):
    audit = tmp_path / "audit.json"
    log = ROOT / "traces" / "stop_delay.mcap"
    res = CliRunner().invoke(main, ["audit", "--coverage", "-r", str(ROOT / "requirements"),
                                    str(log), "--json", str(audit), "--no-progress"])
    assert res.exit_code in (0, 1, 3), res.output
    out = tmp_path / "rep"
    res = CliRunner().invoke(main, ["report", "--requirements", str(ROOT / "requirements"),
                                    "--from-json", str(audit), "-o", str(out)])
    assert res.exit_code in (0, 1), res.output  # 1: the run violates R2
    page = (out / "coverage.html").read_text()
    # R2's trigger fired on that run (covered once: amber, at its tick); its deadline's
    # boundary was never met (red)
    assert "<td>R2</td><td>trigger</td>" in page
    row = page.split("<td>R2</td><td>trigger</td>")[1].split("</tr>")[0]
    assert "class='t n1'>1<" in row and ">293<" in row
    row = page.split("<td>R2</td><td>deadline-reached</td>")[1].split("</tr>")[0]
    assert "class='t n0'>0<" in row


def test_no_coverage_no_matrix(tmp_path):
    audit = tmp_path / "audit.json"
    CliRunner().invoke(main, ["audit", "-r", str(ROOT / "requirements"),
                              str(ROOT / "traces" / "nominal.mcap"), "--json", str(audit),
                              "--no-progress"])
    out = tmp_path / "rep"
    res = CliRunner().invoke(main, ["report", "--requirements", str(ROOT / "requirements"),
                                    "--from-json", str(audit), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert not (out / "coverage.html").exists()
