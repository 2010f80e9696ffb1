"""The audit engine: recorded runs x FRETish requirements -> verdicts with evidence.

One module per step:

1. **Plan** (:mod:`.plan`, data in :mod:`.model`; the verdicts it gives and the audit JSON
   in :mod:`.verdict`): the requirements compiled with the tick
   period of the signal bindings (:mod:`.binding_files`), their monitors generated and
   loaded once, for any number of logs.
2. **Logs** (:mod:`.discovery`) are found under the paths given; each is audited by
   :func:`audit_log` (:mod:`.log`): opened, its inputs checked (:mod:`.checks`), read once
   with every requirement on its own clock (:mod:`.passes`, columns in :mod:`.columns`) and
   cut at the damage.
3. **Verdicts** (:mod:`.finalize`): each requirement judged once over its clock's columns by
   :func:`fretc.monitors.judge.judge` (FRET's interval semantics for the verdict and its
   evidence, the monitor automata for the LTL3 verdict), the verdict at the damage
   (:mod:`.damage`), the values around the first violation and the numbers behind its boolean
   variables (:mod:`.operands`); the problems of every pass (:mod:`.log_problems`).
4. **Many logs** (:mod:`.fleet`): :func:`audit_logs` with ``jobs > 1`` audits logs in worker
   processes (:mod:`.fleet.workers`); results come back in input order; :mod:`.fleet.ray`
   runs one Ray task per log, the same :func:`audit_log`; :mod:`.fleet.statistics` counts
   the runs.

Beside the steps, in subpackages: **per-entity** requirements (:mod:`.entities`: one
verdict per entity of the log) and the **sampled trace** (:mod:`.sampled`: what an audit
judged, written as a CSV trace with ``--write-csv`` and audited back).

This package re-exports the public names of those modules.
"""

from __future__ import annotations

from fretc.audit.columns import CHUNK
from fretc.audit.config import AuditConfig, AuditInputError
from fretc.audit.discovery import LOG_SUFFIXES, discover_bindings, find_logs
from fretc.audit.log import audit_log
from fretc.audit.model import AuditPlan, RequirementPlan
from fretc.audit.passes import MAX_TICKS
from fretc.audit.plan import load_plan
from fretc.audit.fleet.workers import audit_logs

__all__ = ["AuditConfig", "AuditPlan", "RequirementPlan", "AuditInputError", "load_plan",
           "discover_bindings", "find_logs", "audit_log", "audit_logs", "CHUNK",
           "MAX_TICKS", "LOG_SUFFIXES"]
