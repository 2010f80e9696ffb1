"""``fretc testrun DIR --command CMD``: run the tests ``fretc testgen`` wrote into DIR against a
system. For each test, ``CMD TRACE.csv LOG`` turns its trace into a log of the system (the
Safe-ROS simulator: ``python -m fretc.sim drive -b requirements/safe_ros.bindings.toml``),
``fretc audit --coverage`` judges the log with the test set's requirements and binding file,
and the test passes, fails, is unknown or not exercised by the pass rule of
:mod:`fretc.testing.testrun` (no requirement violated, every verdict decided, and the
obligation the test was generated for exercised on the system's log; with
``--all-obligations`` every obligation the test covers).

Design notes: ARCHITECTURE.md, `fretc/cli/testrun.py`."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from fretc.cli.options import shown

__all__ = ["testrun_cmd"]


@click.command("testrun")
@click.argument("folder", type=click.Path(exists=True, file_okay=False))
@click.option("--command", "command", required=True, metavar="CMD",
              help="Run as 'CMD TRACE.csv LOG' for each test: writes the system's log of "
                   "the trace.")
@click.option("-b", "--bindings", "bindings", type=click.Path(exists=True, dir_okay=False),
              default=None, metavar="FILE",
              help="Binding file for the system's logs (default: tests.json's, else the "
                   "audit's search beside the requirement files).")
@click.option("--logs", "logs_dir", type=click.Path(file_okay=False), default=None,
              metavar="DIR", help="Keep the logs and audits here (default: DIR/runs).")
@click.option("--test", "only", multiple=True, metavar="ID",
              help="Only this test (repeatable).")
@click.option("--all-obligations", "all_obligations", is_flag=True,
              help="A test passes only if the system's log exercises every obligation its "
                   "trace covers (default: the one it was generated for).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the outcomes as JSON here.")
def testrun_cmd(folder: str | Path, command: str, bindings: str | None, logs_dir: str | None,
                only: tuple[str, ...], all_obligations: bool, json_path: str | None) -> None:
    """Run the generated tests in FOLDER against the system CMD makes logs of."""
    from fretc.testing.tests_json import TestsJsonError, load_tests
    from fretc.testing.testrun import OUTCOMES, missing_traces, run_test

    folder = Path(folder)
    try:
        doc = load_tests(folder)  # its schema, ids as file names, traces inside the folder
    except TestsJsonError as exc:
        click.echo(shown(f"error: {exc}"), err=True)
        sys.exit(2)
    tests = doc["tests"]
    ids = {t["id"] for t in tests}
    missing = [i for i in only if i not in ids]
    if missing:
        click.echo(shown(f"error: {folder / 'tests.json'}: no test {', '.join(missing)}"),
                   err=True)
        sys.exit(2)
    absent = missing_traces([t for t in tests if not only or t["id"] in only], folder)
    for why in absent:  # (before any test runs: none is run without its trace)
        click.echo(shown(f"error: {why}"), err=True)
    if absent:
        sys.exit(2)
    chosen = [t for t in tests if not only or t["id"] in only]
    _refuse_replacing_inputs(folder, doc, chosen, bindings, logs_dir, json_path)
    from fretc.common.outputs import sub_folder

    # the default runs/ is a folder of fretc's own: a link planted there is refused (exit 2)
    work = Path(logs_dir) if logs_dir else Path(sub_folder(folder, "runs"))
    outcomes = []
    for t in tests:
        if only and t["id"] not in only:
            continue
        o = run_test(t, doc, folder, command, work, bindings,
                     "all" if all_obligations else "target")
        click.echo(shown(o.text()))
        outcomes.append(o)
    summary = {k: sum(o.outcome == k for o in outcomes) for k in OUTCOMES}
    click.echo(shown(f"{len(outcomes)} tests: " + ", ".join(f"{v} {k}" for k, v in
                                                            summary.items())))
    if json_path:
        from fretc.common.outputs import write_file

        write_file(json_path, json.dumps({"tests": [_json(o) for o in outcomes],
                                          "summary": summary}, indent=2) + "\n")
    sys.exit(1 if summary["fail"] else 3 if summary["unknown"] or summary["not exercised"]
             else 0)


def _json(o) -> dict:
    return {"id": o.test, "outcome": o.outcome, "verdicts": o.verdicts,
            "violated": o.violated, "undecided": o.undecided,
            "not_exercised": [{"requirement": r, "obligation": b} for r, b in o.not_exercised],
            "exercised": o.exercised, "log": o.log, "error": o.error,
            "generated_for": o.target}


def _refuse_replacing_inputs(folder: Path, doc: dict, tests: list, bindings: str | None,
                             logs_dir: str | None, json_path: str | None) -> None:
    """No file testrun writes (each test's log and audit in ``--logs``, named as
    :func:`fretc.testing.testrun.run_test` names them; ``--json``) is one of its inputs (the
    folder's tests.json, the tests' traces, the requirement files and the binding file the
    tests are audited with), and ``--logs`` is not the test folder; checked before any test
    runs.

    Raises:
        OutputError: one is (:func:`fretc.cli.options.refuse_outputs_over_inputs`)."""
    import os

    from fretc.testing.tests_json import file_name

    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    work = Path(logs_dir) if logs_dir else folder / "runs"
    outputs: list[tuple[str, Path | str | None]] = [("--json", json_path)]
    for t in tests:
        outputs += [("--logs", work / file_name(t["id"], ".mcap")),
                    ("--logs", work / file_name(t["id"], ".audit.json"))]
    named = [r for r in doc.get("requirements", []) if isinstance(r, str) and os.path.exists(r)]
    files, folders = requirement_inputs(named)
    binding = bindings or doc.get("bindings")
    inputs = ([("the tests' file", folder / "tests.json")]
              + [("the trace", folder / t["trace"]) for t in tests] + files
              + [("the binding file", binding if isinstance(binding, str) else None)])
    refuse_outputs_over_inputs(outputs, inputs, [("--logs", logs_dir)],
                               [("the test folder", folder), *folders])
