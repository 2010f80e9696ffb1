"""``fretc ajpf``: AJPF run on the Gwendolen agent ``fretc shield --emit gwendolen`` wrote
(:mod:`fretc.shield.ajpf_run`).

::

    fretc ajpf DIR [--mcapl DIR] [--java PATH] [--javac PATH] [--property LABEL]...
               [--timeout SECONDS]

Exit status: 0 every property checked holds; 1 a property is violated or its run ended in
an error (the line says which and why: no verdict is a verdict of "holds"); 2 what AJPF needs
is missing (MCAPL, a Java 11 runtime, javac), the folder holds no agent, or a property label
the ``.psl`` lacks.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from fretc.cli.options import shown

__all__ = ["ajpf_cmd"]


@click.command("ajpf")
@click.argument("folder", type=click.Path(exists=True, file_okay=False))
@click.option("--mcapl", default=None, metavar="DIR",
              help="The MCAPL folder (a clone of github.com/mcapl/mcapl built by 'ant "
              "compile'); default: AJPF_HOME.")
@click.option("--java", default=None, metavar="PATH",
              help="A Java 11 runtime's java (MCAPL's JPF runs on Java 11 only); default: "
              "AJPF_JAVA, else java on the PATH.")
@click.option("--javac", default=None, metavar="PATH",
              help="A javac of JDK 11 or later, for the agent's environment; default: javac on "
              "the PATH.")
@click.option("--property", "labels", multiple=True, metavar="LABEL",
              help="Check only this property of the .psl (repeatable); default: every one.")
@click.option("--timeout", type=click.FloatRange(min=1), default=1800.0, show_default=True,
              metavar="SECONDS", help="The most one property's JPF run may take (then an "
              "error, not a verdict).")
def ajpf_cmd(folder: str, mcapl: str | None, java: str | None, javac: str | None,
             labels: tuple[str, ...], timeout: float) -> None:
    """Model-check with AJPF each property of the Gwendolen agent in FOLDER (written by
    fretc shield --emit gwendolen), one JPF run per property: holds, violated, or error with
    its reason."""
    from fretc.shield.ajpf_run import agent_in, check_agent, find_tools

    where = Path(folder)
    base = agent_in(where)  # (the folder before the tools: the first thing a user gets wrong)
    tools = find_tools(mcapl, java, javac)
    verdicts = check_agent(tools, where, labels, timeout)
    click.echo(shown(f"AJPF on {where / (base + '.gwen')} (MCAPL {tools.mcapl}, "
                     f"java {tools.java}): one JPF run per property"))
    counts = {"holds": 0, "violated": 0, "error": 0}
    for v in verdicts:
        counts[v.verdict] += 1
        line = f"  {v.label}: {v.verdict}"
        if v.detail:
            line += f": {v.detail}"
        line += f" (JPF states: {v.states})"
        click.echo(shown(line))
    total = sum(counts.values())
    click.echo(f"{total} propert{'y' if total == 1 else 'ies'}: {counts['holds']} hold, "
               f"{counts['violated']} violated, {counts['error']} error(s)")
    sys.exit(0 if counts["holds"] == total else 1)
