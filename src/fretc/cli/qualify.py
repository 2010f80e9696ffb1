"""``fretc qualify -o DIR``: the validation suite of the tool qualification kit run on the
installed fretc (:mod:`fretc.qualification`), its report written into DIR.

Exit codes: 0 every check passed and every seeded fault of the mutation run was detected;
1 a check failed (standard error and the report name each requirement id), a seeded fault
went undetected, or an installed file differs from ``--manifest``'s; 2 a usage error (DIR a file, a folder with files in it, inside the
installed fretc; an unknown ``FRETC_QUALIFY_SEED_FAULT``), nothing written.
"""

from __future__ import annotations

import sys

import click

from fretc.cli.options import shown

__all__ = ["qualify_cmd"]


@click.command("qualify")
@click.option("-o", "--output", required=True, type=click.Path(),
              help="The report's folder (new or empty): report.json, report.html and the "
                   "checks' work files; nothing is written outside it.")
@click.option("--no-mutation", is_flag=True, default=False,
              help="Skip the mutation run (the faults seeded to show that the suite detects "
                   "a broken fretc).")
@click.option("--manifest", type=click.Path(dir_okay=False),
              help="A release's manifest (python -m fretc.qualification.manifest FILE, "
                   "published with the release): the installed files are compared with it, "
                   "and a file that differs fails the run.")
def qualify_cmd(output: str, no_mutation: bool, manifest: str | None) -> None:
    """Run the tool qualification kit's validation suite on this installation of fretc and
    write its report (report.json, report.html) into OUTPUT: fretc's version and commit,
    Python, the platform, every installed distribution's version and hash, each tool
    operational requirement with its result, and the mutation run (faults seeded in the
    semantics, the tick rules and a log reader, each of which the suite must detect).
    Takes a minute or two (AJPF's check, run where AJPF_HOME and AJPF_JAVA name a built
    MCAPL and a Java 11, minutes more); no network."""
    from fretc.qualification.kit import qualify, summary_lines

    # the whole fretc group, as the console script runs it: the end-to-end checks run it
    command = click.get_current_context().find_root().command
    result = qualify(output, command, mutation=not no_mutation, manifest=manifest)
    out, err = summary_lines(result)
    for line in out:
        click.echo(shown(line))
    for line in err:
        click.echo(shown(line), err=True)
    sys.exit(0 if result.doc["result"] == "passed" else 1)
