"""``fretc estimate --rare``: the violation probability of each target requirement over a
scenario space by adaptive multilevel splitting (:mod:`fretc.sim.splitting`), each robustness
value from one simulator run audited as ``fretc audit`` does (:class:`fretc.sim.estimate.Runner`).

Each target gets its own splitting (its own levels), seeded with ``seed`` and the
requirement's position; the runs of one level's moves go to Ray together when ``--ray``
is given (the result is the same: the splitting's random numbers do not depend on which
run finishes first). Violating runs met on the way are kept as in :mod:`fretc.sim.estimate`
(MCAP + audit JSON), at most ``keep`` of them per requirement.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TYPE_CHECKING

from fretc.common.outputs import write_file
from fretc.sim.estimate import Runner, _finite
from fretc.sim.space import Space
from fretc.sim.splitting import SplittingError, SplittingResult, adaptive_multilevel_splitting

if TYPE_CHECKING:
    from fretc.audit.model import AuditPlan

__all__ = ["RareResult", "rare_estimate"]


@dataclass
class RareResult:
    """Per target requirement its :class:`~fretc.sim.splitting.SplittingResult` (or the
    :class:`~fretc.sim.splitting.SplittingError` text in ``errors``) and its kept violating runs
    (``examples``: ``{"mcap", "parameters", "robustness"}``)."""

    space: Space
    seed: int
    results: dict[str, SplittingResult] = field(default_factory=dict)
    errors: dict[str, str] = field(default_factory=dict)
    examples: dict[str, list[dict]] = field(default_factory=dict)

    def to_json(self) -> dict:
        """``rare`` section of ``estimate.json``."""
        return {"seed": self.seed,
                "requirements": {rid: dict(res.to_json(), examples=self.examples.get(rid, []))
                                 for rid, res in self.results.items()},
                "errors": self.errors}


def rare_estimate(plan: AuditPlan, space: Space, seed: int, out: str | Path, targets: list[str], *,
                  particles: int = 100, kill: int = 10, moves: int = 5,
                  confidence: float = 0.95, budget: int | None = None,
                  ray_address: str | None = None, keep: int = 10,
                  audit_json: Callable[[Any], str] = lambda la: "",
                  progress: Callable[[str, int], None] | None = None) -> RareResult:
    """Splitting estimates of each requirement of ``targets`` (ids of ``plan``).

    Args: as :func:`fretc.sim.splitting.adaptive_multilevel_splitting` (``budget``: runs per
        requirement) and :func:`fretc.sim.estimate.estimate` (``out``, ``ray_address``,
        ``audit_json``); ``progress(requirement, runs so far)`` after each batch.

    A requirement whose robustness gives no levels is reported in ``errors``, the others
    go on. Raises :class:`fretc.sim.space.SpaceError` for a degenerate distribution and
    ``audit.fleet.RayUnavailable`` when Ray cannot start.
    """
    space.check_sampling()
    outp = Path(out)
    runner = Runner(plan, space, outp, ray_address)
    result = RareResult(space, seed)
    counter = [0]
    try:
        for pos, rid in enumerate(targets):
            kept: list[dict] = []

            def score(points, rid=rid, kept=kept):
                batch = []
                for z in points:
                    counter[0] += 1
                    batch.append((counter[0], z, space.at_latent(z), space.seed))
                runs = runner.run(batch)
                for run in runs:
                    path = Path(runner.path(run.index))
                    if run.verdicts.get(rid) == "violated" and len(kept) < keep:
                        write_file(path.with_suffix(".audit.json"), audit_json(run.audit))
                        kept.append({"mcap": str(path.relative_to(outp)),
                                     "parameters": run.parameters,
                                     "robustness": _finite(run.robustness.get(rid))})
                    elif path.exists():
                        os.remove(path)
                if progress is not None:
                    progress(rid, counter[0])
                return [r.robustness.get(rid) if r.verdicts.get(rid) not in ("unknown", "error")
                        else None for r in runs]

            try:
                result.results[rid] = adaptive_multilevel_splitting(
                    score, space.latent_dims, seed + pos, particles=particles, kill=kill,
                    moves=moves, confidence=confidence, budget=budget)
                result.examples[rid] = kept
            except SplittingError as exc:
                result.errors[rid] = str(exc)
    finally:
        runner.close()
    return result
