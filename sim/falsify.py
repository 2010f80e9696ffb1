"""Falsification: search a space of scenario parameters (:mod:`fretc.sim.space`) for simulator runs
that violate a requirement (``fretc falsify``), as S-TaLiRo and Breach do for STL.

Each run simulates the base scenario with one point of the space (:func:`fretc.sim.space.apply`),
records it as MCAP and audits it with the requirements (:func:`fretc.audit.audit_log`, the
same engine as ``fretc audit``). The search minimizes the run's *objective*, the least
robustness (:mod:`fretc.monitors.robustness`) over the target requirements (all, or those
given), with CMA-ES (the ``cma`` library; Hansen's covariance matrix adaptation) over the unit
cube mapped onto the parameters' ranges. When CMA-ES stops before the budget (converged, or a
flat objective) it restarts from the centre with the next seed. A run *falsifies* when a target
requirement is violated on it.

Design notes: ARCHITECTURE.md, `sim/falsify.py`."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TYPE_CHECKING

from fretc.common.outputs import output_folder, sub_folder
from fretc.sim.run import record_scenario, shield_of
from fretc.sim.space import Space, apply

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan

__all__ = ["Run", "Search", "falsify", "CLIP"]

#: Robustness values passed to CMA-ES are clipped to +-CLIP (it needs finite numbers).
CLIP = 1e9


@dataclass
class Run:
    """One simulator run of the search.

    Attributes:
        index: 1-based, in the order the runs were asked.
        parameters: parameter -> value (the space's units).
        robustness: requirement -> its robustness on the run (None: unknown or error).
        verdicts: requirement -> verdict.
        violated: the target requirements violated on the run.
        objective: the least robustness over the targets (None when none has one).
        mcap: the MCAP file written for the run (relative to the output folder), or None
            when the run was not kept (every run violating a target requirement is kept).
        audit: the run's :class:`fretc.audit.verdict.LogAudit`.
    """

    index: int
    parameters: dict[str, float]
    robustness: dict[str, float | None]
    verdicts: dict[str, str]
    violated: list[str]
    objective: float | None
    mcap: str | None = None
    audit: Any = None


@dataclass
class Search:
    """The search's result: its inputs and the runs, in order."""

    space: Space
    budget: int
    seed: int
    targets: list[str]
    runs: list[Run] = field(default_factory=list)
    #: the search was stopped by Ctrl-C before its budget ended (``runs``: those finished)
    interrupted: bool = False

    @property
    def falsified(self) -> bool:
        """A run violated a target requirement."""
        return any(r.violated for r in self.runs)

    def smallest(self) -> dict[str, tuple[float, int, int | None] | None]:
        """Requirement -> (its smallest robustness over the runs, the first run where it
        occurs, the tick), or None when no run gave it one."""
        out: dict[str, tuple[float, int, int | None] | None] = {t: None for t in self.targets}
        for r in self.runs:
            for t in self.targets:
                v = r.robustness.get(t)
                if v is not None and ((cur := out[t]) is None or v < cur[0]):
                    at = _verdict(r.audit, t).robustness_at
                    out[t] = (v, r.index, at.tick if at is not None else None)
        return out


def _verdict(la, rid: str):
    return next(v for v in la.verdicts if v.requirement == rid)


def _objective(values: list[float | None]) -> float | None:
    vals = [v for v in values if v is not None]
    return min(vals) if vals else None


def _to_cma(obj: float | None) -> float:
    if obj is None or math.isnan(obj):
        return CLIP
    return min(max(obj, -CLIP), CLIP)


def simulate(space: Space, parameters: dict[str, float], path: str) -> str:
    """Simulate one point of ``space`` and write the run to ``path`` (MCAP); returns it. The
    space's ``safety`` (a generated shield) replaces the hand-written SIF when given."""
    record_scenario(apply(space.scenario, parameters), space.seed, path,
                    shield=shield_of(space.safety))
    return path


def _make_run(index: int, parameters: dict, la, targets: list[str]) -> Run:
    rob = {v.requirement: v.robustness for v in la.verdicts}
    verdicts = {v.requirement: v.verdict for v in la.verdicts}
    violated = [t for t in targets if verdicts.get(t) == "violated"]
    return Run(index, parameters, rob, verdicts, violated,
               _objective([rob.get(t) for t in targets]), audit=la)


class _Interrupted(KeyboardInterrupt):
    """Ctrl-C during a batch: ``runs`` are the batch's runs finished before it."""

    def __init__(self, runs: list[Run]) -> None:
        super().__init__()
        self.runs = runs


class _Evaluator:
    """Simulates and audits a batch of points, one after another or on Ray."""

    def __init__(self, plan, space: Space, out: Path, ray_address: str | None):
        self.plan, self.space, self.out = plan, space, out
        self.ray_address = ray_address
        self.started = False
        if ray_address is not None:
            from fretc.audit.fleet.ray import connect  # lazy: Ray only with --ray
            self.started = connect(ray_address)

    def path(self, index: int) -> str:
        return str(self.out / "runs" / f"run-{index:04d}.mcap")

    def batch(self, start: int, points: list[dict], targets: list[str],
              first: bool) -> list[Run]:
        if self.ray_address is not None:
            return self._batch_ray(start, points, targets)
        from fretc.audit import audit_log
        runs: list[Run] = []
        try:
            for k, p in enumerate(points):
                path = simulate(self.space, p, self.path(start + k))
                runs.append(_make_run(start + k, p, audit_log(self.plan, path), targets))
                if first and runs[-1].violated:
                    break
        except KeyboardInterrupt:
            raise _Interrupted(runs) from None
        return runs

    def _batch_ray(self, start: int, points: list[dict], targets: list[str]) -> list[Run]:
        import ray  # lazy: Ray only with --ray

        from fretc.audit.fleet.ray import audit_logs_ray
        task = ray.remote(simulate).options(num_cpus=1)
        paths = ray.get([task.remote(self.space, p, self.path(start + k))
                         for k, p in enumerate(points)])
        audits = audit_logs_ray(self.plan, paths, address=self.ray_address)
        return [_make_run(start + k, p, la, targets)
                for k, (p, la) in enumerate(zip(points, audits))]

    def close(self) -> None:
        if self.started:
            import ray
            ray.shutdown()


def falsify(plan: AuditPlan, space: Space, budget: int, seed: int, out: str | Path, *,
            targets: list[str] | None = None, first: bool = False,
            ray_address: str | None = None,
            progress: Callable[[Run], None] | None = None) -> Search:
    """Search ``space`` for runs violating the requirements of ``plan``.

    Args:
        plan: the audit plan (:func:`fretc.audit.load_plan`).
        space: from :func:`fretc.sim.space.load_space`.
        budget: the number of simulator runs at most (``>= 1``).
        seed: CMA-ES's seed (module docstring).
        out: the output folder; runs are written to ``out/runs/``.
        targets: the requirement ids to violate (default: every requirement of the plan).
        first: stop after the first falsifying run; otherwise the search stops when the
            budget is spent or every target has been violated.
        ray_address: run on Ray (``"local"`` or a cluster address, as ``fretc audit --ray``).
        progress: called with each run once it is audited.

    Ctrl-C (KeyboardInterrupt) ends the search: the runs finished so far are returned with
    ``interrupted`` set (the run being made is dropped, its MCAP deleted).

    Raises:
        audit.fleet.RayUnavailable: ``ray_address`` given and Ray cannot start.
        OSError: the output folder cannot be written.
    """
    import cma  # lazy: only fretc falsify needs it

    ids = [r.id for r in plan.requirements]
    targets = list(targets) if targets else ids
    search = Search(space, budget, seed, targets)
    outp = Path(out)
    sub_folder(output_folder(outp), "runs")  # (a link planted as runs/: refused)
    ev = _Evaluator(plan, space, outp, ray_address)
    violated_before: set[str] = set()
    try:
        restart = 0
        while len(search.runs) < budget:
            es = cma.CMAEvolutionStrategy(
                [0.5] * len(space.parameters), 0.3,
                # cma's seed: 0 means "from the clock", numpy's takes 32 bits
                {"seed": (seed + restart) % (2**32 - 1) + 1, "bounds": [0.0, 1.0],
                 "verbose": -9})
            made = len(search.runs)
            while not es.stop() and len(search.runs) < budget:
                xs = es.ask()
                asked = xs[:budget - len(search.runs)]
                runs = ev.batch(len(search.runs) + 1, [space.point(list(x)) for x in asked],
                                targets, first)
                stop = _take(search, runs, first, violated_before, outp, progress)
                if stop:
                    return search
                if len(runs) < len(xs):
                    break
                es.tell(xs, [_to_cma(r.objective) for r in runs])
            if len(search.runs) == made:  # CMA-ES stopped before asking: nothing to gain
                break
            restart += 1
        return search
    except KeyboardInterrupt as exc:  # Ctrl-C: the runs so far, marked interrupted
        search.interrupted = True
        if isinstance(exc, _Interrupted):
            _take(search, exc.runs, first, violated_before, outp, progress)
        for p in (outp / "runs").glob("run-*.mcap"):  # the run being made when it came
            if int(p.stem[4:]) > len(search.runs):
                os.remove(p)
        return search
    finally:
        ev.close()


def _take(search: Search, runs: list[Run], first: bool, violated_before: set[str], out: Path,
          progress) -> bool:
    """Add a batch's runs to the search in order, keep the MCAP of every run violating a
    target (delete the others); True when the search stops."""
    for run in runs:
        search.runs.append(run)
        path = out / "runs" / f"run-{run.index:04d}.mcap"
        if run.violated:
            violated_before.update(run.violated)
            run.mcap = str(path.relative_to(out))
        elif path.exists():
            os.remove(path)
        if progress is not None:
            progress(run)
        if (first and run.violated) or violated_before >= set(search.targets):
            for later in runs[runs.index(run) + 1:]:
                p = out / "runs" / f"run-{later.index:04d}.mcap"
                if p.exists():
                    os.remove(p)
            return True
    return False
