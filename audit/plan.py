"""The audit plan: the requirements compiled, their generated monitors loaded and the signal
bindings merged, ready for any number of logs (:func:`load_plan`).

Requirements are compiled (:mod:`fretc.compiler.build`) with the tick period of the signal
bindings when their file declares none (a declared period must equal a fixed bindings period,
else that requirement is an input error naming both), and their monitors are generated
(:func:`fretc.compiler.codegen.build_monitor_modules`, one module per requirement file) and loaded
in-process into a fresh module: the same code ``fretc FILE --emit monitor`` gives users; the
builder's map pairs requirements with their classes and automata (nothing built twice).
Binding files that select their logs (``[logs]``) give one plan per file
(:class:`fretc.signals.bindings.LogSelector`, :func:`select_variant`).
"""

from __future__ import annotations

import dataclasses
import re
import types
from fractions import Fraction
from pathlib import Path

from fretc.compiler.build import compile_entries
from fretc.compiler.codegen import MonitorModule, MonitorSource, build_monitor_modules
from fretc.common.errors import FretishError
from fretc.fretish.files import load_requirements
from fretc.common.units import NS_PER_S, format_period

from fretc.signals.bindings import Bindings
from fretc.common.problems import FretcInputError
from fretc.logs import open_log
from fretc.audit.binding_files import binding_files, load_audit_bindings
from fretc.audit.config import AuditConfig, AuditInputError
from fretc.audit.model import AuditPlan, RequirementPlan

__all__ = ["load_plan", "select_variant", "load_module", "used_variables", "MODULE_PREFIX"]

#: Name prefix of the modules the generated monitors are loaded into.
MODULE_PREFIX = "fretc_audit_"


def _has_time_units(entry) -> bool:
    """The requirement's text has a duration in time units (not ``ticks``)."""
    req = entry.requirement  # as the requirement file's reader parsed it
    if req is None:
        from fretc.fretish.parser import parse  # lazy: Lark (start-up)

        try:
            req = parse(entry.text)
        except Exception:  # reported when compiled
            return False
    d = getattr(req.timing, "duration", None)
    return d is not None and d.unit != "ticks"


def load_plan(config: AuditConfig) -> AuditPlan:
    """Read requirements and bindings, compile, generate and load the monitors.

    Raises:
        AuditInputError: a requirement file that cannot be read (a bad sentence is not
            this: it becomes that requirement's ``error``), bad or conflicting bindings, bad
            options.
    """
    files = binding_files(config)  # (read once: each read parses every expression)
    if config.select_logs:
        split = _plan_per_log(config, files)
        if split is not None:
            return split
    return _build_plan(config, files)


def _with_msg_path(config: AuditConfig, files: list[tuple[Path, Bindings]]) -> AuditConfig:
    """``config`` with the ``[types] msg_path`` folders of its binding files ``files``
    after the ``--msg-path`` ones."""
    extra = tuple(p for _f, b in files for p in b.msg_path)
    if not extra:
        return config
    return dataclasses.replace(config, msg_path=tuple(config.msg_path) + extra)


def _with_constants(entries: list, files: list[tuple[Path, Bindings]]) -> list:
    """``entries`` whose named durations not declared in their own file take the value of
    the binding files' ``[constants]`` (``files``; :mod:`fretc.fretish.constants`).

    Raises:
        AuditInputError: one constant given two values by two binding files.
    """
    def named(req) -> bool:  # (attributes only: the main line of plain requirements)
        d = req.timing.duration if req is not None and not req.freeform else None
        return d is not None and d.name is not None and not d.amount

    if not any(named(e.requirement) for e in entries):
        return entries
    from fretc.fretish.constants import resolve, unresolved

    constants: dict = {}
    where: dict = {}
    for f, b in files:
        for name, value in b.constants.items():
            if name in constants and constants[name] != value:
                raise AuditInputError(f"[constants] {name} is {' '.join(constants[name])} in "
                                      f"{where[name]} but {' '.join(value)} in {f}")
            constants[name], where[name] = value, f
    for e in entries:
        if unresolved(e.requirement):
            e.requirement = resolve(e.requirement, constants)
    return entries


