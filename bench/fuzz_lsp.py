"""The ``lsp`` class of ``bench/fuzz_hostile.py``: hostile sessions of ``fretc lsp``.

Each input is one session of a server process (``python -m fretc lsp``) spoken to by a raw
client (:class:`RawClient`: the base protocol written by hand, so it can write what no
well-behaved client would) with a fixed seed: the ``initialize`` handshake, then
:data:`STEPS` hostile steps drawn at random:

* framing: a ``Content-Length`` of up to 10^18 bytes, not a number, a header line of
  100 KB, a body that is not JSON, JSON that is not an object, an unknown method, a request
  whose parameters have the wrong types;
* documents: opened and changed to hostile ``.fret`` texts (durations of 10^6 ticks, deep
  nesting, long lines, thousands of requirements, NUL and control characters, lone
  surrogates), changes whose ranges lie outside the document, saves (the check on save);
* requests at random places, inside and outside the documents: hover, completion,
  definition, references, prepare rename and rename (to hostile names), code actions,
  ``fretc.distinguish``, document symbols.

The oracle, after every step: the process is alive; each request is answered (a result or
an error) within :data:`BOUND` seconds; the server's resident memory (with its job
processes') stays under 1 GB; and at the end the session shuts down with exit code 0, and
the server's standard error holds no traceback through fretc's code (pygls's own report of
a request it refuses for its parameters is not one).
"""

from __future__ import annotations

import json
import os
import queue
import random
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: seconds within which every request must be answered
BOUND = 15.0
#: hostile steps per session
STEPS = 12
#: the memory oracle (bytes of resident memory, server and jobs)
MEMORY = 1 << 30


class RawClient:
    """A ``fretc lsp`` process and a reader thread that queues its messages."""

    def __init__(self, cwd: Path, env: dict | None = None):
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "fretc", "lsp"], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=str(cwd),
            env={**os.environ, "PYTHONPATH": str(ROOT / "src"), **(env or {})})
        self.messages: queue.Queue = queue.Queue()
        self.stderr: list[bytes] = []
        self.next_id = 0
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=lambda: self.stderr.extend(iter(
            self.proc.stderr.readline, b"")), daemon=True).start()

    def _read(self) -> None:
        out = self.proc.stdout
        while True:
            length = None
            while True:
                line = out.readline()
                if not line:
                    return
                if line.lower().startswith(b"content-length:"):
                    length = int(line.split(b":")[1])
                elif not line.strip():
                    break
            self.messages.put(json.loads(out.read(length)))

    def raw(self, data: bytes) -> None:
        """Write ``data`` as it is."""
        self.proc.stdin.write(data)
        self.proc.stdin.flush()

    def send(self, message: dict) -> None:
        body = json.dumps(message).encode("utf-8")
        self.raw(b"Content-Length: %d\r\n\r\n" % len(body) + body)

    def notify(self, method: str, params) -> None:
        self.send({"jsonrpc": "2.0", "method": method, "params": params})

    def request(self, method: str, params, bound: float = BOUND):
        """The response to a request (a dict with ``result`` or ``error``), waiting at most
        ``bound`` seconds; None past it."""
        self.next_id += 1
        rid = self.next_id
        self.send({"jsonrpc": "2.0", "id": rid, "method": method, "params": params})
        end = time.monotonic() + bound
        while True:
            try:
                m = self.messages.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                return None
            if m.get("id") == rid and "method" not in m:
                return m
            if time.monotonic() > end:
                return None

    def notifications(self, method: str) -> list[dict]:
        """The queued notifications of ``method`` (the others are dropped)."""
        out = []
        while not self.messages.empty():
            m = self.messages.get_nowait()
            if m.get("method") == method:
                out.append(m)
        return out

    def memory(self) -> int:
        """Resident bytes of the server and its job processes (Linux /proc; 0 elsewhere)."""
        return sum(_rss(p) for p in [self.proc.pid] + job_processes(self.proc.pid))

    def close(self) -> int:
        """Shut down and exit; the exit code (the process is killed past the bound)."""
        try:
            self.request("shutdown", None, bound=BOUND)
            self.notify("exit", None)
            return self.proc.wait(timeout=BOUND)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
            return self.proc.wait()


