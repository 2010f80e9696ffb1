"""``fretc lsp``: a language server for ``.fret`` files over stdio (the Language Server
Protocol 3.17, with ``pygls``). What it knows of a document is :mod:`fretc.editor.document`'s,
of the workspace :mod:`fretc.editor.workspace`'s:

Design notes: ARCHITECTURE.md, `editor/server.py`."""

from __future__ import annotations

import asyncio
import functools
import gc
import os
import logging
import re

from lsprotocol import types as T
from pygls.exceptions import JsonRpcInvalidParams
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path

from fretc.editor.document import Analysis, Memory, Problem, analyse
from fretc.editor.jobs import CHECK_SECONDS, DISTINGUISH_SECONDS, JobFailed, run_job
from fretc.editor.workspace import Place, Workspace, valid_id, valid_variable_name

__all__ = ["make_server", "main", "DISTINGUISH_COMMAND"]

DISTINGUISH_COMMAND = "fretc.distinguish"
#: analyses between two full collections of cyclic garbage (:meth:`_State._tidy`)
TIDY_EVERY = 200
#: seconds without an analysis before the collection of :meth:`_State._tidy`
TIDY_PAUSE = 1.0
_ID_LINE = re.compile(r"([A-Za-z0-9_.-]+)[ \t]*:")
_PARENT = re.compile(r"[ \t]+parent[ \t]*:[ \t]*([A-Za-z0-9_.-]+)")
log = logging.getLogger("fretc.editor")


def _guarded(default=None):
    """A handler that answers ``default`` (and logs one line on the standard error, "fretc
    lsp: internal error ...": a defect of fretc the fuzzer looks for) when it raises
    anything but a refusal of the request (:class:`JsonRpcInvalidParams`)."""
    def wrap(f):
        @functools.wraps(f)
        def guarded(ls, params):
            try:
                return f(ls, params)
            except JsonRpcInvalidParams:
                raise
            except Exception as exc:  # noqa: BLE001 - the server answers, and says so
                log.error("fretc lsp: internal error in %s: %s: %s", f.__name__,
                          type(exc).__name__, str(exc).splitlines()[0] if str(exc) else "")
                return default() if callable(default) else default
        return guarded
    return wrap


def _empty_completion() -> T.CompletionList:
    return T.CompletionList(is_incomplete=False, items=[])


def _kind(kind: str) -> T.CompletionItemKind:
    return {"keyword": T.CompletionItemKind.Keyword, "component": T.CompletionItemKind.Class,
            "variable": T.CompletionItemKind.Variable}[kind]


def _range(line: int, col: int, end: int) -> T.Range:
    return T.Range(T.Position(line, col), T.Position(line, max(end, col)))


def _diagnostics(problems: list[Problem]) -> list[T.Diagnostic]:
    return [T.Diagnostic(range=_range(p.line, p.col, max(p.end_col, p.col + 1)),
                         message=p.message, severity=T.DiagnosticSeverity(p.severity),
                         source="fretc") for p in problems]


def _id_at(line_text: str, col: int) -> str | None:
    """The requirement id written at ``col`` of a line (its ``ID:`` or a ``parent:``)."""
    m = _ID_LINE.match(line_text)
    if m and not line_text.startswith("@") and col <= m.end(1):
        return m.group(1)
    m = _PARENT.match(line_text)
    if m and m.start(1) <= col <= m.end(1):
        return m.group(1)
    return None


