"""The ``testsjson``, ``drive`` and ``lspnest`` classes of ``bench/fuzz_hostile.py`` (its
docstring): test runs and the language server's nesting, rename and references.

* ``testsjson``: a valid ``tests.json`` with 1-3 hostile changes (a member missing or of
  another type, ``requirements`` empty or a string, ids with ``..``, separators, absolute
  paths, NUL, 300 characters, traces outside the folder, JSON nested 10^5 deep, not JSON)
  run by ``fretc testrun`` with a command that writes its log. Oracle: exit 0 to 3, never a
  traceback; a refusal (exit 2) names ``tests.json``; no file appears or changes outside the
  test folder (a canary folder beside it is compared before and after); a test without an
  obligation never passes.
* ``drive``: ``python -m fretc.sim drive`` of a short trace with random ``--lead-in`` and
  ``--lead-out`` (NaN, infinities, negative, 0, huge), traces without a driven column or
  without ticks. Oracle: exit 0 or 2, never a traceback; exit 0 only with a log whose
  driven ``too_close`` over the trace's ticks is the trace's (the run applied it whole).
* ``lspnest``: a ``fretc lsp`` session, given ``rootUri`` and ``workspaceFolders`` (the
  same folder twice), one of them or neither, that receives a message of 200-5,000 nested
  arrays or objects, then references and rename requests (to new names, to existing
  variables, to reserved words), and ends with or without ``shutdown``. Oracle: the server
  answers every request; each place is listed once and no rename edits one place twice;
  a rename never gives the bindings file a key twice; the exit code is LSP's (0 after
  ``shutdown``, else 1).
"""

from __future__ import annotations

import json
import random
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BINDINGS = ROOT / "requirements" / "safe_ros.bindings.toml"


def _cli(args: list[str]):
    from click.testing import CliRunner

    from fretc.cli import main

    return CliRunner().invoke(main, [str(a) for a in args])


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


_HOSTILE_IDS = ["../../canary/victim", "/tmp/fretc-fuzz-victim", "a/b", "..", ".", "a\\b",
                "x\x00y", "x" * 300, "", "C:evil", "T01"]


def _mutate(rng: random.Random, doc: dict) -> str:
    """``doc`` (a tests.json) with hostile changes, as the file's text."""
    t = doc["tests"][0]
    for _ in range(rng.randrange(1, 4)):
        how = rng.randrange(9)
        if how == 0:
            t.pop(rng.choice(["covers", "generated_for", "id", "trace"]), None)
        elif how == 1:
            t[rng.choice(["covers", "generated_for", "id", "trace"])] = rng.choice(
                [None, 7, "x", [], {}, [[]], [{"requirement": 1}], True])
        elif how == 2:
            doc["requirements"] = rng.choice([[], "safe_ros.fret", [7], None, {}])
        elif how == 3:
            t["id"] = rng.choice(_HOSTILE_IDS)
        elif how == 4:
            t["trace"] = rng.choice(["../t.csv", "/etc/passwd", "a/../../x.csv", "T01.csv"])
        elif how == 5:
            t["covers"], t["generated_for"] = [], None
        elif how == 6:
            doc["bindings"] = rng.choice([7, None, "/nonexistent.toml", []])
        elif how == 7:
            return "[" * 100_000 + "]" * 100_000
        else:
            return json.dumps(doc)[: rng.randrange(1, 60)]
    return json.dumps(doc)


