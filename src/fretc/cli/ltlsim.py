"""``fretc ltlsim REQS... [--port N]``: FRET's simulator (LTLSIM) as a page served on
127.0.0.1 (:mod:`fretc.reports.ltlsim`): edit a trace of the requirements' variables, see
each requirement's value at every tick, its verdict and its first violation, judged by the
audit's judge. Runs until interrupted (Ctrl-C).

Exit codes: 0 stopped by the user, 2 an input error (a requirement file, an unknown id, no
requirement that formalized, a port that cannot be bound).
"""

from __future__ import annotations

import sys

import click

from fretc.cli.options import TEXT_ATTRIBUTE_OPTION
from fretc.cli.options import shown as _shown

__all__ = ["ltlsim_cmd"]


@click.command("ltlsim")
@click.argument("requirements", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--id", "ids", multiple=True, metavar="ID",
              help="Only this requirement (repeatable); default: every one of the files.")
@click.option("--port", type=click.IntRange(0, 65535), default=8770, show_default=True,
              help="The port on 127.0.0.1 (0: a free one, printed).")
@click.option("--ticks", type=click.IntRange(1, 5000), default=12, show_default=True,
              help="The length of the first trace shown (ticks can be added on the page).")
@TEXT_ATTRIBUTE_OPTION
def ltlsim_cmd(requirements: tuple[str, ...], ids: tuple[str, ...], port: int,
               ticks: int) -> None:
    """Serve FRET's simulator for the requirements of REQUIREMENTS (files or folders) on
    http://127.0.0.1:PORT/: a trace you edit (booleans toggled per tick, numbers typed,
    ticks added or removed) and, per requirement, its value at each tick, its verdict and
    its first violation, judged as `fretc audit` judges a trace. Loopback only, and only
    the page's own requests: a request of another origin is refused (a script's POST to
    /api/judge sends Origin: http://127.0.0.1:PORT)."""
    from fretc.common.errors import FretcError
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.reports.ltlsim import make_server

    from fretc.cli.options import text_attribute

    try:
        compiled = compile_entries(load_requirements(list(requirements),
                                                     text_attribute=text_attribute()))
    except FretcError as exc:
        click.echo(_shown(f"error: {exc}"), err=True)
        sys.exit(2)
    known = [c.id for c in compiled]
    unknown = [i for i in ids if i not in known]
    if unknown:
        click.echo(_shown(f"error: no requirement {', '.join(map(repr, unknown))} in "
                          f"{', '.join(requirements)} (they have {', '.join(known)})"),
                   err=True)
        sys.exit(2)
    chosen = [c for c in compiled if not ids or c.id in ids]
    for c in chosen:
        if c.error is not None:
            click.echo(_shown(f"note: {c.error}"), err=True)
    if not any(c.formalization is not None for c in chosen):
        click.echo("error: no requirement formalized: nothing to simulate", err=True)
        sys.exit(2)
    try:
        server = make_server(chosen, port, ticks)
    except OSError as exc:
        click.echo(f"error: --port {port}: cannot listen on 127.0.0.1: {exc}", err=True)
        sys.exit(2)
    click.echo(f"fretc ltlsim: {len(chosen)} requirements on "
               f"http://127.0.0.1:{server.server_address[1]}/ (Ctrl-C stops)", err=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
