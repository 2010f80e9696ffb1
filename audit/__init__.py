"""The audit engine: recorded runs x FRETish requirements -> verdicts with evidence.

One module per step:

Design notes: ARCHITECTURE.md, `audit/__init__.py`."""

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
