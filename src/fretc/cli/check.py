"""``fretc check``: find conflicting, vacuous, redundant and unrealizable requirements before
any robot runs (the analyses are in :mod:`fretc.check.analysis`).

Design notes: ARCHITECTURE.md, `fretc/cli/check.py`."""

from __future__ import annotations

import contextlib
import json
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import click

from fretc.check.budget import MUS_BUDGET
from fretc.check.streams import STREAM_USE
from fretc.common.textsafe import file_stems

from fretc.cli.options import (TEXT_ATTRIBUTE_OPTION, TICK_PERIOD_OPTION, FiniteRange,
                               budget_options, io_options,
                               names_of, requirement_set, selection_options,
                               set_bindings_option, shown)

if TYPE_CHECKING:
    from fretc.check.findings import CheckResult

__all__ = ["check_cmd", "render_text"]


def render_text(result: CheckResult) -> str:
    """The terminal report of a :class:`fretc.check.analysis.CheckResult`."""
    lines = []
    mark = {"error": "ERROR", "warning": "warning", "unknown": "UNKNOWN", "input": "ERROR"}
    for r in result.requirements:
        sat = r["satisfiable"]
        nv = r["non_vacuous"]
        lines.append(f"{r['id']:<10} satisfiable={_fmt(sat):<8} non-vacuous={_fmt(nv):<8} "
                     f"redundant={_fmt(r['redundant']):<8} ({r['source']}:{r['line']})")
    if result.realizability is not None:
        rz = result.realizability
        lines.append("")
        lines.append("realizability (" + rz["machine"] + "): inputs "
                     + (", ".join(rz["inputs"]) or "-")
                     + "; outputs " + (", ".join(rz["outputs"]) or "-")
                     + (("; declared neither: " + ", ".join(rz["undeclared"]))
                        if rz["undeclared"] else "")
                     + _streams_text(rz.get("streams", {})))
        for c in rz["groups"]:
            status = c["realizable"]
            extra = ""
            if "undeclared" in c:
                lines.append(f"  {', '.join(c['requirements'])}: not checked: "
                             + ", ".join(c["undeclared"]) + " declared neither input nor "
                             "output")
                continue
            if status is True and "mealy_states" in c:
                extra = f" by a Mealy machine of {c['mealy_states']} states (Spot's game)"
            elif status is True and "strategy" in c:
                st = c["strategy"]
                bits, nodes = st["state_bits"], st["winning_region_bdd_nodes"]
                region = (f"winning region a BDD of {nodes} node{'s' * (nodes != 1)}"
                          if nodes else "every state winning")
                extra = (f" by a controller over {bits} state bit{'s' * (bits != 1)} "
                         f"({st['method']}; {region})")
            elif status is False:
                extra = f" ({c['method']})"
            lines.append(f"  {', '.join(c['requirements'])}: "
                         f"{'realizable' if status is True else 'UNREALIZABLE' if status is False else 'unknown'}"
                         + extra)
            env = c.get("environment")
            if env and "prefix" in env:
                lines.append("    inputs that defeat every controller: "
                             + _lasso(env["prefix"], env["cycle"]))
            elif env:
                lines.append("    " + env["note"])
    lines.append("")
    if not result.findings:
        lines.append("no findings")
    for f in result.findings:
        lines.append(f"{mark[f.severity]} {f.kind}: {f.message}")
        if f.witness:
            lines.append(f"    witness {f.witness}: expected "
                         + ", ".join(f"{k}={v}" for k, v in f.expected.items()))
        note = f.details.get("witness_note") or (f.details.get("witness")
                                                 if isinstance(f.details.get("witness"), str)
                                                 else None)
        if note:
            lines.append(f"    {note}")
    for w in result.witnesses:
        if w["kind"] == "consistent":
            lines.append(f"witness of a run meeting every requirement: {w['path']}")
    for a in result.abstractions:
        lines.append(f"abstraction: {a['atom']}: {a['why']} (a finding may be spurious)")
    for n in result.notes:
        lines.append(f"note: {n}")
    lines.append(f"{len(result.requirements)} requirements, {len(result.groups)} "
                 f"group{'s' * (len(result.groups) != 1)} sharing no variable, {result.queries} solver queries ({result.smt_queries} by z3, "
                 f"{result.monitor_queries} by pt monitors)"
                 + (f" ({result.unknown_queries} past their budget or refused)"
                    if result.unknown_queries else "") + f"; exit {result.exit_code}")
    return "\n".join(lines)


def _streams_text(streams: dict[str, dict[str, Any]]) -> str:
    """The FRET stream variables of a realizability summary with their roles (those of the
    variables their definitions read: :mod:`fretc.check.streams`), "" when none."""
    role = {"input": "the environment's", "output": "the controller's", None: "no role"}
    return "".join(("; streams: " if k == 0 else ", ") + f"{n} ({role[s['role']]}: reads "
                   + (", ".join(s["reads"]) or "no variable") + ")"
                   for k, (n, s) in enumerate(streams.items()))


