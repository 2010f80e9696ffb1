"""``fretc lsp`` driven by a real LSP client (pytest-lsp) over stdio: a syntax error is a
diagnostic at its line and column and goes away when fixed; hovering a requirement shows
its ft_inf; completion after ``upon too_close `` offers the document's components; go to
definition reaches the binding line; document symbols are the requirement ids."""

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
GOOD = ("@tick_period 100 ms\n"
        "R1: upon too_close agilex_agent shall within 1 second satisfy stopped\n"
        "R2: the scout_mini shall always satisfy clearance > 0\n")
BAD = GOOD + "R3: upon too_close the robot shall always satisfy stopped &\n"


@pytest_lsp.fixture(config=ClientServerConfig(
    server_command=[sys.executable, "-m", "fretc", "lsp"],
    server_env={**os.environ, "PYTHONPATH": str(ROOT / "src")}))
async def client(lsp_client: LanguageClient):
    await lsp_client.initialize_session(T.InitializeParams(
        capabilities=T.ClientCapabilities(), root_uri=(ROOT / "requirements").as_uri()))
    yield
    await lsp_client.shutdown_session()


async def _open(client: LanguageClient, text: str) -> str:
    # beside requirements/safe_ros.bindings.toml: its variables are the document's
    uri = (ROOT / "requirements" / "editor_test.fret").as_uri()
    client.text_document_did_open(T.DidOpenTextDocumentParams(
        text_document=T.TextDocumentItem(uri=uri, language_id="fretish", version=1,
                                         text=text)))
    await client.wait_for_notification(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    return uri


@pytest.mark.asyncio
async def test_a_syntax_error_is_a_diagnostic_until_it_is_fixed(client: LanguageClient):
    uri = await _open(client, BAD)
    (d,) = client.diagnostics[uri]
    # where the CLI puts it: line 4, after the '&' the expression is missing (1-based
    # column len + 1 there, 0-based len here)
    assert (d.range.start.line, d.range.start.character) == (3, len(BAD.splitlines()[3]))
    assert d.severity == T.DiagnosticSeverity.Error and "expression" in d.message
    client.text_document_did_change(T.DidChangeTextDocumentParams(
        text_document=T.VersionedTextDocumentIdentifier(uri=uri, version=2),
        content_changes=[T.TextDocumentContentChangeWholeDocument(text=GOOD)]))
    await client.wait_for_notification(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    assert list(client.diagnostics[uri]) == []


@pytest.mark.asyncio
async def test_hover_completion_definition_and_symbols(client: LanguageClient):
    uri = await _open(client, GOOD)
    doc = T.TextDocumentIdentifier(uri=uri)
    hover = await client.text_document_hover_async(T.HoverParams(
        text_document=doc, position=T.Position(1, 1)))  # on the id: the requirement
    assert "ft_inf" in hover.contents.value and "F[0,10] stopped" in hover.contents.value
    items = await client.text_document_completion_async(T.CompletionParams(
        text_document=doc, position=T.Position(1, len("R1: upon too_close "))))
    labels = [i.label for i in items.items]
    assert labels[:2] == ["agilex_agent", "scout_mini"]  # the components first
    assert "shall" in labels and "stopped" in labels
    loc = await client.text_document_definition_async(T.DefinitionParams(
        text_document=doc, position=T.Position(1, 12)))  # on "too_close"
    assert loc.uri.endswith("safe_ros.bindings.toml")
    lines = (ROOT / "requirements" / "safe_ros.bindings.toml").read_text().splitlines()
    assert lines[loc.range.start.line].lstrip().startswith("too_close")
    syms = await client.text_document_document_symbol_async(T.DocumentSymbolParams(
        text_document=doc))
    assert [s.name for s in syms] == ["R1", "R2"]
