"""Authoring help in the engineer's editor: the FRETish language server (``fretc lsp``):
:mod:`editor.document` what it knows of a ``.fret`` document, :mod:`editor.server` the
protocol (pygls)."""
