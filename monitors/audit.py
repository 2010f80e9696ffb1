"""The audit engine: recorded runs x FRETish requirements -> verdicts with evidence.

For each log (:func:`audit_log`):

1. **Requirements** are compiled (:mod:`compiler.build`) with the tick period of the signal
   bindings when their file declares none (a declared period must equal a fixed bindings
   period, else that requirement is an input error naming both), and their monitors are
   generated (:func:`compiler.codegen.emit_monitors`, one module per requirement file) and
   loaded in-process by ``exec`` into a fresh module: the same code ``fretc FILE --emit
   monitor`` gives users.
2. **Signals**: the log is opened (:func:`monitors.sources.open_log`) and sampled
   (:func:`monitors.signals.sample`) with the bindings restricted to the variables the
   requirements use; ticks stream through. A CSV trace is read with its columns as the
   variables unless the bindings read ``/csv`` fields.
3. **Monitors**: every tick goes to every requirement's generated ``step()`` (engine
   ``stepwise``), or, on long logs, the pt verdicts and LTL3 status are computed at the end
   from the columns by :mod:`compiler.vectorized` (engine ``vectorized``; equal by test).
   ``finish()`` gives FRET's finite-trace verdict; ``status``/``status_tick`` the earliest
   definitive (LTL3) verdict.
   A requirement whose pt formula needs a future-time function (``persists``, ``occurs``)
   has no online monitor; offline it is decided by step 4 alone (engine ``interval``).
4. **Evidence**: :func:`monitors.evidence.evaluate_requirement` re-decides the requirement by
   FRET's interval semantics from the columns and gives the vacuity, the first violated
   trigger, its scope interval and response window; the values of the requirement's
   variables and the log times of the messages behind them are taken around the trigger and
   the violation.

Memory: messages are streamed (:mod:`monitors.sources`), never kept. What grows with the
length of the log is only the compact columns kept for the evidence and the vectorized
engine: per evaluated tick, 8 bytes of time, 8 bytes per bound topic (log time of the held
message), 1 byte per boolean and 8 per numeric variable - about 80 bytes a tick for the
Safe-ROS set, 3 MB for an hour at 10 Hz. (Kept in chunks of :data:`CHUNK` ticks.)

Damage (../shared/DESIGN.md "Damage is never evidence"): a damaged log (cut short, a chunk skipped, its
summary lost) is ``partial``; only the ticks before its first cut or gap
(``LogAudit.damage_time_ns``, :attr:`monitors.sources.LogSource.intact_end`) are judged, and
a verdict that the end of that span would decide is ``unknown`` (:mod:`monitors.damage`); a
fixed tick period giving more than :data:`MAX_TICKS` ticks is an input error; a topic whose
schema is unknown makes only the requirements reading it ``error`` - the others are audited
without it (a second pass over the log, only in that case). Problems of every pass are kept.

Parallel: :func:`audit_logs` with ``jobs > 1`` audits logs in worker processes
(``concurrent.futures``, fork where available); results come back in input order.
"""

from __future__ import annotations

import dataclasses
import re
import types
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from fretish.units import NS_PER_S
from fretish.units import format_ns as _fmt_ns, format_period as _fmt_period

from .bindings import Binding, Bindings, TickSpec, load_bindings, parse_duration
from .problems import BindingError, DataProblem, FretcInputError, LogError, SignalError

__all__ = ["AuditConfig", "AuditPlan", "RequirementPlan", "AuditInputError", "load_plan",
           "discover_bindings", "find_logs", "audit_log", "audit_logs", "CHUNK",
           "VECTORIZE_MIN_TICKS", "LOG_SUFFIXES"]

#: Ticks per column chunk.
CHUNK = 4096
#: Engine "auto" evaluates vectorized on logs expected to have at least this many ticks.
VECTORIZE_MIN_TICKS = 20_000
#: At most this many ticks per log: a tick period that would give more (``tick period =
#: "1 ns"`` on an 88 s log: 8.8e10) is an input error that says how many (issue 15 item 11).
MAX_TICKS = 10**8
#: File kinds audited when a folder is given.
LOG_SUFFIXES = (".mcap", ".bag", ".csv")
_MODULE_PREFIX = "fretc_audit_"


class AuditInputError(FretcInputError):
    """Input the audit cannot start with (exit code 2): unreadable requirement or binding
    files, conflicting bindings, bad options, no logs. The message names the file."""


# --------------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class AuditConfig:
    """Everything an audit needs besides the logs; plain values (picklable for workers).

    Attributes:
        requirements: requirement files or folders (``.fret``, FRET JSON exports).
        bindings: binding files (TOML); None: discover ``*.bindings.toml`` next to the
            requirements (:func:`discover_bindings`).
        inline: ``NAME=EXPR`` bindings (``--bind``), added last.
        tick_period: override of the bindings' tick (``"100 ms"``); ``tick_topic``: one tick
            per message of this topic; ``time_base``: ``"log"`` or ``"header"``.
        engine: ``"auto"``, ``"stepwise"`` or ``"vectorized"`` (module docstring, step 3).
        window: ticks of values shown on each side of the trigger and the violation.
    """

    requirements: Tuple[str, ...]
    bindings: Optional[Tuple[str, ...]] = None
    inline: Tuple[str, ...] = ()
    tick_period: Optional[str] = None
    tick_topic: Optional[str] = None
    time_base: Optional[str] = None
    engine: str = "auto"
    window: int = 5
    select_logs: bool = True


def discover_bindings(requirement_paths: Sequence[str]) -> List[Path]:
    """Binding files for requirement paths: for a folder, its ``*.bindings.toml``; for a
    file ``X.fret`` (or ``X.json``), ``X.bindings.toml`` beside it if it exists, else every
    ``*.bindings.toml`` in its folder. Sorted by name, without duplicates."""
    out: List[Path] = []
    for p in requirement_paths:
        path = Path(p)
        if path.is_dir():
            found = sorted(path.glob("*.bindings.toml"))
        else:
            own = path.with_name(path.name.split(".")[0] + ".bindings.toml")
            found = [own] if own.is_file() else sorted(path.parent.glob("*.bindings.toml"))
        for f in found:
            if f not in out:
                out.append(f)
    return out


#: A tick topic's measured rate may differ this much from its nominal rate without warning.
RATE_TOLERANCE = 0.10


def _check_nominal_rate(la, bindings: Optional[Bindings]) -> None:
    """Warn when one tick per message of a topic whose nominal rate converts the durations
    runs at a measured rate (messages over the log's span) more than
    :data:`RATE_TOLERANCE` away from it: ``within 1 second`` then means a different time."""
    if bindings is None or bindings.tick.topic is None or not bindings.tick.nominal_period_ns:
        return
    n = la.messages.get(bindings.tick.topic, 0)
    st, en = la.start_time_ns, la.end_time_ns
    if n < 2 or st is None or en is None or en <= st:
        return
    measured = (n - 1) * NS_PER_S / (en - st)
    nominal = NS_PER_S / bindings.tick.nominal_period_ns
    if abs(measured - nominal) > RATE_TOLERANCE * nominal:
        la.warnings.append(
            f"{bindings.tick.topic} runs at {measured:.3g} Hz, not its nominal "
            f"{nominal:.3g} Hz ({bindings.source}): durations in time units, converted with "
            f"the nominal rate, are off by {abs(measured / nominal - 1):.0%}")


def _has_time_units(entry) -> bool:
    """The requirement's text has a duration in time units (not ``ticks``)."""
    from fretish.errors import FretishError
    from fretish.parser import parse

    try:
        req = parse(entry.text)
    except (FretishError, Exception):  # reported when compiled
        return False
    d = getattr(req.timing, "duration", None)
    return d is not None and d.unit != "ticks"