def run_testsjson(rng: random.Random, tmp: Path) -> list[str]:
    """One hostile tests.json run by fretc testrun (module docstring)."""
    base = tmp / f"tj{rng.randrange(10**9)}"
    folder, canary = base / "a" / "b", base / "canary"
    folder.mkdir(parents=True)
    canary.mkdir()
    (canary / "victim.mcap").write_text("precious")
    (folder / "T01.csv").write_text("too_close\nfalse\n")
    doc = {"requirements": [str(ROOT / "requirements" / "safe_ros.fret")],
           "tests": [{"id": "T01", "trace": "T01.csv", "ticks": 1,
                      "generated_for": {"requirement": "R5", "obligation": "trigger"},
                      "covers": [{"requirement": "R5", "obligation": "trigger", "tick": 0}],
                      "expected": {"R5": "satisfied"}}]}
    (folder / "tests.json").write_text(_mutate(rng, doc))
    before = _snapshot(canary)
    writer = f"{sys.executable} -c \"import sys; open(sys.argv[2], 'w').write('log')\""
    res = _cli(["testrun", folder, "--command", writer])
    bad = []
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        bad.append(f"traceback: {type(res.exception).__name__}: {res.exception}")
    if res.exit_code not in (0, 1, 2, 3):
        bad.append(f"exit {res.exit_code}: {res.output[-300:]}")
    if res.exit_code == 2 and "tests.json" not in res.output:
        bad.append(f"a refusal that names no tests.json: {res.output[-300:]}")
    if _snapshot(canary) != before or Path("/tmp/fretc-fuzz-victim.mcap").exists():
        bad.append("a file outside the test folder was written or removed")
    if " pass:" in res.output and ('"covers": []' in (folder / "tests.json").read_text()):
        bad.append(f"a test without an obligation passed: {res.output[-300:]}")
    return bad


def _trace(rng: random.Random, path: Path) -> list[bool] | None:
    """A short trace with ``too_close`` (or without it, or without ticks); its values."""
    n = rng.choice([0, 3, 12, 25])
    close = [3 <= k < 6 for k in range(n)]
    kind = rng.randrange(4)
    if kind == 0:
        path.write_text("time,stopped\n" + "".join(f"{k / 10},true\n" for k in range(n)))
        return None
    path.write_text("time,too_close\n" + "".join(f"{k / 10},{str(c).lower()}\n"
                                                 for k, c in enumerate(close)))
    return close


def run_drive(rng: random.Random, tmp: Path) -> list[str]:
    """One drive of the simulator with hostile options (module docstring)."""
    from click.testing import CliRunner

    from fretc.logs import open_log
    from fretc.signals.bindings.files import load_bindings
    from fretc.signals.clock import sample
    from fretc.sim.__main__ import main as sim_main

    d = tmp / f"drive{rng.randrange(10**9)}"
    d.mkdir()
    close = _trace(rng, d / "t.csv")
    opts = []
    for flag in ("--lead-in", "--lead-out"):
        if rng.random() < 0.7:
            opts += [flag, rng.choice(["nan", "inf", "-inf", "-1", "0", "0.5", "2", "1e9",
                                       "-100", "1e-9"])]
    res = CliRunner().invoke(sim_main, ["drive", str(d / "t.csv"), str(d / "x.mcap"), "-b",
                                        str(BINDINGS), *opts])
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        return [f"traceback {opts}: {type(res.exception).__name__}: {res.exception}"]
    if res.exit_code not in (0, 2):
        return [f"exit {res.exit_code} {opts}: {res.output[-300:]}"]
    if res.exit_code == 2:
        return [] if not (d / "x.mcap").exists() else [f"exit 2 {opts} but a log is written"]
    if close is None or not close:
        return [f"exit 0 {opts} for a trace with nothing to drive: {res.output[-200:]}"]
    b = load_bindings(str(BINDINGS))
    got = [t.values["too_close"] for t in sample(open_log(str(d / "x.mcap")), b)]
    n = len(close)
    if not any(got[i:i + n] == close for i in range(len(got) - n + 1)):
        return [f"exit 0 {opts}: the log's too_close does not hold the trace's {n} ticks"]
    return []


def _nested(rng: random.Random) -> bytes:
    depth = rng.choice([200, 1000, 5000])
    inner = ("[" * depth + "]" * depth) if rng.random() < 0.5 else \
        ('{"a":' * depth + "1" + "}" * depth)
    body = ('{"jsonrpc": "2.0", "id": 9999, "method": "textDocument/hover", "params": '
            + inner + "}").encode()
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


REF = ("R1: the robot shall always satisfy speed < 1\n"
       "R2: upon speed > 2 the robot shall immediately satisfy slow\n")


