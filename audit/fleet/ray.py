"""Fleet audits on Ray: ``fretc audit --ray [ADDRESS]`` and ``fretc report --ray``.

One Ray task per log (a log's messages are needed in order, so a log is the unit of work).
The requirements are compiled once, on the driver (:func:`fretc.audit.load_plan`), and
shipped to the workers as a :class:`ShippedPlan`: the compiled requirements, the generated
monitor module texts (each worker ``exec``\\s them once, as the local audit does) and the
binding expressions (recompiled on the worker: their evaluators are closures). Each task
runs :func:`fretc.audit.audit_log`, the same engine as a local run, so the JSON, JUnit,
report and exit code are those of ``-j 1``; results are put back in the order of the logs.

Design notes: ARCHITECTURE.md, `audit/fleet/ray.py`."""

from __future__ import annotations

import hashlib
import logging
import os
import pickle
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, TYPE_CHECKING

from fretc.audit import AuditInputError, AuditPlan, audit_log
from fretc.audit.plan import MODULE_PREFIX, load_module
from fretc.signals.bindings import Bindings, compile_expression
from fretc.common.problems import BindingError
from fretc.common.textsafe import visible
from fretc.audit.verdict import LogAudit, Verdict

if TYPE_CHECKING:
    from fretc.audit.fleet.workers import LogProgress

__all__ = ["RayUnavailable", "ShippedPlan", "ship_plan", "connect",
           "audit_logs_ray", "error_audit", "RAY_HINT"]

#: How to get Ray (printed when ``--ray`` is used without it).
RAY_HINT = "--ray needs Ray: pip install 'fretc[ray]' (or pip install 'ray>=2.40')"


class RayUnavailable(AuditInputError):
    """``--ray`` without Ray installed, or a cluster that cannot be reached (exit code 2)."""


# --------------------------------------------------------------------------- log lists
# --------------------------------------------------------------------------- shipping a plan
@dataclass
class ShippedPlan:
    """A picklable :class:`~fretc.audit.AuditPlan` (built by :func:`ship_plan`).

    Attributes:
        plan: the plan with its monitor classes and binding evaluators taken out.
        classes: requirement index -> (module stem, requirement id) of its monitor class in
            ``plan.modules``.
        bindings: (name, expr, source, line, col, exact) of every binding, in order.
        key: identifies the plan (workers keep the last one they rebuilt).
    """

    plan: AuditPlan
    classes: dict[int, tuple[str, str]]
    bindings: list[tuple] | None
    key: str
    #: binding files that select their logs: (selector, file, ShippedPlan of that file)
    variants: list[tuple[Any, str, ShippedPlan]] = field(default_factory=list)

    def rebuild(self) -> AuditPlan:
        """The runnable plan: monitor modules ``exec``'d, binding expressions compiled."""
        mods = {stem: load_module(stem, text) for stem, text in self.plan.modules.items()}
        reqs = []
        for r in self.plan.requirements:
            r = replace(r)
            where = self.classes.get(r.index)
            if where is not None:
                r.monitor_cls = mods[where[0]].MONITORS[where[1]]
            reqs.append(r)
        b = self.plan.bindings
        if b is not None:
            variables: dict[str, Any] = {}
            todo = list(self.bindings or [])
            for _round in range(len(todo) + 1):  # references compile after their targets
                left = []
                for spec in todo:
                    name, expr, source, line, col, exact = spec
                    try:
                        variables[name] = compile_expression(
                            name, expr, source=source, line=line, col=col, exact=exact,
                            refs=variables)
                    except BindingError:
                        left.append(spec)
                if not left or len(left) == len(todo):
                    todo = left
                    break
                todo = left
            for name, expr, source, line, col, exact in todo:  # raises the real error
                variables[name] = compile_expression(name, expr, source=source, line=line,
                                                     col=col, exact=exact, refs=variables)
            order = [spec[0] for spec in self.bindings or []]
            variables = {n: variables[n] for n in order}
            b = Bindings(variables, b.tick, b.time_base, b.header_lag_ns, b.source)
        return replace(self.plan, requirements=reqs, bindings=b,
                       variants=[(sel, f, sp.rebuild()) for sel, f, sp in self.variants])


