"""``fretc ltlsim`` (reports/ltlsim.py, templates/ltlsim.html): the server judges a posted
trace with the audit's judge (the same verdicts as ``fretc audit`` on the same trace as a
CSV), answers bad traces with a 400 naming the variable and tick, refuses a foreign Host;
and the page, in headless Chromium, shows a new verdict after a value is edited."""

from __future__ import annotations

import json
import shutil
import subprocess
import tempfile
import threading
import urllib.error
import urllib.request
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.reports.ltlsim import judge_trace, make_server, variables_of

REQS = """\
@tick_period 100 ms
R1: whenever too_close agilex_agent shall eventually satisfy stopped
R2: upon too_close agilex_agent shall within 300 milliseconds satisfy stopped
R5: the scout_mini shall always satisfy clearance > 0.25
R7: in docking mode the robot shall always satisfy speed < 0.3
"""


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ltlsim")
    path = tmp / "reqs.fret"
    path.write_text(REQS)
    compiled = compile_entries(load_requirements([str(path)]))
    server = make_server(compiled, 0, ticks=8)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield {"url": f"http://127.0.0.1:{server.server_address[1]}", "compiled": compiled,
           "path": path, "tmp": tmp}
    server.shutdown()
    server.server_close()


def _post(url: str, body: bytes, headers: dict | None = None) -> tuple[int, dict]:
    req = urllib.request.Request(url + "/api/judge", data=body, method="POST",
                                 headers={"Content-Type": "application/json", **(headers or {})})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


def _trace(n: int, **cols) -> dict:
    values = {"too_close": [False] * n, "stopped": [False] * n, "clearance": [1.5] * n,
              "docking": [False] * n, "speed": [0.125] * n}
    values.update(cols)
    return {"ticks": n, "values": values}


TRACES = [
    _trace(8),
    _trace(8, too_close=[False, True, True, False, False, False, False, False],
           stopped=[False, False, False, False, True, False, False, False]),
    _trace(8, too_close=[False, True, False, False, False, False, False, False],
           stopped=[False, False, False, False, False, False, True, False],
           clearance=[1.5, 1.0, 0.5, 0.2, 0.5, 1.0, 1.5, 2.0]),
    _trace(6, docking=[False, True, True, True, False, False],
           speed=[0.5, 0.125, 0.375, 0.125, 0.5, 0.5]),
]


def _audit_verdicts(tmp: Path, reqs: Path, trace: dict, k: int) -> dict[str, str]:
    """``fretc audit`` of the same trace written as the audit's CSV."""
    names = list(trace["values"])
    rows = [",".join(names)]
    for i in range(trace["ticks"]):
        rows.append(",".join(("true" if v else "false") if isinstance(v, bool) else repr(v)
                             for v in (trace["values"][n][i] for n in names)))
    csv = tmp / f"t{k}.csv"
    csv.write_text("\n".join(rows) + "\n")
    out = tmp / f"a{k}.json"
    res = CliRunner().invoke(main, ["audit", "--requirements", str(reqs), str(csv),
                                    "--json", str(out)])
    assert res.exit_code in (0, 1), res.output
    doc = json.loads(out.read_text())
    return {v["requirement"]: v["verdict"] for v in doc["logs"][0]["verdicts"]}


def test_served_verdicts_are_the_audit_verdicts(served):
    variables = {v["name"]: v["type"] for v in variables_of(served["compiled"])}
    assert variables == {"too_close": "boolean", "stopped": "boolean", "clearance": "number",
                         "docking": "boolean", "speed": "number"}
    seen = set()
    for k, trace in enumerate(TRACES):
        code, answer = _post(served["url"], json.dumps(trace).encode())
        assert code == 200, answer
        got = {r["id"]: r["verdict"] for r in answer["requirements"]}
        assert got == _audit_verdicts(served["tmp"], served["path"], trace, k)
        seen |= set(got.values())
        for r in answer["requirements"]:
            assert len(r["values"]) == trace["ticks"]
            # the value at the last tick is the verdict of the whole trace
            assert r["values"][-1] == (r["verdict"] != "violated")
            if r["verdict"] == "violated":
                fv = r["first_violation"]
                assert fv["window"][0] <= fv["tick"] <= fv["window"][1] and fv["reason"]
    assert seen == {"satisfied", "vacuous", "violated"}