def _merge_bindings(parts: List[Bindings]) -> Bindings:
    """One Bindings from several files: variables united; the same variable bound twice
    differently, or different ticks / time bases, is an :class:`AuditInputError`."""
    first = parts[0]
    variables: Dict[str, Binding] = {}
    for b in parts:
        if (b.tick, b.time_base, b.header_lag_ns) != (first.tick, first.time_base,
                                                        first.header_lag_ns):
            raise AuditInputError(
                f"{b.source}: [tick] ({_tick_text(b.tick)}, time {b.time_base}) differs from "
                f"{first.source} ({_tick_text(first.tick)}, time {first.time_base}); one audit "
                "uses one clock: pass --bindings to choose")
        for name, v in b.variables.items():
            old = variables.get(name)
            if old is not None and old.expr.strip() != v.expr.strip():
                raise AuditInputError(
                    f"{v.source}:{v.line}: variable {name!r} is bound to {v.expr!r}, but "
                    f"{old.source}:{old.line} binds it to {old.expr!r}")
            variables.setdefault(name, v)
    source = ", ".join(str(b.source) for b in parts)
    return Bindings(variables, first.tick, first.time_base, first.header_lag_ns, source)


def _tick_text(tick: TickSpec) -> str:
    if tick.period_ns is not None:
        return f"every {_fmt_ns(tick.period_ns)}"
    return f"one per {tick.topic} message"


# --------------------------------------------------------------------------- the plan
@dataclass
class RequirementPlan:
    """One requirement as the audit runs it.

    Attributes:
        index: position in the requirement files (order of the report).
        id, text, source (``file:line``): from the requirement file.
        compiled: the :class:`compiler.build.Compiled` (None if the period check failed).
        monitor_cls: the generated monitor class (``MONITORS[id]`` of its module), or None.
        variables: the FRET variables the monitor reads (``VARIABLES``), then any others of
            the formalization.
        error: why it cannot be audited (parse/formalization error, no monitor, tick period
            mismatch), or None.
        notes: warnings of the formalization.
        offline: no generated monitor because the pt formula needs a future-time function
            (``persists``, ``occurs``, ``nextOcc``); the verdict then comes from
            :mod:`monitors.evidence` over the whole trace (engine ``"interval"``).
    """

    index: int
    id: str
    text: str
    source: str
    line: int
    compiled: Any = None
    monitor_cls: Optional[type] = None
    variables: List[str] = field(default_factory=list)
    error: Optional[str] = None
    notes: List[str] = field(default_factory=list)
    tick_period: Optional[Fraction] = None
    offline: bool = False
    _msource: Any = None

    @property
    def formalization(self):
        return self.compiled.formalization if self.compiled is not None else None

    @property
    def requirement(self):
        return self.compiled.requirement if self.compiled is not None else None

    def monitor_source(self):
        """codegen's :class:`~compiler.codegen.MonitorSource` (automata tables for the
        vectorized engine), built once."""
        if self._msource is None:
            from compiler.codegen import monitor_source
            self._msource = monitor_source(self.compiled, self.index)
        return self._msource

    def vectorizable(self) -> bool:
        from compiler.vectorized import supports

        if self.offline:
            return False
        f = self.formalization
        if f is None or not f.pt_causal or not supports(f.pt):
            return False
        ms = self.monitor_source()
        return all(a is None or a.table is not None or a.complete for a in (ms.bad, ms.good))

    def to_json(self) -> dict:
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
        if c.formalization is not None:
            out.update(ft=c.smv("ft"), ft_inf=c.smv("ft_inf"), pt=c.smv("pt"))
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
    requirements: List[RequirementPlan]
    bindings: Optional[Bindings]
    binding_files: List[str]
    modules: Dict[str, str]
    csv_period_ns: int
    freeform: List[str] = field(default_factory=list)
    #: remarks on the inputs (bound variables no requirement uses)
    warnings: List[str] = field(default_factory=list)
    #: binding files with ``[logs]``: (selector, file, the plan for the logs it selects)
    variants: List[Tuple[Any, str, "AuditPlan"]] = field(default_factory=list)

    def requirements_json(self) -> List[dict]:
        return [r.to_json() for r in self.requirements]

    def bindings_json(self) -> Optional[dict]:
        if self.variants:
            variables = {}
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
        tick = ({"period_ns": b.tick.period_ns} if b.tick.period_ns is not None
                else {"topic": b.tick.topic})
        return {"sources": self.binding_files, "tick": tick, "time_base": b.time_base,
                "variables": {n: {"expr": v.expr, "source": v.source, "line": v.line,
                                  "topics": sorted(v.topics)}
                              for n, v in b.variables.items()}}


def _load_bindings(config: AuditConfig) -> Tuple[Optional[Bindings], List[str]]:
    files = ([Path(p) for p in config.bindings] if config.bindings is not None
             else discover_bindings(config.requirements))
    parts = []
    for f in files:
        try:
            parts.append(load_bindings(f))
        except BindingError as exc:
            raise AuditInputError(str(exc)) from None
    b = _merge_bindings(parts) if parts else None
    if config.tick_period is not None and config.tick_topic is not None:
        raise AuditInputError("--tick-period and --tick-topic exclude each other")
    tick = None
    if config.tick_period is not None:
        try:
            tick = TickSpec(period_ns=parse_duration(config.tick_period))
        except ValueError as exc:
            raise AuditInputError(f"--tick-period: {exc}") from None
    elif config.tick_topic is not None:
        if not re.fullmatch(r"(/[A-Za-z0-9_]+)+", config.tick_topic):
            raise AuditInputError(f"--tick-topic {config.tick_topic!r} is not a topic name")
        tick = TickSpec(topic=config.tick_topic)
    if b is None and (config.inline or tick is not None):
        if tick is None:
            raise AuditInputError("--bind without a binding file needs --tick-period or "
                                  "--tick-topic (signals are declared, never guessed)")
        b = Bindings({}, tick, config.time_base or "log")
    if b is not None:
        if tick is not None or config.time_base is not None:
            b = Bindings(dict(b.variables), tick or b.tick, config.time_base or b.time_base,
                         b.header_lag_ns, b.source)
        if config.inline:
            try:
                b = b.with_inline(config.inline)
            except BindingError as exc:
                raise AuditInputError(str(exc)) from None
    return b, [str(f) for f in files]


