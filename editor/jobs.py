"""The language server's long work, in a child process it can stop: ``fretc check`` on save
(conflicts, vacuity) and ``fretc distinguish`` from a code action.

A job is ``python -m fretc.editor.jobs`` with one JSON request on its standard input and one
JSON answer on its standard output. The server (:func:`run_job`) starts it in a session of its
own, waits at most the job's wall-clock bound, and kills the whole session past it, when the
job is cancelled (the next edit of the document) or when the server ends; the child asks
Linux to kill it when the server's process dies (``prctl(PR_SET_PDEATHSIG, SIGKILL)``), so a
killed server leaves no job behind, and it runs Spot, BuDDy and z3 in its own process (no
query worker of its own: :class:`fretc.check.solver.SpotWorker` with ``fork=False``, BuDDy's node
table capped as the worker caps it), its address space capped at :data:`MEMORY_BYTES`.

Design notes: ARCHITECTURE.md, `editor/jobs.py`."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import sys

__all__ = ["run_job", "JobFailed", "MEMORY_BYTES", "CHECK_SECONDS", "DISTINGUISH_SECONDS"]

#: the address space of a job (bytes)
MEMORY_BYTES = 1 << 30
#: the wall-clock bound of the check on save, and of a distinguish (seconds)
CHECK_SECONDS = 20.0
DISTINGUISH_SECONDS = 30.0


class JobFailed(Exception):
    """A job that gave no answer: past its bound, killed, or ended without one (the
    message says which)."""


async def run_job(request: dict, timeout: float) -> dict:
    """The answer of the job ``request`` (module docstring), run in a child process of its
    own session; raises :class:`JobFailed` past ``timeout`` seconds or when the child ends
    without an answer. Cancelling the awaiting task kills the child (and anything it
    started)."""
    # one thread for numpy's BLAS: a thread per core would reserve address space past the
    # job's cap on a many-core machine
    env = dict(os.environ, FRETC_LSP_PARENT=str(os.getpid()), OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "fretc.editor.jobs", stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.DEVNULL,
        start_new_session=True, env=env)
    try:
        out, _err = await asyncio.wait_for(proc.communicate(json.dumps(request).encode()),
                                           timeout)
    except TimeoutError:
        raise JobFailed(f"not finished within {timeout:g} s") from None
    finally:
        if proc.returncode is None:
            _kill(proc.pid)
            try:
                await asyncio.wait_for(proc.wait(), 5)
            except (TimeoutError, ProcessLookupError):
                pass
    try:
        return json.loads(out.decode("utf-8"))
    except (ValueError, UnicodeDecodeError):
        raise JobFailed(f"the job ended without an answer (exit code {proc.returncode})") \
            from None


def _kill(pid: int) -> None:
    """Kill the job's session (the child and what it started)."""
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def _die_with_parent() -> None:
    """Ask Linux to kill this process when the server's process dies, and end at once if it
    already has (elsewhere: nothing)."""
    parent = int(os.environ.get("FRETC_LSP_PARENT") or 0)
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if parent and os.getppid() != parent:
        os._exit(1)


def _cap_memory() -> None:
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_BYTES, MEMORY_BYTES))
    except (ImportError, ValueError, OSError):
        pass


def _budget(work: int):
    """The queries' budget, BuDDy's node table capped at its memory budget in this process
    (as :func:`fretc.check.solver._serve` caps the forked worker's)."""
    import spot  # noqa: F401  Spot initializes BuDDy
    import buddy

    from fretc.check.budget import Budget

    budget = Budget(work)
    buddy.bdd_setmaxnodenum(budget.memory)
    return budget


def _check(req: dict) -> dict:
    from fretc.editor.document import analyse, check_problems

    from fretc.check.solver import SpotWorker

    a = analyse(req["text"], req["path"])
    work = int(req.get("work") or 2_000_000)
    with SpotWorker(_budget(work), fork=False) as worker:
        problems = check_problems(a, work, worker=worker)
    return {"problems": [[p.line, p.col, p.end_col, p.severity, p.message]
                         for p in problems]}


def _distinguish(req: dict) -> dict:
    from fractions import Fraction

    from fretc.compiler.build import compile_entries
    from fretc.fretish.entry import RequirementEntry
    from fretc.fretish.parser import parse
    from fretc.check.distinguish import distinguish
    from fretc.reports.distinction import distinction_text

    period = Fraction(req["period"]) if req.get("period") else None
    entries = []
    for which in ("a", "b"):
        e = RequirementEntry(which.upper(), req[which], f"<{which}>", 1, 1, tick_period=period)
        e.requirement = parse(req[which], source=f"<{req.get(which + '_label', which)}>")
        entries.append(e)
    ca, cb = compile_entries(entries)
    for c in (ca, cb):
        if c.formalization is None:
            return {"error": str(c.error) if c.error else f"{c.id} is free-form"}
    d = distinguish(ca, cb, budget=_budget(int(req.get("work") or 2_000_000)), fork=False)
    return {"text": distinction_text(d, req.get("a_label", "A"), req["a"],
                                     req.get("b_label", "B"), req["b"]),
            "equivalent": d.equivalent}


def main() -> None:  # pragma: no cover - runs in the job's process
    """Answer the one request on standard input (module docstring)."""
    _die_with_parent()
    _cap_memory()
    req = json.loads(sys.stdin.buffer.read().decode("utf-8"))
    try:
        out = {"check": _check, "distinguish": _distinguish}[req["kind"]](req)
    except Exception as exc:  # noqa: BLE001 - the answer says it; the server stays up
        out = {"error": f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"}
    sys.stdout.write(json.dumps(out))
    sys.stdout.flush()


if __name__ == "__main__":  # pragma: no cover
    main()
