"""``fretc lsp``: a language server for ``.fret`` files over stdio (the Language Server
Protocol 3.17, with ``pygls``). What it knows of a document is :mod:`fretc.editor.document`'s:

* diagnostics, published when a document is opened, changed or saved: syntax and file
  errors at their line and column with the CLI's messages, formalization errors (a duration
  that is not a whole number of ticks, an undeclared named duration), variables that the
  bindings file beside the document does not bind; on save also ``fretc check``'s
  conflicts, unsatisfiable and vacuous requirements under a small work budget;
* hover on a requirement: its template key and ft_inf, ft and pt (FRET/SMV text);
* completion: the components the document names, the variables of the bindings and
  FRETish's words (components first after a condition);
* go to definition from a variable to its line in the bindings file;
* document symbols: the requirement ids.

A document the server cannot read gives a diagnostic, never an exit: every handler catches
what the analysis raises.
"""

from __future__ import annotations

from lsprotocol import types as T
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path

from fretc.editor.document import Analysis, analyse, check_problems

__all__ = ["make_server", "main"]


def _kind(kind: str) -> T.CompletionItemKind:
    return {"keyword": T.CompletionItemKind.Keyword, "component": T.CompletionItemKind.Class,
            "variable": T.CompletionItemKind.Variable}[kind]


def _analysed(server: LanguageServer, uri: str, text: str, check: bool) -> Analysis:
    """The document's analysis (and on save ``fretc check``'s findings); an analysis that
    fails is logged to the client, never the server's end."""
    try:
        a = analyse(text, to_fs_path(uri) or uri)
        if check:  # on save: fretc check's conflicts and vacuity, small budget
            a.problems = a.problems + check_problems(a)
        return a
    except Exception as exc:  # never exit on a document: say so in the editor
        server.window_log_message(T.LogMessageParams(
            T.MessageType.Error, f"fretc could not analyse {uri}: {exc!r}"))
        return Analysis(lines=text.split("\n"))


def _publish(server: LanguageServer, uri: str, version, a: Analysis) -> None:
    """The document's problems as LSP diagnostics (source ``fretc``)."""
    server.text_document_publish_diagnostics(T.PublishDiagnosticsParams(
        uri=uri, version=version, diagnostics=[
            T.Diagnostic(range=T.Range(T.Position(p.line, p.col),
                                       T.Position(p.line, max(p.end_col, p.col + 1))),
                         message=p.message, severity=T.DiagnosticSeverity(p.severity),
                         source="fretc") for p in a.problems]))


def make_server() -> LanguageServer:
    """A server with the features of the module docstring (not started)."""
    from importlib.metadata import version

    server = LanguageServer("fretc", version("fretc"))
    cache: dict[str, Analysis] = {}

    def refresh(uri: str, check: bool = False) -> Analysis:
        doc = server.workspace.get_text_document(uri)
        cache[uri] = a = _analysed(server, uri, doc.source, check)
        _publish(server, uri, doc.version, a)
        return a

    def analysis(uri: str) -> Analysis:
        return cache.get(uri) or refresh(uri)

    @server.feature(T.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls, params: T.DidOpenTextDocumentParams):
        refresh(params.text_document.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls, params: T.DidChangeTextDocumentParams):
        refresh(params.text_document.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls, params: T.DidSaveTextDocumentParams):
        refresh(params.text_document.uri, check=True)

    @server.feature(T.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls, params: T.DidCloseTextDocumentParams):
        cache.pop(params.text_document.uri, None)

    @server.feature(T.TEXT_DOCUMENT_HOVER)
    def hover(ls, params: T.HoverParams):
        text = analysis(params.text_document.uri).hover(params.position.line)
        if text is None:
            return None
        return T.Hover(contents=T.MarkupContent(kind=T.MarkupKind.Markdown, value=text))

    @server.feature(T.TEXT_DOCUMENT_COMPLETION,
                    T.CompletionOptions(trigger_characters=[" "]))
    def completion(ls, params: T.CompletionParams):
        a = analysis(params.text_document.uri)
        items = [T.CompletionItem(label=label, kind=_kind(kind), sort_text=f"{i:05d}")
                 for i, (label, kind) in enumerate(a.completions(params.position.line,
                                                                 params.position.character))]
        return T.CompletionList(is_incomplete=False, items=items)

    @server.feature(T.TEXT_DOCUMENT_DEFINITION)
    def definition(ls, params: T.DefinitionParams):
        doc = server.workspace.get_text_document(params.text_document.uri)
        word = doc.word_at_position(params.position)
        found = analysis(params.text_document.uri).definition(word) if word else None
        if found is None:
            return None
        path, line = found
        return T.Location(uri=from_fs_path(path),
                          range=T.Range(T.Position(line, 0), T.Position(line, 0)))

    @server.feature(T.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    def symbols(ls, params: T.DocumentSymbolParams):
        a = analysis(params.text_document.uri)
        out = []
        for c, start in zip(a.compiled, a.starts):
            r = T.Range(T.Position(start, 0), T.Position(start, len(a.lines[start])
                                                         if start < len(a.lines) else 0))
            out.append(T.DocumentSymbol(name=c.id, kind=T.SymbolKind.Object, range=r,
                                        selection_range=r, detail=c.text[:80]))
        return out

    return server


def main() -> None:
    """Serve over stdio until the client exits."""
    make_server().start_io()
