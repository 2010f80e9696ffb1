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

Damage (DESIGN.md "Damage is never evidence"): a damaged log (cut short, a chunk skipped, its
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

from .bindings import Binding, Bindings, TickSpec, load_bindings, parse_duration
from .problems import BindingError, DataProblem, FretcInputError, LogError, SignalError

__all__ = ["AuditConfig", "AuditPlan", "RequirementPlan", "AuditInputError", "load_plan",
           "discover_bindings", "find_logs", "audit_log", "audit_logs", "CHUNK",
           "VECTORIZE_MIN_TICKS", "LOG_SUFFIXES"]

NS_PER_S = 1_000_000_000
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


def _fmt_ns(ns: int) -> str:
    if ns % NS_PER_S == 0:
        return f"{ns // NS_PER_S} s"
    if ns % 1_000_000 == 0:
        return f"{ns // 1_000_000} ms"
    if ns % 1000 == 0:
        return f"{ns // 1000} us"
    return f"{ns} ns"


def _fmt_period(p: Fraction) -> str:
    return _fmt_ns(int(p * NS_PER_S)) if (p * NS_PER_S).denominator == 1 else f"{float(p)} s"


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

    def requirements_json(self) -> List[dict]:
        return [r.to_json() for r in self.requirements]

    def bindings_json(self) -> Optional[dict]:
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
    if bindings is not None and bindings.tick.period_ns is not None:
        period = Fraction(bindings.tick.period_ns, NS_PER_S)
    plans: List[RequirementPlan] = []
    to_compile = []
    for i, e in enumerate(entries):
        rp = RequirementPlan(i, e.id, e.text, f"{e.source}:{e.line}", e.line)
        if e.tick_period is None and period is not None:
            e = dataclasses.replace(e, tick_period=period)
        elif e.tick_period is not None and period is not None and e.tick_period != period:
            rp.error = (f"{e.source}:{e.line}: {e.id} declares a tick period of "
                        f"{_fmt_period(e.tick_period)} but the bindings ({bindings.source}) "
                        f"tick every {_fmt_period(period)}: durations would convert with the "
                        "wrong period; make them equal")
        elif e.tick_period is not None and bindings is not None and bindings.tick.topic:
            rp.notes.append(f"durations convert with the declared {_fmt_period(e.tick_period)}"
                            f" as the nominal period of {bindings.tick.topic}")
        rp.tick_period = e.tick_period
        plans.append(rp)
        to_compile.append(e)
    compiled = compile_entries(to_compile)
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
    return AuditPlan(config, plans, bindings, binding_files, modules, max(1, csv_period),
                     freeform)


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
            lst.append(v[name])
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


def _run_pass(plan: AuditPlan, source, bindings: Optional[Bindings], active: List[RequirementPlan],
              progress: Optional[Callable[[float], None]]) -> _Pass:
    from .signals import sample

    names: List[str] = []
    for r in active:
        for v in r.variables:
            if v not in names:
                names.append(v)
    if bindings is not None:
        topics = sorted({t for n in names for t in bindings.variables[n].topics})
    else:
        from .sources import CSV_TOPIC
        topics = [CSV_TOPIC]
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
    monitors = {r.index: r.monitor_cls() for r in active if engine[r.index] == "stepwise"}
    steppers = [m.step for m in monitors.values()]
    cols = _Columns(names, topics)
    sampling = sample(source, bindings)
    start_t = source.start_time
    end_t = source.end_time
    span = (end_t - start_t) if (start_t is not None and end_t is not None
                                 and end_t > start_t) else None
    every = 512
    count = 0
    for tick in sampling:
        vals = tick.values
        for step in steppers:
            step(vals)
        cols.append(tick)
        count += 1
        if count > MAX_TICKS:
            raise SignalError(f"{source.path}: more than {MAX_TICKS:,} ticks (the limit); "
                              "choose a longer tick period")
        if progress is not None and count % every == 0:
            if span is not None:
                progress(min(1.0, max(0.0, (tick.time - start_t) / span)))
            elif expected:
                progress(min(1.0, count / expected))
    times, columns, log_times = cols.finish()
    res = _Pass(sampling, times, columns, log_times, monitors, engine)
    _cut_at_damage(res, source, bindings, active)
    return res


def _cut_at_damage(res: _Pass, source, bindings: Optional[Bindings],
                   active: List[RequirementPlan]) -> None:
    """Keep only the ticks of the span read completely (DESIGN.md "Damage is never
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
            v.ticks_evaluated = la.ticks_evaluated
            v.warmup_ticks = la.warmup_ticks
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
        from .sources import CSV_TOPIC
        if bindings is not None and not (bindings.topics <= {CSV_TOPIC}):
            bindings = None  # a trace of FRET variables: its columns are the variables
        elif bindings is not None and not bindings.variables:
            bindings = None
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

    active = [r for r in plan.requirements if r.error is None]
    # variables without a binding (or CSV column)
    available = set(bindings.variables) if bindings is not None else set(source.columns)
    for r in active:
        missing = [v for v in r.variables if v not in available]
        if missing:
            where = (f"bindings ({bindings.source})" if bindings is not None
                     else f"the CSV columns ({', '.join(source.columns)})")
            verdicts[r.index].error = (f"no binding for {', '.join(map(repr, missing))} in "
                                       f"{where}")
    # topics absent from the log
    try:
        log_topics = source.topics()
    except FretcInputError as exc:
        la.error = str(exc)
        fail_all(f"log not audited: {exc}")
        return finish()
    too_many = _too_many_ticks(source, bindings, path)
    if too_many is not None:
        la.error = too_many
        fail_all(too_many)
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
                msg = ("; ".join(f"topic {t} (bound to {', '.join(users[t])}) is not in the log"
                                 for t in absent)
                       + f" (it has {', '.join(log_topics) or 'no topics'})")
                if damaged:
                    verdicts[r.index].verdict = "unknown"
                    verdicts[r.index].unknown_reason = f"{msg}; {damaged}"
                    verdicts[r.index].error = None
                    r_skip.add(r.index)
                else:
                    verdicts[r.index].error = msg
    problems: Dict[Tuple, DataProblem] = {}
    problem_counts: Dict[str, int] = {}
    result: Optional[_Pass] = None
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
        silent = set(result.sampling.missing_topics)
        if silent and b is not None:
            hit = [r for r in active
                   if any(t in silent for v in r.variables for t in b.variables[v].topics)]
            if hit:
                why = _silent_reasons(silent, problems.values())
                for r in hit:
                    topics = sorted({t for v in r.variables for t in b.variables[v].topics
                                     if t in silent})
                    verdicts[r.index].error = "; ".join(why[t] for t in topics)
                result = None
                continue
        break
    la.partial = bool(source.partial) or la.partial
    if source.partial or la.damage_time_ns is None:
        la.damage_time_ns = source.damage_time
    la.damage_cut = bool(source.damage_cut) or la.damage_cut
    la.messages = dict(sorted(source.counts.items()))
    if problems or not la.problems:  # (else: only the damage found with the topics)
        la.problems = [_problem_json(p) for p in problems.values()]
        la.problem_counts = dict(sorted(problem_counts.items()))
    if result is None:
        return finish()
    s = result.sampling
    la.start_time_ns = s.start_time
    la.first_time_ns = s.first_time
    la.end_time_ns = s.end_time
    la.ticks_evaluated = len(result.times)
    if result.cut:
        la.end_time_ns = int(result.times[-1]) if len(result.times) else None
        la.ticks_after_damage = result.cut
    la.warmup_ticks = s.warmup_ticks
    la.waiting_for = list(s.waiting_for)
    la.missing_topics = list(s.missing_topics)
    engines = sorted(set(result.engine.values()))
    la.engine = engines[0] if len(engines) == 1 else "mixed"
    for r in active:
        if r.index not in r_skip:
            _finalize(plan, r, result, bindings, verdicts[r.index], la)
    if bindings is not None:
        _operand_values(path, plan, bindings, active, verdicts, result.times)
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
                    times) -> None:
    """Evidence of violations: the numbers behind their boolean variables (the operands of
    the comparisons a binding is made of, :func:`monitors.bindings.operand_signals`) at the
    ticks whose values are shown. A second streaming pass over the log, only when something
    was violated and only for those operands; ticks are matched by time."""
    from .bindings import operand_signals
    from .signals import sample
    from .sources import open_log

    wanted: Dict[str, Tuple[str, object]] = {}  # aux name -> (label, binding)
    needs: Dict[str, List[Tuple[object, List[str]]]] = {}
    for r in active:
        v = verdicts[r.index]
        if v.verdict != "violated" or not v.values:
            continue
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
                needs.setdefault(aux.name, []).append((v, [t for t, _ns, _x in v.values[name]]))
    if not wanted:
        return
    at_time = {}  # tick time -> tick index of the first pass
    for aux_name, uses in needs.items():
        for v, ticks in uses:
            for t in ticks:
                at_time[int(times[t])] = t
    aux_bindings = Bindings({name: aux for name, (_l, aux) in wanted.items()}, bindings.tick,
                            bindings.time_base, bindings.header_lag_ns, bindings.source)
    got: Dict[str, Dict[int, object]] = {name: {} for name in wanted}
    try:
        source = open_log(path, csv_period_ns=plan.csv_period_ns)
        for tick in sample(source, aux_bindings):
            t = at_time.get(int(tick.time))
            if t is None:
                continue
            for name in wanted:
                got[name][t] = _py(tick.values.get(name))
    except (LogError, SignalError, OSError):
        return  # the first pass already reported what is wrong with the log
    for aux_name, uses in needs.items():
        label = wanted[aux_name][0]
        for v, ticks in uses:
            rows = [(t, int(times[t]), got[aux_name][t]) for t in ticks if t in got[aux_name]]
            if rows:
                v.values[label] = rows


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

    def tp(i: int) -> TimePoint:
        return TimePoint(int(i), int(times[min(max(i, 0), n - 1)]))

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