def load_plan(config: AuditConfig) -> AuditPlan:
    """Read requirements and bindings, compile, generate and load the monitors.

    Raises:
        AuditInputError: a requirement file that cannot be read (a bad sentence is not
            this: it becomes that requirement's ``error``), bad or conflicting bindings, bad
            options.
    """
    from compiler.build import compile_entries
    from compiler.codegen import emit_monitors, file_stems
    from fretish.errors import FretishError
    from fretish.files import load_requirements

    if config.engine not in ("auto", "stepwise", "vectorized"):
        raise AuditInputError(f"unknown engine {config.engine!r} (auto, stepwise, vectorized)")
    if config.select_logs:
        split = _plan_per_log(config)
        if split is not None:
            return split
    bindings, binding_files = _load_bindings(config)
    try:
        entries = load_requirements([Path(p) for p in config.requirements])
    except FretishError as exc:
        raise AuditInputError(str(exc)) from None
    except OSError as exc:
        raise AuditInputError(f"cannot read requirements: {exc}") from None
    if not entries:
        raise AuditInputError(f"no requirements in {', '.join(config.requirements)}")
    period = None
    nominal = None
    if bindings is not None and bindings.tick.period_ns is not None:
        period = Fraction(bindings.tick.period_ns, NS_PER_S)
    elif bindings is not None and bindings.tick.nominal_period_ns is not None:
        nominal = Fraction(bindings.tick.nominal_period_ns, NS_PER_S)
    flag = config.tick_period is not None  # --tick-period overrides every declared period
    plans: List[RequirementPlan] = []
    to_compile = []
    for i, e in enumerate(entries):
        rp = RequirementPlan(i, e.id, e.text, f"{e.source}:{e.line}", e.line)
        if flag:
            if e.tick_period is not None and e.tick_period != period:
                rp.notes.append(f"durations converted with --tick-period "
                                f"{_fmt_period(period)} instead of the declared "
                                f"{_fmt_period(e.tick_period)}")
            e = dataclasses.replace(e, tick_period=period)
        elif e.tick_period is None and period is not None:
            e = dataclasses.replace(e, tick_period=period)
        elif e.tick_period is not None and period is not None and e.tick_period != period:
            rp.error = (f"{e.source}:{e.line}: {e.id} declares a tick period of "
                        f"{_fmt_period(e.tick_period)} but the bindings ({bindings.source}) "
                        f"tick every {_fmt_period(period)}: durations would convert with the "
                        "wrong period; make them equal (or pass --tick-period to override "
                        "both for this run)")
        elif bindings is not None and bindings.tick.topic:
            if nominal is not None and e.tick_period is not None and e.tick_period != nominal:
                rp.error = (f"{e.source}:{e.line}: {e.id} declares a tick period of "
                            f"{_fmt_period(e.tick_period)} but the bindings ({bindings.source})"
                            f" give {bindings.tick.topic} a nominal period of "
                            f"{_fmt_period(nominal)}; make them equal")
            elif nominal is not None:
                e = dataclasses.replace(e, tick_period=nominal)
            elif _has_time_units(e):
                rp.error = (f"{e.source}:{e.line}: {e.id} has a duration in time units but "
                            f"the bindings ({bindings.source}) tick once per "
                            f"{bindings.tick.topic} message, whose rate is not declared: add "
                            f"nominal_rate = \"10 Hz\" (the topic's rate) to [tick]; the "
                            "audit checks it against the log")
        rp.tick_period = e.tick_period
        plans.append(rp)
        to_compile.append(e)
    compiled = compile_entries(to_compile)
    if flag:
        for c, rp in zip(compiled, plans):
            if c.error is not None and rp.error is None:
                rp.error = (f"{c.error} (the tick period {_fmt_period(period)} comes from "
                            "--tick-period)")
    ok = [c for c, rp in zip(compiled, plans) if rp.error is None]
    modules = emit_monitors(ok) if ok else {}
    classes: Dict[Tuple[str, str], type] = {}
    skipped: Dict[Tuple[str, str], str] = {}
    stem_of = file_stems([c.entry.source for c in ok], "_monitors")  # as emit_monitors
    for stem, text in modules.items():
        mod = types.ModuleType(_MODULE_PREFIX + stem)
        exec(compile(text, f"<fretc monitors {stem}>", "exec"), mod.__dict__)
        # map by (source, id): emit_monitors groups by source in input order
        for c in ok:
            if stem_of[c.entry.source] == stem:
                src = c.entry.source
                if c.id in mod.MONITORS:
                    classes[(src, c.id)] = mod.MONITORS[c.id]
                elif c.id in mod.SKIPPED:
                    skipped[(src, c.id)] = mod.SKIPPED[c.id]
    for c, rp in zip(compiled, plans):
        rp.compiled = c
        if rp.error is not None:
            continue
        key = (c.entry.source, c.id)
        if c.error is not None:
            rp.error = str(c.error)
        elif c.freeform:
            rp.error = "free-form"  # dropped below: not audited, not an error
        elif key in classes:
            rp.monitor_cls = classes[key]
            names = list(rp.monitor_cls.VARIABLES)
            rp.variables = names + [v for v in c.formalization.variables if v not in names]
            rp.notes.extend(c.formalization.warnings)
        elif not c.formalization.pt_causal:
            # a future-time function in the pt formula: no online monitor, but the audit is
            # offline - decide it by the interval semantics over the whole trace
            rp.offline = True
            rp.variables = list(c.formalization.variables)
            rp.notes.extend(c.formalization.warnings)
            rp.notes.append("no online monitor (the pt formula needs a future-time function): "
                            "decided offline by the interval semantics; no LTL3 verdict")
        else:
            rp.error = f"no monitor: {skipped.get(key, 'not generated')}"
    csv_period = bindings.tick.period_ns if (bindings is not None
                                             and bindings.tick.period_ns) else None
    if csv_period is None:
        periods = {rp.tick_period for rp in plans if rp.tick_period is not None}
        csv_period = int(periods.pop() * NS_PER_S) if len(periods) == 1 else NS_PER_S
    freeform = [f"{rp.id} ({rp.source})" for rp in plans if rp.error == "free-form"]
    plans = [rp for rp in plans if rp.error != "free-form"]
    if not plans:
        raise AuditInputError(f"only free-form requirements in {', '.join(config.requirements)}"
                              ": nothing to audit")
    warnings = []
    if bindings is not None:
        used = {v for rp in plans for v in (rp.variables or (
            rp.formalization.variables if rp.formalization is not None else []))}
        for name, b in bindings.variables.items():
            if name not in used:
                at = f"{b.source}:{b.line}" if b.line is not None else str(b.source)
                warnings.append(f"{at}: {name!r} is bound but no requirement uses it")
    return AuditPlan(config, plans, bindings, binding_files, modules, max(1, csv_period),
                     freeform, warnings)


def _plan_per_log(config: AuditConfig) -> Optional[AuditPlan]:
    """Binding files that select their logs (``[logs]``, :class:`monitors.bindings.LogSelector`):
    one plan per selecting file (merged with the files that select nothing, which apply to
    every log), each compiled with its own tick. A requirement whose variables are bound
    only by another selecting file is not applicable to that file's logs (it is left out of
    their verdicts); one bound nowhere stays an error. None when no file selects logs."""
    files = ([Path(p) for p in config.bindings] if config.bindings is not None
             else discover_bindings(config.requirements))
    parts = []
    for f in files:
        try:
            parts.append((f, load_bindings(f)))
        except BindingError as exc:
            raise AuditInputError(str(exc)) from None
    selecting = [(f, b) for f, b in parts if b.logs is not None]
    if not selecting:
        return None
    plain = [str(f) for f, b in parts if b.logs is None]
    variants = []
    for f, b in selecting:
        sub = load_plan(dataclasses.replace(config, bindings=tuple([str(f)] + plain),
                                            select_logs=False))
        variants.append((b.logs, str(f), sub))
    anywhere = {n for _s, _f, sub in variants for n in sub.bindings.variables}
    union: Dict[Tuple[str, str], RequirementPlan] = {}
    for _s, _f, sub in variants:
        keep = []
        for r in sub.requirements:
            names = r.variables or (list(r.formalization.variables)
                                    if r.formalization is not None else [])
            missing = [v for v in names if v not in sub.bindings.variables]
            if missing and all(v in anywhere for v in missing):
                continue  # bound by another selecting file: for its logs, not these
            keep.append(r)
            union.setdefault((r.source, r.id), r)
        sub.requirements = keep
    reqs = sorted(union.values(), key=lambda r: r.index)
    used = {v for r in reqs for v in (r.variables or (
        r.formalization.variables if r.formalization is not None else []))}
    warnings = sorted({w for _s, _f, sub in variants for w in sub.warnings
                       if w.split("'")[1] not in used})
    return AuditPlan(config, reqs, None, [str(f) for f in files], {}, NS_PER_S,
                     variants[0][2].freeform, warnings, variants)


