"""``fretc explain FILE [ID...]``: each requirement's reading in plain English, its template
key, durations in ticks and time, and its diagram in FRET's manner (:mod:`fretc.monitors.explain`)
in the terminal, and as SVG with ``-o DIR``; ``--semantics DIR`` writes FRET's semantics
diagram of each (:mod:`fretc.reports.semantics_diagram`: scope intervals, triggers, the
timing's window).

Exit codes: 0 explained, 1 a requirement did not formalize (its error printed), 2 an input
error (a file, an id that does not exist).
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from fretc.cli.options import TEXT_ATTRIBUTE_OPTION, TICK_PERIOD_OPTION
from fretc.cli.options import shown as _shown

__all__ = ["explain_cmd"]


@click.command("explain")
@click.argument("file", type=click.Path(exists=True))
@click.argument("ids", nargs=-1)
@click.option("-o", "--output", type=click.Path(file_okay=False), default=None,
              help="Write one SVG diagram per requirement into this folder.")
@click.option("--semantics", "semantics", type=click.Path(file_okay=False), default=None,
              help="Write FRET's semantics diagram of each requirement (its scope intervals, "
                   "trigger points and the timing's window, as FRET's Semantics panel draws "
                   "them) into this folder, one ID.svg each.")
@TICK_PERIOD_OPTION
@TEXT_ATTRIBUTE_OPTION
def explain_cmd(file: str, ids: tuple[str, ...], output: str | None,
                tick_period: str | None, semantics: str | None = None) -> None:
    """Explain the requirements of FILE (or only IDS): plain English, template key and a
    diagram of the scope, the triggers and the response windows."""
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.monitors.explain import explain
    from fretc.common.textsafe import file_stems
    from fretc.reports.explanation import svg, text

    from fretc.cli.options import entries_with_period, text_attribute

    compiled = compile_entries(entries_with_period(
        load_requirements([file], text_attribute=text_attribute()), tick_period))
    known = [c.id for c in compiled]
    unknown = [i for i in ids if i not in known]
    if unknown:
        click.echo(_shown(f"error: {file}: no requirement {', '.join(map(repr, unknown))} "
                          f"(it has {', '.join(known)})"), err=True)
        sys.exit(2)
    code = 0
    stems = file_stems(known)
    _prepare_outputs(file, compiled, ids, stems, [("-o", output), ("--semantics", semantics)])
    for c in compiled:
        if ids and c.id not in ids:
            continue
        if c.formalization is None:
            click.echo(_shown(str(c.error) if c.error else f"{c.id}: free-form, not "
                              "formalized"), err=True)
            code = 1 if c.error else code
            continue
        x = explain(c)
        click.echo(_shown(text(x)))
        if output is not None:
            _write(Path(output) / f"{stems[c.id]}.svg", svg(x))
        if semantics is not None:
            from fretc.reports.semantics_diagram import svg as semantics_svg

            req = c.requirement
            assert req is not None  # (it formalized)
            _write(Path(semantics) / f"{stems[c.id]}.svg",
                   semantics_svg(req, c.formalization.ticks, c.id))
    sys.exit(code)


def _write(path: Path, text: str) -> None:
    from fretc.common.outputs import write_file

    write_file(path, text)
    click.echo(_shown(f"wrote {path}"), err=True)


def _prepare_outputs(file: str, compiled, ids, stems, outputs) -> None:
    """Refuse an output folder over the inputs, then make each folder given."""
    outputs = [(flag, folder) for flag, folder in outputs if folder is not None]
    if not outputs:
        return
    from fretc.common.outputs import output_folder

    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    files, folders = requirement_inputs([file])
    refuse_outputs_over_inputs(
        [(flag, Path(folder) / f"{stems[c.id]}.svg") for flag, folder in outputs
         for c in compiled if (not ids or c.id in ids) and c.formalization is not None],
        files, outputs, folders)
    for _flag, folder in outputs:
        output_folder(folder)
