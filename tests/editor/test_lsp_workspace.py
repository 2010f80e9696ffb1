"""``fretc lsp`` over a workspace of two requirement files and a bindings file, driven by a real
LSP client (pytest-lsp): find references and rename of a variable and of a requirement id
across the files, a variable's type and unit from its binding in hover and completion, the
diagnostic of a variable read as a boolean here and as a number there, the check on save in a
job, and the code action that runs ``fretc distinguish`` on an edited requirement."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

pytest.importorskip("pygls")
pytest_lsp = pytest.importorskip("pytest_lsp")

from lsprotocol import types as T  # noqa: E402
from pytest_lsp import ClientServerConfig, LanguageClient  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
A = ("@tick_period 100 ms\n"
     "R1: upon too_close the robot shall within 1 second satisfy speed < 0.1\n"
     "R2: the robot shall always satisfy speed <= 0.5\n"
     "    parent: R1\n")
B = ("R3: whenever fast the robot shall immediately satisfy alarm\n"
     "    parent: R1\n"
     "R4: the robot shall always satisfy level\n")
C = "R5: the robot shall always satisfy level > 2\n"
BINDINGS = ('[tick]\nperiod = "100 ms"\n'
            '[types]\n"/cmd_vel" = "geometry_msgs/msg/Twist"\n'
            '"/scan" = "sensor_msgs/msg/LaserScan"\n'
            '[variables]\n'
            'too_close = "min(/scan.ranges) < 0.9"\n'
            'speed = "abs(/cmd_vel.linear.x)"\n'
            'fast = "speed > 0.4"\n'
            'alarm = "/alarm.data"\n'
            'level = "/level.data"\n')


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    ws = tmp_path_factory.mktemp("ws")
    (ws / "a.fret").write_text(A)
    (ws / "b.fret").write_text(B)
    (ws / "sub").mkdir()
    (ws / "sub" / "c.fret").write_text(C)
    (ws / "robot.bindings.toml").write_text(BINDINGS)
    return ws


WS: dict = {}


@pytest_lsp.fixture(config=ClientServerConfig(
    server_command=[sys.executable, "-m", "fretc", "lsp"],
    server_env={**os.environ, "PYTHONPATH": str(ROOT / "src")}))
async def client(lsp_client: LanguageClient, workspace):
    WS["root"] = workspace
    await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(), root_uri=workspace.as_uri()))
    yield
    await lsp_client.shutdown_session()


async def _open(client: LanguageClient, path: Path, text: str | None = None) -> str:
    uri = path.as_uri()
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="fretish", version=1,
                                         text=path.read_text() if text is None else text)))
    await client.wait_for_notification(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    return uri


def _apply(text: str, edits: list) -> str:
    lines = text.split("\n")
    for e in sorted(edits, key=lambda e: (e.range.start.line, e.range.start.character),
                    reverse=True):
        ln = lines[e.range.start.line]
        lines[e.range.start.line] = (ln[:e.range.start.character] + e.new_text
                                     + ln[e.range.end.character:])
    return "\n".join(lines)


@pytest.mark.asyncio
async def test_references_and_rename_of_a_variable_across_files(client: LanguageClient):
    ws = WS["root"]
    uri = await _open(client, ws / "a.fret")
    at = T.Position(1, A.splitlines()[1].index("speed") + 2)
    refs = await client.text_document_references_async(T.ReferenceParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=at,
        context=T.ReferenceContext(include_declaration=True)))
    got = sorted((Path(r.uri[len("file://"):]).name, r.range.start.line,
                  r.range.start.character) for r in refs)
    bind = BINDINGS.splitlines()
    key_line = next(i for i, s in enumerate(bind) if s.startswith("speed ="))
    ref_line = next(i for i, s in enumerate(bind) if s.startswith("fast ="))
    assert got == sorted([("a.fret", 1, A.splitlines()[1].index("speed")),
                          ("a.fret", 2, A.splitlines()[2].index("speed")),
                          ("robot.bindings.toml", key_line, 0),
                          ("robot.bindings.toml", ref_line, bind[ref_line].index("speed"))])
    edit = await client.text_document_rename_async(T.RenameParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=at, new_name="velocity"))
    files = {Path(u[len("file://"):]).name: e for u, e in edit.changes.items()}
    assert set(files) == {"a.fret", "robot.bindings.toml"}
    new_a = _apply(A, files["a.fret"])
    new_b = _apply(BINDINGS, files["robot.bindings.toml"])
    assert "speed" not in new_a and "speed" not in new_b and new_b.count("velocity") == 2
    from fretc.editor.bindings_info import read_bindings

    assert read_bindings(new_b, "x").variables["fast"].expr == "velocity > 0.4"
    with pytest.raises(Exception, match="not a FRETish variable name"):
        await client.text_document_rename_async(T.RenameParams(
            text_document=T.TextDocumentIdentifier(uri=uri), position=at,
            new_name="shall"))


@pytest.mark.asyncio
async def test_references_and_rename_of_a_requirement_id(client: LanguageClient):
    ws = WS["root"]
    uri = await _open(client, ws / "a.fret")
    refs = await client.text_document_references_async(T.ReferenceParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(1, 1),
        context=T.ReferenceContext(include_declaration=True)))
    assert sorted((Path(r.uri[len("file://"):]).name, r.range.start.line) for r in refs) == \
        [("a.fret", 1), ("a.fret", 3), ("b.fret", 1)]
    edit = await client.text_document_rename_async(T.RenameParams(
        text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(1, 0),
        new_name="SAFE-1"))
    files = {Path(u[len("file://"):]).name: e for u, e in edit.changes.items()}
    assert _apply(B, files["b.fret"]).splitlines()[1] == "    parent: SAFE-1"
    assert _apply(A, files["a.fret"]).splitlines()[1].startswith("SAFE-1: upon")
    with pytest.raises(Exception, match="exists already"):
        await client.text_document_rename_async(T.RenameParams(
            text_document=T.TextDocumentIdentifier(uri=uri), position=T.Position(1, 0),
            new_name="R4"))


@pytest.mark.asyncio
async def test_hover_and_completion_give_the_type_and_unit_of_the_binding(client):
    ws = WS["root"]
    uri = await _open(client, ws / "a.fret")
    doc = T.TextDocumentIdentifier(uri=uri)
    hover = await client.text_document_hover_async(T.HoverParams(
        text_document=doc, position=T.Position(2, A.splitlines()[2].index("speed"))))
    text = hover.contents.value
    assert "type: number, unit: m/s" in text and "abs(/cmd_vel.linear.x)" in text
    assert "robot.bindings.toml:" in text and "read as number by R1" in text
    hover = await client.text_document_hover_async(T.HoverParams(
        text_document=doc, position=T.Position(1, A.splitlines()[1].index("too_close"))))
    assert "type: boolean" in hover.contents.value
    items = await client.text_document_completion_async(T.CompletionParams(
        text_document=doc, position=T.Position(2, len("R2: the robot shall always satisfy "))))
    detail = {i.label: i.detail for i in items.items}
    assert detail["speed"] == "number (m/s)" and detail["too_close"] == "boolean"
    assert detail["level"] == "unknown type"      # /level's type is not in [types]


@pytest.mark.asyncio
async def test_a_variable_read_as_boolean_and_as_number_is_an_error(client):
    ws = WS["root"]
    await _open(client, ws / "b.fret")               # R4 reads level as a boolean
    uri = await _open(client, ws / "sub" / "c.fret")  # R5 as a number
    (d,) = [d for d in client.diagnostics[uri] if "level" in d.message]
    assert d.severity == T.DiagnosticSeverity.Error
    assert "R5 reads 'level' as a number" in d.message and "R4 (b.fret:3)" in d.message
    assert (d.range.start.line, d.range.start.character) == (0, C.index("level"))
    # bound to a boolean, read as a number: too_close > 1
    uri = await _open(client, ws / "d.fret", "R6: the robot shall always satisfy "
                                             "too_close > 1\n")
    (d,) = client.diagnostics[uri]
    assert "bound to a boolean in robot.bindings.toml:" in d.message


@pytest.mark.asyncio
async def test_on_save_check_runs_in_a_job_and_finds_a_conflict(client, workspace):
    text = "R7: the robot shall always satisfy alarm\nR8: the robot shall always satisfy !alarm\n"
    uri = await _open(client, workspace / "e.fret", text)
    client.text_document_did_save(T.DidSaveTextDocumentParams(
        text_document=T.TextDocumentIdentifier(uri=uri)))
    for _ in range(3):  # the analysis, then the job's answer
        await client.wait_for_notification(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        if any("conflict" in d.message for d in client.diagnostics[uri]):
            break
    assert {d.range.start.line for d in client.diagnostics[uri]
            if "conflict" in d.message} == {0, 1}


@pytest.mark.asyncio
async def test_code_action_distinguishes_an_edited_requirement(client, workspace):
    uri = await _open(client, workspace / "a.fret")
    edited = A.replace("within 1 second", "within 2 seconds")
    client.text_document_did_change(T.DidChangeTextDocumentParams(
        text_document=T.VersionedTextDocumentIdentifier(uri=uri, version=2),
        content_changes=[T.TextDocumentContentChangeWholeDocument(text=edited)]))
    await client.wait_for_notification(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    doc = T.TextDocumentIdentifier(uri=uri)
    none = await client.text_document_code_action_async(T.CodeActionParams(
        text_document=doc, range=T.Range(T.Position(2, 0), T.Position(2, 0)),
        context=T.CodeActionContext(diagnostics=[])))
    assert not none                                   # R2 is as saved
    (action,) = await client.text_document_code_action_async(T.CodeActionParams(
        text_document=doc, range=T.Range(T.Position(1, 0), T.Position(1, 0)),
        context=T.CodeActionContext(diagnostics=[])))
    assert "R1" in action.title and action.command == "fretc.distinguish"
    out = await client.workspace_execute_command_async(T.ExecuteCommandParams(
        command=action.command, arguments=action.arguments))
    assert out.startswith("not equivalent: R1 (saved) and R1 (edited) disagree")
    assert "R1 (saved)   violated" in out and "of 11 ticks" in out