def _select_variant(plan: AuditPlan, path: str):
    """(plan for ``path``, None) or (None, the input error naming the binding files)."""
    need_topics = any(sel.topics for sel, _f, _p in plan.variants)
    topics = None
    if need_topics:
        from .sources import open_log
        try:
            topics = list(open_log(path).topics())
        except (FretcInputError, OSError):
            topics = None
    hits = [(sel, f, sub) for sel, f, sub in plan.variants if sel.matches(path, topics)]
    if len(hits) == 1:
        return hits[0][2], None
    if not hits:
        return None, (f"{path}: no binding file selects this log ("
                      + "; ".join(f"{f}: {sel.text()}" for sel, f, _p in plan.variants)
                      + "); add a [logs] glob or topics that match it")
    return None, (f"{path} is selected by both {hits[0][1]} ({hits[0][0].text()}) and "
                  f"{hits[1][1]} ({hits[1][0].text()}): make their [logs] tables exclusive")


# --------------------------------------------------------------------------- logs
def find_logs(paths: Sequence[str]) -> List[str]:
    """Logs named by ``paths``: files as given; a rosbag2 folder (``metadata.yaml``) as one
    log; other folders searched recursively (sorted) for ``*.mcap``, ``*.bag``, ``*.csv``
    and rosbag2 folders.

    Raises:
        AuditInputError: a path that does not exist, or a folder holding no log.
    """
    out: List[str] = []
    for p in paths:
        path = Path(p)
        if not path.exists():
            raise AuditInputError(f"{p}: no such file or folder")
        if path.is_file() or (path / "metadata.yaml").is_file():
            out.append(str(path))
            continue
        found = _walk_logs(path)
        if not found:
            raise AuditInputError(f"{p}: no logs (*.mcap, *.bag, *.csv, rosbag2 folders)")
        out.extend(found)
    seen = set()
    return [x for x in out if not (x in seen or seen.add(x))]


def _walk_logs(folder: Path) -> List[str]:
    out: List[str] = []
    for child in sorted(folder.iterdir(), key=lambda c: c.name):
        if child.name.startswith("."):
            continue
        if child.is_dir():
            if (child / "metadata.yaml").is_file():
                out.append(str(child))
            else:
                out.extend(_walk_logs(child))
        elif child.suffix.lower() in LOG_SUFFIXES:
            out.append(str(child))
    return out


# --------------------------------------------------------------------------- columns
class _Columns:
    """Per-tick columns kept for evidence and the vectorized engine (module docstring,
    "Memory"): values of ``names``, tick times, and log times of the messages of ``topics``
    held at each tick; in numpy chunks of :data:`CHUNK` ticks."""

    def __init__(self, names: List[str], topics: List[str]):
        self.names = names
        self.topics = topics
        self.n = 0
        self._vals: List[list] = [[] for _ in names]
        self._lts: List[list] = [[] for _ in topics]
        self._times: list = []
        self._vchunks: List[List[np.ndarray]] = [[] for _ in names]
        self._lchunks: List[List[np.ndarray]] = [[] for _ in topics]
        self._tchunks: List[np.ndarray] = []

    def append(self, tick) -> None:
        v = tick.values
        for name, lst in zip(self.names, self._vals):
            lst.append(v.get(name, False))  # a failed variable: its requirements are errors
        lt = tick.log_times
        for topic, lst in zip(self.topics, self._lts):
            lst.append(lt.get(topic, -1))
        self._times.append(tick.time)
        self.n += 1
        if len(self._times) >= CHUNK:
            self._flush()

    @staticmethod
    def _array(values: list) -> np.ndarray:
        if all(type(x) is bool for x in values):
            return np.array(values, dtype=np.bool_)
        return np.array(values, dtype=np.float64)

    def _flush(self) -> None:
        if not self._times:
            return
        for lst, chunks in zip(self._vals, self._vchunks):
            chunks.append(self._array(lst))
            lst.clear()
        for lst, chunks in zip(self._lts, self._lchunks):
            chunks.append(np.array(lst, dtype=np.int64))
            lst.clear()
        self._tchunks.append(np.array(self._times, dtype=np.int64))
        self._times.clear()

    def finish(self) -> Tuple[np.ndarray, Dict[str, np.ndarray], Dict[str, np.ndarray]]:
        """(times, variable -> values, topic -> held log times), each of length ``n``.
        Chunks are joined one column at a time and released, so the peak is the columns
        plus one column."""
        self._flush()

        def cat(chunks: List[np.ndarray], dtype) -> np.ndarray:
            if not chunks:
                return np.zeros(0, dtype=dtype)
            if any(c.dtype != chunks[0].dtype for c in chunks):
                out = np.concatenate([c.astype(np.float64) for c in chunks])
            else:
                out = np.concatenate(chunks) if len(chunks) > 1 else chunks[0]
            chunks.clear()
            return out

        times = cat(self._tchunks, np.int64)
        cols = {n: cat(c, np.bool_) for n, c in zip(self.names, self._vchunks)}
        lts = {t: cat(c, np.int64) for t, c in zip(self.topics, self._lchunks)}
        return times, cols, lts


# --------------------------------------------------------------------------- one log
@dataclass
class _Pass:
    sampling: Any
    times: np.ndarray
    columns: Dict[str, np.ndarray]
    log_times: Dict[str, np.ndarray]
    monitors: Dict[int, Any]
    engine: Dict[int, str]
    cut: int = 0  # ticks dropped after the damage (_cut_at_damage)
    intact_end: Optional[int] = None  # exclusive bound of the judged ticks' times


def _restrict(b: Bindings, names: List[str]) -> Bindings:
    return Bindings({n: b.variables[n] for n in b.variables if n in names}, b.tick, b.time_base,
                    b.header_lag_ns, b.source)


def _expected_ticks(source, bindings: Optional[Bindings]) -> Optional[int]:
    if source.kind == "csv":
        return getattr(source, "row_count", None)
    if bindings is None or bindings.tick.period_ns is None:
        return None
    st, en = source.start_time, source.end_time
    if st is None or en is None:
        return None
    return (en - st) // bindings.tick.period_ns + 1


def _clock_key(r: RequirementPlan, bindings: Optional[Bindings]) -> frozenset:
    """The clock a requirement is sampled on: the topics of its own variables (../shared/DESIGN.md,
    "Each verdict stands alone": its tick grid, start, end and warm-up come from them and
    the bindings' tick, never from other requirements of the run)."""
    if bindings is None:
        return frozenset()
    return frozenset(t for v in r.variables if v in bindings.variables
                     for t in bindings.variables[v].topics)


@dataclass
class _Passes:
    """One read of a log: a :class:`_Pass` per clock, and what went wrong per clock."""

    sampling: Any
    passes: Dict[frozenset, "_Pass"]
    failed: Dict[frozenset, Dict[str, SignalError]]
    errors: Dict[frozenset, SignalError]