def test_first_violation_of_a_deadline(served):
    trace = _trace(8, too_close=[False, True, False, False, False, False, False, False])
    answer = judge_trace(served["compiled"], trace)
    r2 = next(r for r in answer["requirements"] if r["id"] == "R2")
    assert r2["verdict"] == "violated"
    assert r2["first_violation"]["trigger"] == 1
    assert r2["first_violation"]["window"] == [1, 4]        # 300 ms = 3 ticks after it
    assert r2["values"][:4] == [True] * 4 and r2["values"][4] is False


@pytest.mark.parametrize("body, says", [
    (b"not json", "Expecting value"),
    (json.dumps({"ticks": 0, "values": {}}).encode(), '"ticks"'),
    (json.dumps(_trace(3, stopped=[False, 1, False])).encode(),
     "variable 'stopped' at tick 1: true or false expected"),
    (json.dumps(_trace(3, speed=[0.1, "fast", 0.2])).encode(),
     "variable 'speed' at tick 1: a finite number expected"),
    (json.dumps({"ticks": 2, "values": {"too_close": [True, False]}}).encode(),
     "missing from the trace"),
])
def test_bad_traces_get_400_naming_where(served, body, says):
    code, answer = _post(served["url"], body)
    assert code == 400 and says in answer["error"], answer


def test_only_loopback_hosts_are_answered(served):
    code, answer = _post(served["url"], json.dumps(_trace(2)).encode(), {"Host": "evil.test"})
    assert code == 403
    page = urllib.request.urlopen(served["url"] + "/", timeout=10).read().decode()
    assert "<script" in page and "http://" not in page.split("<script", 1)[1]  # no CDN


def test_cli_refuses_bad_input(tmp_path):
    res = CliRunner().invoke(main, ["ltlsim", str(tmp_path / "none.fret")])
    assert res.exit_code == 2
    f = tmp_path / "r.fret"
    f.write_text("R1: the sw shall always satisfy p\n")
    res = CliRunner().invoke(main, ["ltlsim", str(f), "--id", "R9"])
    assert res.exit_code == 2 and "R9" in res.output


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _dom(url: str) -> str:
    with tempfile.TemporaryDirectory() as profile:
        res = subprocess.run([_chromium(), "--headless", "--no-sandbox", "--disable-gpu",
                              "--disable-background-networking", "--disable-component-update",
                              "--no-first-run", f"--user-data-dir={profile}",
                              "--virtual-time-budget=10000", "--dump-dom", url],
                             capture_output=True, text=True, timeout=60)
    return res.stdout


def _verdicts(dom: str) -> dict[str, str]:
    import re

    assert 'data-state="ready"' in dom, dom[-2000:]
    return dict(re.findall(r'<tr class="result" data-requirement="([^"]+)" '
                           r'data-verdict="([^"]+)"', dom))


def test_editing_a_value_in_chromium_changes_the_verdict(served):
    if _chromium() is None:
        pytest.skip("chromium not installed (apt-get install -y chromium)")
    from urllib.parse import quote

    trace = _trace(8, too_close=[False, True, False, False, False, False, False, False],
                   stopped=[False, False, True, False, False, False, False, False])
    base = served["url"] + "/?trace=" + quote(json.dumps(trace))
    before = _verdicts(_dom(base))
    assert before["R2"] == "satisfied" and before["R5"] == "satisfied"
    # a click on stopped at tick 2 (it becomes false: R2's deadline is missed) and 0.1
    # typed as the clearance at tick 5
    after = _verdicts(_dom(base + "&edit=stopped:2&edit=clearance:5:0.1"))
    assert after["R2"] == "violated" and after["R5"] == "violated"
    assert after["R7"] == before["R7"] == "vacuous"
