"""MkDocs hook: the command reference rendered from fretc's click commands at build time.

A page that holds the line ``<!-- fretc-commands -->`` gets, in its place, one section per
command of ``fretc`` (the group itself first): its usage line, its help text as ``--help``
prints it, and a table of its options (flags and value, help with the default and range
click shows). Nothing is checked in, so the reference cannot fall behind the code; ``mkdocs
build --strict`` fails if fretc cannot be imported.
"""

from __future__ import annotations

import click

MARKER = "<!-- fretc-commands -->"


def _cell(text: str) -> str:
    """``text`` as one Markdown table cell: pipes escaped, line breaks as spaces."""
    return " ".join(text.split()).replace("|", "\\|")


def _options_table(cmd: click.Command, ctx: click.Context) -> list[str]:
    rows = []
    for param in cmd.get_params(ctx):
        record = param.get_help_record(ctx)
        if record is None or isinstance(param, click.Argument):  # named in the usage line
            continue
        flags, help_text = record
        rows.append(f"| `{_cell(flags)}` | {_cell(help_text)} |")
    if not rows:
        return []
    return ["| option | meaning |", "|---|---|", *rows, ""]


def _help_text(cmd: click.Command, ctx: click.Context) -> list[str]:
    """The command's description as ``--help`` formats it (indentation and ``\\b``
    paragraphs kept), in a text block."""
    formatter = ctx.make_formatter()
    cmd.format_help_text(ctx, formatter)
    text = formatter.getvalue().rstrip()
    if not text:
        return []
    lines = [ln[2:] if ln.startswith("  ") else ln for ln in text.splitlines()]
    return ["```text", *lines, "```", ""]


def _section(name: str, cmd: click.Command, parent: click.Context | None,
             settings: dict) -> list[str]:
    ctx = click.Context(cmd, info_name=name, parent=parent, **settings)
    usage = " ".join(cmd.collect_usage_pieces(ctx))
    out = [f"## `{ctx.command_path}`", "", f"    {ctx.command_path} {usage}", ""]
    return out + _help_text(cmd, ctx) + _options_table(cmd, ctx)


def render() -> str:
    """Markdown of every command's reference, the ``fretc`` group first, then its
    sub-commands in name order."""
    from fretc.cli import main

    root = click.Context(main, info_name="fretc")
    settings = dict(main.context_settings)  # -h as well as --help, as the commands have
    out = _section("fretc", main, None, settings)
    for name in main.list_commands(root):
        cmd = main.get_command(root, name)
        out += _section(name, cmd, root, {**settings, **cmd.context_settings})
    return "\n".join(out) + "\n"


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER in markdown:
        return markdown.replace(MARKER, render())
    return markdown
