"""``fretc lsp`` against what a hostile tester found: each test failed before its fix.

* a ``Content-Length: 1000000000000`` header ended the server with exit code 4: now the
  message is skipped and the next request answered;
* malformed messages (not JSON, a header line of 100 KB, parameters of the wrong types) are
  logged and skipped, and a request among them answered with an error;
* saving a 1 KB file with 10^6-tick deadlines hung the server in its check, and killing the
  server left the check's worker at 100 % CPU: the check is a job process that the server
  keeps answering beside, that the next edit cancels, and that dies with the server;
* a keystroke in a 10,000-requirement document parsed all of them again (5.5-6.7 s): it
  parses the one sentence edited;
* a 5 MB document took 31 s a keystroke: it is refused at once, with a diagnostic;
* a hover on a requirement with a 10^6-tick deadline was 184 MB: at most 64,000 characters.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("pygls")
ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
from fuzz_lsp import RawClient, alive, job_processes  # noqa: E402

from fretc.editor.document import MAX_DOCUMENT, MAX_HOVER, Memory, analyse  # noqa: E402

#: a 1 KB requirement file whose fretc check takes about a minute (found by the tester's
#: kind of search: deadlines of 10^6 ticks in scopes)
SLOW = """\
R1: when in m mode upon p & q the sw shall before r satisfy q
R2: before m upon p & q the sw shall within 1000000 ticks satisfy !p
R3: when in m mode upon x > 3 the sw shall eventually satisfy x > 1
R4: before m the sw shall eventually satisfy x > 1
R5: after m upon x > 3 the sw shall after 500000 ticks satisfy !q & r
R6: after m whenever y < 2 the sw shall at the next timepoint satisfy x > 1
R7: after m the sw shall within 999999 ticks satisfy !p
R8: after m upon p the sw shall always satisfy r
R9: before m upon p the sw shall eventually satisfy x > 1
R10: whenever q the sw shall never satisfy !p
R11: only after m the sw shall immediately satisfy r
R12: when in m mode the sw shall always satisfy r
R14: unless in m mode upon p & q the sw shall after 1000000 ticks satisfy q
R15: upon p & q the sw shall immediately satisfy !q & r
R16: whenever y < 2 the sw shall never satisfy r
R17: upon x > 3 the sw shall within 1000000 ticks satisfy p | r
R18: before m the sw shall eventually satisfy !q & r
"""


def _until(what, bound: float = 20.0):
    """Poll ``what()`` until it is true (at most ``bound`` s: a bound, not a measurement)."""
    end = time.monotonic() + bound
    while time.monotonic() < end:
        got = what()
        if got:
            return got
        time.sleep(0.05)
    return what()


@pytest.fixture
def session(tmp_path):
    client = RawClient(tmp_path)
    got = client.request("initialize", {"processId": None, "rootUri": tmp_path.as_uri(),
                                        "capabilities": {}})
    assert got is not None and "result" in got
    client.notify("initialized", {})
    yield client, tmp_path
    if client.proc.poll() is None:
        client.close()
    for pid in job_processes(client.proc.pid):  # (none are left; the test says so)
        os.kill(pid, signal.SIGKILL)


def _open(client, path: Path, text: str) -> str:
    uri = path.as_uri()
    client.notify("textDocument/didOpen", {"textDocument": {
        "uri": uri, "languageId": "fretish", "version": 1, "text": text}})
    return uri


def test_a_terabyte_content_length_is_skipped_and_the_next_request_answered(session):
    client, tmp = session
    client.raw(b"Content-Length: 1000000000000\r\n\r\n")
    got = client.request("textDocument/documentSymbol",
                         {"textDocument": {"uri": (tmp / "none.fret").as_uri()}})
    assert got is not None and got.get("result") == []
    assert client.proc.poll() is None
    assert client.close() == 0
    assert b"over the limit" in b"".join(client.stderr)


def test_malformed_messages_are_logged_and_skipped(session):
    client, tmp = session
    client.raw(b"Content-Length: 9\r\n\r\n{not json")
    client.raw(b"X-Junk: " + b"a" * 100_000 + b"\r\n")
    client.raw(b"Content-Length: " + b"9" * 5000 + b"\r\n\r\n")
    got = client.request("textDocument/hover", {"textDocument": 5, "position": "here"})
    assert got is not None and got["error"]["code"] == -32602     # refused, not ignored
    got = client.request("fretc/unknown", {})
    assert got is not None and "error" in got
    got = client.request("textDocument/documentSymbol",
                         {"textDocument": {"uri": (tmp / "none.fret").as_uri()}})
    assert got is not None and got.get("result") == []
    assert client.close() == 0


def test_the_check_on_save_is_a_job_the_next_edit_cancels(session):
    client, tmp = session
    uri = _open(client, tmp / "slow.fret", SLOW)
    client.notify("textDocument/didSave", {"textDocument": {"uri": uri}})
    (job,) = _until(lambda: job_processes(client.proc.pid))
    got = client.request("textDocument/hover", {"textDocument": {"uri": uri},
                                                "position": {"line": 0, "character": 1}})
    assert got is not None and "R1" in got["result"]["contents"]["value"]  # still serving
    assert alive(job)
    client.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": 2},
                                             "contentChanges": [{"text": SLOW + "\n"}]})
    assert _until(lambda: not alive(job)), "the edit did not stop the check"


def test_the_check_dies_with_the_server(session):
    client, tmp = session
    uri = _open(client, tmp / "slow.fret", SLOW)
    client.notify("textDocument/didSave", {"textDocument": {"uri": uri}})
    (job,) = _until(lambda: job_processes(client.proc.pid))
    client.proc.send_signal(signal.SIGKILL)
    client.proc.wait()
    assert _until(lambda: not alive(job)), "the check outlived the server"


def _document(n: int) -> str:
    return "@tick_period 100 ms\n" + "".join(
        f"R{i}: upon p the robot shall within {i % 7 + 1} seconds satisfy q & x > {i % 5}\n"
        for i in range(n))


def test_an_edit_of_a_10000_requirement_document_parses_the_one_sentence_edited():
    memory = Memory()
    text = _document(10_000)
    first = analyse(text, "/nonexistent/x.fret", memory)
    assert len(first.compiled) == 10_000 and not first.problems
    misses = memory.sentences.misses
    edited = text.replace("R5000: upon p", "R5000: upon p ")
    again = analyse("# a line above moves every requirement\n" + edited, "/nonexistent/x.fret",
                    memory)
    assert memory.sentences.misses == misses + 1
    assert [c.id for c in again.compiled] == [c.id for c in first.compiled]
    assert again.starts[10] == first.starts[10] + 1


def test_a_5_mb_document_is_refused_at_once_with_a_diagnostic():
    memory = Memory()
    text = _document(80_000)
    assert len(text) > 5_000_000 > MAX_DOCUMENT
    a = analyse(text, "/nonexistent/x.fret", memory)
    (p,) = a.problems
    assert "at most 2,000,000" in p.message and memory.sentences.misses == 0


def test_a_hover_on_a_million_tick_requirement_is_bounded():
    a = analyse("R1: upon p the sw shall within 1000000 ticks satisfy q\n", "/nonexistent/x.fret")
    text = a.hover(0, 1)
    assert len(text) <= MAX_HOVER and "F[0,1000000]" in text and "no diagram" in text


# --------------------------------------------------------------------------- round 7
def test_a_message_of_deeply_nested_arrays_is_skipped_and_the_server_lives(session):
    """A 2 KB JSON-RPC message of 1,000 nested arrays ended the server (RecursionError)."""
    client, tmp = session
    body = b'{"jsonrpc": "2.0", "id": 99, "method": "textDocument/hover", "params": ' + \
        b"[" * 1000 + b"]" * 1000 + b"}"
    client.raw(b"Content-Length: %d\r\n\r\n" % len(body) + body)
    got = client.request("textDocument/documentSymbol",
                         {"textDocument": {"uri": (tmp / "none.fret").as_uri()}})
    assert got is not None and got.get("result") == []
    assert client.proc.poll() is None and client.close() == 0


def test_exit_without_shutdown_exits_1(session):
    """LSP: the server exits with 1 on ``exit`` without ``shutdown`` before it (was 0)."""
    client, _tmp = session
    client.notify("exit", None)
    assert client.proc.wait(timeout=20) == 1


REF = ("R1: the robot shall always satisfy speed < 1\n"
       "R2: upon speed > 2 the robot shall immediately satisfy slow\n")


def _places(got) -> list:
    return sorted((r["uri"].rsplit("/", 1)[-1], r["range"]["start"]["line"],
                   r["range"]["start"]["character"]) for r in got["result"])


@pytest.mark.parametrize("init", ["root_and_folders", "no_root"])
def test_references_and_rename_list_each_place_once_with_or_without_a_root(tmp_path, init):
    """A client that gives ``rootUri`` and the same folder in ``workspaceFolders`` got each
    place twice (and every rename edit twice: overlapping edits, forbidden by LSP); one
    that gives neither got nothing: the open document's folder is the workspace then."""
    (tmp_path / "a.fret").write_text(REF)
    client = RawClient(tmp_path)
    try:
        params = {"processId": None, "capabilities": {}}
        if init == "root_and_folders":
            params.update(rootUri=tmp_path.as_uri(), workspaceFolders=[
                {"uri": tmp_path.as_uri(), "name": "ws"},
                {"uri": (tmp_path / ".").as_uri() + "/", "name": "again"}])
        else:
            params.update(rootUri=None)
        assert "result" in client.request("initialize", params)
        client.notify("initialized", {})
        uri = _open(client, tmp_path / "a.fret", REF)
        at = {"textDocument": {"uri": uri}, "position": {"line": 0, "character": 36}}
        got = client.request("textDocument/references",
                             {**at, "context": {"includeDeclaration": True}})
        want = [(i, line.index("speed")) for i, line in enumerate(REF.splitlines())]
        assert _places(got) == [("a.fret", i, c) for i, c in want], got
        got = client.request("textDocument/rename", {**at, "newName": "velocity"})
        edits = got["result"]["changes"][uri]
        assert sorted((e["range"]["start"]["line"], e["range"]["start"]["character"])
                      for e in edits) == want, got
    finally:
        client.close()


def test_rename_to_an_existing_variable_is_refused(session):
    """Renaming ``speed`` to ``slow`` merged two variables and gave the bindings file a
    duplicate key (a TOML it cannot read): refused, naming the variable."""
    client, tmp = session
    (tmp / "a.fret").write_text(REF)
    (tmp / "a.bindings.toml").write_text('[variables]\nspeed = "/v.data"\nslow = "/s.data"\n')
    uri = _open(client, tmp / "a.fret", REF)
    got = client.request("textDocument/rename", {"textDocument": {"uri": uri}, "position": {
        "line": 0, "character": 36}, "newName": "slow"})
    assert "error" in got and "slow" in got["error"]["message"] and \
        "exists" in got["error"]["message"], got
    assert (tmp / "a.bindings.toml").read_text().count("slow") == 1
