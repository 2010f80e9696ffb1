"""``fretc ltlsim`` (reports/ltlsim.py, templates/ltlsim.html): the server judges a posted
trace with the audit's judge (the same verdicts as ``fretc audit`` on the same trace as a
CSV), answers bad traces with a 400 naming the variable and tick, refuses a foreign Host and
a request of another origin (a POST must name the page's own); every malformed request,
fuzzed (headers, methods, paths, bodies), gets a 4xx with a JSON error, nothing on stderr, and
the server answers the next request; and the page, in headless Chromium, shows a new verdict
after a value is edited, while a page of another origin posting to it is refused."""

from __future__ import annotations

import json
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings, strategies as st

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
    """POST ``body`` to /api/judge as the page does (its own Origin, JSON)."""
    req = urllib.request.Request(url + "/api/judge", data=body, method="POST",
                                 headers={"Content-Type": "application/json", "Origin": url,
                                          **(headers or {})})
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


def _raw(url: str, data: bytes) -> tuple[int, dict[str, str], bytes]:
    """Send ``data`` (a whole HTTP request, as bytes) to the server of ``url``, close the
    sending side and read the answer: ``(status, headers (names lower case), body)``;
    status 0 when nothing came back."""
    port = int(url.rsplit(":", 1)[1])
    with socket.create_connection(("127.0.0.1", port), timeout=20) as s:
        try:
            s.sendall(data)
            s.shutdown(socket.SHUT_WR)
        except OSError:
            pass  # (the server answered before reading all: its answer is still read)
        got = b""
        while True:
            chunk = s.recv(65536)
            if not chunk:
                break
            got += chunk
    head, _, body = got.partition(b"\r\n\r\n")
    lines = head.decode("iso-8859-1").split("\r\n")
    if not lines[0].startswith("HTTP/"):
        return 0, {}, got
    headers = dict((k.strip().lower(), v.strip()) for k, _, v in
                   (line.partition(":") for line in lines[1:]))
    return int(lines[0].split()[1]), headers, body


def _request(url: str, method: str, path: str, headers: list[tuple[str, str]],
             body: bytes = b"", version: str = "HTTP/1.1") -> bytes:
    host = url.split("//", 1)[1]
    lines = [f"{method} {path} {version}", f"Host: {host}"]
    lines += [f"{k}: {v}" for k, v in headers]
    return ("\r\n".join(lines) + "\r\n\r\n").encode("iso-8859-1") + body


def _json_post(url: str, body: bytes, extra: list[tuple[str, str]] | None = None,
               origin: str | None = "") -> bytes:
    """A POST /api/judge of ``body`` as the page sends it (``origin`` "": its own)."""
    headers = [("Content-Type", "application/json"), ("Content-Length", str(len(body)))]
    if origin is not None:
        headers.append(("Origin", origin or url))
    return _request(url, "POST", "/api/judge", headers + (extra or []), body)


@pytest.mark.parametrize("method, headers, expected", [
    # the page's own requests: its POSTs carry Origin; its GETs none, or its own Referer
    ("POST", [("Origin", "{url}")], 200),
    ("POST", [("Origin", "http://localhost:{port}")], 200),
    ("POST", [("Referer", "{url}/?trace=x")], 200),
    ("GET", [], 200),
    ("GET", [("Referer", "{url}/")], 200),
    ("GET", [("Origin", "{url}")], 200),
    # another origin, however named
    ("POST", [("Origin", "http://evil.test")], 403),
    ("POST", [("Origin", "null")], 403),
    ("POST", [("Origin", "http://127.0.0.1:1")], 403),
    ("POST", [("Origin", "https://127.0.0.1:{port}")], 403),
    ("POST", [("Origin", "")], 403),
    ("POST", [("Origin", "{url}"), ("Origin", "http://evil.test")], 403),
    ("POST", [("Origin", "http://evil.test"), ("Referer", "{url}/")], 403),
    ("POST", [("Referer", "http://evil.test/{url}")], 403),
    ("POST", [], 403),  # a POST names its origin
    ("GET", [("Origin", "http://evil.test")], 403),
    ("GET", [("Referer", "http://evil.test/page")], 403),
])
def test_requests_of_another_origin_are_refused(served, method, headers, expected):
    url = served["url"]
    port = url.rsplit(":", 1)[1]
    headers = [(k, v.format(url=url, port=port)) for k, v in headers]
    if method == "POST":
        body = json.dumps(_trace(2)).encode()
        data = _request(url, "POST", "/api/judge", [("Content-Type", "application/json"),
                                                    ("Content-Length", str(len(body)))]
                        + headers, body)
    else:
        data = _request(url, "GET", "/api/requirements", headers)
    code, got, body = _raw(url, data)
    assert code == expected, body
    assert got["content-type"] == "application/json"
    answer = json.loads(body)
    if expected == 403:
        assert "origin" in answer["error"] and f"http://127.0.0.1:{port}" in answer["error"]