def ship_plan(plan: AuditPlan) -> ShippedPlan:
    """Strip ``plan`` of what does not pickle (generated classes, compiled closures)."""
    classes: dict[int, tuple[str, str]] = {}
    reqs = []
    for r in plan.requirements:
        r2 = replace(r, monitor_cls=None, _msource=None)
        if r.monitor_cls is not None and not plan.variants:  # variants ship their own
            classes[r.index] = (r.monitor_cls.__module__[len(MODULE_PREFIX):], r.id)
        reqs.append(r2)
    b = plan.bindings
    shipped_b = None
    if b is not None:
        shipped_b = [(v.name, v.expr, v.source, v.line, v.col, v._exact)
                     for v in b.variables.values()]
        b = Bindings({}, b.tick, b.time_base, b.header_lag_ns, b.source)
    h = hashlib.sha256()
    for stem, text in sorted(plan.modules.items()):
        h.update(stem.encode() + b"\0" + text.encode() + b"\0")
    h.update(repr(shipped_b).encode())
    h.update(repr(plan.config).encode())
    variants = [(sel, f, ship_plan(sub)) for sel, f, sub in plan.variants]
    for _sel, _f, sp in variants:
        h.update(sp.key.encode())
    return ShippedPlan(replace(plan, requirements=reqs, bindings=b, variants=[]), classes,
                       shipped_b, h.hexdigest(), variants)


# --------------------------------------------------------------------------- Ray
def _import_ray():
    try:
        import ray  # noqa: F401 - imported only with --ray (start-up cost)
    except ImportError:
        raise RayUnavailable(RAY_HINT) from None
    return ray


def connect(address: str | None = None, num_cpus: int | None = None) -> bool:
    """Connect to Ray; returns True when this call started a local Ray (stop it with
    ``ray.shutdown()``), False when Ray was already initialized or a cluster was joined.

    Args:
        address: None or ``"local"``: a local Ray for this run (``num_cpus`` default: the
            machine's CPUs; no dashboard web server; logs not forwarded; usage statistics
            off).
            ``"auto"``, ``"ray://host:port"``, ``"host:port"``: an existing cluster.

    Raises:
        RayUnavailable: Ray is not installed, or the cluster cannot be reached.
    """
    ray = _import_ray()
    if ray.is_initialized():
        return False
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    try:
        if address in (None, "local"):
            ray.init(num_cpus=num_cpus or os.cpu_count() or 1, include_dashboard=False,
                     log_to_driver=False, logging_level=logging.ERROR,
                     configure_logging=True)
            return True
        ray.init(address=address, log_to_driver=False, logging_level=logging.ERROR)
        return False
    except Exception as exc:  # ConnectionError, RuntimeError, ...
        raise RayUnavailable(f"--ray {address or 'local'}: cannot start or reach Ray: "
                             f"{type(exc).__name__}: {exc}") from None


_WORKER_PLAN: dict[str, Any] = {}


def _audit_task(shipped: ShippedPlan, path: str, kill: tuple[str, str] | None = None):
    """The Ray task body: audit one log with the shipped plan (rebuilt once per worker)."""
    plan = _WORKER_PLAN.get(shipped.key)
    if plan is None:
        _WORKER_PLAN.clear()
        plan = _WORKER_PLAN[shipped.key] = shipped.rebuild()
    progress = None
    if kill is not None and kill[0] in path:
        marker = kill[1]
        if marker == ":raise":
            raise RuntimeError("fault injected by the tests")
        if marker.startswith(":raylet:") and os.path.exists(marker[8:]):
            # fault injection for the tests: this node's raylet (the worker's parent) dies
            os.remove(marker[8:])
            os.kill(os.getppid(), signal.SIGKILL)
            time.sleep(60)

        def progress(frac: float) -> None:
            # fault injection for the tests: the worker dies mid-run, once per marker file
            if frac > 0.2 and os.path.exists(marker):
                os.remove(marker)
                os._exit(1)

    return audit_log(plan, path, progress)


def error_audit(plan: AuditPlan, path: str, reason: str) -> LogAudit:
    """A :class:`~fretc.audit.verdict.LogAudit` of a log that could not be audited: the
    log's ``error`` is ``reason`` and every requirement's verdict is ``error`` with it (so the
    exit code is 2 and nothing reads as satisfied)."""
    la = LogAudit(log=str(path), error=f"{path}: {reason}")
    for r in plan.requirements:
        v = Verdict(log=str(path), requirement=r.id, text=r.text, source=r.source,
                    notes=list(r.notes))
        v.error = r.error if r.error is not None else f"log not audited: {reason}"
        v.verdict = "error"
        la.verdicts.append(v)
    return la