def _run_pass(plan: AuditPlan, source, bindings: Optional[Bindings], active: List[RequirementPlan],
              progress: Optional[Callable[[float], None]]) -> _Passes:
    from .signals import sample, sample_groups

    expected = _expected_ticks(source, bindings)
    engine: Dict[int, str] = {}
    for r in active:
        mode = plan.config.engine
        if mode == "auto":
            mode = ("vectorized" if expected is not None and expected >= VECTORIZE_MIN_TICKS
                    else "stepwise")
        if mode == "vectorized" and not r.vectorizable():
            mode = "stepwise"
        engine[r.index] = "interval" if r.offline else mode
    groups: Dict[frozenset, List[RequirementPlan]] = {}
    for r in active:
        groups.setdefault(_clock_key(r, bindings), []).append(r)
    cols: Dict[frozenset, _Columns] = {}
    monitors: Dict[frozenset, Dict[int, Any]] = {}
    steppers: Dict[frozenset, List[Tuple[RequirementPlan, Any]]] = {}
    spec: Dict[frozenset, Tuple[List[str], frozenset]] = {}
    for key, rs in groups.items():
        names: List[str] = []
        for r in rs:
            for v in r.variables:
                if v not in names:
                    names.append(v)
        if bindings is not None:
            topics = sorted(key)
        else:
            from .sources import CSV_TOPIC
            topics = [CSV_TOPIC]
        spec[key] = (names, key)
        cols[key] = _Columns(names, topics)
        monitors[key] = {r.index: r.monitor_cls() for r in rs if engine[r.index] == "stepwise"}
        steppers[key] = [(r, monitors[key][r.index].step) for r in rs
                         if r.index in monitors[key]]
    if bindings is not None:
        sampling = sample_groups(source, bindings, spec)
        stream = iter(sampling)
        failed = sampling.failed
        errors = sampling.errors
    else:
        single = sample(source, None)
        key0 = next(iter(groups))
        stream = ((key0, t) for t in single)
        failed = {key0: {}}
        errors = {}
        sampling = single
    start_t = source.start_time
    end_t = source.end_time
    span = (end_t - start_t) if (start_t is not None and end_t is not None
                                 and end_t > start_t) else None
    every = 512
    count = 0
    for key, tick in stream:
        vals = tick.values
        fails = failed[key]
        steps = steppers[key]
        if fails and any(v not in vals for r, _ in steps for v in r.variables):
            steps[:] = [(r, st) for r, st in steps if all(v in vals for v in r.variables)]
        for _r, step in steps:
            step(vals)
        cols[key].append(tick)
        count += 1
        if count > MAX_TICKS:
            raise SignalError(f"{source.path}: more than {MAX_TICKS:,} ticks (the limit); "
                              "choose a longer tick period")
        if progress is not None and count % every == 0:
            if span is not None:
                progress(min(1.0, max(0.0, (tick.time - start_t) / span)))
            elif expected:
                progress(min(1.0, count / expected))
    passes: Dict[frozenset, _Pass] = {}
    for key in groups:
        times, columns, log_times = cols[key].finish()
        s = sampling.groups[key] if bindings is not None else sampling
        passes[key] = _Pass(s, times, columns, log_times, monitors[key], engine)
        _cut_at_damage(passes[key], source, bindings, groups[key])
    return _Passes(sampling, passes, failed, errors)


def _cut_at_damage(res: _Pass, source, bindings: Optional[Bindings],
                   active: List[RequirementPlan]) -> None:
    """Keep only the ticks of the span read completely (../shared/DESIGN.md "Damage is never
    evidence"): those strictly before the source's ``intact_end`` (a cut or the first gap;
    under the header time base, ``header_lag_ns`` earlier, since a lost message's stamp may
    precede its log time by that much). The stepwise monitors, which saw every tick, are
    replayed over the kept ones. Sets ``res.cut`` to the number of ticks dropped."""
    end = source.intact_end
    if end is None:
        return
    if bindings is not None and bindings.time_base == "header":
        end -= bindings.header_lag_ns
    keep = int(np.searchsorted(res.times, end, side="left"))
    n = len(res.times)
    res.intact_end = end
    if keep >= n:
        return
    res.cut = n - keep
    res.times = res.times[:keep]
    res.columns = {k: v[:keep] for k, v in res.columns.items()}
    res.log_times = {k: v[:keep] for k, v in res.log_times.items()}
    by_index = {r.index: r for r in active}
    names = list(res.columns)
    for idx in list(res.monitors):
        mon = by_index[idx].monitor_cls()
        cols = [res.columns[k] for k in names]
        for i in range(keep):
            mon.step({k: _py(c[i]) for k, c in zip(names, cols)})
        res.monitors[idx] = mon


def _problem_json(p: DataProblem) -> dict:
    return {"kind": p.kind, "topic": p.topic, "log_time_ns": p.log_time,
            "end_time_ns": p.end_time, "detail": p.detail}




