"""``fretc testgen FILE... -o DIR``: requirements-based tests. For every coverage obligation
of the requirements of FILES (:mod:`fretc.compiler.coverage`: each atom's own effect, the
trigger, the scope entered and left, the deadline reached and missed, each threshold's two
sides) a finite trace meeting it, found by ``fretc check``'s engines and confirmed by the
audit's judge (:mod:`fretc.testing.generate`); traces meeting several obligations are merged by
a greedy cover.

Design notes: ARCHITECTURE.md, `fretc/cli/testgen.py`."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from fretc.cli.options import (TEXT_ATTRIBUTE_OPTION, TICK_PERIOD_OPTION,
                               exit_on_compile_errors, requirement_set, selection_options,
                               set_bindings_option, shown)

__all__ = ["testgen_cmd"]


@click.command("testgen")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("-o", "--output", "out_dir", required=True,
              type=click.Path(file_okay=False), metavar="DIR",
              help="Folder to write the tests (T01.csv, ...) and tests.json into.")
@click.option("--pytest", "with_pytest", is_flag=True,
              help="Also write DIR/test_fretc_generated.py: a pytest file auditing each "
                   "test's trace against its expected verdicts, or, with FRETC_RUN_TRACE set, "
                   "the log that command makes of it ('COMMAND TRACE.csv LOG') by the pass "
                   "rule of fretc testrun.")
@set_bindings_option("A binding file (*.bindings.toml): also write DIR/T01.mcap... , each "
                     "test's messages on the bound topics, read back by fretc audit with the "
                     "same file.")
@TICK_PERIOD_OPTION
@selection_options
@TEXT_ATTRIBUTE_OPTION
def testgen_cmd(files: tuple[str, ...], out_dir: str, with_pytest: bool, bindings_file: str | None,
                tick_period: str | None, component: str | None, only: str | None,
                exclude: str | None) -> None:
    """Generate requirements-based tests of FILES into DIR: one CSV trace per test and
    tests.json (what each covers, the expected verdict of every requirement)."""
    from fretc.testing.generate import generate, write_tests
    from fretc.compiler.build import compile_entries

    rs = requirement_set(files, bindings_file, component=component, only=only, exclude=exclude,
                         tick_period=tick_period)
    entries = rs.entries
    compiled = compile_entries(entries)
    exit_on_compile_errors(files, compiled)
    bindings = rs.bindings
    gen = generate(compiled)
    _refuse_replacing_inputs(files, bindings_file, out_dir, len(gen.tests), with_pytest)
    if bindings is not None:
        from fretc.testing.mcap_log import bind_tests

        bind_tests(gen, compiled, bindings, out_dir)
    sources = list(dict.fromkeys(c.entry.source for c in compiled))
    period = next((e.tick_period for e in entries if e.tick_period is not None), None)
    try:
        doc = write_tests(gen, out_dir, sources, period, bindings_file)
    except ValueError as exc:  # a variable no CSV trace can carry: named
        click.echo(shown(f"error: {exc}"), err=True)
        sys.exit(2)
    if with_pytest:
        from fretc.testing.pytest_file import (PYTEST_FILE, PYTEST_INI, PYTEST_INI_TEXT,
                                               pytest_file)

        from fretc.common.outputs import write_file

        write_file(Path(out_dir) / PYTEST_FILE, pytest_file())
        write_file(Path(out_dir) / PYTEST_INI, PYTEST_INI_TEXT)
    total = len(doc["obligations"])
    met = len({(c["requirement"], c["obligation"]) for t in doc["tests"] for c in t["covers"]})
    click.echo(shown(f"{len(doc['tests'])} tests in {out_dir}: {met} of {total} obligations "
                     f"covered, {len(doc['unmeetable'])} unmeetable, "
                     f"{len(doc['unknown'])} unknown"))
    for which in ("unmeetable", "unknown"):
        for o in doc[which]:
            click.echo(shown(f"  {which}: {o['requirement']} {o['obligation']}: "
                             f"{o['reason']}"))
    for note in _stream_notes(compiled):
        click.echo(shown(f"  note: {note}"))
    if bindings is not None:
        logs = [t for t in doc["tests"] if t["log"]]
        click.echo(shown(f"{len(logs)} of {len(doc['tests'])} tests written as MCAP logs "
                         f"of the topics bound in {bindings_file}"))
        for t in doc["tests"]:
            if t["adjusted"]:
                click.echo(shown(f"  {t['id']}: adjusted to the bindings: "
                                 f"{', '.join(t['adjusted'])} (verdicts re-judged)"))
            if not t["log"]:
                click.echo(shown(f"  {t['id']}: no MCAP log: {t['log_not_written']}"))
        if doc["tests"] and not logs:
            sys.exit(1)
    sys.exit(3 if doc["unknown"] else 0)



def _stream_notes(compiled: list[Any]) -> list[str]:
    """One note per FRET stream variable the requirements ``compiled`` read (an Internal
    variable whose Lustre definition reads itself through ``pre``:
    :mod:`fretc.check.streams`): each test's column of it is computed from the variables
    its definition reads (:mod:`fretc.check.stream_rows`), as FRET and ``fretc audit``
    replaying the trace compute it."""
    from fretc.check.streams import streams_of_entry

    found: dict[str, Any] = {}
    readers: dict[str, list[str]] = {}
    for c in compiled:
        f = c.formalization
        if f is None:
            continue
        for n, st in streams_of_entry(c.entry, f.variables).items():
            found.setdefault(n, st)
            readers.setdefault(n, []).append(c.id)
    return [f"{n} (read by {', '.join(readers[n])}) is a FRET stream variable (its "
            f"definition {st.text} reads " + (", ".join(st.reads) or "no variable")
            + " now and through pre): each test's column of it is computed from the "
            "columns of those variables, as fretc audit computes it again when it replays "
            "the test" for n, st in sorted(found.items())]


def _refuse_replacing_inputs(files: tuple[str, ...], bindings_file: str | None, out_dir: str,
                             tests: int, with_pytest: bool) -> None:
    """No file testgen writes into ``out_dir`` (T01.csv, T01.mcap ... as
    :func:`fretc.testing.generate.write_tests` and :func:`fretc.testing.mcap_log.bind_tests`
    name them, tests.json, the pytest files) is one of its inputs (the requirement files, the
    binding file), and ``out_dir`` is not the folder of requirements read; checked before
    any is written.

    Raises:
        OutputError: one is (:func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    names = [f"T{k:02d}{s}" for k in range(1, tests + 1) for s in (".csv", ".mcap")]
    names.append("tests.json")
    if with_pytest:
        from fretc.testing.pytest_file import PYTEST_FILE, PYTEST_INI

        names += [PYTEST_FILE, PYTEST_INI]
    req_files, req_folders = requirement_inputs(files)
    refuse_outputs_over_inputs([("-o", Path(out_dir) / n) for n in names],
                               req_files + [("the binding file", bindings_file)],
                               [("-o", out_dir)], req_folders)
