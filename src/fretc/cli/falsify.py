"""``fretc falsify``: search the simulator's scenario parameters for runs that violate a
requirement (click command; the search: :mod:`fretc.sim.falsify`, its report:
:mod:`fretc.reports.falsify`, the space files: :mod:`fretc.sim.space`).

::

    fretc falsify --requirements requirements/ --space sim/spaces/interceptor_delay.toml \\
                  --budget 200 --seed 1 -o OUT [--only R2]... [--first] [--ray [ADDRESS]]

Exit status: 0 the budget ended without a falsifying run, 1 a run violates a target
requirement, 2 usage or input errors (a requirement that cannot be audited included).
Only click is imported at module level; the simulator and the engine load on first use.
"""

from __future__ import annotations

import os

import click

from fretc.cli.options import (BINDINGS_OPTION, REQUIREMENTS_OPTION, SAFETY_OPTION,
                               SIMULATOR_RAY_OPTION, SPACE_OPTION, FleetError,
                               refuse_folder_over_inputs, shown, with_safety)

__all__ = ["falsify_cmd"]


@click.command("falsify")
@REQUIREMENTS_OPTION
@BINDINGS_OPTION
@SPACE_OPTION
@click.option("--budget", type=click.IntRange(min=1), default=50, show_default=True,
              help="Simulator runs at most.")
@click.option("--seed", type=click.IntRange(min=0, max=2**32 - 1), default=1, show_default=True,
              help="CMA-ES's seed: the same seed gives the same runs.")
@click.option("-o", "--output", required=True, type=click.Path(file_okay=False),
              help="Output folder: falsify.json/.md/.svg, runs/run-NNNN.mcap and their "
                   "audits.")
@click.option("--only", "only", multiple=True, metavar="ID",
              help="Target only this requirement (repeatable): the search minimizes its "
                   "robustness and only its violation falsifies. Default: every requirement.")
@click.option("--first", is_flag=True,
              help="Stop at the first falsifying run (default: spend the budget, or stop "
                   "once every target is violated).")
@SIMULATOR_RAY_OPTION
@SAFETY_OPTION
@click.pass_context
def falsify_cmd(ctx: click.Context, requirements: tuple[str, ...], bindings: tuple[str, ...],
                space_path: str, budget: int, seed: int, output: str, only: tuple[str, ...],
                first: bool, ray: str | None, safety: str | None) -> None:
    """Search the simulator's scenario parameters for runs that violate a requirement:
    CMA-ES minimizes the least robustness (the margin behind each verdict, as fretc audit
    gives it) over the target requirements, one simulator run per evaluation.

    Each run that violates a target requirement is kept as runs/run-NNNN.mcap
    with its audit (run-NNNN.audit.json); falsify.json, falsify.md and falsify.svg report
    the search (robustness against runs, each requirement's smallest margin).

    \b
    Exit status:
      0  the budget ended without a run violating a target
      1  a run violates a target requirement
      2  usage or input errors
      130  interrupted (Ctrl-C) without a violating run; the runs so far are written"""
    # lazy: the simulator, the audit engine and cma only when the command runs
    from fretc.audit import AuditConfig, AuditInputError, load_plan
    from fretc.audit.fleet.ray import RayUnavailable
    from fretc.sim.falsify import falsify
    from fretc.reports.falsify import write_search
    from fretc.sim.space import load_space

    from fretc.cli.options import audit_config

    refuse_folder_over_inputs(output, requirements, bindings, space_path)
    if os.path.isdir(output) and os.listdir(output):
        raise click.BadParameter(f"{output} is not empty: give a new folder (runs of another "
                                 "search would mix with this one's)", param_hint="-o")
    config = audit_config(requirements, bindings, (), None, None, None, 5)
    assert isinstance(config, AuditConfig)
    space = with_safety(load_space(space_path), safety)
    try:
        plan = load_plan(config)
    except AuditInputError as exc:
        click.echo(shown(f"error: {exc}"), err=True)
        ctx.exit(2)
        return
    ids = [r.id for r in plan.requirements]
    bad = [r for r in plan.requirements if r.error is not None]
    if bad:
        for r in bad:
            click.echo(shown(f"error: {r.id} ({r.source}): {r.error}"), err=True)
        ctx.exit(2)
        return
    unknown = [t for t in only if t not in ids]
    if unknown:
        raise click.BadParameter(f"no requirement {', '.join(unknown)} (known: "
                                 f"{', '.join(ids)})", param_hint="--only")

    def progress(run) -> None:
        obj = "-" if run.objective is None else f"{run.objective:+.4g}"
        params = ", ".join(f"{k}={v:g}" for k, v in run.parameters.items())
        viol = f"  VIOLATED {', '.join(run.violated)}" if run.violated else ""
        click.echo(shown(f"run {run.index}: {params}: robustness {obj}{viol}"), err=True)

    try:
        search = falsify(plan, space, budget, seed, output, targets=list(only) or None,
                         first=first, ray_address=ray, progress=progress)
    except RayUnavailable as exc:
        raise FleetError(str(exc)) from None
    doc = write_search(search, output, plan)
    for rid, s in doc["smallest"].items():
        value = "-" if s is None else s["value"]
        where = "" if s is None else f" (run {s['run']}, tick {s['tick']})"
        click.echo(f"{rid}: smallest robustness {value}{where}")
    kept = [r["mcap"] for r in doc["runs"] if r["mcap"]]
    click.echo(f"{len(search.runs)} runs; "
               + (f"falsified: {', '.join(kept)} in {output}" if search.falsified
                  else "interrupted (Ctrl-C) before the budget ended, not falsified so far"
                  if search.interrupted else "not falsified within the budget"))
    ctx.exit(doc["exit_code"])