def _rss(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def job_processes(server_pid: int) -> list[int]:
    """The pids of the server's job processes (``fretc.editor.jobs``) alive now."""
    out = []
    for name in os.listdir("/proc") if os.path.isdir("/proc") else []:
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{name}/cmdline", "rb") as f:
                cmd = f.read()
        except OSError:
            continue
        if int(fields[1]) == server_pid and b"fretc.editor.jobs" in cmd:
            out.append(int(name))
    return out


def alive(pid: int) -> bool:
    """Whether process ``pid`` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def fretc_traceback(stderr: list[bytes]) -> str | None:
    """The first defect of fretc's in the server's standard error: a traceback through
    fretc's code (but a refusal of a request, ``JsonRpcInvalidParams``, which pygls logs with
    its traceback), or a handler's "fretc lsp: internal error" line."""
    text = b"".join(stderr).decode("utf-8", "replace")
    for line in text.splitlines():
        if "fretc lsp: internal error" in line:
            return line
    for block in text.split("Traceback (most recent call last):")[1:]:
        lines = block.splitlines()
        frames = [ln for ln in lines if ln.strip().startswith("File ")]
        last = next((ln for ln in lines if ln and not ln.startswith(" ")), "")
        if "JsonRpcInvalidParams" in last:
            continue
        if any(f"{ROOT}/" in f or "/fretc/" in f for f in frames):
            return "Traceback (most recent call last):" + block[:3000]
    return None


# ----------------------------------------------------------------------------- inputs
_PIECES = ["upon p ", "whenever q ", "in m mode ", "the sw shall ", "within 1000000 ticks ",
           "for 999999 ticks ", "eventually ", "satisfy ", "x > 3 ", "(((((", ")))))",
           "& ", "| ", "! ", "\x00", "\u202e", "\ud800", "#", "\"", "R1: ", "\n    ",
           "parent: R1\n", "@tick_period 100 ms\n", "@constant T 1 s\n", " " * 200]


def hostile_document(rng: random.Random) -> str:
    """A ``.fret`` text for the session (module docstring)."""
    kind = rng.randrange(4)
    if kind == 0:  # many requirements, long deadlines
        n = rng.choice([10, 300, 3000])
        return "\n".join(f"R{i}: upon p the sw shall within {rng.choice([5, 10**6])} ticks "
                         f"satisfy q & x{i % 7} > {i % 5}" for i in range(n)) + "\n"
    if kind == 1:  # deep nesting
        d = rng.choice([50, 500, 5000])
        return "R1: the sw shall always satisfy " + "(" * d + "p" + ")" * d + "\n"
    if kind == 2:  # one long line
        return "R1: the sw shall always satisfy " + " & ".join(
            f"v{i}" for i in range(rng.choice([100, 20000]))) + "\n"
    return "".join(rng.choice(_PIECES) for _ in range(rng.randrange(1, 120)))


def _position(rng: random.Random) -> dict:
    return {"line": rng.choice([0, 1, 2, 5, 10**6, -1]),
            "character": rng.choice([0, 3, 12, 40, 10**6, -5])}


def _framing(client: RawClient, rng: random.Random) -> None:
    kind = rng.randrange(6)
    if kind == 0:
        client.raw(b"Content-Length: %d\r\n\r\n" % rng.choice([10**12, 10**18, 70 << 20]))
    elif kind == 1:
        client.raw(b"Content-Length: " + rng.choice([b"-5", b"abc", b"9" * 5000]) + b"\r\n\r\n")
    elif kind == 2:
        client.raw(b"X-Junk: " + b"a" * 100_000 + b"\r\n")
    elif kind == 3:
        body = rng.choice([b"{not json", b"[1, 2]", b"\"text\"", b"{}", b"\xff\xfe"])
        client.raw(b"Content-Length: %d\r\n\r\n" % len(body) + body)
    elif kind == 4:
        client.request("fretc/unknown", {"x": 1}, bound=BOUND)
    else:
        client.request("textDocument/hover", {"textDocument": 5, "position": "here"},
                       bound=BOUND)