def _init(client, rng: random.Random, folder: Path):
    params = {"processId": None, "capabilities": {}}
    how = rng.randrange(4)
    if how in (0, 1):
        params["rootUri"] = folder.as_uri()
    if how in (0, 2):
        params["workspaceFolders"] = [{"uri": folder.as_uri(), "name": "a"},
                                      {"uri": folder.as_uri() + "/", "name": "b"}]
    return client.request("initialize", params)


def _rename_step(client, rng: random.Random, folder: Path, uri: str, at: dict) -> list[str]:
    new = rng.choice(["velocity", "slow", "shall", "x1", "speed"])
    got = client.request("textDocument/rename", {**at, "newName": new})
    if got is None:
        return [f"rename to {new} not answered"]
    edits = (got.get("result") or {}).get("changes") or {}
    bad = []
    for u, es in edits.items():
        spots = [(e["range"]["start"]["line"], e["range"]["start"]["character"]) for e in es]
        if len(spots) != len(set(spots)):
            bad.append(f"rename edits a place twice in {u}")
        if u.endswith(".toml"):
            text = (folder / "a.bindings.toml").read_text().split("\n")
            for e in sorted(es, key=lambda e: (e["range"]["start"]["line"],
                                               e["range"]["start"]["character"]), reverse=True):
                s, t = e["range"]["start"], e["range"]["end"]
                ln = text[s["line"]]
                text[s["line"]] = ln[:s["character"]] + e["newText"] + ln[t["character"]:]
            try:
                tomllib.loads("\n".join(text))
            except tomllib.TOMLDecodeError as exc:
                bad.append(f"rename to {new} breaks the bindings file: {exc}")
    return bad


def run_lspnest(rng: random.Random, tmp: Path) -> list[str]:
    """One LSP session: nesting, references and rename (module docstring)."""
    from fuzz_lsp import RawClient

    folder = tmp / f"lspn{rng.randrange(10**9)}"
    folder.mkdir(parents=True)
    (folder / "a.fret").write_text(REF)
    (folder / "a.bindings.toml").write_text('[variables]\nspeed = "/v.data"\n'
                                            'slow = "/s.data < 1"\n')
    client = RawClient(folder)
    bad: list[str] = []
    shutdown = rng.random() < 0.7
    try:
        if _init(client, rng, folder) is None:
            return ["initialize not answered"]
        client.notify("initialized", {})
        uri = (folder / "a.fret").as_uri()
        client.notify("textDocument/didOpen", {"textDocument": {
            "uri": uri, "languageId": "fretish", "version": 1, "text": REF}})
        client.raw(_nested(rng))
        at = {"textDocument": {"uri": uri}, "position": {"line": 0, "character": 36}}
        got = client.request("textDocument/references",
                             {**at, "context": {"includeDeclaration": True}})
        if got is None or client.proc.poll() is not None:
            return ["the server did not answer after a nested message"]
        spots = [(r["uri"], r["range"]["start"]["line"], r["range"]["start"]["character"])
                 for r in got.get("result") or []]
        if len(spots) != len(set(spots)) or len(spots) < 3:
            bad.append(f"references {spots}")
        bad += _rename_step(client, rng, folder, uri, at)
    finally:
        try:
            if shutdown:
                client.request("shutdown", None)
            client.notify("exit", None)
        except OSError:  # the server is gone: said below with its exit code
            bad.append("the server ended before shutdown: "
                       + b"".join(client.stderr).decode("utf-8", "replace")[-600:])
        try:
            code = client.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            client.proc.kill()
            code = client.proc.wait()
    if code != (0 if shutdown else 1):
        bad.append(f"exit code {code} {'after' if shutdown else 'without'} shutdown")
    return bad


#: the classes of this module for bench/fuzz_hostile.py: name -> (runner, weight)
RUN_CLASSES = {"testsjson": (run_testsjson, 4), "drive": (run_drive, 0.5),
               "lspnest": (run_lspnest, 0.3)}

__all__ = ["RUN_CLASSES", "run_testsjson", "run_drive", "run_lspnest"]
