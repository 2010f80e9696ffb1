"""``fretc lsp``: the FRETish language server over stdio (:mod:`fretc.editor.server`), for any
editor with a Language Server Protocol client (VS Code, Neovim, Emacs' eglot; see
docs/guide/editors.md). Needs the ``editor`` extra (``pip install 'fretc[editor]'``)."""

from __future__ import annotations

import sys

import click

__all__ = ["lsp_cmd"]


@click.command("lsp")
@click.option("--stdio", is_flag=True, help="Serve over stdin/stdout (the default; "
              "accepted because editors pass it).")
def lsp_cmd(stdio: bool) -> None:
    """Serve the FRETish language server over stdio: diagnostics, hover (with a variable's
    type and unit), completion, go to definition, find references, rename, a code action
    comparing a requirement with its saved wording, document symbols for .fret files."""
    try:
        from fretc.editor.server import main
    except ImportError as exc:
        click.echo(f"error: fretc lsp needs pygls ({exc.name} is missing): "
                   "pip install 'fretc[editor]'", err=True)
        sys.exit(2)
    sys.exit(main())
