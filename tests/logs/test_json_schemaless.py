"""A json MCAP whose jsonschema declares no ``properties`` (``{"type": "object"}``: any
object): ``fretc inspect`` lists its topics (schema unknown, never a crash) and an audit
reads its fields from the messages themselves."""

from __future__ import annotations

import json

from click.testing import CliRunner
from mcap.writer import Writer

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main


def test_a_jsonschema_without_properties(tmp_path):
    log = tmp_path / "j.mcap"
    with open(log, "wb") as f:
        w = Writer(f)
        w.start()
        s = w.register_schema("Thing", "jsonschema", json.dumps({"type": "object"}).encode())
        c = w.register_channel("/thing", "json", s)
        for k in range(6):
            w.add_message(c, k * 10**9, json.dumps({"x": k, "y": {"z": [1, 2]}}).encode(),
                          k * 10**9)
        w.finish()
    res = CliRunner().invoke(main, ["inspect", str(log)])
    assert res.exit_code == 0 and "/thing" in res.output, res.output
    (tmp_path / "r.fret").write_text("R: the sw shall always satisfy x < 5\n")
    (tmp_path / "r.bindings.toml").write_text('[tick]\nperiod = "1 s"\n[variables]\n'
                                              'x = "/thing.x"\n')
    (v,) = audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),))),
                     str(log)).verdicts
    assert v.verdict == "violated" and v.first_violation.at.time_ns == 5 * 10**9
