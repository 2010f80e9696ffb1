"""``fretc estimate``: judge requirements ``with probability OP p`` over the simulator's
scenario space by sampling it (click command; the campaign: :mod:`fretc.sim.estimate`, the
sequential tests: :mod:`fretc.sim.sequential`, rare violations: :mod:`fretc.sim.rare`, the report:
:mod:`fretc.reports.estimate`).
::

    fretc estimate --requirements R --space SPACE.toml -o OUT [--seed N] [--budget N]
                   [--test sprt|cp] [--delta D] [--alpha A] [--beta B] [--confidence C]
                   [--trial trigger|run] [--unknown-runs worst-case|exclude]
                   [--rare [--target ID]...] [--ray [ADDRESS]]

Exit status: 0 every probability requirement holds (and no other requirement was violated
on a run; with --rare: every target estimated), 1 a probability requirement fails or a
requirement without a bound was violated on some run, 2 usage or input errors (a degenerate
distribution included; with --rare, a target whose robustness gives no levels) or a run
that could not be judged, 5 the budget ended before a probability requirement was decided,
130 interrupted.

Only click is imported at module level; the simulator and the engine load on first use.
"""

from __future__ import annotations

import os

import click

from fretc.cli.options import (BINDINGS_OPTION, REQUIREMENTS_OPTION, SAFETY_OPTION,
                               SIMULATOR_RAY_OPTION, SPACE_OPTION, FiniteRange, FleetError,
                               audit_config, refuse_folder_over_inputs, shown,
                               statistics_options, with_safety)

__all__ = ["estimate_cmd"]


@click.command("estimate")
@REQUIREMENTS_OPTION
@BINDINGS_OPTION
@SPACE_OPTION
@click.option("--seed", type=click.IntRange(min=0, max=2**32 - 1), default=1, show_default=True,
              help="The campaign's seed: the same seed gives the same runs and answer, "
                   "locally and on Ray.")
@click.option("--budget", type=click.IntRange(min=1), default=1000, show_default=True,
              help="Simulator runs at most (with --rare: per target requirement).")
@click.option("-o", "--output", required=True, type=click.Path(file_okay=False),
              help="Output folder: estimate.json, estimate.md, one SVG per test, "
                   "runs/run-NNNNN.mcap + .audit.json of the violating runs.")
@click.option("--test", type=click.Choice(["sprt", "cp"]), default="sprt", show_default=True,
              help="Sequential test: Wald's SPRT (with --delta) or repeated Clopper-Pearson.")
@click.option("--delta", type=FiniteRange(0, 0.5, min_open=True), default=0.05,
              show_default=True,
              help="SPRT: half-width of the indifference region around p.")
@click.option("--alpha", type=FiniteRange(0, 0.5, min_open=True, max_open=True),
              default=0.05, show_default=True,
              help="Error of deciding 'holds' when the bound is false (by delta or more).")
@click.option("--beta", type=FiniteRange(0, 0.5, min_open=True, max_open=True),
              default=0.05, show_default=True,
              help="SPRT: error of deciding 'fails' when the bound holds (by delta or more).")
@statistics_options
@click.option("--rare", is_flag=True,
              help="Estimate small violation probabilities (down to 1e-6) by adaptive "
                   "multilevel splitting on the robustness, instead of the sequential test.")
@click.option("--target", "targets", multiple=True, metavar="ID",
              help="--rare: the requirement(s) to estimate (default: every requirement).")
@click.option("--particles", type=click.IntRange(min=2), default=100, show_default=True,
              help="--rare: particles per level.")
@click.option("--kill", type=click.IntRange(min=1), default=10, show_default=True,
              help="--rare: particles replaced per level (fewer: more levels, less error).")
@click.option("--moves", type=click.IntRange(min=1), default=5, show_default=True,
              help="--rare: Markov chain steps per replaced particle.")
