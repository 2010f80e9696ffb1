"""``fretc FILE --emit c -o DIR``, ``--emit c2po``, ``--emit cocospec`` and ``--emit ogma``:
the C99 monitors of :mod:`fretc.compiler.c_codegen`, the R2U2 specifications of
:mod:`fretc.compiler.c2po`, the Kind 2 contracts of :mod:`fretc.compiler.cocospec` and
Ogma's component specifications of :mod:`fretc.compiler.ogma`, written by ``fretc compile``
(:mod:`fretc.cli.compile`)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import click

from fretc.cli.options import shown

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["write_c", "write_c2po", "write_exports"]


def write_c(compiled: Sequence[Compiled], output: str | None, split: bool,
            inputs: tuple[list, list] = ([], [])) -> None:
    """Write the C files of ``compiled`` into the folder ``output`` (required: several
    files) and report the requirements without a monitor on stderr; exit 2 without
    ``-o``. ``inputs``: ``(files, folders)`` of the command, none of which a file written
    may be, nor ``output`` one of the folders (refused before any is written:
    :func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    if output is None or output.endswith((".c", ".h")):
        click.echo("error: --emit c writes a header, a source and runner.c: give the folder "
                   "with -o DIR", err=True)
        sys.exit(2)
    from fretc.compiler.c_codegen import emit_c  # lazy: Jinja2 and Spot

    from fretc.common.outputs import output_folder, write_file

    from fretc.cli.options import refuse_outputs_over_inputs

    files, skipped = emit_c(compiled, split=split)
    refuse_outputs_over_inputs([("-o", Path(output) / name) for name in files], inputs[0],
                               [("-o", output)], inputs[1])
    folder = Path(output_folder(output))
    for name, text in files.items():
        path = folder / name
        write_file(path, text)
        click.echo(f"wrote {path}", err=True)
    reported = {c.id for c in compiled if c.error is not None}
    for stem, rid, why in skipped:
        if rid not in reported:
            click.echo(shown(f"skipped {rid} ({stem}): {why}".replace("\n", " ")), err=True)


def write_c2po(compiled: Sequence[Compiled], output: str | None,
               check_output: Callable[[dict, str | None, str], None],
               write_outputs: Callable[[dict, str | None, str], None]) -> None:
    """Write one C2PO specification per requirement file (``-o`` a file for one, a
    folder for several; stdout without ``-o``: ``fretc compile``'s ``check_output`` and
    ``write_outputs``) and report on stderr what could not be expressed."""
    from fretc.compiler.c2po import emit_c2po

    outputs, skipped = emit_c2po(compiled)
    check_output(outputs, output, ".c2po")
    write_outputs(outputs, output, ".c2po")
    reported = {c.id for c in compiled if c.error is not None}
    for stem, rid, why in skipped:
        if rid not in reported:
            click.echo(shown(f"not in {stem}.c2po: {rid}: {why}".replace("\n", " ")),
                       err=True)


def write_exports(emit: str, compiled: Sequence[Compiled], output: str | None,
                  check_output: Callable[[dict, str | None, str], None],
                  write_outputs: Callable[[dict, str | None, str], None]) -> None:
    """``--emit cocospec`` (``<component>Spec.lus``) or ``--emit ogma``
    (``<component>Spec.json``): one file per component, as FRET's exports name them (``-o``
    a file for one, a folder for several; stdout without ``-o``: ``fretc compile``'s
    ``check_output`` and ``write_outputs``, which refuse an output over an input); each
    requirement left out is named on stderr with the reason."""
    if emit == "cocospec":
        from fretc.compiler.cocospec import emit_cocospec

        outputs, skipped, notes = emit_cocospec(compiled)
        suffix = ".lus"
    else:
        from fretc.compiler.ogma import emit_ogma

        outputs, skipped, notes = emit_ogma(compiled)
        suffix = ".json"
    if output is not None and len(outputs) > 1 and Path(output).suffix == suffix:
        click.echo(shown(f"error: -o {output}: {len(outputs)} files are written (one per "
                         f"component: {', '.join(outputs)}); give a directory (no {suffix} "
                         "suffix) or the requirements of one component"), err=True)
        sys.exit(2)
    check_output(outputs, output, suffix)
    write_outputs(outputs, output, suffix)
    reported = {c.id for c in compiled if c.error is not None}
    for stem, rid, why in skipped:
        if rid not in reported:
            where = "" if stem == "-" else f" ({stem}{suffix})"  # "-": in no file
            click.echo(shown(f"skipped {rid}{where}: {why}".replace("\n", " ")), err=True)
    for note in notes:
        click.echo(shown(f"note: {note}".replace("\n", " ")), err=True)