class _State:
    """The server's memory: analyses of open documents, saved texts, running jobs."""

    def __init__(self, server: LanguageServer):
        self.server = server
        self.memory = Memory()
        self.cache: dict[str, Analysis] = {}
        self.saved: dict[str, str] = {}
        self.jobs: dict[str, asyncio.Task] = {}
        self.analyses = 0
        self._tidied = 0
        self._tidy_handle: asyncio.TimerHandle | None = None
        self._roots: list[str] | None = None
        self._workspaces: dict[tuple[str, ...], Workspace] = {}

    def workspace(self, uri: str | None = None) -> Workspace:
        """The files the client's folders hold (``workspaceFolders``, else ``rootUri``),
        each folder once (:func:`_distinct`); a client that gave neither: the folder of
        ``uri``'s document."""
        if self._roots is None:
            ws = self.server.workspace
            roots = [p for f in (ws.folders or {}).values() if (p := to_fs_path(f.uri))]
            if ws.root_path:
                roots.append(ws.root_path)
            self._roots = _distinct([r for r in roots if r])
        key = tuple(self._roots)
        if not key and uri:
            key = (os.path.dirname(to_fs_path(uri) or ""),)
        if key not in self._workspaces:
            self._workspaces[key] = Workspace(list(key), self.memory, self.open_text)
        return self._workspaces[key]

    def forget(self) -> None:
        """List the workspaces' files again at the next request."""
        for w in self._workspaces.values():
            w.forget()

    def document(self, uri: str):
        """The open document ``uri`` (pygls's), or None when the client has not opened it."""
        return self.server.workspace.text_documents.get(uri)

    def open_text(self, path: str) -> str | None:
        doc = self.document(from_fs_path(path))
        return doc.source if doc is not None else None

    def analyse(self, uri: str) -> Analysis:
        """The open document's analysis, published (an empty one for a document the client
        has not opened); an analysis that fails is logged to the client, never the server's
        end."""
        doc = self.document(uri)
        if doc is None:
            return Analysis()
        path = to_fs_path(uri) or uri
        try:
            elsewhere = self.workspace(uri).uses_elsewhere(path)
            a = analyse(doc.source, path, self.memory, elsewhere)
        except Exception as exc:  # noqa: BLE001 - never exit on a document: say so
            self.log(f"fretc could not analyse {uri}: {exc!r}", T.MessageType.Error)
            log.error("fretc lsp: internal error in the analysis: %s: %s",
                      type(exc).__name__, str(exc).splitlines()[0] if str(exc) else "")
            a = Analysis(lines=doc.source.split("\n"))
        self.cache[uri] = a
        self.publish(uri, doc.version, a.problems)
        self._tidy()
        return a

    def _tidy(self) -> None:
        """After :data:`TIDY_EVERY` analyses (and after the first), at the first pause of
        :data:`TIDY_PAUSE` s without an analysis (at the latest after five times as many): a
        full collection of cyclic garbage, then the survivors frozen out of the collector's
        sight (``gc.freeze``), so that no keystroke waits for a full collection over the
        session's thousands of kept sentences (one took 130 ms at 1,000 requirements:
        bench/bench_lsp.py; :func:`main` leaves full collections to this method). Frozen
        objects are still freed when no longer referenced."""
        self.analyses += 1
        if self._tidy_handle is not None:
            self._tidy_handle.cancel()
            self._tidy_handle = None
        if self.analyses - self._tidied >= 5 * TIDY_EVERY:  # no pause came: now
            self._tidy_now()
        elif self.analyses - self._tidied >= TIDY_EVERY or self._tidied == 0:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:  # not serving (a test's direct call)
                return
            self._tidy_handle = loop.call_later(TIDY_PAUSE, self._tidy_now)

    def _tidy_now(self) -> None:
        self._tidy_handle = None
        self._tidied = self.analyses
        gc.collect()
        gc.freeze()

    def analysis(self, uri: str) -> Analysis:
        return self.cache.get(uri) or self.analyse(uri)

    def publish(self, uri: str, version, problems: list[Problem]) -> None:
        self.server.text_document_publish_diagnostics(T.PublishDiagnosticsParams(
            uri=uri, version=version, diagnostics=_diagnostics(problems)))

    def log(self, text: str, kind=T.MessageType.Info) -> None:
        self.server.window_log_message(T.LogMessageParams(kind, text))

    def cancel(self, uri: str) -> None:
        task = self.jobs.pop(uri, None)
        if task is not None and not task.done():
            task.cancel()

    async def check_on_save(self, uri: str, version, text: str, a: Analysis) -> None:
        """``fretc check`` of the saved document in a job; its problems join the
        document's when it answers for this version."""
        path = to_fs_path(uri) or uri
        try:
            out = await run_job({"kind": "check", "text": text, "path": path}, CHECK_SECONDS)
        except JobFailed as exc:
            extra = [Problem(0, 0, 1, 3, f"fretc check on save: {exc}: conflicts and "
                                         "vacuity were not checked")]
        else:
            if "error" in out:
                extra = [Problem(0, 0, 1, 3, f"fretc check on save failed: {out['error']}")]
            else:
                extra = [Problem(*p) for p in out.get("problems", [])]
        doc = self.document(uri)
        if doc is not None and doc.version == version and self.cache.get(uri) is a:
            self.publish(uri, version, a.problems + extra)