def _with_definitions(entries: list, bindings: Bindings | None, notes: list[str]) -> list:
    """``entries`` with the Internal variables their FRET export defines, and the bindings
    do not bind, read as their definitions (FRET's glossary:
    :func:`fretc.fretish.fret_variables.with_fret_definitions`), each such variable named
    once in ``notes``; a bound one is read from the log, as every bound variable is. A
    stream variable (a definition reading itself through ``pre``) is the entry's
    ``streams``, its column computed tick by tick from the columns of the variables it
    reads (:mod:`fretc.audit.streams`), named once in ``notes`` too."""
    from fretc.fretish.fret_definitions import definitions
    from fretc.fretish.fret_streams import stream_why
    from fretc.fretish.fret_variables import names_read, with_fret_definitions

    bound = set(bindings.variables) | set(bindings.per_entity) if bindings is not None \
        else set()
    out, said = [], set()
    for e in entries:
        if not getattr(e, "variables", ()) or e.requirement is None:
            out.append(e)
            continue
        defs = definitions(tuple(e.variables), since=False)  # (streams tick by tick)
        read = names_read([e])
        used = sorted(n for n in read if n in defs.values and n not in bound)
        if used or any(n in defs.streams and n not in bound for n in read):
            e = with_fret_definitions(e, keep=bound, streams=True)
        computed = [(n, "computed from the variables it reads (no binding of its own)")
                    for n in used]
        if e.streams is not None:
            computed += [(n, "computed tick by tick from the variables it reads (a stream "
                          f"with state: {stream_why(defs.free.get(n, ''))}; no binding of "
                          "its own)") for n in e.streams.names]
        for n, how in sorted(computed):
            if n not in said:
                said.add(n)
                notes.append(f"{n}: FRET's definition of this Internal variable {how}")
        out.append(e)
    return out


def _build_plan(config: AuditConfig, files: list[tuple[Path, Bindings]]) -> AuditPlan:
    """The plan of one set of bindings (:func:`load_plan` without ``[logs]`` selection;
    ``files``: its binding files, read)."""
    config = _with_msg_path(config, files)
    bindings, binding_files = load_audit_bindings(config, files)
    notes: list[str] = []
    unformalized: list = []
    entries = _with_constants(_read_requirements(config, notes, unformalized), files)
    entries = _with_definitions(entries, bindings, notes)
    period, nominal = _bindings_periods(bindings)
    plans: list[RequirementPlan] = []
    to_compile = []
    for i, e in enumerate(entries):
        rp = RequirementPlan(i, e.id, e.text, f"{e.source}:{e.line}", e.line)
        e = _with_tick_period(rp, e, config, bindings, period, nominal)
        rp.tick_period = e.tick_period
        plans.append(rp)
        to_compile.append(e)
    compiled = compile_entries(to_compile)
    if config.tick_period is not None:
        for c, rp in zip(compiled, plans):
            if c.error is not None and rp.error is None:
                assert period is not None  # (the --tick-period's)
                rp.error = (f"{c.error} (the tick period {format_period(period)} comes from "
                            "--tick-period)")
    ok = [c for c, rp in zip(compiled, plans) if rp.error is None]
    built = build_monitor_modules(ok) if ok else {}
    modules = {m.name: m.text for m in built.values()}
    classes, skipped, sources = _load_monitors(built)
    for c, rp in zip(compiled, plans):
        _attach(rp, c, classes, skipped)
        if (c.entry.source, c.id) in sources:  # the automata built with the module, not again
            rp._msource = sources[(c.entry.source, c.id)]
    _streams_per_entity(plans, bindings)
    bindings = _with_elements(bindings, plans, notes)
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
    return AuditPlan(config, plans, bindings, binding_files, modules, max(1, csv_period),
                     freeform, notes + _unused_bindings(bindings, plans),
                     not_formalized=unformalized)


_ELEMENT = re.compile(r"([A-Za-z][A-Za-z0-9_.%]*)\s*\(\s*([0-9]+)\s*\)\Z")
_PATH = re.compile(r"\s*/[A-Za-z0-9_/]*(?:\.[A-Za-z_][A-Za-z0-9_]*|\[-?[0-9]+\])*\s*\Z")


