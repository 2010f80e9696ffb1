"""The ``fretc`` command (click).

``fretc FILE... --emit ltl|monitor|psl`` compiles requirement files (the default command,
``fretc compile``); ``fretc audit`` checks recorded runs; ``fretc report`` writes the
traceability report. Exit codes: 0 success, 1 a requirement failed (or, for ``audit``, a
violation), 2 usage or input errors, 3 an internal error (a generated monitor that is not
valid: nothing is written).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Optional

import click

from fretish.errors import FretishError


class _DefaultGroup(click.Group):
    """A group whose first argument, when it is not a sub-command, goes to ``compile``
    (so ``fretc requirements/r1.fret --emit ltl`` works as the users wrote it).

    The optional sub-commands (:func:`_register_optional`) are attached on first need: not
    when the first argument is a requirement file (a path with a folder or a ``.fret`` /
    ``.json`` name, which no sub-command is called), so ``fretc FILE`` does not import the
    audit and report machinery (start-up time, issue 9)."""

    _optional_registered = False

    def _ensure_optional(self) -> None:
        if not _DefaultGroup._optional_registered:
            _DefaultGroup._optional_registered = True
            _register_optional()

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h",
                                                                     "--version"):
            if not _names_a_file(args[0]):
                self._ensure_optional()
            if args[0] not in self.commands:
                args = ["compile"] + list(args)
        return super().parse_args(ctx, args)

    def get_command(self, ctx, cmd_name):
        if cmd_name not in self.commands:
            self._ensure_optional()
        return super().get_command(ctx, cmd_name)

    def list_commands(self, ctx):
        self._ensure_optional()
        return super().list_commands(ctx)


def _names_a_file(arg: str) -> bool:
    """Can ``arg`` only be a requirement file (never a sub-command name)?"""
    return "/" in arg or os.sep in arg or arg.lower().endswith((".fret", ".json"))


@click.group(cls=_DefaultGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="fretc")
def main():
    """fretc: FRETish requirements to FRET's LTL, runtime monitors and AJPF properties, and
    audits of recorded robot runs against them."""


def _load(paths) -> list:
    from compiler.build import compile_entries
    from fretish.files import load_requirements

    try:
        entries = load_requirements([Path(p) for p in paths])
    except FretishError as exc:
        click.echo(_shown(str(exc)), err=True)
        sys.exit(2)
    except OSError as exc:
        click.echo(_shown(f"error: {exc}"), err=True)
        sys.exit(2)
    return compile_entries(entries)


def _shown(text: str) -> str:
    """Text for the terminal: control and bidi characters escaped, lines kept
    (:func:`fretish.textsafe.visible`)."""
    from fretish.textsafe import visible

    return visible(text, keep="\n")


@main.command("compile")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--emit", type=click.Choice(["ltl", "monitor", "psl"]), default="ltl",
              show_default=True, help="What to produce.")
@click.option("--json", "as_json", is_flag=True, help="ltl: print a JSON list instead of text.")
@click.option("-o", "--output", type=click.Path(), default=None,
              help="monitor/psl: output file (one input) or directory; default: stdout.")
@click.option("--psl-map", type=click.Path(exists=True), default=None,
              help="psl: TOML mapping of variables to AJPF beliefs, percepts and actions.")
def compile_cmd(files, emit, as_json, output, psl_map):
    """Compile requirement FILES (.fret or FRET JSON exports)."""
    compiled = _load(files)
    if not compiled:
        click.echo(f"error: no requirements in {', '.join(files)} (empty or only comments)",
                   err=True)
        sys.exit(2)
    failed = [c for c in compiled if c.error is not None]
    for c in failed:
        click.echo(_shown(str(c.error)), err=True)
    if emit == "ltl":
        _emit_ltl(compiled, as_json)
    elif emit == "monitor":
        from compiler.codegen import emit_monitors
        internal: list = []
        outputs = emit_monitors(compiled, internal)
        for exc in internal:  # never exit 0 with a monitor that is not valid
            click.echo(str(exc), err=True)
        if internal:
            sys.exit(4)  # internal error: not audit's 3 (incomplete)
        _check_output(outputs, output, ".py")
        _write_outputs(outputs, output, ".py")
        for stem, text in outputs.items():
            for rid, reason in _skipped(text):
                if not any(c.id == rid and c.error is not None for c in compiled):
                    click.echo(f"skipped {rid} ({stem}): {reason}", err=True)
    elif emit == "psl":
        from compiler.ajpf import emit_psl
        try:
            outputs = emit_psl(compiled, mapping_path=psl_map)
        except FretishError as exc:
            click.echo(str(exc), err=True)
            sys.exit(2)
        _check_output(outputs, output, ".psl")
        _write_outputs(outputs, output, ".psl")
    sys.exit(1 if failed else 0)


def _emit_ltl(compiled, as_json: bool) -> None:
    if as_json:
        click.echo(json.dumps([c.to_json() for c in compiled], indent=2))
        return
    for c in compiled:
        click.echo(_shown(f"{c.id}  ({c.location()})"))
        click.echo(_shown(f"  text    {c.text}"))
        if c.formalization is not None:
            f = c.formalization
            click.echo(f"  key     {f.key}")
            click.echo(f"  ft      {c.smv('ft')}")
            click.echo(f"  ft_inf  {c.smv('ft_inf')}")
            click.echo(f"  pt      {c.smv('pt')}")
            for w in f.warnings:
                click.echo(f"  warning {w}")
        elif c.freeform:
            click.echo("  free-form: kept, not formalized")
        else:
            click.echo(_shown("  error   " + getattr(c.error, "message", str(c.error))))
        click.echo("")


def _skipped(module_text: str) -> list:
    """(id, reason) of the ``SKIPPED`` dict literal of a generated module."""
    import ast

    start = module_text.find("\nSKIPPED = {")
    if start < 0:
        return []
    end = module_text.find("\n}", start)
    try:
        return list(ast.literal_eval(module_text[start + len("\nSKIPPED = "):end + 2]).items())
    except (ValueError, SyntaxError):  # pragma: no cover - the template writes a literal
        return []


def _check_output(outputs: dict, output: Optional[str], suffix: str) -> None:
    """``-o`` is a file for one output and a directory for several: a path ending in
    ``suffix`` for several outputs is an error (it would become a directory named so)."""
    if output is not None and len(outputs) > 1 and Path(output).suffix == suffix:
        click.echo(f"error: -o {output}: {len(outputs)} modules are written (one per input "
                   f"file: {', '.join(sorted(outputs))}); give a directory (no {suffix} "
                   "suffix) or one input file", err=True)
        sys.exit(2)


def _write_outputs(outputs: dict, output: Optional[str], suffix: str) -> None:
    """``outputs`` maps a file stem to text. One output and ``-o FILE``: write the file;
    ``-o DIR``: one file per stem; no ``-o``: print them."""
    if output is None:
        for text in outputs.values():
            click.echo(text, nl=False)
        return
    out = Path(output)
    if len(outputs) == 1 and not out.is_dir() and not output.endswith(("/", "\\")):
        # one module: -o is the file
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(next(iter(outputs.values())), encoding="utf-8")
        click.echo(f"wrote {out}", err=True)
        return
    out.mkdir(parents=True, exist_ok=True)
    for stem, text in outputs.items():
        path = out / f"{stem}{suffix}"
        path.write_text(text, encoding="utf-8")
        click.echo(f"wrote {path}", err=True)


def _register_optional() -> None:
    """Attach ``audit`` (``monitors/cli.py``; it imports its engine lazily) and, once
    ``monitors/report.py`` provides it, ``report``. Called on first need by
    :class:`_DefaultGroup` (not at import: ``fretc FILE`` does not need them)."""
    from monitors.cli import audit_cmd

    main.add_command(audit_cmd, "audit")
    main.add_command(__import__("fretc.check", fromlist=["check_cmd"]).check_cmd, "check")
    from fretc.inspect import inspect_cmd; main.add_command(inspect_cmd, "inspect")  # noqa: E702
    try:
        from monitors.report import report_cmd
    except ModuleNotFoundError as exc:
        if exc.name != "monitors.report":
            raise
    else:
        main.add_command(report_cmd, "report")
    __import__("fretc.watch").watch.register(main)


if __name__ == "__main__":  # pragma: no cover
    main()
