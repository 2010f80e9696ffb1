"""Statistical campaigns over a scenario space (``fretc estimate``): sample the space's
distributions (:mod:`fretc.sim.distributions`), simulate and audit each run, and stop when every
probability requirement is decided by its sequential test (:mod:`fretc.sim.sequential`) or the
budget ends.

Design notes: ARCHITECTURE.md, `sim/estimate.py`."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TYPE_CHECKING

from fretc.common.outputs import output_folder, sub_folder, write_file
from fretc.audit.fleet.statistics import RequirementStatistics, fleet_statistics, unknown_policy

from fretc.sim.run import record_scenario, shield_of
from fretc.sim.sequential import make_test
from fretc.sim.space import Space, apply

if TYPE_CHECKING:
    from fretc.audit.verdict import LogAudit
    from fretc.audit.model import AuditPlan

__all__ = ["EstimateRun", "Estimate", "estimate", "sample_point", "Runner", "simulate_run",
           "observation"]


def sample_point(space: Space, seed: int, index: int) -> tuple[list[float], dict, int]:
    """``(z, parameters, sim_seed)`` of run ``index`` (1-based) of a campaign seeded with
    ``seed``: its latent standard normal coordinates, the parameter values they give, and
    the simulator's seed (the space's, module docstring)."""
    import numpy as np

    rng = np.random.default_rng([int(seed), int(index)])
    z = [float(x) for x in rng.standard_normal(space.latent_dims)]
    return z, space.at_latent(z), space.seed


def simulate_run(space: Space, parameters: dict, sim_seed: int, path: str) -> str:
    """Simulate the space's scenario with ``parameters`` and simulator seed ``sim_seed``,
    with the space's Safety System (its ``safety``: a generated shield, else the
    hand-written SIF); write the MCAP to ``path`` and return it."""
    record_scenario(apply(space.scenario, parameters), sim_seed, path,
                    shield=shield_of(space.safety))
    return path


@dataclass
class EstimateRun:
    """One run: ``index`` (1-based), ``parameters``, ``sim_seed``, ``z`` (latent
    coordinates), per requirement its ``verdicts`` and ``robustness`` (None: unknown or
    error), ``audit`` (:class:`fretc.audit.verdict.LogAudit`) and ``mcap`` (kept file, relative to
    the output folder, or None)."""

    index: int
    parameters: dict[str, float]
    sim_seed: int
    z: list[float]
    verdicts: dict[str, str]
    robustness: dict[str, float | None]
    audit: Any = None
    mcap: str | None = None

    def violated(self) -> list[str]:
        """The requirements violated on this run."""
        return [r for r, v in self.verdicts.items() if v == "violated"]


class Runner:
    """Simulates and audits runs given as ``(index, z, parameters, sim_seed)``, one after
    another or on Ray, returning :class:`EstimateRun` in the order given."""

    def __init__(self, plan, space: Space, out: Path, ray_address: str | None = None):
        self.plan, self.space, self.out, self.ray_address = plan, space, out, ray_address
        self.started = False
        sub_folder(output_folder(out), "runs")  # (a link planted as runs/: refused)
        if ray_address is not None:
            from fretc.audit.fleet.ray import connect  # lazy: Ray only with --ray
            self.started = connect(ray_address)

    def path(self, index: int) -> str:
        """The MCAP path of run ``index``."""
        return str(self.out / "runs" / f"run-{index:05d}.mcap")

    def run(self, points: list[tuple[int, list[float], dict, int]]) -> list[EstimateRun]:
        """Simulate and audit ``points``; results in the same order."""
        if self.ray_address is not None:
            import ray  # lazy: Ray only with --ray

            from fretc.audit.fleet.ray import audit_logs_ray
            task = ray.remote(simulate_run).options(num_cpus=1)
            paths = ray.get([task.remote(self.space, p, s, self.path(i))
                             for i, _z, p, s in points])
            audits = audit_logs_ray(self.plan, paths, address=self.ray_address)
        else:
            from fretc.audit import audit_log
            audits = [audit_log(self.plan, simulate_run(self.space, p, s, self.path(i)))
                      for i, _z, p, s in points]
        return [EstimateRun(i, p, s, z, {v.requirement: v.verdict for v in la.verdicts},
                            {v.requirement: v.robustness for v in la.verdicts}, la)
                for (i, z, p, s), la in zip(points, audits)]

    def keep_or_drop(self, run: EstimateRun, audit_json: Callable[[Any], str]) -> None:
        """Keep a violating run's MCAP and write its audit JSON beside it; delete the
        MCAP of any other run."""
        mcap = Path(self.path(run.index))
        if run.violated():
            write_file(mcap.with_suffix(".audit.json"), audit_json(run.audit))
            run.mcap = str(mcap.relative_to(self.out))
        elif mcap.exists():
            os.remove(mcap)

    def close(self) -> None:
        """Stop the Ray this runner started."""
        if self.started:
            import ray
            ray.shutdown()


@dataclass
class Estimate:
    """A campaign's result: its inputs, the runs used (in order), per requirement its
    :class:`~fretc.audit.fleet.statistics.RequirementStatistics` and sequential test (None for a
    requirement without a probability bound), and why it stopped."""

    space: Space
    seed: int
    budget: int
    test: str
    runs: list[EstimateRun] = field(default_factory=list)
    statistics: list[RequirementStatistics] = field(default_factory=list)
    tests: dict[str, Any] = field(default_factory=dict)
    stopped: str = ""
    interrupted: bool = False
    trial: str = "trigger"
    #: per requirement, why its test can decide nothing more (a run it could not judge)
    blocked: dict[str, str] = field(default_factory=dict)
    #: the runs that could not be judged: ``{"run", "requirement", "error"}``, in order
    errors: list[dict] = field(default_factory=list)

    def to_json(self) -> dict:
        """The campaign as ``estimate.json`` gives it (no wall-clock time: byte-identical
        for the same seed, locally and on Ray)."""
        return {
            "schema": "fretc-estimate/1", "space": self.space.path, "seed": self.seed,
            "budget": self.budget, "test": self.test, "trial": self.trial,
            "runs_used": len(self.runs), "stopped": self.stopped,
            "interrupted": self.interrupted, "errors": self.errors,
            "statistics": [dict(st.to_json(), sequential=(
                self.tests[st.id].to_json() if self.tests.get(st.id) else None))
                for st in self.statistics],
            "runs": [{"index": r.index, "parameters": r.parameters, "sim_seed": r.sim_seed,
                      "verdicts": r.verdicts,
                      "robustness": {k: _finite(v) for k, v in r.robustness.items()},
                      "mcap": r.mcap} for r in self.runs],
        }


def _finite(v):
    if v is None or v != v:
        return None if v is None else "nan"
    if v in (float("inf"), float("-inf")):
        return "inf" if v > 0 else "-inf"
    return v


def estimate(plan: AuditPlan, space: Space, seed: int, out: str | Path, *, budget: int = 1000,
             test: str = "sprt", delta: float = 0.05, alpha: float = 0.05,
             beta: float = 0.05, confidence: float = 0.95, unknown: str = "worst-case",
             trial: str = "trigger", ray_address: str | None = None, batch: int = 8,
             audit_json: Callable[[Any], str] = lambda la: "",
             progress: Callable[[EstimateRun], None] | None = None) -> Estimate:
    """Run the campaign (module docstring).

    Args:
        plan: the audit plan (:func:`fretc.audit.load_plan`); its requirements ``with probability``
            get a sequential test each (``test``: ``sprt`` or ``cp``, with ``delta``,
            ``alpha``, ``beta``); the others are counted.
        space: from :func:`fretc.sim.space.load_space` (checked for degenerate distributions).
        seed: the campaign's seed; ``budget``: the most runs (>= 1).
        confidence, unknown, trial: of the tests and the reported intervals
            (:func:`fretc.audit.fleet.statistics.fleet_statistics`).
        ray_address: simulate and audit on Ray, ``batch`` runs at a time (same answer).
        audit_json: a kept run's audit JSON text from its LogAudit (the caller's writer).
        progress: called with each run taken, in order.

    Without any probability requirement the campaign spends its budget. Ctrl-C ends it
    with the runs taken so far (``interrupted``).

    Raises:
        sim.space.SpaceError: a degenerate distribution; ValueError: bad test parameters,
        policy, unit or confidence; audit.fleet.RayUnavailable: Ray cannot start.
    """
    space.check_sampling()
    unknown = unknown_policy(unknown)
    bounds = {r.id: getattr(r.compiled, "probability", None) for r in plan.requirements}
    tests = {rid: make_test(test, b.op, b.p, delta, alpha, beta)
             for rid, b in bounds.items() if b is not None}
    fleet_statistics([], bounds, confidence, unknown, trial)  # the arguments checked first
    result = Estimate(space, seed, budget, test, tests=tests, trial=trial)
    outp = Path(out)
    runner = Runner(plan, space, outp, ray_address)
    step = batch if ray_address is not None else 1
    try:
        while len(result.runs) < budget and not result.stopped:
            start = len(result.runs) + 1
            points = [(i, *sample_point(space, seed, i))
                      for i in range(start, min(start + step, budget + 1))]
            for run in runner.run(points):
                if result.stopped:  # after the deciding run: dropped, as locally
                    mcap = Path(runner.path(run.index))
                    if mcap.exists():
                        os.remove(mcap)
                    continue
                _take(result, run, runner, audit_json, unknown, progress)
        if not result.stopped:
            result.stopped = (f"the budget of {budget} runs ended" if tests else
                              f"{budget} runs (no probability requirement to decide)")
    except KeyboardInterrupt:
        result.interrupted = True
        result.stopped = f"interrupted after {len(result.runs)} runs"
        for mcap in (outp / "runs").glob("run-*.mcap"):  # runs made but not taken
            if int(mcap.stem[4:]) > len(result.runs):
                os.remove(mcap)
    finally:
        runner.close()
    _judge(result, bounds, confidence, unknown)
    return result


def observation(la: LogAudit, rid: str, trial: str, unknown: str) -> tuple[int, int, int] | None:
    """What one run (:class:`fretc.audit.verdict.LogAudit`) gives requirement ``rid``'s
    test: ``(k, n, u)``, ``k`` satisfied of ``n`` trials of known outcome and ``u`` of
    unknown outcome (0 under ``exclude``); None when the run could not be judged per trigger
    under ``worst-case`` (module docstring)."""
    v = None if la.error else next((x for x in la.verdicts if x.requirement == rid), None)
    keep = unknown == "worst-case"
    if trial == "run":
        verdict = "error" if v is None else v.verdict
        if verdict in ("satisfied", "vacuous", "violated"):
            return int(verdict != "violated"), 1, 0
        return 0, 0, int(keep)
    t = None if v is None or v.verdict == "error" else v.trials
    if t is None:
        return None if keep else (0, 0, 0)
    return t.satisfied, t.trials, t.unknown if keep else 0


def _take(result: Estimate, run: EstimateRun, runner: Runner, audit_json, unknown: str,
          progress) -> None:
    result.runs.append(run)
    runner.keep_or_drop(run, audit_json)
    _errors(result, run)
    for rid, t in result.tests.items():
        if rid in result.blocked or t.decision is not None:
            continue
        obs = observation(run.audit, rid, result.trial, unknown)
        if obs is None:
            result.blocked[rid] = (f"run {run.index} could not be judged per trigger, and may "
                                   "hide any number of triggers of any outcome; nothing "
                                   "after it is decided (--unknown-runs exclude leaves such "
                                   "runs out)")
            continue
        t.observe(*obs)
    if progress is not None:
        progress(run)
    if result.tests and all(t.decision is not None or rid in result.blocked
                            for rid, t in result.tests.items()):
        done = "decided" if not result.blocked else "decided or blocked"
        result.stopped = (f"every probability requirement {done} after {len(result.runs)} "
                          "runs")


def _errors(result: Estimate, run: EstimateRun) -> None:
    """Record the requirements ``run`` could not judge (``result.errors``)."""
    la = run.audit
    for rid, v in run.verdicts.items():
        if v != "error":
            continue
        x = next((x for x in la.verdicts if x.requirement == rid), None) if la else None
        why = (la.error if la is not None and la.error else None) or (x.error if x else None)
        result.errors.append({"run": run.index, "requirement": rid,
                              "error": why or "not judged"})


def _judge(result: Estimate, bounds: dict, confidence: float, unknown: str) -> None:
    """The statistics of the runs taken; a probability requirement's verdict is its
    sequential test's decision (``undecided`` with why when it has none)."""
    stats = fleet_statistics([r.audit for r in result.runs], bounds, confidence, unknown,
                             result.trial)
    for st in stats:
        t = result.tests.get(st.id)
        if t is None:
            continue
        st.verdict = t.decision or "undecided"
        st.more_runs = None
        if t.decision:
            st.why = None
        elif st.id in result.blocked:
            st.why = result.blocked[st.id]
        else:
            st.why = f"{result.stopped}: " + t.why_undecided()
    result.statistics = stats