def _with_elements(bindings: Bindings | None, plans: list[RequirementPlan],
                   notes: list[str]) -> Bindings | None:
    """``bindings`` with a binding for each array element a requirement reads as FRET
    writes it, ``yout(3)`` (FRET's exports from Simulink: MATLAB's indexing, the first
    element is 1), where the bindings bind the array ``yout`` to a field path and not the
    element itself: ``yout(3)`` is the path's item ``[2]`` (docs/bindings.md); one note per
    element says so. A binding of the element itself wins; an array bound to an expression
    that is not a path gets none (the variable stays unbound, named as such)."""
    if bindings is None:
        return None
    added: dict[str, str] = {}
    for rp in plans:
        for name in rp.variables:
            m = _ELEMENT.match(name)
            base = bindings.variables.get(m.group(1)) if m else None
            if m is None or name in bindings.variables or name in added or base is None \
                    or not _PATH.match(base.expr) or int(m.group(2)) < 1:
                continue
            added[name] = f"{base.expr.strip()}[{int(m.group(2)) - 1}]"
            notes.append(f"{name}: the element {m.group(2)} of {m.group(1)} (FRET counts from "
                         f"1), bound to {added[name]}")
    if not added:
        return bindings
    from fretc.signals.bindings.spec import make_bindings

    extra = make_bindings(added, bindings.tick).variables
    return dataclasses.replace(bindings, variables={**bindings.variables, **extra})


def _read_requirements(config: AuditConfig, skipped: list[str],
                       unformalized: list | None = None) -> list:
    """The requirement entries of ``config.requirements``
    (:func:`fretc.fretish.files.load_requirements`; notes of skipped files into ``skipped``, the
    items of ReqIF / Doorstop sources without FRETish text into ``unformalized``)."""
    try:
        entries = load_requirements([Path(p) for p in config.requirements], skipped,
                                    config.text_attribute, unformalized)
    except FretishError as exc:
        raise AuditInputError(str(exc)) from None
    except OSError as exc:
        raise AuditInputError(f"cannot read requirements: {exc}") from None
    if not entries:
        raise AuditInputError(f"no requirements in {', '.join(config.requirements)}"
                              + (f" ({len(unformalized)} items without FRETish text)"
                                 if unformalized else ""))
    return entries


def _bindings_periods(bindings: Bindings | None) -> tuple[Fraction | None, Fraction | None]:
    """(the bindings' fixed tick period, the tick topic's nominal period), in seconds."""
    if bindings is not None and bindings.tick.period_ns is not None:
        return Fraction(bindings.tick.period_ns, NS_PER_S), None
    if bindings is not None and bindings.tick.nominal_period_ns is not None:
        return None, Fraction(bindings.tick.nominal_period_ns, NS_PER_S)
    return None, None


def _with_tick_period(rp: RequirementPlan, e, config: AuditConfig, bindings: Bindings | None,
                      period: Fraction | None, nominal: Fraction | None):
    """The entry ``e`` with the tick period its durations convert with: ``--tick-period``
    overrides every declared period (a note says so); else the bindings' period where the
    file declares none. A declared period that differs from the bindings' (or from the tick
    topic's nominal rate), or time units on a topic tick of undeclared rate, set
    ``rp.error``."""
    if config.tick_period is not None:
        assert period is not None  # (the --tick-period's)
        if e.tick_period is not None and e.tick_period != period:
            rp.notes.append(f"durations converted with --tick-period "
                            f"{format_period(period)} instead of the declared "
                            f"{format_period(e.tick_period)}")
        return dataclasses.replace(e, tick_period=period)
    if e.tick_period is None and period is not None:
        return dataclasses.replace(e, tick_period=period)
    if e.tick_period is not None and period is not None and e.tick_period != period:
        rp.error = (f"{e.source}:{e.line}: {e.id} declares a tick period of "
                    f"{format_period(e.tick_period)} but the bindings "
                    f"({bindings.source if bindings is not None else None}) "
                    f"tick every {format_period(period)}: durations would convert with the "
                    "wrong period; make them equal (or pass --tick-period to override "
                    "both for this run)")
    elif bindings is not None and bindings.tick.topic:
        if nominal is not None and e.tick_period is not None and e.tick_period != nominal:
            rp.error = (f"{e.source}:{e.line}: {e.id} declares a tick period of "
                        f"{format_period(e.tick_period)} but the bindings ({bindings.source})"
                        f" give {bindings.tick.topic} a nominal period of "
                        f"{format_period(nominal)}; make them equal")
        elif nominal is not None:
            return dataclasses.replace(e, tick_period=nominal)
        elif _has_time_units(e):
            rp.error = (f"{e.source}:{e.line}: {e.id} has a duration in time units but "
                        f"the bindings ({bindings.source}) tick once per "
                        f"{bindings.tick.topic} message, whose rate is not declared: add "
                        "the topic's rate as nominal_rate to [tick] (fretc inspect prints "
                        "it); the audit checks it against the log")
            rp.rate_topic = bindings.tick.topic
    return e


