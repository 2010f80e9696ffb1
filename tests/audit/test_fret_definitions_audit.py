"""``fretc audit`` of a FRET export whose requirement reads an Internal variable FRET's
glossary defines (``rise`` is ``a and not pre a``): the variable, bound by nothing, is its
definition computed from the log's ``a``, and every verdict equals the one of the same
requirement with the definition written out in FRETish (a binding file that binds the
variable itself makes it read from the log instead: audit/plan.py)."""

from __future__ import annotations

import json

from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.cli import main


def _export(response_text: str, rise: bool) -> dict:
    variables = [
        {"component_name": "ctrl", "variable_name": "a", "idType": "Input",
         "dataType": "boolean"},
        {"component_name": "ctrl", "variable_name": "o", "idType": "Output",
         "dataType": "boolean"}]
    if rise:
        variables.append({"component_name": "ctrl", "variable_name": "rise",
                          "idType": "Internal", "dataType": "boolean",
                          "assignment": "a and not pre a"})
    return {"requirements": [{"reqid": "R1", "fulltext": response_text}],
            "variables": variables}


def _verdict(tmp, doc: dict, rows: list[tuple[bool, bool]], extra: list[str] = ()) -> dict:
    req = tmp / "p.json"
    req.write_text(json.dumps(doc), encoding="utf-8")
    trace = tmp / "t.csv"
    trace.write_text("time,a,o\n" + "".join(
        f"{k * 0.1:.1f},{str(a).lower()},{str(o).lower()}\n" for k, (a, o) in enumerate(rows)),
        encoding="utf-8")
    out = tmp / "a.json"
    got = CliRunner().invoke(main, ["audit", "-r", str(req), str(trace), "--tick-period",
                                    "100ms", "--no-progress", "--json", str(out), *extra])
    assert got.exit_code in (0, 1), got.output
    res = json.loads(out.read_text(encoding="utf-8"))
    return {"output": got.output, "verdicts": [
        (v["requirement"], v["verdict"], (v.get("first_violation") or {}).get("tick"))
        for log in res["logs"] for v in log["verdicts"]]}


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=8))
def test_the_definition_is_computed_from_the_log(tmp_path_factory, rows):
    tmp = tmp_path_factory.mktemp("d")
    defined = _verdict(tmp, _export("whenever rise ctrl shall immediately satisfy o", True),
                       rows)
    written = _verdict(tmp, _export(
        "whenever a & !preBool(false, a) ctrl shall immediately satisfy o", False), rows)
    assert defined["verdicts"] == written["verdicts"]
    assert "rise: FRET's definition of this Internal variable computed" in defined["output"]