def _nested(k: int) -> bytes:
    """``k`` arrays, one inside the other (past the JSON reader's recursion limit when ``k``
    is over about a thousand)."""
    return b"[" * k + b"]" * k


_DEEP = _nested(100_000)  # (200 KB)


@pytest.mark.parametrize("make, says", [
    (lambda url: _request(url, "POST", "/api/judge",
                          [("Origin", url), ("Content-Type", "application/json"),
                           ("Content-Length", "abc")], b"{}"), "Content-Length"),
    (lambda url: _json_post(url, _DEEP), "nested too deeply"),
    (lambda url: _json_post(url, json.dumps(_trace(2, speed=[10 ** 400, 0.5])).encode()),
     "variable 'speed' at tick 0: a finite number expected, got an integer of 401 digits"),
    (lambda url: _json_post(url, b"\xff\xfe{}"), "not UTF-8"),
    (lambda url: _json_post(url, b'{"ticks": 2, "val'), "not JSON"),
    (lambda url: _request(url, "POST", "/api/judge", [("Origin", url),
                                                      ("Content-Type", "application/json")]),
     "Content-Length is required"),
    (lambda url: _json_post(url, b"{}", [("Content-Length", "-2")]), "one byte count"),
    (lambda url: _request(url, "POST", "/api/judge",
                          [("Origin", url), ("Content-Type", "application/json"),
                           ("Content-Length", str(10 ** 9))], b"{}"), "bytes expected"),
    (lambda url: _request(url, "POST", "/api/judge",
                          [("Origin", url), ("Content-Type", "text/plain"),
                           ("Content-Length", "2")], b"{}"), "application/json expected"),
    (lambda url: _request(url, "DELETE", "/api/judge", []), "only GET and POST"),
    (lambda url: _request(url, "GET", "/nowhere", []), "not found"),
])
def test_malformed_requests_get_a_4xx_and_the_server_goes_on(served, capsys, make, says):
    """The three requests that were dropped with a traceback (``Content-Length: abc``,
    200 KB of nested brackets, a 400-digit number) and their kin: a 4xx with a JSON error
    saying what, nothing on stderr, and the next request answered."""
    url = served["url"]
    code, headers, body = _raw(url, make(url))
    assert 400 <= code < 500 and headers["content-type"] == "application/json", body[:300]
    assert says in json.loads(body)["error"]
    assert _post(url, json.dumps(_trace(2)).encode())[0] == 200
    assert capsys.readouterr().err == ""


_ALPHABET = st.characters(min_codepoint=0x21, max_codepoint=0x7E)


def _bodies() -> st.SearchStrategy:
    """Bodies of a POST: a valid trace, nested arrays and objects, integers past a double
    and past JSON's digit limit, NaN and infinities, truncated JSON, bytes that are not
    UTF-8, JSON of every shape, traces of wrong types."""
    valid = json.dumps(_trace(3)).encode()
    return st.one_of(
        st.just(valid), st.integers(1, 100_000).map(_nested),
        st.integers(1, 5000).map(lambda k: b"{" * k),
        st.integers(300, 4300).map(lambda k: json.dumps(
            _trace(2, speed=[1, int("9" * k)])).encode()),
        st.integers(4301, 6000).map(lambda k: b'{"ticks": ' + b"9" * k + b"}"),
        st.just(b'{"ticks": 1e999, "values": NaN}'),
        st.integers(0, len(valid)).map(lambda k: valid[:k]),
        st.binary(max_size=64), st.just(b"\xc3\x28\xa0\xa1"),
        st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(),
                     lambda sub: st.lists(sub) | st.dictionaries(st.text(), sub),
                     max_leaves=8).map(lambda v: json.dumps(v).encode()),
        st.fixed_dictionaries({"ticks": st.integers(-3, 10 ** 30) | st.text(),
                               "values": st.dictionaries(
                                   st.sampled_from(["too_close", "stopped", "clearance",
                                                    "docking", "speed"]),
                                   st.lists(st.booleans() | st.floats() | st.integers(),
                                            max_size=4))}).map(
                                                lambda v: json.dumps(v).encode()))