def _locations(places: list[Place]) -> list[T.Location]:
    return [T.Location(uri=from_fs_path(p.path), range=_range(p.line, p.col, p.end_col))
            for p in dict.fromkeys(places)]


def _distinct(roots: list[str]) -> list[str]:
    """The folders of ``roots`` each once (by real path), none inside another kept one: a
    client that names one folder as ``rootUri`` and in ``workspaceFolders`` (or a folder
    and a sub-folder) would have each file listed twice."""
    real = sorted({os.path.realpath(r) for r in roots}, key=len)
    out: list[str] = []
    for r in real:
        if not any(os.path.commonpath([r, k]) == k for k in out):
            out.append(r)
    return out


def _name_at(st: _State, uri: str, pos: T.Position) -> tuple[str, str] | None:
    """("variable" | "id", name) written at ``pos``, or None."""
    a = st.analysis(uri)
    name = a.word_at(pos.line, pos.character)
    if name:
        return "variable", name
    line = a.lines[pos.line] if pos.line < len(a.lines) else ""
    rid = _id_at(line, pos.character)
    return ("id", rid) if rid else None


def _rename(st: _State, uri: str, pos: T.Position, new: str) -> T.WorkspaceEdit:
    found = _name_at(st, uri, pos)
    if found is None:
        raise JsonRpcInvalidParams("no variable or requirement id here to rename")
    kind, old = found
    ws = st.workspace(uri)
    shown = new if len(new) <= 80 else new[:80] + "..."
    if kind == "variable":
        if not valid_variable_name(new):
            raise JsonRpcInvalidParams(f"{shown!r} is not a FRETish variable name (a letter, "
                                       "then letters, digits and '_'; not a reserved word)")
        if new != old and ws.variable_places(new):
            raise JsonRpcInvalidParams(f"the variable {new!r} exists already: the rename would "
                                       "make two variables one (and a bindings file's key "
                                       "twice)")
        places = ws.variable_places(old)
    else:
        if not valid_id(new):
            raise JsonRpcInvalidParams(f"{shown!r} is not a requirement id (letters, digits, "
                                       "'_', '.', '-')")
        if new in ws.ids():
            raise JsonRpcInvalidParams(f"the requirement id {new!r} exists already")
        places = ws.id_places(old)
    changes: dict[str, list[T.TextEdit]] = {}
    for p in dict.fromkeys(places):  # each place once: LSP forbids overlapping edits
        changes.setdefault(from_fs_path(p.path), []).append(
            T.TextEdit(range=_range(p.line, p.col, p.end_col), new_text=new))
    return T.WorkspaceEdit(changes=changes)


def _edited(st: _State, uri: str, line: int):
    """(id, saved text, edited text, tick period) of the requirement at ``line`` when its
    wording differs from the saved document's requirement of that id, else None."""
    a = st.analysis(uri)
    c = a.requirement_at(line)
    if c is None or c.error is not None or uri not in st.saved:
        return None
    before = analyse(st.saved[uri], to_fs_path(uri) or uri, st.memory)
    old = next((x for x in before.compiled if x.id == c.id), None)
    if old is None or old.error is not None or " ".join(old.text.split()) == " ".join(
            c.text.split()):
        return None
    return c.id, old.text, c.text, c.entry.tick_period