def audit_log(plan: AuditPlan, path: str,
              progress: Optional[Callable[[float], None]] = None) -> LogAudit:
    """Audit one log against every requirement of ``plan``.

    Args:
        plan: from :func:`load_plan`.
        path: a log file or rosbag2 folder.
        progress: called now and then with the fraction of the log read (0..1).

    Returns:
        A :class:`~monitors.report_model.LogAudit` with one verdict per requirement. Input
        problems of this log (unreadable file, missing topic or binding) are reported in it
        (``error`` / ``error`` verdicts), never raised.
    """
    from .report_model import LogAudit, Verdict
    from .sources import open_log

    if plan.variants:
        sub, err = _select_variant(plan, str(path))
        if sub is None:
            la = LogAudit(log=str(path), error=err)
            damaged = _damage_of(path, la)
            if damaged:  # the damage may have taken the topics that select it: unknown
                la.error = None
                la.verdicts = [Verdict(log=str(path), requirement=r.id, text=r.text,
                                       source=r.source, verdict="unknown", partial=True,
                                       unknown_reason=f"{err}; {damaged}")
                               for r in plan.requirements]
                return la
            la.verdicts = [Verdict(log=str(path), requirement=r.id, text=r.text,
                                   source=r.source, error=f"log not audited: {err}")
                           for r in plan.requirements]
            return la
        return audit_log(sub, path, progress)
    la = LogAudit(log=str(path))
    verdicts: Dict[int, Verdict] = {}
    for r in plan.requirements:
        verdicts[r.index] = Verdict(log=str(path), requirement=r.id, text=r.text,
                                    source=r.source, notes=list(r.notes))
        if r.error is not None:
            verdicts[r.index].error = r.error

    def finish() -> LogAudit:
        la.verdicts = [verdicts[r.index] for r in plan.requirements]
        for v in la.verdicts:
            if v.error is not None:
                v.verdict = "error"
            v.partial = la.partial
        return la

    def fail_all(message: str, rs=None) -> None:
        for r in (rs if rs is not None else plan.requirements):
            if verdicts[r.index].error is None:
                verdicts[r.index].error = message

    try:
        source = open_log(path, csv_period_ns=plan.csv_period_ns)
    except FretcInputError as exc:
        la.error = str(exc)
        fail_all(f"log not audited: {exc}")
        return finish()
    except OSError as exc:
        la.error = f"{path}: {exc}"
        fail_all(f"log not audited: {la.error}")
        return finish()
    la.kind = source.kind
    bindings = plan.bindings
    if source.kind == "csv":
        # the same binding rules as any log (README "CSV traces"): with bindings, bound
        # variables are their expressions over /csv.<column> (a missing topic or column is
        # an error naming the columns), unbound ones read the column of their name; without
        # bindings the columns are the variables
        if bindings is not None and not bindings.variables:
            bindings = None
        elif bindings is not None:
            bindings = _csv_bindings(plan, bindings, source)
    elif bindings is None:
        la.error = (f"{path}: a {source.kind} log needs signal bindings (*.bindings.toml next to "
                    "the requirements, --bindings or --bind): signals are declared, never "
                    "guessed")
        fail_all(la.error)
        return finish()
    if bindings is not None:
        la.tick = ({"period_ns": bindings.tick.period_ns} if bindings.tick.period_ns
                   else {"topic": bindings.tick.topic})
        la.time_base = bindings.time_base
    else:
        la.tick = {"period_ns": plan.csv_period_ns, "rows": True}
        la.time_base = "csv"
    too_many = _too_many_ticks(source, bindings, path)
    if too_many is not None:
        la.error = too_many
        fail_all(too_many)
        return finish()

    active = [r for r in plan.requirements if r.error is None]
    # variables without a binding (or CSV column)
    available = set(bindings.variables) if bindings is not None else set(source.columns)
    for r in active:
        missing = [v for v in r.variables if v not in available]
        if missing:
            where = (f"bindings ({bindings.source})" if bindings is not None
                     else f"the CSV columns ({', '.join(source.columns)})")
            from .schema import closest
            hints = [(m, closest(m, sorted(available))) for m in missing]
            hint = "; ".join(f"did you mean {h!r} for {m!r}?" for m, h in hints if h)
            verdicts[r.index].error = (f"no binding for {', '.join(map(repr, missing))} in "
                                       f"{where}" + (f"; {hint}" if hint else ""))
    # topics absent from the log
    try:
        log_topics = source.topics()
    except FretcInputError as exc:
        la.error = str(exc)
        fail_all(f"log not audited: {exc}")
        return finish()
    r_skip: set = set()  # requirements already decided (unknown) before the pass
    damaged = _damage_before_topics(source, la)  # damage seen while finding the topics
    if bindings is not None:
        if bindings.tick.topic is not None and bindings.tick.topic not in log_topics:
            msg = (f"{path}: the tick topic {bindings.tick.topic} is not in the log (it has "
                   f"{', '.join(log_topics) or 'no topics'})")
            if damaged:  # the damage may have taken it: unknown, with the damage's reason
                for r in active:
                    if verdicts[r.index].error is None:
                        verdicts[r.index].verdict = "unknown"
                        verdicts[r.index].unknown_reason = f"{msg}; {damaged}"
                return finish()
            la.error = msg
            fail_all(la.error)
            return finish()
        for r in active:
            if verdicts[r.index].error is not None:
                continue
            absent = sorted({t for v in r.variables for t in bindings.variables[v].topics
                             if t not in log_topics})
            if absent:
                users = {t: sorted(v for v in r.variables if t in bindings.variables[v].topics)
                         for t in absent}
                has = (f"a CSV trace has one topic, /csv, with the columns "
                       f"{', '.join(source.columns)}" if source.kind == "csv"
                       else f"it has {', '.join(log_topics) or 'no topics'}")
                msg = ("; ".join(f"topic {t} (bound to {', '.join(users[t])}) is not in the log"
                                 for t in absent) + f" ({has})")
                if damaged:
                    verdicts[r.index].verdict = "unknown"
                    verdicts[r.index].unknown_reason = f"{msg}; {damaged}"
                    r_skip.add(r.index)
                else:
                    verdicts[r.index].error = msg
    if bindings is not None:
        _check_binding_types(source, bindings, plan, verdicts)
    problems: Dict[Tuple, DataProblem] = {}
    problem_counts: Dict[str, int] = {}
    result: Optional[_Passes] = None
    while True:
        active = [r for r in plan.requirements if verdicts[r.index].error is None
                  and r.index not in r_skip]
        if not active:
            break
        names = sorted({v for r in active for v in r.variables})
        b = _restrict(bindings, names) if bindings is not None else None
        try:
            result = _run_pass(plan, source, b, active, progress)
        except SignalError as exc:
            culprit = exc.variable
            hit = [r for r in active if culprit in r.variables] if culprit else []
            _collect_problems(source, None, problems, problem_counts)
            if hit:
                for r in hit:
                    verdicts[r.index].error = str(exc)
                result = None
                continue
            fail_all(str(exc), active)
            result = None
            break
        _collect_problems(source, result.sampling, problems, problem_counts)
        break
    la.partial = bool(source.partial) or la.partial
    if source.partial or la.damage_time_ns is None:
        la.damage_time_ns = source.damage_time
    la.damage_cut = bool(source.damage_cut) or la.damage_cut
    la.messages = dict(sorted(source.counts.items()))
    if problems or not la.problems:  # (else: only the damage found with the topics)
        la.problems = [_problem_json(p) for p in problems.values()]
        la.problem_counts = dict(sorted(problem_counts.items()))
    la.start_time_ns = source.start_time
    la.end_time_ns = source.end_time
    _check_nominal_rate(la, bindings)
    if result is None:
        return finish()
    engines = set()
    by_key: Dict[int, Any] = {}
    for r in active:
        key = _clock_key(r, b)
        res = result.passes[key]
        by_key[r.index] = res
        v = verdicts[r.index]
        s = res.sampling
        v.ticks_evaluated = len(res.times)
        v.warmup_ticks = s.warmup_ticks
        v.first_tick_ns = s.first_time
        v.last_tick_ns = s.end_time
        if res.cut:  # ticks after the damage are not judged
            v.last_tick_ns = int(res.times[-1]) if len(res.times) else None
            la.ticks_after_damage = max(la.ticks_after_damage, res.cut)
        v.waiting_for = list(s.waiting_for)
        err = result.errors.get(key)
        bad = [n for n in r.variables if n in result.failed.get(key, {})]
        if err is not None:
            v.error = str(err)
            continue
        if bad:
            v.error = str(result.failed[key][bad[0]])
            continue
        silent = list(s.missing_topics) if b is not None else []
        if silent:
            why = _silent_reasons(silent, problems.values())
            v.error = "; ".join(why[t] for t in sorted(silent))
            continue
        engines.add(res.engine[r.index])
    # the log's figures summarize its requirements' clocks (each verdict has its own)
    ok = [r for r in active if verdicts[r.index].error is None]
    if ok:
        la.ticks_evaluated = max(verdicts[r.index].ticks_evaluated for r in ok)
        la.warmup_ticks = max(verdicts[r.index].warmup_ticks for r in ok)
        firsts = [verdicts[r.index].first_tick_ns for r in ok
                  if verdicts[r.index].first_tick_ns is not None]
        la.first_time_ns = min(firsts) if firsts else None
        la.waiting_for = sorted({t for r in ok for t in verdicts[r.index].waiting_for})
        if la.ticks_after_damage:  # the log's judged span ends at the damage
            lasts = [verdicts[r.index].last_tick_ns for r in ok
                     if verdicts[r.index].last_tick_ns is not None]
            la.end_time_ns = max(lasts) if lasts else None
    la.missing_topics = sorted({t for res in result.passes.values()
                                for t in (res.sampling.missing_topics if b is not None else [])})
    if la.start_time_ns is None:
        starts = [res.sampling.start_time for res in result.passes.values()
                  if res.sampling.start_time is not None]
        la.start_time_ns = min(starts) if starts else None
    engines = sorted(engines)
    la.engine = engines[0] if len(engines) == 1 else ("mixed" if engines else None)
    for r in ok:
        _finalize(plan, r, by_key[r.index], bindings, verdicts[r.index], la)
    if bindings is not None:
        _operand_values(path, plan, bindings, ok, verdicts, by_key)
    return finish()


def _too_many_ticks(source, bindings: Optional[Bindings], path: str) -> Optional[str]:
    """The error when the fixed tick period would give more than :data:`MAX_TICKS` ticks
    over the log's span (first to last message), else None."""
    if bindings is None or not bindings.tick.period_ns or source.kind == "csv":
        return None
    n = _expected_ticks(source, bindings)
    if n is None or n <= MAX_TICKS:
        return None
    span = (source.end_time - source.start_time) / NS_PER_S
    return (f"{path}: the tick period {_fmt_ns(bindings.tick.period_ns)} ({bindings.source}) "
            f"would give {n:,} ticks over the {span:.3f} s of the log, more than the limit of "
            f"{MAX_TICKS:,}; choose a longer period")


def _damage_of(path: str, la) -> Optional[str]:
    """Open ``path`` and read its topics; when that meets damage, mark ``la`` partial and
    return the reason (:func:`_damage_before_topics`), else None (also when it cannot be
    opened at all: that is an input error, not damage)."""
    from .sources import open_log

    try:
        source = open_log(path)
        source.topics()
    except (FretcInputError, OSError):
        return None
    return _damage_before_topics(source, la)


