"""Many logs: :func:`audit_logs` audits them one after the other, or ``jobs`` at a time in
worker processes (``concurrent.futures``, fork where available, the plan inherited or built
once per worker); results come back in input order."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

from fretc.audit.verdict import LogAudit
from fretc.audit.config import AuditConfig
from fretc.audit.log import audit_log
from fretc.audit.model import AuditPlan
from fretc.audit.plan import load_plan

__all__ = ["audit_logs"]

#: The worker process's plan and progress queue.
_WORKER: dict[str, Any] = {}


def _worker_init(config: AuditConfig, queue) -> None:
    plan = _WORKER.get("plan")
    if plan is None or plan.config != config:
        _WORKER["plan"] = load_plan(config)
    _WORKER["queue"] = queue


def _worker_audit(index: int, path: str):
    plan = _WORKER["plan"]
    queue = _WORKER.get("queue")
    cb = None
    if queue is not None:
        def cb(frac: float, _i=index) -> None:
            try:
                queue.put_nowait((_i, frac))
            except Exception:  # a full or closed queue only costs progress updates
                pass
    return index, audit_log(plan, path, cb)


class LogProgress(Protocol):
    """What the audit of several logs tells as it goes (:class:`fretc.reports.terminal.
    AuditProgress` shows it): log ``index`` (of ``path``) started, the fraction of it read,
    its audit done."""

    def start(self, index: int, path: str) -> None:
        """Log ``index`` (``path``) is being read."""

    def update(self, index: int, fraction: float) -> None:
        """``fraction`` (0 to 1) of log ``index`` read."""

    def done(self, index: int, la: LogAudit) -> None:
        """Log ``index`` audited: ``la``."""

def audit_logs(plan: AuditPlan, paths: Sequence[str], jobs: int = 1,
               progress: LogProgress | None = None) -> list[LogAudit]:
    """Audit ``paths`` (from :func:`find_logs`), ``jobs`` at a time in worker processes.

    Args:
        progress: optional object with ``start(index, path)``, ``update(index, fraction)``
            and ``done(index, log_audit)`` methods (the CLI's progress bar).

    Returns:
        One :class:`~fretc.audit.verdict.LogAudit` per path, in the order of ``paths``.
    """
    results: dict[int, Any] = {}
    if jobs <= 1 or len(paths) <= 1:
        for i, p in enumerate(paths):
            if progress is not None:
                progress.start(i, p)
            cb = (lambda frac, _i=i: progress.update(_i, frac)) if progress is not None else None
            results[i] = audit_log(plan, p, cb)
            if progress is not None:
                progress.done(i, results[i])
        return [results[i] for i in range(len(paths))]
    # lazy: only for -j N (start-up time of the others)
    import multiprocessing as mp
    import queue as queue_mod
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    try:
        ctx = mp.get_context("fork")
    except ValueError:  # pragma: no cover - platforms without fork
        ctx = mp.get_context()  # type: ignore[assignment]  # (a context all the same)
    q = ctx.Queue() if progress is not None else None
    _WORKER["plan"] = plan  # inherited by forked workers
    with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=_worker_init,
                             initargs=(plan.config, q)) as pool:
        futures = {}
        for i, p in enumerate(paths):
            futures[pool.submit(_worker_audit, i, p)] = i
            if progress is not None:
                progress.start(i, p)
        pending = set(futures)
        while pending:
            done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            if q is not None:
                while True:
                    try:
                        i, frac = q.get_nowait()
                    except queue_mod.Empty:
                        break
                    except Exception:
                        break
                    if progress is not None:  # (q is made with it)
                        progress.update(i, frac)
            for fut in done:
                i, la = fut.result()
                results[i] = la
                if progress is not None:
                    progress.done(i, la)
    return [results[i] for i in range(len(paths))]