@st.composite
def _fuzzed(draw: st.DrawFn, url: str) -> bytes:
    """A request as the page posts a trace, up to three of its parts replaced by others
    (methods, paths, versions, Host, Origin, Referer, Content-Type, Content-Length missing,
    negative, huge, not a number, longer or shorter than the body, a Transfer-Encoding),
    with a body of :func:`_bodies`."""
    port = url.rsplit(":", 1)[1]
    parts: dict[str, str | None] = {
        "method": "POST", "path": "/api/judge", "version": "HTTP/1.1",
        "Host": f"127.0.0.1:{port}", "Origin": url, "Referer": None,
        "Content-Type": "application/json", "Content-Length": "LENGTH",
        "Transfer-Encoding": None}
    others = {
        "method": st.sampled_from(["GET", "PUT", "DELETE", "OPTIONS", "PATCH", "HEAD",
                                   "TRACE", "CONNECT", "get", "BREW"]),
        "path": st.one_of(st.sampled_from(["/", "/index.html", "/api/requirements",
                                           "/api/judge?x=1", "//api/judge",
                                           "/../../etc/passwd", "/%00", "*",
                                           "http://evil.test/api/judge", "/a b"]),
                          st.integers(60_000, 70_000).map(lambda k: "/" + "a" * k),
                          st.text(_ALPHABET, min_size=1, max_size=30).map(
                              lambda t: "/" + t)),
        "version": st.sampled_from(["HTTP/1.0", "HTTP/2.0", "HTTPS/1.1", "HTTP/1.x", ""]),
        "Host": st.sampled_from([None, f"localhost:{port}", "127.0.0.1", "evil.test",
                                 "127.0.0.1:1", ""]),
        "Origin": st.sampled_from([None, f"http://localhost:{port}", "null",
                                   "http://evil.test", ""]),
        "Referer": st.sampled_from([url + "/", "http://evil.test/", "not a url"]),
        "Content-Type": st.sampled_from([None, "application/json; charset=utf-8",
                                         "text/plain", "APPLICATION/JSON",
                                         "multipart/form-data; boundary=x", ""]),
        "Content-Length": st.sampled_from([None, "-1", "0", "99999999999999999999", "abc",
                                           "1e3", "+5", "0x10", " LENGTH ", "12, 13",
                                           "LONGER", "SHORTER"]),
        "Transfer-Encoding": st.just("chunked"),
    }
    for name in draw(st.sets(st.sampled_from(sorted(others)), max_size=3)):
        parts[name] = draw(others[name])
    body = draw(_bodies())
    line = f"{parts.pop('method')} {parts.pop('path')} {parts.pop('version')}".rstrip()
    length = parts["Content-Length"]
    if length is not None:
        parts["Content-Length"] = length.replace("LONGER", str(len(body) + 5)).replace(
            "SHORTER", str(max(len(body) - 1, 0))).replace("LENGTH", str(len(body)))
    headers = [f"{k}: {v}" for k, v in parts.items() if v is not None]
    return ("\r\n".join([line, *headers]) + "\r\n\r\n").encode("iso-8859-1") + body