def _damage_before_topics(source, la) -> Optional[str]:
    """When finding the log's topics met damage (a log cut inside its only chunk, say): mark
    ``la`` partial with the problems, and return the reason in words (else None). Issue 15
    item 10: the reason for the damage is kept even when nothing readable is left."""
    if not source.partial:
        return None
    la.partial = True
    la.damage_time_ns = source.damage_time
    la.damage_cut = bool(source.damage_cut)
    probs = [p for p in source.problems if p.kind in _DAMAGE_KINDS]
    la.problems = [_problem_json(p) for p in source.problems]
    la.problem_counts = {f"{k} {t or '-'}": n for (k, t), n in sorted(
        source.problem_counts.items(), key=lambda kv: (kv[0][0], kv[0][1] or ""))}
    if not probs:
        return "the log is damaged"
    return "the log is damaged: " + "; ".join(str(p) for p in probs[:3])


_DAMAGE_KINDS = ("truncated", "chunk_crc", "chunk_corrupt", "corrupt_record", "summary_corrupt",
                 "data_crc", "unknown_channel", "out_of_order")


def _operand_values(path: str, plan: AuditPlan, bindings: Bindings, active, verdicts,
                    passes) -> None:
    """Evidence of violations: the numbers behind their boolean variables (the operands of
    the comparisons a binding is made of, :func:`monitors.bindings.operand_signals`) at the
    ticks whose values are shown. A second streaming pass over the log, only when something
    was violated and only for those operands, each on its requirement's own clock (so tick
    indexes match the first pass)."""
    from .bindings import operand_signals
    from .signals import sample_groups
    from .sources import open_log

    wanted: Dict[str, Tuple[str, object]] = {}  # aux name -> (label, binding)
    groups: Dict[frozenset, Tuple[List[str], frozenset]] = {}
    needs: List[Tuple[frozenset, str, object, List[int]]] = []
    for r in active:
        v = verdicts[r.index]
        if v.verdict != "violated" or not v.values:
            continue
        key = _clock_key(r, bindings)
        for name in r.variables:
            b = bindings.variables.get(name)
            if b is None or name not in v.values:
                continue
            try:
                pairs = operand_signals(b)
            except Exception:  # an operand that cannot stand alone: show the boolean only
                continue
            for label, aux in pairs:
                wanted[aux.name] = (label, aux)
                names = groups.setdefault(key, ([], key))[0]
                if aux.name not in names:
                    names.append(aux.name)
                needs.append((key, aux.name, v, [t for t, _ns, _x in v.values[name]]))
    if not wanted:
        return
    at = {(key, t) for key, _a, _v, ticks in needs for t in ticks}
    aux_bindings = Bindings({name: aux for name, (_l, aux) in wanted.items()}, bindings.tick,
                            bindings.time_base, bindings.header_lag_ns, bindings.source)
    got: Dict[Tuple[frozenset, str], Dict[int, object]] = {}
    try:
        source = open_log(path, csv_period_ns=plan.csv_period_ns)
        for key, tick in sample_groups(source, aux_bindings, groups):
            if (key, tick.index) not in at:
                continue
            for name in groups[key][0]:
                if name in tick.values:
                    got.setdefault((key, name), {})[tick.index] = _py(tick.values[name])
    except (LogError, SignalError, OSError):
        return  # the first pass already reported what is wrong with the log
    for key, aux_name, v, ticks in needs:
        label = wanted[aux_name][0]
        times = passes_times = None
        for r_index, res in passes.items():
            if verdicts[r_index] is v:
                passes_times = res.times
        times = passes_times
        vals = got.get((key, aux_name), {})
        rows = [(t, int(times[t]), vals[t]) for t in ticks if t in vals]
        if rows:
            v.values[label] = rows


def _csv_bindings(plan: AuditPlan, bindings: Bindings, source) -> Bindings:
    """CSV with bindings: the bound variables as bound; every other variable of the
    requirements that names a column reads it (``/csv.<column>``)."""
    from .bindings import compile_expression
    from .sources import CSV_TOPIC

    variables = dict(bindings.variables)
    for r in plan.requirements:
        for v in r.variables:
            if v not in variables and v in source.columns:
                variables[v] = compile_expression(v, f"{CSV_TOPIC}.{v}",
                                                  source=f"<CSV column {v}>")
    return Bindings(variables, bindings.tick, bindings.time_base, bindings.header_lag_ns,
                    bindings.source)


def _check_binding_types(source, bindings: Bindings, plan: AuditPlan, verdicts) -> None:
    """Check the bindings the requirements use against the log's message types
    (:func:`monitors.bindings.check_types`): a binding that names a field the schema does
    not declare, or mixes strings, booleans and numbers, makes its requirements ``error``
    before anything is evaluated."""
    from .bindings import check_types
    from .schema import log_schemas

    try:
        schemas = log_schemas(source)
    except Exception:  # unreadable schemas: the reader reports the damage itself
        return
    bad: Dict[str, str] = {}
    types: Dict[str, str] = {}
    for r in plan.requirements:
        if verdicts[r.index].error is not None:
            continue
        uses = _variable_uses(r)
        for v in r.variables:
            b = bindings.variables.get(v)
            if b is None:
                continue
            if v not in bad:
                try:
                    types[v] = check_types(b, schemas)
                    bad[v] = ""
                except BindingError as exc:
                    bad[v] = str(exc)
            if bad[v]:
                verdicts[r.index].error = bad[v]
                break
            use, t = uses.get(v, set()), types.get(v)
            where = f"{b.source}:{b.line}" if b.line is not None else str(b.source)
            if t == "bool" and "var" in use:
                verdicts[r.index].error = (
                    f"{where}: type error: {r.id} uses {v!r} as a number, but its binding "
                    f"{b.expr!r} is a boolean; bind it to a number")
                break
            if t == "number" and "ap" in use:
                verdicts[r.index].error = (
                    f"{where}: type error: {r.id} uses {v!r} as a boolean, but its binding "
                    f"{b.expr!r} is a number; compare it (e.g. {b.expr.strip()} > 0) to make "
                    "a boolean")
                break


def _variable_uses(r: RequirementPlan) -> Dict[str, set]:
    """FRET variable -> {"ap"} (used as a boolean) and/or {"var"} (used as a number, inside
    a comparison or arithmetic), from the requirement's formulas (compiler.ir)."""
    out: Dict[str, set] = {}
    f = r.formalization
    if f is None:
        return out
    stack = [f.pt, f.ft]
    while stack:
        n = stack.pop()
        if n is None:
            continue
        if n.op in ("ap", "var"):
            out.setdefault(n.name, set()).add(n.op)
        stack.extend(n.args)
    return out


def _silent_reasons(silent, problems) -> Dict[str, str]:
    out = {}
    for t in silent:
        detail = next((f"{p.kind}: {p.detail}" for p in problems
                       if p.topic == t and p.kind in ("unknown_schema", "unknown_encoding")),
                      None)
        out[t] = (f"topic {t} cannot be read ({detail})" if detail
                  else f"topic {t} has no message in the log")
    return out


def _collect_problems(source, sampling, problems: Dict[Tuple, DataProblem],
                      counts: Dict[str, int]) -> None:
    """Add the problems of one pass (the source's and the clock's) to ``problems`` (kept
    once each) and ``counts`` ("kind topic" -> number, including those beyond the cap)."""
    found = list(sampling.problems) if sampling is not None else list(source.problems)
    for p in found:
        problems.setdefault((p.kind, p.topic, p.log_time, p.detail), p)
    for (kind, topic), n in source.problem_counts.items():
        k = f"{kind} {topic or '-'}"
        counts[k] = max(counts.get(k, 0), n)
    if sampling is not None:
        mine: Dict[str, int] = {}
        for p in sampling.signal_problems:
            k = f"{p.kind} {p.topic or '-'}"
            mine[k] = mine.get(k, 0) + 1
        for k, n in mine.items():
            counts[k] = max(counts.get(k, 0), n)


