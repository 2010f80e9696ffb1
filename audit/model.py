"""The audit plan as data: one :class:`RequirementPlan` per requirement (its compiled form,
monitor class, variables, or why it cannot be audited) in an :class:`AuditPlan` with the
merged bindings (built by :func:`fretc.audit.plan.load_plan`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, TYPE_CHECKING

from fretc.compiler.codegen import monitor_source

from fretc.signals.bindings import Bindings
from fretc.audit.config import AuditConfig

if TYPE_CHECKING:
    from fretc.compiler.codegen import MonitorSource
    from fretc.fretish.ast import Requirement
    from fretc.compiler.semantics import Formalization

__all__ = ["RequirementPlan", "AuditPlan"]


@dataclass
class RequirementPlan:
    """One requirement as the audit runs it.

    Attributes:
        index: position in the requirement files (order of the report).
        id, text, source (``file:line``): from the requirement file.
        compiled: the :class:`fretc.compiler.build.Compiled` (None if the period check failed).
        monitor_cls: the generated monitor class (``MONITORS[id]`` of its module), or None.
        variables: the FRET variables the monitor reads (``VARIABLES``), then any others of
            the formalization: those read from the log (a stream variable FRET defines,
            :attr:`streams`, is not; the variables it reads are).
        error: why it cannot be audited (parse/formalization error, no monitor, tick period
            mismatch), or None.
        notes: warnings of the formalization.
        rate_topic: set with ``error`` when the requirement has durations in time units
            and the tick topic's rate is not declared: the topic whose measured rate the
            audit of each log adds to the error as the ``nominal_rate`` to write.
        offline: no generated monitor because the pt formula needs a future-time function
            (``persists``, ``occurs``, ``nextOcc``); the verdict then comes from
            :mod:`fretc.monitors.interval` over the whole trace (engine ``"interval"``).
    """

    index: int
    id: str
    text: str
    source: str
    line: int
    compiled: Any = None
    monitor_cls: type | None = None
    variables: list[str] = field(default_factory=list)
    error: str | None = None
    notes: list[str] = field(default_factory=list)
    tick_period: Fraction | None = None
    offline: bool = False
    rate_topic: str | None = None
    _msource: Any = None

    @property
    def formalization(self) -> Formalization | None:
        """The :class:`fretc.compiler.semantics.Formalization`, or None."""
        return self.compiled.formalization if self.compiled is not None else None

    @property
    def requirement(self) -> Requirement | None:
        """The parsed requirement (:class:`fretc.fretish.ast.Requirement`), or None."""
        return self.compiled.requirement if self.compiled is not None else None

    @property
    def streams(self) -> Any:
        """The stream variables it reads, computed from the log's columns
        (:class:`fretc.fretish.fret_streams.StreamSystem`; their inputs are among
        ``variables``, they are not), or None."""
        return getattr(self.compiled.entry, "streams", None) if self.compiled is not None \
            else None

    @property
    def stream_names(self) -> tuple[str, ...]:
        """The names of :attr:`streams`' variables (none: ``()``)."""
        system = self.streams
        return system.names if system is not None else ()

    @property
    def judged_variables(self) -> list[str]:
        """The variables whose unknown ticks are the requirement's: :attr:`variables`, but
        with stream variables those its formulas read (the streams, not the inputs only
        they read: a stream is unknown where an unknown input changes it,
        :mod:`fretc.audit.streams`)."""
        system, f = self.streams, self.formalization
        if system is None or f is None:
            return self.variables
        own = list(f.variables)
        return own + [n for n in system.names if n not in own]

    @property
    def monitor_source(self) -> MonitorSource:
        """codegen's :class:`~fretc.compiler.codegen.MonitorSource` (the LTL3 automata tables the
        judge runs, :mod:`fretc.monitors.judge`), built on first use and kept."""
        if self._msource is None:
            self._msource = monitor_source(self.compiled, self.index)
        return self._msource

    def to_json(self) -> dict:
        """The requirement as the audit JSON's ``requirements`` list gives it."""
        f = self.formalization
        return {"id": self.id, "text": self.text, "source": self.source, "line": self.line,
                "key": f.key if f is not None else None,
                "variables": self.variables,
                "tick_period_s": (None if self.tick_period is None
                                  else float(self.tick_period)),
                "duration_ticks": f.ticks if f is not None else None,
                "offline": self.offline, "error": self.error, "notes": self.notes,
                **self._trace_json()}

    def _trace_json(self) -> dict:
        """Traceability: parent, rationale, the three formulas (FRET syntax), the source
        hash the generated monitor carries and its class name."""
        c = self.compiled
        if c is None:
            return {}
        out = {"parent": c.entry.parent, "rationale": c.entry.rationale,
               "source_hash": c.source_hash}
        if getattr(c.entry, "origin", None) is not None:  # a ReqIF, Doorstop or FRET source
            out["origin"] = c.entry.origin.to_json()
        if c.formalization is not None:
            out.update(ft=c.smv_text["ft"], ft_inf=c.smv_text["ft_inf"], pt=c.smv_text["pt"])
        if self.monitor_cls is not None:
            out["monitor_class"] = self.monitor_cls.__name__
        return out


