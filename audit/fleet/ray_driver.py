"""The Ray driver of a fleet audit, run in a process of its own.

Ray ends its driver process when the driver's raylet dies (the core worker exits at once,
from C++, after printing the raylet's last lines to standard output): a fleet audit driven
from the ``fretc`` process would then end with no verdicts, no JSON and an exit code that
reads as "violated". So :func:`fretc.audit.fleet.ray.audit_logs_ray` starts this module as a
child process (``python -m fretc.audit.fleet.ray_driver``) and reads its results:

Design notes: ARCHITECTURE.md, `audit/fleet/ray_driver.py`."""

from __future__ import annotations

import os
import pickle
import sys
from typing import Any, BinaryIO

from fretc.audit.fleet.ray import (RayUnavailable, _audit_task, _first_line, _import_ray, connect,
                                   error_audit)

__all__ = ["drive", "main"]


def drive(job: dict[str, Any], out: BinaryIO) -> int:
    """Run the job's audits on Ray, writing each result to ``out`` as it finishes.

    Returns the process exit code: 0 when every log has a result, 2 when Ray could not be
    started or reached (after writing ``("unavailable", message)``), 130 on Ctrl-C (the
    running tasks cancelled).
    """
    shipped, paths = job["shipped"], job["paths"]
    plan = shipped.plan  # the requirements' ids and texts, for error entries

    def send(*frame) -> None:
        pickle.dump(frame, out, protocol=pickle.HIGHEST_PROTOCOL)
        out.flush()

    try:
        ray = _import_ray()
        started = connect(job["address"], job["num_cpus"])
    except RayUnavailable as exc:
        send("unavailable", str(exc))
        return 2
    try:
        task = ray.remote(_audit_task).options(max_retries=max(0, job["retries"]),
                                               retry_exceptions=False, num_cpus=1)
        ref = ray.put(shipped)
        refs = {task.remote(ref, str(p), job["kill"]): i for i, p in enumerate(paths)}
        pending = list(refs)
        try:
            while pending:
                try:
                    done, pending = ray.wait(pending, num_returns=1, timeout=0.5)
                except Exception as exc:  # the raylet or the node is gone: nothing more
                    reason = (f"Ray failed while the log was being audited "
                              f"({type(exc).__name__}: {_first_line(exc)}); run it again, "
                              "with --retries or without --ray")
                    for r in pending:
                        send("done", refs[r], error_audit(plan, paths[refs[r]], reason))
                    break
                for r in done:
                    send("done", refs[r], _result(ray, plan, paths[refs[r]], r,
                                                  job["retries"]))
        except KeyboardInterrupt:
            for r in pending:
                try:
                    ray.cancel(r, force=True)
                except Exception:
                    pass
            return 130
        return 0
    finally:
        if started:
            ray.shutdown()


def _result(ray, plan, path: str, ref, retries: int):
    """The LogAudit a finished task returned, or an :func:`error_audit` saying why not."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as exc:
        cause = getattr(exc, "cause", None) or exc
        return error_audit(plan, path, "the audit task raised "
                           f"{type(cause).__name__}: {_first_line(cause)}")
    except Exception as exc:  # worker died, node or raylet lost, object lost, ...
        return error_audit(plan, path, f"{type(exc).__name__}: the Ray worker was lost "
                           f"({_first_line(exc)}) after {retries + 1} attempt(s); try "
                           "--retries")


def main() -> int:
    """Entry point of the child process: read the job from standard input, drive it."""
    job = pickle.load(sys.stdin.buffer)
    with os.fdopen(job["fd"], "wb") as out:
        try:
            return drive(job, out)
        except KeyboardInterrupt:
            return 130


if __name__ == "__main__":
    sys.exit(main())