def _finalize(plan: AuditPlan, r: RequirementPlan, res: _Pass, bindings: Optional[Bindings],
              v, la) -> None:
    from compiler.vectorized import ltl3_status, pt_series
    from .evidence import OBLIGATIONS, EvidenceUnsupported, evaluate_requirement
    from .report_model import FirstViolation, Ltl3, TimePoint

    n = len(res.times)
    v.engine = res.engine[r.index]
    if n == 0 and res.intact_end is not None:
        v.verdict = "unknown"
        v.unknown_reason = ("the log is damaged before its first evaluated tick: nothing was "
                            "read completely to judge")
        return
    if n == 0:
        waiting = la.missing_topics or la.waiting_for
        v.error = ("no tick evaluated" + (f": waiting for {', '.join(waiting)}" if waiting
                                          else ": the log has no message on the bound topics"))
        return
    times = res.times
    f = r.formalization
    ev = None
    try:
        ev = evaluate_requirement(r.requirement, res.columns, n, f.ticks)
    except EvidenceUnsupported as exc:
        if v.engine == "interval":
            v.error = f"no online monitor and no interval semantics for it: {exc}"
            return
        v.notes.append(f"interval evidence unavailable: {exc}")
    if v.engine == "interval":
        holds = ev.holds
        status, st_tick = "unknown", None
    elif v.engine == "stepwise":
        mon = res.monitors[r.index]
        holds = bool(mon.finish())
        status, st_tick = mon.status, mon.status_tick
    else:
        holds = bool(pt_series(f.pt, res.columns, n)[-1])
        status, st_tick = ltl3_status(r.monitor_source(), res.columns, n)
    v.ltl3 = Ltl3(status, st_tick, int(times[st_tick]) if st_tick is not None else None)
    if ev is not None:
        v.intervals, v.triggers, v.violations = ev.intervals, ev.triggers, ev.violations
        if ev.holds != holds:  # never seen in tests; the monitor's verdict stands
            v.notes.append("the interval semantics disagrees with the monitor "
                           f"({'holds' if ev.holds else 'violated'}); please report this")
            ev = None
    if res.intact_end is not None:
        holds = _judge_at_damage(r, res, v, holds, ev, status, st_tick, n)
        if holds is None:
            return
    if holds:
        v.verdict = "vacuous" if (ev is not None and ev.vacuous) else "satisfied"
        if v.verdict == "vacuous":
            v.notes.append("vacuous: " + ("the scope was never entered" if ev.intervals == 0
                                          else "the trigger never fired"))
        return
    v.verdict = "violated"
    scope_kind = r.requirement.scope.kind
    timing = r.requirement.timing.kind
    obligation = OBLIGATIONS.get(timing, ("", ""))[1 if scope_kind.startswith("only") else 0]
    k = f.ticks

    own_topics = sorted(_clock_key(r, bindings)) if bindings is not None else []
    held = [res.log_times[t] for t in own_topics if t in res.log_times] or \
        list(res.log_times.values())

    def tp(i: int) -> TimePoint:
        j = min(max(i, 0), n - 1)
        lts = [int(h[j]) for h in held if h[j] >= 0]
        # the message that decided the tick: the newest one held among its topics
        return TimePoint(int(i), int(times[j]), max(lts) if lts else None)

    def time_at(i: int) -> Optional[int]:
        if 0 <= i < n:
            return int(times[i])
        if i >= n and bindings is not None and bindings.tick.period_ns:
            return int(times[-1]) + (i - n + 1) * bindings.tick.period_ns
        return None

    if ev is not None and ev.violation is not None:
        w = ev.violation
        vt = min(w.violation_tick, n - 1)
        fv = FirstViolation(
            at=tp(vt), trigger=tp(w.trigger_tick), scope=(tp(w.interval[0]), tp(w.interval[1])),
            window=w.window, window_time_ns=(time_at(w.window[0]), time_at(w.window[1])),
            obligation=obligation.replace("t+k", f"t+{k}") if k is not None else obligation,
            reason=w.reason)
        centres = [w.trigger_tick, vt]
        v.violation_list = [(tp(x.trigger_tick), tp(min(x.violation_tick, n - 1)))
                            for x in ev.listed]
    else:
        vt = st_tick if (status == "violated" and st_tick is not None) else n - 1
        fv = FirstViolation(at=tp(vt), obligation=obligation,
                            reason="the monitor's verdict (no interval evidence)")
        centres = [vt]
    v.first_violation = fv
    W = plan.config.window
    ticks = sorted({i for c in centres for i in range(c - W, c + W + 1) if 0 <= i < n})
    for name in r.variables:
        col = res.columns.get(name)
        if col is None:
            continue
        v.values[name] = [(i, int(times[i]), _py(col[i])) for i in ticks]
    if bindings is not None:
        topics = sorted({t for name in r.variables if name in bindings.variables
                         for t in bindings.variables[name].topics})
    else:
        topics = sorted(res.log_times)
    for t in topics:
        lt = res.log_times.get(t)
        if lt is None:
            continue
        v.sources[t] = [(i, int(times[i]), int(lt[i]) if lt[i] >= 0 else None) for i in ticks]


def _judge_at_damage(r: RequirementPlan, res: _Pass, v, holds: bool, ev, status, st_tick,
                     n: int) -> Optional[bool]:
    """The verdict over the intact span of a damaged log (:mod:`monitors.damage`): True /
    False for the usual satisfied-or-vacuous / violated paths of :func:`_finalize`, None
    when the verdict (``unknown``) is set here."""
    from .damage import open_obligations, verdict_at_damage
    from .evidence import EvidenceUnsupported

    opened = []
    try:
        opened = open_obligations(r.requirement, res.columns, n, r.formalization.ticks)
    except (EvidenceUnsupported, KeyError) as exc:
        if holds:  # cannot tell whether an obligation is open at the damage
            v.verdict = "unknown"
            v.unknown_reason = (f"the log is damaged and whether an obligation is open at "
                                f"the damage cannot be decided ({exc})")
            return None
    verdict, why = verdict_at_damage(holds, bool(ev is not None and ev.vacuous), status,
                                     st_tick, n, ev, opened, has_ltl3=v.engine != "interval")
    if verdict == "unknown":
        v.verdict = "unknown"
        v.unknown_reason = why
        return None
    return verdict != "violated"


def _py(x):
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    return float(x)


# --------------------------------------------------------------------------- many logs
_WORKER: Dict[str, Any] = {}


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


def audit_logs(plan: AuditPlan, paths: Sequence[str], jobs: int = 1, progress=None
               ) -> List[LogAudit]:
    """Audit ``paths`` (from :func:`find_logs`), ``jobs`` at a time in worker processes.

    Args:
        progress: optional object with ``start(index, path)``, ``update(index, fraction)``
            and ``done(index, log_audit)`` methods (the CLI's progress bar).

    Returns:
        One :class:`~monitors.report_model.LogAudit` per path, in the order of ``paths``.
    """
    results: Dict[int, Any] = {}
    if jobs <= 1 or len(paths) <= 1:
        for i, p in enumerate(paths):
            if progress is not None:
                progress.start(i, p)
            cb = (lambda frac, _i=i: progress.update(_i, frac)) if progress is not None else None
            results[i] = audit_log(plan, p, cb)
            if progress is not None:
                progress.done(i, results[i])
        return [results[i] for i in range(len(paths))]
    import multiprocessing as mp
    import queue as queue_mod
    from concurrent.futures import FIRST_COMPLETED, wait

    try:
        ctx = mp.get_context("fork")
    except ValueError:  # pragma: no cover - platforms without fork
        ctx = mp.get_context()
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
                    progress.update(i, frac)
            for fut in done:
                i, la = fut.result()
                results[i] = la
                if progress is not None:
                    progress.done(i, la)
    return [results[i] for i in range(len(paths))]


# imported late to keep the module's public names importable without cycles
from .report_model import LogAudit  # noqa: E402
