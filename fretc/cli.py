"""The ``fretc`` command (click).

``fretc FILE... --emit ltl|monitor|psl`` compiles requirement files (the default command,
``fretc compile``); ``fretc audit`` checks recorded runs; ``fretc report`` writes the
traceability report. Exit codes: 0 success, 1 a requirement failed (or, for ``audit``, a
violation), 2 usage or input errors, 3 an internal error (a generated monitor that is not
valid: nothing is written).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Optional

import click

from fretish.errors import FretishError


class _DefaultGroup(click.Group):
    """A group whose first argument, when it is not a sub-command, goes to ``compile``
    (so ``fretc requirements/r1.fret --emit ltl`` works as the users wrote it)."""

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h",
                                                                     "--version"):
            args = ["compile"] + list(args)
        return super().parse_args(ctx, args)


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
        click.echo(str(exc), err=True)
        sys.exit(2)
    except OSError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(2)
    return compile_entries(entries)


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
    failed = [c for c in compiled if c.error is not None]
    for c in failed:
        click.echo(str(c.error), err=True)
    if emit == "ltl":
        _emit_ltl(compiled, as_json)
    elif emit == "monitor":
        from compiler.codegen import emit_monitors
        internal: list = []
        outputs = emit_monitors(compiled, internal)
        for exc in internal:  # never exit 0 with a monitor that is not valid
            click.echo(str(exc), err=True)
        if internal:
            sys.exit(3)
        _write_outputs(outputs, output, ".py")
    elif emit == "psl":
        from compiler.ajpf import emit_psl
        try:
            outputs = emit_psl(compiled, mapping_path=psl_map)
        except FretishError as exc:
            click.echo(str(exc), err=True)
            sys.exit(2)
        _write_outputs(outputs, output, ".psl")
    sys.exit(1 if failed else 0)


def _emit_ltl(compiled, as_json: bool) -> None:
    if as_json:
        click.echo(json.dumps([c.to_json() for c in compiled], indent=2))
        return
    for c in compiled:
        click.echo(f"{c.id}  ({c.location()})")
        click.echo(f"  text    {c.text}")
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
            click.echo("  error   " + getattr(c.error, "message", str(c.error)))
        click.echo("")


def _write_outputs(outputs: dict, output: Optional[str], suffix: str) -> None:
    """``outputs`` maps a file stem to text. One output and ``-o FILE``: write the file;
    ``-o DIR``: one file per stem; no ``-o``: print them."""
    if output is None:
        for text in outputs.values():
            click.echo(text, nl=False)
        return
    out = Path(output)
    if len(outputs) == 1 and (out.suffix or not out.is_dir()) and out.suffix:
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
    ``monitors/report.py`` provides it, ``report``."""
    from monitors.cli import audit_cmd

    main.add_command(audit_cmd, "audit")
    try:
        from monitors.report import report_cmd
    except ModuleNotFoundError as exc:
        if exc.name != "monitors.report":
            raise
    else:
        main.add_command(report_cmd, "report")
    __import__("fretc.watch").watch.register(main)


_register_optional()

if __name__ == "__main__":  # pragma: no cover
    main()