def _load_monitors(built: dict[str, MonitorModule]
                   ) -> tuple[dict[tuple[str, str], type], dict[tuple[str, str], str],
                              dict[tuple[str, str], MonitorSource]]:
    """Execute each generated module once into a fresh module object: ((source, id) ->
    monitor class, (source, id) -> why it was skipped, (source, id) -> the
    :class:`~fretc.compiler.codegen.MonitorSource` its class was generated from), paired through
    :func:`fretc.compiler.codegen.build_monitor_modules`' map (keyed by requirement file)."""
    classes: dict[tuple[str, str], type] = {}
    skipped: dict[tuple[str, str], str] = {}
    sources: dict[tuple[str, str], MonitorSource] = {}
    for src, mm in built.items():
        mod = load_module(mm.name, mm.text)
        for rid, info in mm.monitors.items():
            classes[(src, rid)] = mod.MONITORS[rid]
            sources[(src, rid)] = info.source
        for rid, why in mm.skipped.items():
            skipped[(src, rid)] = why
    return classes, skipped, sources


def load_module(stem: str, text: str) -> types.ModuleType:
    """The generated monitor module ``text`` executed into a fresh module named
    :data:`MODULE_PREFIX` + ``stem`` (its ``MONITORS`` map requirement ids to classes)."""
    mod = types.ModuleType(MODULE_PREFIX + stem)
    exec(compile(text, f"<fretc monitors {stem}>", "exec"), mod.__dict__)
    return mod


def _attach(rp: RequirementPlan, c, classes: dict[tuple[str, str], type],
            skipped: dict[tuple[str, str], str]) -> None:
    """Give ``rp`` its compiled form and monitor class, or the reason it has none."""
    rp.compiled = c
    if rp.error is not None:
        return
    key = (c.entry.source, c.id)
    if c.error is not None:
        rp.error = str(c.error)
    elif c.freeform:
        rp.error = "free-form"  # dropped by load_plan: not audited, not an error
    elif key in classes:
        rp.monitor_cls = classes[key]
        names = list(rp.monitor_cls.VARIABLES)  # type: ignore[attr-defined]  # a generated monitor class
        rp.variables = _read_from_log(rp, names + [v for v in c.formalization.variables
                                                   if v not in names])
        rp.notes.extend(c.formalization.warnings)
    elif not c.formalization.pt_causal:
        # a future-time function in the pt formula: no online monitor, but the audit is
        # offline - decide it by the interval semantics over the whole trace
        rp.offline = True
        rp.variables = _read_from_log(rp, list(c.formalization.variables))
        rp.notes.extend(c.formalization.warnings)
        rp.notes.append("no online monitor (the pt formula needs a future-time function): "
                        "decided offline by the interval semantics; no LTL3 verdict")
    else:
        rp.error = f"no monitor: {skipped.get(key, 'not generated')}"


def _streams_per_entity(plans: list[RequirementPlan], bindings: Bindings | None) -> None:
    """A requirement judged per entity (it reads a ``$name`` variable) that reads a stream
    variable is an error saying so: the per-entity audit judges entities together from
    their columns chunk by chunk, where the stream's column is not computed."""
    per_entity = set(bindings.per_entity) if bindings is not None else set()
    for rp in plans:
        system = rp.streams
        if rp.error is None and system is not None and per_entity & set(rp.variables):
            rp.error = (f"it reads {', '.join(system.names)}, which FRET defines as a stream "
                        "with state (through pre), and variables per entity: the audit "
                        "per entity does not compute such a stream; bind "
                        f"{', '.join(system.names)} per entity instead")


