"""``fretc simulate FILE TRACE``: FRET's simulator without NuSMV (:mod:`fretc.monitors.simulate`):
the requirements' ft and pt values and their parts at every tick of a small trace, several
requirements side by side; a table in the terminal, SVG and HTML with ``-o DIR``, JSON with
``--json FILE``.

Exit codes: 0 every requirement holds on the whole trace, 1 one is violated, 2 an input error
(a requirement file, a trace without ticks or past 2000, an id that does not exist), 3 none
is violated but one is unknown (NaN values in the trace leave it undecided, as in the
audit).
"""

from __future__ import annotations

import sys

import click

from fretc.cli.options import TEXT_ATTRIBUTE_OPTION, TICK_PERIOD_OPTION
from fretc.cli.options import shown as _shown

__all__ = ["simulate_cmd"]


@click.command("simulate")
@click.argument("file", type=click.Path(exists=True))
@click.argument("trace", type=click.Path(exists=True, dir_okay=False))
@click.option("--id", "ids", multiple=True, metavar="ID",
              help="Only this requirement (repeatable); default: every one of FILE.")
@click.option("-o", "--output", type=click.Path(file_okay=False), default=None,
              help="Write one SVG per requirement and simulation.html into this folder.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help='Write {"ticks", "requirements": [{"id", "ft", "pt", "parts"}]} here.')
@TICK_PERIOD_OPTION
@TEXT_ATTRIBUTE_OPTION
def simulate_cmd(file: str, trace: str, ids: tuple[str, ...], output: str | None,
                 json_path: str | None, tick_period: str | None) -> None:
    """Simulate the requirements of FILE on TRACE (a .csv as the audit's, or a timeline
    text: one line per variable, 'p: 0-3, 7' for the ticks a boolean holds, 'speed: 0.0 0.2
    0.6' for one value per tick, '@ticks N' for the length)."""
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.monitors.simulate import read_trace, simulate
    from fretc.reports.simulation import text_table, write_outputs

    from fretc.cli.options import entries_with_period, text_attribute

    compiled = compile_entries(entries_with_period(
        load_requirements([file], text_attribute=text_attribute()), tick_period))
    known = {c.id for c in compiled}
    unknown = [i for i in ids if i not in known]
    if unknown:
        click.echo(_shown(f"error: {file}: no requirement {', '.join(map(repr, unknown))} "
                          f"(it has {', '.join(sorted(known))})"), err=True)
        sys.exit(2)
    chosen = [c for c in compiled if not ids or c.id in ids]
    failed = [c for c in chosen if c.error is not None]
    for c in failed:
        click.echo(_shown(str(c.error)), err=True)
    if failed:
        sys.exit(2)
    _refuse_replacing_inputs(file, trace, output, json_path,
                             [c.id for c in chosen if c.formalization is not None])
    data = read_trace(trace)
    n = len(next(iter(data.values()), []))
    sims = [simulate(c, data) for c in chosen if c.formalization is not None]
    click.echo(_shown(text_table(sims, n)))
    for p in write_outputs(sims, n, output, json_path):
        click.echo(_shown(f"wrote {p}"), err=True)
    first = [s.ft[0] for s in sims if s.ft]
    sys.exit(1 if False in first else 3 if None in first else 0)


def _refuse_replacing_inputs(file: str, trace: str, output: str | None, json_path: str | None,
                             ids: list[str]) -> None:
    """No file simulate writes (``-o DIR``'s SVGs, as :func:`fretc.reports.simulation.
    write_outputs` names them, and simulation.html; ``--json``) is one of its inputs (the
    requirement files, the trace), and ``-o`` is not the folder of requirements read.

    Raises:
        OutputError: one is (:func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    from pathlib import Path

    from fretc.common.textsafe import file_stems

    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    files, folders = requirement_inputs([file])
    outputs: list[tuple[str, Path | str | None]] = [("--json", json_path)]
    if output is not None:
        outputs += [("-o", Path(output) / f"{s}.svg") for s in file_stems(ids).values()]
        outputs.append(("-o", Path(output) / "simulation.html"))
    refuse_outputs_over_inputs(outputs, files + [("the trace", trace)], [("-o", output)], folders)