def make_server() -> LanguageServer:
    """A server with the features of the module docstring (not started)."""
    from importlib.metadata import version

    server = LanguageServer("fretc", version("fretc"))
    st = _State(server)
    server.fretc_state = st  # type: ignore[attr-defined]  # (the tests and main() reach the jobs through it)

    @server.feature(T.TEXT_DOCUMENT_DID_OPEN)
    @_guarded(None)
    def did_open(ls, params: T.DidOpenTextDocumentParams):
        st.forget()
        st.saved[params.text_document.uri] = params.text_document.text
        st.cache.pop(params.text_document.uri, None)
        st.analyse(params.text_document.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_CHANGE)
    @_guarded(None)
    def did_change(ls, params: T.DidChangeTextDocumentParams):
        st.cancel(params.text_document.uri)
        st.analyse(params.text_document.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_SAVE)
    @_guarded(None)
    def did_save(ls, params: T.DidSaveTextDocumentParams):
        uri = params.text_document.uri
        st.cancel(uri)
        doc = st.document(uri)
        if doc is None:  # a save of a document the client has not opened
            return
        st.forget()
        a = st.analyse(uri)
        st.saved[uri] = doc.source
        st.jobs[uri] = asyncio.ensure_future(st.check_on_save(uri, doc.version, doc.source, a))

    @server.feature(T.TEXT_DOCUMENT_DID_CLOSE)
    @_guarded(None)
    def did_close(ls, params: T.DidCloseTextDocumentParams):
        st.cancel(params.text_document.uri)
        st.cache.pop(params.text_document.uri, None)
        st.saved.pop(params.text_document.uri, None)

    _reading_features(server, st)
    _editing_features(server, st)
    return server


