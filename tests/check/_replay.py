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


def replayed_unrealizable(req: Path, inputs: list[str], method: str, tmp_path: Path) -> dict:
    """``fretc check`` of the unrealizable set in ``req`` with ``inputs`` as the inputs (the
    other variables the outputs) and
    witness CSVs: asserts the component is unrealizable by ``method``, that its witness (the
    defeating inputs with a controller's best effort) replays through ``fretc audit`` with
    the promised verdicts, and that a requirement of the set is violated on it. Returns the
    component's realizability entry."""
    from fretc.check.analysis import check_requirements
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.monitors.interval import verdict_of

    from tests.check._roles import rest_as_outputs

    compiled = compile_entries(load_requirements([req]))
    r = check_requirements(compiled, inputs=inputs, outputs=rest_as_outputs(compiled, inputs),
                           witness_dir=str(tmp_path / "w"), witness_judge=verdict_of)
    comp = r.realizability["groups"][0]
    assert comp["realizable"] is False and comp["method"] == method, comp
    found = [f for f in r.findings if f.kind == "unrealizable"]
    assert found and found[0].witness, r.findings
    promised = json.loads(json.dumps(found[0].expected))
    got = audit_verdicts(req, Path(found[0].witness), tmp_path)
    assert got == promised
    assert any(got[i] == "violated" for i in found[0].requirements), got
    assert found[0].details["witness_shows_finding"] is True
    return comp