def _fmt(v) -> str:
    return {True: "yes", False: "NO", None: "-"}.get(v, str(v)) if not isinstance(v, str) \
        else v


def _lasso(prefix, cycle) -> str:
    """The input lasso, equal consecutive rows written once with their count (``x197``)."""
    def row(r):
        return "{" + ", ".join(f"{k}={str(v).lower() if isinstance(v, bool) else v}"
                               for k, v in r.items()) + "}"

    def runs(rows):
        out: list[list] = []
        for r in rows:
            if out and out[-1][0] == r:
                out[-1][1] += 1
            else:
                out.append([r, 1])
        return " ".join(row(r) + (f" x{k}" if k > 1 else "") for r, k in out)

    text = runs(prefix)
    return (text + " then forever (" if text else "forever (") + runs(cycle) + ")"


@click.command("check")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True))
@io_options("Environment variables (realizability: a component reading a variable that "
            "is neither input nor output is not decided, exit 2); default: @inputs of the "
            "files, or a FRET export's Input variables.",
            "Component variables (realizability); default: @outputs of the files, or a FRET "
            "export's Output variables.")
@set_bindings_option("A binding file; fretc check reads its tick period only.")
@TICK_PERIOD_OPTION
@selection_options
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@click.option("--witness-dir", type=click.Path(file_okay=False), default=None,
              help="Write a witness CSV per finding (replay with fretc audit).")
@budget_options("query")
@click.option("--mus-budget", type=click.IntRange(min=0), default=MUS_BUDGET,
              show_default=True, metavar="CHECKS",
              help="Subset checks per enumeration of minimal subsets.")
@click.option("--timeout", type=FiniteRange(0, 1e7, min_open=True), default=None,
              metavar="SECONDS", help="Wall-clock limit of the whole run: past it the run "
              "stops with no report (exit 3); it never changes an answer.")
@click.option("--engine", type=click.Choice(["auto", "spot", "smt", "bdd"]), default="auto",
              show_default=True, help="Satisfiability solver: Spot up to 16 ticks, past them "
              "fixed points over the requirements' pt monitors (with Spot's Büchi automata "
              "of an eventually) or z3 (auto); Spot, z3 or the monitors alone (spot, smt, "
              "bdd: z3 for what the monitors do not take); realizability: the safety game, "
              "or the Büchi game with an eventually (auto, smt, bdd), or Spot's game only "
              "(spot).")
@click.option("--no-redundancy", is_flag=True, help="Skip the redundancy warnings.")
@click.option("--no-progress", is_flag=True,
              help="No progress display (shown on a terminal: stage and query of each "
              "group of requirements sharing variables).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Also write the JSON result to FILE (for fretc report --check).")
@TEXT_ATTRIBUTE_OPTION
def check_cmd(files: tuple[str, ...], inputs: str | None, outputs: str | None,
              bindings_file: str | None, tick_period: str | None, component: str | None,
              only: str | None, exclude: str | None, as_json: bool, witness_dir: str | None, budget: int,
              memory_budget: int, query_cpu: float, mus_budget: int, timeout: float | None,
              engine: str, no_redundancy: bool, no_progress: bool, output: str | None) -> None:
    """Check requirement FILES for conflicts, vacuity, redundancy and (with inputs/outputs)
    realizability; a FRET project of several components, one component at a time."""
    import time

    from fretc.check.budget import Budget, RunStopped
    from fretc.check.realizability import RealizabilityError

    from fretc.cli.options import refuse_outputs_over_inputs, requirement_inputs

    # no output replaces an input: -o a requirement or binding file, --witness-dir the
    # folder of requirements read (the witnesses, NN_kind_ids.csv, never a requirement's name)
    req_files, req_folders = requirement_inputs(files)
    refuse_outputs_over_inputs([("-o", output)],
                               req_files + [("the binding file", bindings_file)],
                               [("--witness-dir", witness_dir)], req_folders)
    rs = requirement_set(files, bindings_file, component=component, only=only,
                         exclude=exclude, tick_period=tick_period, stream_use=STREAM_USE,
                         bits=True, defer_periods=component is None and inputs is None
                         and outputs is None)
    ins, outs = names_of(inputs), names_of(outputs)
    settings = _Settings(Budget(budget, memory_budget, query_cpu), mus_budget,
                         not no_redundancy, engine,
                         None if timeout is None else time.monotonic() + timeout,
                         _CheckProgress() if not no_progress and sys.stderr.isatty() else None)
    parts = rs.by_component() if component is None and ins is None and outs is None else []
    if rs.period_errors and not parts:  # (not a FRET project: no period is an input error)
        from fretc.common.errors import InputError

        raise InputError("\n".join(rs.period_errors.values()))
    try:
        if parts:  # (a FRET project: FRET's table, a check per component)
            _check_project(parts, settings, witness_dir, as_json, output)
        result = _checked(rs, rs.inputs if ins is None else ins,
                          rs.outputs if outs is None else outs, settings, witness_dir)
    except RealizabilityError as exc:
        click.echo(shown(f"error: {exc}"), err=True)
        sys.exit(2)
    except RunStopped:
        click.echo(f"fretc check: stopped by --timeout after {timeout:g} s of wall-clock "
                   "time, no report (the answers do not depend on time: rerun with a larger "
                   "--timeout or none)", err=True)
        sys.exit(3)
    doc = result.to_json()
    if output:
        from fretc.common.outputs import write_file

        write_file(output, json.dumps(doc, indent=2) + "\n")
    if as_json:
        click.echo(json.dumps(doc, indent=2))
    else:
        click.echo(shown(render_text(result)))
    sys.exit(result.exit_code)


