"""Replaying a witness of ``fretc check`` through ``fretc audit``, shared by the check tests."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main


def audit_verdicts(req: Path, csv: Path, tmp_path: Path) -> dict[str, str]:
    """``fretc audit -r REQ CSV --json``: requirement id -> verdict (asserts exit 0 or 1)."""
    out = tmp_path / (csv.stem + ".json")
    res = CliRunner().invoke(main, ["audit", "-r", str(req), str(csv), "--json", str(out),
                                    "--no-progress"])
    assert res.exit_code in (0, 1), res.output
    doc = json.loads(out.read_text())
    return {v["requirement"]: v["verdict"] for log in doc["logs"] for v in log["verdicts"]}