def audit_logs_ray(plan: AuditPlan, paths: Sequence[str], address: str | None = None,
                   retries: int = 0, progress: LogProgress | None = None,
                   num_cpus: int | None = None,
                   _kill: tuple[str, str] | None = None) -> list[Any]:
    """Audit ``paths`` on Ray, one task per log; results in the order of ``paths``.

    Ray is driven from a child process (:mod:`fretc.audit.fleet.ray_driver`), because Ray ends
    its driver when the driver's raylet dies: the logs whose results arrived before keep
    their verdicts, the others get :func:`error_audit` entries naming the failure. When this
    process already has Ray initialized, the child joins that session (as :func:`connect`
    keeps an initialized Ray, whatever ``address`` says).

    Args:
        plan: from :func:`fretc.audit.load_plan` (compiled here, once).
        address: see :func:`connect`.
        retries: times a task is re-run after its worker died (not after an exception).
        progress: as :func:`fretc.audit.audit_logs` (``start``, ``done``; ``update`` is
            not called: a task reports when it finishes).
        num_cpus: CPUs of a local Ray (default: all).

    Returns:
        One :class:`~fretc.audit.verdict.LogAudit` per path; a log whose task failed has
        an :func:`error_audit` entry naming the failure.

    Raises:
        RayUnavailable: no Ray, or the cluster cannot be reached.
        KeyboardInterrupt: after the driver cancelled the running tasks.
    """
    if not paths:
        return []
    if "ray" in sys.modules and sys.modules["ray"].is_initialized():  # as connect() does
        address = sys.modules["ray"].get_runtime_context().gcs_address
    job = {"shipped": ship_plan(plan), "paths": [str(p) for p in paths], "address": address,
           "retries": retries, "num_cpus": num_cpus, "kill": _kill}
    if progress is not None:
        for i, p in enumerate(paths):
            progress.start(i, p)
    results: dict[int, Any] = {}
    with tempfile.TemporaryFile() as said:
        rc = _run_driver(job, said, results, progress)
        if rc == 130:
            raise KeyboardInterrupt
        if len(results) < len(paths):
            said.seek(0)
            reason = (f"the Ray driver process ended (exit code {rc}) before this log's "
                      f"result arrived{_last_words(said.read())}; the raylet or the node "
                      "was lost: run it again, with --retries or without --ray")
            for i, p in enumerate(paths):
                if i not in results:
                    results[i] = error_audit(plan, p, reason)
                    if progress is not None:
                        progress.done(i, results[i])
    return [results[i] for i in range(len(paths))]


def _run_driver(job: dict, said, results: dict, progress) -> int:
    """Start the driver process, collect its ``("done", i, LogAudit)`` frames into
    ``results``; returns its exit code. Raises :class:`RayUnavailable` when it says so."""
    read_fd, write_fd = os.pipe()
    job["fd"] = write_fd
    try:
        child = subprocess.Popen([sys.executable, "-m", "fretc.audit.fleet.ray_driver"],
                                 stdin=subprocess.PIPE, stdout=said, stderr=said,
                                 pass_fds=(write_fd,), env=_driver_env(),
                                 start_new_session=True)  # Ctrl-C is forwarded once, below
    finally:
        os.close(write_fd)
    unavailable = None
    try:
        with os.fdopen(read_fd, "rb") as frames:
            assert child.stdin is not None  # (stdin=PIPE)
            child.stdin.write(pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL))
            child.stdin.close()
            while True:
                try:
                    frame = pickle.load(frames)
                except (EOFError, pickle.UnpicklingError):
                    break
                if frame[0] == "unavailable":
                    unavailable = frame[1]
                elif frame[0] == "done":
                    results[frame[1]] = frame[2]
                    if progress is not None:
                        progress.done(frame[1], frame[2])
        rc = child.wait()
    except KeyboardInterrupt:  # the driver cancels its tasks and stops its Ray
        child.send_signal(signal.SIGINT)
        try:
            child.wait(timeout=20)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
        raise
    if unavailable is not None:
        raise RayUnavailable(unavailable)
    return rc


def _driver_env() -> dict[str, str]:
    """The driver's environment: this one, with this checkout of fretc first on the path."""
    env = dict(os.environ)
    # the folder holding this fretc package (src/ of a checkout, or site-packages): __file__
    # as imported, not resolved (src/fretc links the checkout's folders)
    root = str(Path(__file__).parents[2])
    env["PYTHONPATH"] = os.pathsep.join([root, *filter(None, [env.get("PYTHONPATH")])])
    return env


def _last_words(text: bytes) -> str:
    """Ray's first message about the raylet's end (its ``(raylet)`` lines), or ''."""
    lines = [re.sub(r"\x1b\[[0-9;]*m", "", ln).strip()
             for ln in text.decode("utf-8", "replace").splitlines()]
    said = [ln[len("(raylet)"):].strip() for ln in lines if ln.startswith("(raylet)")]
    return f" (Ray said: {visible(said[0][:240])})" if said else ""


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