@dataclass
class _Settings:
    """The options of one ``fretc check`` run that every checked set shares."""

    budget: Any
    mus_budget: int
    redundancy: bool
    engine: str
    deadline: float | None
    progress: Any


def _checked(rs: Any, ins: list[str] | None, outs: list[str] | None, settings: _Settings,
             witness_dir: str | None) -> CheckResult:
    """The check of the requirement set ``rs`` (:class:`fretc.cli.options.RequirementSet`)
    with inputs ``ins`` and outputs ``outs`` (None: no realizability); its compile errors
    printed, its FRET export's notes added. Raises what
    :func:`fretc.check.analysis.check_requirements` raises."""
    from fretc.check.analysis import check_requirements
    from fretc.compiler.build import compile_entries

    compiled = compile_entries(rs.entries)
    judge = None
    if witness_dir is not None:  # the witnesses' expected verdicts: the audit's
        from fretc.monitors.judge3 import nan_rule_judge
        judge = nan_rule_judge(compiled)
    with settings.progress or contextlib.nullcontext():
        result = check_requirements(
            compiled, budget=settings.budget, mus_budget=settings.mus_budget,
            redundancy=settings.redundancy, witness_dir=witness_dir, inputs=ins,
            outputs=outs, witness_judge=judge, engine=settings.engine,
            deadline=settings.deadline, progress=settings.progress)
    for e in result.input_errors:
        click.echo(shown(str(e)), err=True)
    result.notes += rs.notes  # (a FRET export's declarations: what is not used is said)
    return result


def _check_project(parts: list[tuple[str, Any]], settings: _Settings, witness_dir: str | None,
                   as_json: bool, output: str | None) -> None:
    """Check each FRET component of ``parts`` (name, its requirement set) with its own
    Inputs and Outputs, print each report and FRET's table
    (:mod:`fretc.check.fret_components`), write ``-o``, and exit with the largest exit code.
    Witnesses go to ``witness_dir/COMPONENT``."""
    import os

    from fretc.check.findings import CheckResult
    from fretc.check.fret_components import project_json, table_text

    done = []
    stems = file_stems([name for name, _part in parts])
    for name, part in parts:
        wdir = None if witness_dir is None else os.path.join(witness_dir, stems[name])
        if part.period_errors:  # (not checked, the others are: its row says why)
            for why in part.period_errors.values():
                click.echo(shown(f"error: {why}"), err=True)
            result = CheckResult(not_checked="; ".join(part.period_errors.values()))
        else:
            result = _checked(part, part.inputs, part.outputs, settings, wdir)
        done.append((name, [e.id for e in part.entries], result))
    doc = project_json(done)
    if output:
        from fretc.common.outputs import write_file

        write_file(output, json.dumps(doc, indent=2) + "\n")
    if as_json:
        click.echo(json.dumps(doc, indent=2))
    else:
        for name, ids, result in done:
            click.echo(shown(f"== component {name}: {', '.join(ids)}"))
            click.echo(shown(render_text(result)))
            click.echo("")
        click.echo(shown(table_text(doc["fret_components"]) + f"; exit {doc['exit_code']}"))
    sys.exit(doc["exit_code"])


class _CheckProgress:
    """The check's progress on the standard error (a terminal): a transient bar of the
    current stage of the current component (:data:`fretc.check.analysis.STAGES`), with the
    time elapsed. Called as :data:`fretc.check.analysis.Progress`."""

    _WORDS = {"alone": "each requirement alone", "set": "the set",
              "vacuity": "non-vacuity", "redundancy": "redundancy"}

    def __init__(self) -> None:
        from rich.console import Console  # lazy: only on a terminal
        from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TextColumn,
                                   TimeElapsedColumn)

        self.bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                            TimeElapsedColumn(), console=Console(stderr=True, emoji=False),
                            transient=True)
        self.task = self.bar.add_task("checking", total=None)

    def __enter__(self) -> _CheckProgress:
        self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bar.stop()

    def __call__(self, stage: str, at: int, total: int, group: int, groups: int) -> None:
        where = f"group {group} of {groups}: " if groups > 1 else ""
        self.bar.update(self.task, description=where + self._WORDS.get(stage, stage),
                        completed=at - 1, total=total)