@dataclass
class AuditPlan:
    """Compiled requirements, loaded monitors and bindings, ready for any number of logs.

    Attributes:
        config: the :class:`AuditConfig` it was built from.
        requirements: one :class:`RequirementPlan` per requirement, in file order.
        bindings: merged bindings (None when none were found or given: only CSV traces
            can then be audited).
        binding_files: the binding files read.
        modules: generated monitor module texts by module name.
        csv_period_ns: time step of CSV rows without a ``time`` column.
        freeform: ids (``file:line``) of free-form requirements: kept, never formalized,
            so not audited (not an error).
    """

    config: AuditConfig
    requirements: list[RequirementPlan]
    bindings: Bindings | None
    binding_files: list[str]
    modules: dict[str, str]
    csv_period_ns: int
    freeform: list[str] = field(default_factory=list)
    #: remarks on the inputs (bound variables no requirement uses)
    warnings: list[str] = field(default_factory=list)
    #: binding files with ``[logs]``: (selector, file, the plan for the logs it selects)
    variants: list[tuple[Any, str, AuditPlan]] = field(default_factory=list)
    #: items of ReqIF / Doorstop sources without FRETish text (RequirementEntry): listed as
    #: not formalized, never audited
    not_formalized: list = field(default_factory=list)
    #: ``fretc audit --coverage``: record each verdict's coverage obligations
    #: (:mod:`fretc.audit.coverage`)
    coverage: bool = False

    def sources_json(self) -> dict:
        """The audit JSON's ``not_formalized`` list (``{id, source, line, origin}`` each),
        as ``{"not_formalized": [...]}``; ``{}`` when every item had FRETish text."""
        if not self.not_formalized:
            return {}
        return {"not_formalized": [
            {"id": e.id, "source": e.source, "line": e.line,
             "origin": e.origin.to_json() if e.origin is not None else None}
            for e in self.not_formalized]}

    def requirements_json(self) -> list[dict]:
        """Every requirement's :meth:`RequirementPlan.to_json`."""
        return [r.to_json() for r in self.requirements]

    def bindings_json(self) -> dict | None:
        """The bindings as the audit JSON gives them (per log with ``[logs]``)."""
        if self.variants:
            variables: dict[str, Any] = {}
            for _sel, _f, sub in self.variants:
                for name, v in (sub.bindings_json() or {}).get("variables", {}).items():
                    variables.setdefault(name, v)
            return {"sources": self.binding_files, "tick": None, "time_base": None,
                    "variables": variables,
                    "per_log": [dict(sub.bindings_json() or {}, file=f,
                                     logs={"glob": list(sel.glob), "topics": list(sel.topics)})
                                for sel, f, sub in self.variants]}
        b = self.bindings
        if b is None:
            return None
        tick: dict[str, Any] = ({"period_ns": b.tick.period_ns} if b.tick.period_ns is not None
                else {"topic": b.tick.topic})
        if b.tick.nan != "unread":  # a binding file's own NaN policy ([tick] nan)
            tick["nan"] = b.tick.nan
        if b.tick.inf != "unread":  # and its ±inf policy ([tick] inf)
            tick["inf"] = b.tick.inf
        return {"sources": self.binding_files, "tick": tick, "time_base": b.time_base,
                **({"allowance_ns": dict(sorted(b.allowance.items()))} if b.allowance
                   else {}),
                "variables": {n: {"expr": v.expr, "source": v.source, "line": v.line,
                                  "topics": sorted(v.topics)}
                              for n, v in b.variables.items()}}
