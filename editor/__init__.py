"""Authoring help in the engineer's editor: the FRETish language server (``fretc lsp``):
:mod:`fretc.editor.document` what it knows of a ``.fret`` document, :mod:`fretc.editor.server` the
protocol (pygls)."""