def _read_from_log(rp: RequirementPlan, names: list[str]) -> list[str]:
    """The variables of ``names`` (a requirement's) read from the log: its stream
    variables' inputs in place of the stream variables (:mod:`fretc.audit.streams`)."""
    system = rp.streams
    if system is None:
        return names
    out = [n for n in names if n not in system.names]
    return out + [n for n in system.inputs if n not in out]


def used_variables(plans: list[RequirementPlan]) -> set[str]:
    """The FRET variables the requirements read (their monitors' ``VARIABLES`` and the rest
    of their formalizations)."""
    return {v for rp in plans for v in (rp.variables or (
        rp.formalization.variables if rp.formalization is not None else []))}


def _unused_bindings(bindings: Bindings | None, plans: list[RequirementPlan]) -> list[str]:
    """A remark per bound variable that no requirement uses."""
    warnings = []
    if bindings is not None:
        used = set(used_variables(plans))
        used |= {m.group(1) for n in used if (m := _ELEMENT.match(n))}  # (arrays: yout(3))
        # a requirement that failed before its variables were known (a syntax error) may
        # use any name of its text: never call those unused
        failed = " ".join(rp.text for rp in plans
                          if rp.error is not None and not rp.variables)
        words = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", failed))
        for name, b in bindings.variables.items():
            if name not in used and name not in words:
                at = f"{b.source}:{b.line}" if b.line is not None else str(b.source)
                warnings.append(f"{at}: {name!r} is bound but no requirement uses it")
    return warnings


def _plan_per_log(config: AuditConfig, parts: list[tuple[Path, Bindings]]
                  ) -> AuditPlan | None:
    """Binding files that select their logs (``[logs]``, :class:`fretc.signals.bindings.LogSelector`):
    one plan per selecting file (merged with the files that select nothing, which apply to
    every log), each compiled with its own tick. A requirement whose variables are bound
    only by another selecting file is not applicable to that file's logs (it is left out of
    their verdicts); one bound nowhere stays an error. None when no file selects logs."""
    selecting = [(f, b) for f, b in parts if b.logs is not None]
    if not selecting:
        return None
    plain = [str(f) for f, b in parts if b.logs is None]
    variants = []
    for f, b in selecting:
        sub = load_plan(dataclasses.replace(config, bindings=tuple([str(f)] + plain),
                                            select_logs=False))
        variants.append((b.logs, str(f), sub))
    # (each variant has the bindings of its selecting file)
    anywhere = {n for _s, _f, sub in variants if sub.bindings for n in sub.bindings.variables}
    union: dict[tuple[str, str], RequirementPlan] = {}
    for _s, _f, sub in variants:
        keep = []
        for r in sub.requirements:
            names = r.variables or (list(r.formalization.variables)
                                    if r.formalization is not None else [])
            missing = [v for v in names if sub.bindings and v not in sub.bindings.variables]
            if missing and all(v in anywhere for v in missing):
                continue  # bound by another selecting file: for its logs, not these
            keep.append(r)
            union.setdefault((r.source, r.id), r)
        sub.requirements = keep
    reqs = sorted(union.values(), key=lambda r: r.index)
    used = used_variables(reqs)
    warnings = sorted({w for _s, _f, sub in variants for w in sub.warnings
                       if w.split("'")[1] not in used})
    return AuditPlan(config, reqs, None, [str(f) for f, _b in parts], {}, NS_PER_S,
                     variants[0][2].freeform, warnings, variants,
                     variants[0][2].not_formalized)


def select_variant(plan: AuditPlan, path: str) -> tuple[AuditPlan | None, str | None]:
    """(plan for ``path``, None) or (None, the input error naming the binding files)."""
    need_topics = any(sel.topics for sel, _f, _p in plan.variants)
    topics = None
    if need_topics:
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