@SIMULATOR_RAY_OPTION
@SAFETY_OPTION
@click.pass_context
def estimate_cmd(ctx: click.Context, requirements: tuple[str, ...], bindings: tuple[str, ...],
                 space_path: str, seed: int, budget: int, output: str, test: str, delta: float,
                 alpha: float, beta: float, confidence: float, trial: str, unknown_runs: str,
                 rare: bool, targets: tuple[str, ...], particles: int, kill: int, moves: int,
                 ray: str | None, safety: str | None) -> None:
    """Judge requirements 'with probability OP p' over the simulator's scenario space:
    sample its distributions with SEED, simulate and audit each run, and stop when every
    probability requirement is decided by the sequential test or the budget ends. A
    trial is a trigger (FRET's bound is per trigger; --trial run: a run). The report
    gives per requirement the estimate of the probability of a satisfied trial, its
    Clopper-Pearson interval, the triggers per run, the runs used and the test's path
    (SVG); violating runs are kept (MCAP + audit). --rare estimates violation probabilities by adaptive multilevel
    splitting instead (estimate, relative error, interval).

    \b
    Exit status:
      0  every probability requirement holds (--rare: every target estimated)
      1  a probability requirement fails, or a requirement without a bound is
         violated on some run
      2  usage or input errors (a degenerate distribution; --rare: a target
         whose robustness is boolean), or a run could not be judged
      5  undecided: the budget ended before the test decided
      130  interrupted (Ctrl-C); the runs so far are reported"""
    # lazy: the simulator, the audit engine, scipy only when the command runs
    from fretc.audit import AuditInputError, load_plan
    from fretc.audit.fleet.ray import RayUnavailable
    from fretc.sim.space import load_space

    refuse_folder_over_inputs(output, requirements, bindings, space_path)
    if os.path.isdir(output) and os.listdir(output):
        raise click.BadParameter(f"{output} is not empty: give a new folder (runs of another "
                                 "campaign would mix with this one's)", param_hint="-o")
    config = audit_config(requirements, bindings, (), None, None, None, 5)
    space = with_safety(load_space(space_path), safety)  # SpaceError: exit 2 (the group)
    try:
        plan = load_plan(config)
    except AuditInputError as exc:
        click.echo(shown(f"error: {exc}"), err=True)
        ctx.exit(2)
        return
    bad = [r for r in plan.requirements if r.error is not None]
    for r in bad:
        click.echo(shown(f"error: {r.id} ({r.source}): {r.error}"), err=True)
    if bad:
        ctx.exit(2)
        return
    ids = [r.id for r in plan.requirements]
    unknown = [t for t in targets if t not in ids]
    if unknown:
        raise click.BadParameter(f"no requirement {', '.join(unknown)} (known: "
                                 f"{', '.join(ids)})", param_hint="--target")
    if rare and not kill < particles:
        raise click.BadParameter("--kill must be less than --particles", param_hint="--kill")

    try:
        doc = _campaign(plan, space, seed, budget, output, test, delta, alpha, beta,
                        confidence, (trial, unknown_runs), rare, list(targets) or ids,
                        particles, kill, moves, ray)
    except RayUnavailable as exc:
        raise FleetError(str(exc)) from None
    for line in doc["summary_lines"]:
        click.echo(shown(line))
    click.echo(f"report: {os.path.join(output, 'estimate.md')}")
    ctx.exit(doc["exit_code"])


def _campaign(plan, space, seed, budget, output, test, delta, alpha, beta, confidence,
              counting, rare, targets, particles, kill, moves, ray) -> dict:
    """Run the campaign (or the splitting with ``rare``) and write its report; returns the
    report document (:func:`fretc.reports.estimate.write_estimate`). ``counting``: the
    ``(trial, unknown_runs)`` options."""
    trial, unknown_runs = counting
    from fretc.audit.verdict import audit_json
    from fretc.reports.estimate import write_estimate

    def one_log_json(la) -> str:
        return audit_json([la], plan.requirements_json(), plan.bindings_json())

    if rare:
        from fretc.sim.rare import rare_estimate

        def said(rid, n):
            click.echo(f"{rid}: {n} runs", err=True)

        result = rare_estimate(plan, space, seed, output, targets, particles=particles,
                               kill=kill, moves=moves, confidence=confidence, budget=budget,
                               ray_address=ray, audit_json=one_log_json, progress=said)
        return write_estimate(output, None, result)
    from fretc.sim.estimate import estimate

    def progress(run) -> None:
        viol = f"  VIOLATED {', '.join(run.violated())}" if run.violated() else ""
        params = ", ".join(f"{k}={v:g}" for k, v in run.parameters.items())
        click.echo(shown(f"run {run.index}: {params}{viol}"), err=True)

    found = estimate(plan, space, seed, output, budget=budget, test=test, delta=delta,
                     alpha=alpha, beta=beta, confidence=confidence, unknown=unknown_runs,
                     trial=trial, ray_address=ray, audit_json=one_log_json,
                     progress=progress)
    return write_estimate(output, found, None)
