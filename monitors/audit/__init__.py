"""The audit engine: recorded runs x FRETish requirements -> verdicts with evidence.

One module per step:

1. **Plan** (:mod:`.plan`, data in :mod:`.model`): the requirements compiled with the tick
   period of the signal bindings (:mod:`.binding_files`), their monitors generated and
   loaded once, for any number of logs.
2. **Logs** (:mod:`.discovery`) are found under the paths given; each is audited by
   :func:`audit_log` (:mod:`.log`): opened, its inputs checked (:mod:`.checks`), read once
   with every requirement on its own clock (:mod:`.passes`, columns in :mod:`.columns`) and
   cut at the damage.
3. **Monitors**: every tick goes to every requirement's generated ``step()`` (engine
   ``stepwise``), or, on long logs, the pt verdicts and LTL3 status are computed at the end
   from the columns (engine ``vectorized``; equal by test); a requirement whose pt formula
   needs a future-time function (``persists``, ``occurs``) has no online monitor and is
   decided by the interval semantics alone (engine ``interval``). The engines are in
   :mod:`monitors.engines`.
4. **Verdicts** (:mod:`.finalize`): the engine's verdict, the interval-semantics evidence,
   the verdict at the damage (:mod:`monitors.audit.damage`), the values around the first
   violation and the numbers behind its boolean variables (:mod:`.operands`); the problems of
   every pass (:mod:`.log_problems`).
5. **Many logs** (:mod:`.workers`): :func:`audit_logs` with ``jobs > 1`` audits logs in worker
   processes; results come back in input order.

This package re-exports the public names of those modules.
"""

from __future__ import annotations

from .columns import CHUNK
from .config import AuditConfig, AuditInputError
from .discovery import LOG_SUFFIXES, discover_bindings, find_logs
from .log import audit_log
from .model import AuditPlan, RequirementPlan
from .passes import MAX_TICKS, VECTORIZE_MIN_TICKS
from .plan import load_plan
from .workers import audit_logs

__all__ = ["AuditConfig", "AuditPlan", "RequirementPlan", "AuditInputError", "load_plan",
           "discover_bindings", "find_logs", "audit_log", "audit_logs", "CHUNK",
           "VECTORIZE_MIN_TICKS", "MAX_TICKS", "LOG_SUFFIXES"]