def test_fuzzed_requests_get_2xx_or_4xx_json_and_the_server_goes_on(served, capsys):
    """Hypothesis over methods, paths, versions, Host, Origin, Referer, Content-Type,
    Content-Length (missing, negative, huge, not a number, longer or shorter than the body)
    and bodies (deep nesting, huge numbers, wrong types, not UTF-8, truncated JSON): every
    answer is 2xx or 4xx, JSON but for the page itself, nothing is written on stderr, and a
    valid request is answered afterwards."""
    url = served["url"]

    @settings(max_examples=250, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(_fuzzed(url))
    def one(data: bytes) -> None:
        code, headers, body = _raw(url, data)
        assert 200 <= code < 300 or 400 <= code < 500, (code, data[:200], body[:200])
        if headers.get("content-type", "").startswith("text/html"):
            assert code == 200 and data.split(b" ", 2)[1] in (b"/", b"/index.html")
            return
        assert headers["content-type"] == "application/json", (data[:200], headers)
        if not data.startswith(b"HEAD "):
            answer = json.loads(body)
            assert 200 <= code < 300 or set(answer) == {"error"}, answer

    one()
    assert _post(url, json.dumps(_trace(2)).encode())[0] == 200
    assert capsys.readouterr().err == ""


def test_the_command_keeps_serving_without_a_traceback(tmp_path):
    """``fretc ltlsim`` itself (its stderr read): the three requests that were dropped with
    a traceback are answered 400, then a valid one 200; stderr holds only the address."""
    reqs = tmp_path / "reqs.fret"
    reqs.write_text(REQS)
    err = tmp_path / "stderr.txt"
    with open(err, "w") as sink:
        proc = subprocess.Popen([sys.executable, "-m", "fretc", "ltlsim", str(reqs), "--port",
                                 "0"], stderr=sink, cwd=tmp_path)
    try:
        for _ in range(300):
            m = re.search(r"http://127\.0\.0\.1:(\d+)/", err.read_text())
            if m or proc.poll() is not None:
                break
            time.sleep(0.05)
        assert m, err.read_text()
        url = f"http://127.0.0.1:{m.group(1)}"
        for data in (_request(url, "POST", "/api/judge", [("Origin", url), (
                "Content-Type", "application/json"), ("Content-Length", "abc")], b"{}"),
                     _json_post(url, b"[" * 200_000),
                     _json_post(url, json.dumps(_trace(2, speed=[10 ** 400, 0])).encode())):
            code, _headers, body = _raw(url, data)
            assert code == 400 and json.loads(body)["error"], body
        assert _post(url, json.dumps(_trace(2)).encode())[0] == 200
    finally:
        proc.terminate()
        proc.wait(timeout=20)
    lines = err.read_text().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fretc ltlsim: 4 requirements on"), lines


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


def test_the_page_works_and_another_origin_cannot_post_in_chromium(served, tmp_path):
    """In headless Chromium: the page at its own address judges its trace (its GET and its
    fetch POST pass the origin checks), and a page of another origin (another port of
    127.0.0.1) that submits a trace to the simulator as a form, the classic cross-site
    post, gets the 403 that names the origin, not verdicts."""
    if _chromium() is None:
        pytest.skip("chromium not installed (apt-get install -y chromium)")
    import functools
    from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

    verdicts = _verdicts(_dom(served["url"] + "/"))
    assert set(verdicts) == {"R1", "R2", "R5", "R7"}, verdicts
    trace = json.dumps(_trace(2))
    # a text/plain form posts "NAME=VALUE": the name opens the JSON, the value closes it
    name, value = trace[:-1] + ', "pad": "', '"}'
    site = tmp_path / "site"
    site.mkdir()
    (site / "index.html").write_text(
        '<!DOCTYPE html><html><body><form id="f" method="post" enctype="text/plain" '
        f'action="{served["url"]}/api/judge"><input type="hidden" name=\'{name}\' '
        f'value=\'{value}\'></form><script>document.getElementById("f").submit();'
        "</script></body></html>")
    handler = functools.partial(SimpleHTTPRequestHandler, directory=str(site))
    handler.log_message = lambda *args: None  # type: ignore[attr-defined]  # (quiet)
    other = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=other.serve_forever, daemon=True).start()
    try:
        dom = _dom(f"http://127.0.0.1:{other.server_address[1]}/index.html")
    finally:
        other.shutdown()
        other.server_close()
    assert "a request of another origin (Origin)" in dom, dom[-1500:]
    assert "requirements" not in dom