def _document_step(client: RawClient, rng: random.Random, uri: str, version: list) -> None:
    kind = rng.randrange(4)
    version[0] += 1
    text = hostile_document(rng)
    if kind == 0:
        client.notify("textDocument/didOpen", {"textDocument": {
            "uri": uri, "languageId": "fretish", "version": version[0], "text": text}})
    elif kind == 1:
        client.notify("textDocument/didChange", {
            "textDocument": {"uri": uri, "version": version[0]},
            "contentChanges": [{"text": text}]})
    elif kind == 2:
        client.notify("textDocument/didChange", {
            "textDocument": {"uri": uri, "version": version[0]},
            "contentChanges": [{"range": {"start": _position(rng), "end": _position(rng)},
                                "text": text[:200]}]})
    else:
        client.notify("textDocument/didSave", {"textDocument": {"uri": uri}})


_REQUESTS = ("textDocument/hover", "textDocument/completion", "textDocument/definition",
             "textDocument/references", "textDocument/prepareRename", "textDocument/rename",
             "textDocument/codeAction", "workspace/executeCommand",
             "textDocument/documentSymbol")


def _request_step(client: RawClient, rng: random.Random, uri: str) -> str | None:
    method = rng.choice(_REQUESTS)
    doc = {"uri": rng.choice([uri, uri, "file:///nonexistent/x.fret"])}
    params: dict = {"textDocument": doc, "position": _position(rng)}
    if method == "textDocument/references":
        params["context"] = {"includeDeclaration": True}
    elif method == "textDocument/rename":
        params["newName"] = rng.choice(["v2", "shall", "", "a b", "\x00", "R9", "x" * 5000])
    elif method == "textDocument/codeAction":
        params = {"textDocument": doc, "range": {"start": _position(rng),
                                                 "end": _position(rng)},
                  "context": {"diagnostics": []}}
    elif method == "workspace/executeCommand":
        params = {"command": "fretc.distinguish",
                  "arguments": rng.choice([[doc["uri"], 1], [], ["x"], [doc["uri"], -3]])}
    elif method == "textDocument/documentSymbol":
        params = {"textDocument": doc}
    got = client.request(method, params)
    return None if got is not None else f"{method} not answered within {BOUND:g} s"


def run_lsp(rng: random.Random, tmp: Path) -> list[str]:
    """One hostile session (module docstring); what the oracle found wrong."""
    folder = Path(tmp) / f"lsp{rng.randrange(10**9)}"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "x.bindings.toml").write_text('[tick]\nperiod = "100 ms"\n[variables]\n'
                                            'p = "/a.data > 0"\nx = "/b.data"\n')
    client = RawClient(folder)
    bad: list[str] = []
    try:
        if client.request("initialize", {"processId": None, "rootUri": folder.as_uri(),
                                         "capabilities": {}}) is None:
            return [f"initialize not answered within {BOUND:g} s"]
        client.notify("initialized", {})
        uri, version = (folder / "h.fret").as_uri(), [0]
        for _step in range(STEPS):
            kind = rng.randrange(3)
            if kind == 0:
                _framing(client, rng)
            elif kind == 1:
                _document_step(client, rng, uri, version)
            else:
                late = _request_step(client, rng, uri)
                if late:
                    bad.append(late)
            if client.proc.poll() is not None:
                bad.append(f"the server ended (exit code {client.proc.returncode})")
                break
            if client.memory() > MEMORY:
                bad.append(f"the server and its jobs hold {client.memory() >> 20} MB")
        client.notifications("textDocument/publishDiagnostics")
    finally:
        code = client.close()
    if code != 0 and not bad:
        bad.append(f"exit code {code} after shutdown and exit")
    tb = fretc_traceback(client.stderr)
    if tb:
        bad.append(tb)
    return bad