def _reading_features(server: LanguageServer, st: _State) -> None:
    """Hover, completion, definition, references, symbols."""

    @server.feature(T.TEXT_DOCUMENT_HOVER)
    @_guarded(None)
    def hover(ls, params: T.HoverParams):
        a = st.analysis(params.text_document.uri)
        text = a.hover(params.position.line, params.position.character)
        if text is None:
            return None
        return T.Hover(contents=T.MarkupContent(kind=T.MarkupKind.Markdown, value=text))

    @server.feature(T.TEXT_DOCUMENT_COMPLETION, T.CompletionOptions(trigger_characters=[" "]))
    @_guarded(_empty_completion)
    def completion(ls, params: T.CompletionParams):
        a = st.analysis(params.text_document.uri)
        items = []
        for i, (label, kind) in enumerate(a.completions(params.position.line,
                                                        params.position.character)):
            info = a.variables.get(label) if kind == "variable" else None
            items.append(T.CompletionItem(
                label=label, kind=_kind(kind), sort_text=f"{i:05d}",
                detail=info.detail() if info else None,
                documentation=(T.MarkupContent(kind=T.MarkupKind.Markdown,
                                               value=f"`{info.expr}`\n\n{info.how}")
                               if info else None)))
        return T.CompletionList(is_incomplete=False, items=items)

    @server.feature(T.TEXT_DOCUMENT_DEFINITION)
    @_guarded(None)
    def definition(ls, params: T.DefinitionParams):
        found = _name_at(st, params.text_document.uri, params.position)
        if found is None:
            return None
        kind, name = found
        if kind == "id":
            places = [p for p in st.workspace(params.text_document.uri).id_places(name)
                      if p.col == 0]
            return _locations(places)[0] if places else None
        where = st.analysis(params.text_document.uri).definition(name)
        if where is None:
            return None
        return T.Location(uri=from_fs_path(where[0]), range=_range(where[1], 0, 0))

    @server.feature(T.TEXT_DOCUMENT_REFERENCES)
    @_guarded(list)
    def references(ls, params: T.ReferenceParams):
        found = _name_at(st, params.text_document.uri, params.position)
        if found is None:
            return []
        kind, name = found
        ws = st.workspace(params.text_document.uri)
        return _locations(ws.variable_places(name) if kind == "variable"
                          else ws.id_places(name))

    @server.feature(T.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    @_guarded(list)
    def symbols(ls, params: T.DocumentSymbolParams):
        a = st.analysis(params.text_document.uri)
        out = []
        for c, start in zip(a.compiled, a.starts):
            r = _range(start, 0, len(a.lines[start]) if start < len(a.lines) else 0)
            out.append(T.DocumentSymbol(name=c.id, kind=T.SymbolKind.Object, range=r,
                                        selection_range=r, detail=c.text[:80]))
        return out


def _editing_features(server: LanguageServer, st: _State) -> None:
    """Rename, the distinguish code action and its command."""

    @server.feature(T.TEXT_DOCUMENT_PREPARE_RENAME)
    @_guarded(None)
    def prepare_rename(ls, params: T.PrepareRenameParams):
        found = _name_at(st, params.text_document.uri, params.position)
        if found is None:
            return None
        kind, name = found
        ws = st.workspace(params.text_document.uri)
        places = [p for p in (ws.variable_places(name) if kind == "variable"
                              else ws.id_places(name))
                  if from_fs_path(p.path) == params.text_document.uri
                  and p.line == params.position.line
                  and p.col <= params.position.character <= p.end_col]
        return _range(places[0].line, places[0].col, places[0].end_col) if places else None

    @server.feature(T.TEXT_DOCUMENT_RENAME)
    @_guarded(None)
    def rename(ls, params: T.RenameParams):
        return _rename(st, params.text_document.uri, params.position, params.new_name)

    @server.feature(T.TEXT_DOCUMENT_CODE_ACTION, T.CodeActionOptions(
        code_action_kinds=[T.CodeActionKind.Source]))
    @_guarded(list)
    def code_action(ls, params: T.CodeActionParams):
        edited = _edited(st, params.text_document.uri, params.range.start.line)
        if edited is None:
            return []
        # a Command (LSP allows one in place of a CodeAction): clients built on lsprotocol
        # read any action with a "command" member as a Command
        return [T.Command(title=f"Compare {edited[0]} with its saved wording (fretc "
                                "distinguish)", command=DISTINGUISH_COMMAND,
                          arguments=[params.text_document.uri, params.range.start.line])]

    @server.command(DISTINGUISH_COMMAND)
    async def distinguish(ls, *args):
        if len(args) != 2 or not isinstance(args[0], str) or not isinstance(args[1], int):
            return "fretc.distinguish takes the document's uri and a 0-based line"
        uri, line = args
        edited = _edited(st, uri, line)
        if edited is None:
            return "no requirement here whose wording differs from the saved one"
        rid, old, new, period = edited
        try:
            out = await run_job({"kind": "distinguish", "a": old, "b": new,
                                 "a_label": f"{rid} (saved)", "b_label": f"{rid} (edited)",
                                 "period": None if period is None else str(period)},
                                DISTINGUISH_SECONDS)
        except JobFailed as exc:
            out = {"error": str(exc)}
        text = out.get("text") or f"fretc distinguish: {out.get('error')}"
        st.log(text)
        server.window_show_message(T.ShowMessageParams(T.MessageType.Info,
                                                       text.splitlines()[0]))
        return text


def main() -> int:
    """Serve over stdio until the client exits; the jobs still running end with it. The
    exit code (:func:`fretc.editor.transport.serve_stdio`'s)."""
    from fretc.editor.transport import serve_stdio

    gc.set_threshold(700, 10, 1 << 30)  # full collections: _State._tidy's, at pauses
    server = make_server()
    try:
        return serve_stdio(server)
    finally:
        for task in list(server.fretc_state.jobs.values()):  # type: ignore[attr-defined]  # (set above)
            task.cancel()
