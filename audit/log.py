"""One log audited against every requirement of a plan (:func:`audit_log`).

The log is opened (:func:`fretc.logs.open_log`); its inputs are checked (a binding for
every variable, every bound topic in the log, binding types against the schemas); it is read
once (:func:`fretc.audit.passes.run_passes`: every requirement on its own clock); each
requirement is finalized (:func:`fretc.audit.finalize.finalize`); violated ones get the
numbers behind their boolean variables (:func:`fretc.audit.operands.operand_values`).

A CSV trace is read with its columns as the variables unless the bindings read ``/csv``
fields. A topic whose schema is unknown makes only the requirements reading it ``error`` -
the others are audited without it (a second pass over the log, only in that case). Damage
(../shared/DESIGN.md "Damage is never evidence"): a damaged log is ``partial``; only the ticks
before its first cut or gap are judged. Problems of every pass are kept.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from fretc.signals.bindings import Bindings
from fretc.signals.clock import missing_topics
from fretc.common import problems as P
from fretc.common.problems import DataProblem, FretcInputError, SignalError
from fretc.common.streams import log_topics as log_topics_of
from fretc.common.collections_gc import fewer_full_collections
from fretc.audit.verdict import LogAudit, Verdict
from fretc.logs.schema import closest
from fretc.logs import open_log
from fretc.logs.allowance import with_allowance
from fretc.logs.csv.clocks import split_clocks
from fretc.logs.csv.source import CsvSource, sampled_header, sampled_trace
from fretc.audit.checks import (binding_type_errors, call_hint, check_nominal_rate, csv_bindings,
                     rate_hint, too_many_ticks)
from fretc.audit.finalize import between_ticks, finalize
from fretc.audit.gaps import merged_gaps
from fretc.audit.log_problems import (collect_problems, damage_before_topics, damage_of, problem_json,
                           silent_reasons)
from fretc.audit.model import AuditPlan, RequirementPlan
from fretc.audit.operands import operand_values
from fretc.audit.passes import LogPasses, clock_key, restrict, run_passes
from fretc.audit.plan import select_variant
from fretc.audit.streamed import CsvStreams, StreamedResult
from fretc.audit.streamed_log import LogStreams, pick_ticks, picked_times
from fretc.audit.streamed_verdict import (finalize_clock_streamed, finalize_streamed,
                                          streamed_values)
from fretc.audit.streamed_three import ThreeResult, finalize_three, judged_three
from fretc.signals.csv_columns import csv_streamed_pass

if TYPE_CHECKING:
    from fretc.logs.base import LogSource

__all__ = ["audit_log", "audit_keeping_passes", "KeptPasses", "summarize_clocks",
           "log_engine"]


#: A sampled trace of more clocks than this (a per-entity requirement has one per entity) is
#: read once and split by clock (:func:`fretc.logs.csv.clocks.split_clocks`: its rows held
#: at once); one of fewer is read once per clock (its columns alone held at a time).
SPLIT_CLOCKS = 8


def audit_log(plan: AuditPlan, path: str,
              progress: Callable[[float], None] | None = None) -> LogAudit:
    """Audit one log against every requirement of ``plan``.

    Args:
        plan: from :func:`fretc.audit.plan.load_plan`.
        path: a log file or rosbag2 folder.
        progress: called now and then with the fraction of the log read (0..1).

    Returns:
        A :class:`~fretc.audit.verdict.LogAudit` with one verdict per requirement. Input
        problems of this log (unreadable file, missing topic or binding) are reported in it
        (``error`` / ``error`` verdicts), never raised.
    """
    with fewer_full_collections():
        return _audit_log(plan, path, progress)


def _audit_log(plan: AuditPlan, path: str, progress: Callable[[float], None] | None
               ) -> LogAudit:
    csv = str(path).lower().endswith(".csv")
    head = sampled_header(path) if csv else None
    if head is not None and (head.clocks or head.per_entity or head.not_sampled):
        # (a trace --write-csv wrote: each requirement on its own clock's rows)
        from fretc.audit.sampled.audit import audit_clocks

        clocks = head.clocks

        split = (split_clocks(path, plan.csv_period_ns, clocks) if len(clocks) > SPLIT_CLOCKS
                 else None)
        # every clock read over the same bytes: the file's size now (a file still being
        # written judged over one extent, :attr:`fretc.logs.CsvSource.extent`)
        extent = os.path.getsize(path) if split is None else None
        return audit_clocks(plan, str(path), head, lambda p, c: _LogRun(
            p, path, split[c] if split is not None else
            lambda: CsvSource(path, period_ns=plan.csv_period_ns, clock=c, extent=extent)
        ).run(progress))
    if plan.variants:
        sub, err = select_variant(plan, str(path))
        if sub is None:
            return _not_selected(plan, str(path), err or "")
        return _audit_log(sub, path, progress)
    if plan.bindings is not None and plan.bindings.per_entity and not sampled_trace(path):
        # (a sampled trace's columns are the variables: per-entity ones too, as testgen
        # writes them)
        from fretc.audit.entities.log import audit_entities

        return audit_entities(plan, str(path), progress,
                              lambda p, f, pr: _LogRun(p, f).run(pr))
    return _LogRun(plan, path).run(progress)


@dataclass
class KeptPasses:
    """A log's audit with the passes it judged (:func:`audit_keeping_passes`).

    Attributes:
        plan: the plan audited (a binding file's ``[logs]`` variant when one selects the log).
        audit: the :class:`~fretc.audit.verdict.LogAudit`.
        passes: the read of the log (:class:`~fretc.audit.passes.LogPasses`), or None when
            nothing was read.
        bindings: the bindings it was read with (None: a CSV trace's columns).
        unjudged: indexes of the requirements decided ``unknown`` before their ticks were
            judged (a topic the damage may have taken).
    """

    plan: AuditPlan
    audit: LogAudit
    passes: LogPasses | None
    bindings: Bindings | None
    unjudged: set[int]


def audit_keeping_passes(plan: AuditPlan, path: str) -> KeptPasses:
    """:func:`audit_log` of ``path``, keeping what each requirement was judged on (the
    sampled trace of ``--write-csv``, :mod:`fretc.audit.sampled.csv`).

    Raises:
        ValueError: per-entity requirements: their entities' passes are kept by
            :func:`fretc.audit.entities.log.entity_passes` (:mod:`fretc.audit.sampled.entities`)."""
    if plan.variants:
        sub, err = select_variant(plan, str(path))
        if sub is None:
            return KeptPasses(plan, _not_selected(plan, str(path), err or ""), None, None,
                              set())
        return audit_keeping_passes(sub, path)
    from fretc.audit.entities.log import entity_of_requirements

    if plan.bindings is not None and entity_of_requirements(plan):
        raise ValueError("audit_keeping_passes keeps the passes of plain requirements; "
                         "per-entity ones: fretc.audit.entities.log.entity_passes")
    run = _LogRun(plan, path, stream=False)  # (the columns kept: they are written)
    la = run.run(None)
    return KeptPasses(plan, la, run.result, run.read_bindings, set(run.skip))


def _not_selected(plan: AuditPlan, path: str, err: str) -> LogAudit:
    """No binding file (or two) selects the log: every verdict an error, or ``unknown``
    when the damage may have taken the topics that would select it."""
    la = LogAudit(log=path, error=err)
    damaged = damage_of(path, la)
    if damaged:
        la.error = None
        la.verdicts = [Verdict(log=path, requirement=r.id, text=r.text, source=r.source,
                               verdict="unknown", partial=True,
                               unknown_reason=f"{err}; {damaged}")
                       for r in plan.requirements]
        return la
    la.verdicts = [Verdict(log=path, requirement=r.id, text=r.text, source=r.source,
                           error=f"log not audited: {err}")
                   for r in plan.requirements]
    return la


class _LogRun:
    """The audit of one log in steps; each returns False when the log's audit ends there."""

    def __init__(self, plan: AuditPlan, path: str,
                 opener: Callable[[], LogSource] | None = None, stream: bool = True) -> None:
        self.plan = plan
        self.path = path
        self.opener = opener  # opens the log (None: open_log)
        #: a CSV trace's requirements may be judged as it is read (False: every column kept)
        self.stream = stream
        self.result: LogPasses | None = None  # the passes, once read
        self.read_bindings: Bindings | None = None  # the bindings they were read with
        self.la = LogAudit(log=str(path))
        self.verdicts: dict[int, Verdict] = {}
        for r in plan.requirements:
            self.verdicts[r.index] = Verdict(log=str(path), requirement=r.id, text=r.text,
                                             source=r.source, notes=list(r.notes))
            if r.error is not None:
                self.verdicts[r.index].error = r.error
        self.source: LogSource | None = None  # (opened by the first pass)
        self.bindings: Bindings | None = None
        self.skip: set = set()  # requirements already decided (unknown) before the pass
        self.problems: dict[tuple, DataProblem] = {}
        self.problem_counts: dict[str, int] = {}
        #: a CSV trace's requirements judged while it was read (:mod:`fretc.audit.streamed`)
        self.streams: CsvStreams | None = None
        self.stream_sampling: Any = None  # (the Sampling of their pass, once read)

    def run(self, progress: Callable[[float], None] | None) -> LogAudit:
        if self._open() and self._check_inputs():
            result, active, b = self._read(progress)
            self.result, self.read_bindings = result, b
            self._record_source()
            if result is not None or self.stream_sampling is not None:
                self._judge(result, active, b)
        return self._finish()

    def _finish(self) -> LogAudit:
        la = self.la
        la.verdicts = [self.verdicts[r.index] for r in self.plan.requirements]
        for v in la.verdicts:
            if v.error is not None:
                v.verdict = "error"
            # a verdict that read the log is partial with it; an error read nothing of it
            v.partial = la.partial and v.error is None
        return la

    def _fail_all(self, message: str, rs=None) -> None:
        for r in (rs if rs is not None else self.plan.requirements):
            if self.verdicts[r.index].error is None:
                self.verdicts[r.index].error = message

    def _fail_log(self, message: str, prefix: str = "") -> bool:
        self.la.error = message
        self._fail_all(prefix + message)
        return False

    def _open(self) -> bool:
        """Open the log and choose its bindings (a CSV trace's columns, else the plan's)."""
        plan, path, la = self.plan, self.path, self.la
        # a CSV trace read without bindings keeps only the columns of the requirements'
        # variables (those with bindings read every column as /csv fields)
        keep = ({v for r in plan.requirements for v in r.variables}
                if plan.bindings is None or not plan.bindings.variables else None)
        try:
            source = self.source = (self.opener() if self.opener is not None
                                    else self._open_log(keep))
        except FretcInputError as exc:
            return self._fail_log(str(exc), "log not audited: ")
        except OSError as exc:
            return self._fail_log(f"{path}: {exc}", "log not audited: ")
        la.kind = source.kind
        bindings = plan.bindings
        if bindings is not None and any(bindings.allowance.values()):
            if source.kind == "csv":
                return self._fail_log(f"{path}: an allowance (--allowance, [audit] allowance) "
                                      "reads topics of a log earlier; a CSV trace's rows are "
                                      "one clock", "log not audited: ")
            self.source = source = with_allowance(source, bindings.allowance)
        if bindings is not None and bindings.allowance:
            la.allowance_ns = dict(sorted(bindings.allowance.items()))
        if source.kind == "csv":
            # the same binding rules as any log (docs/guide/ticks.md "CSV traces"): with bindings, bound
            # variables are their expressions over /csv.<column> (a missing topic or column
            # is an error naming the columns), unbound ones read the column of their name;
            # without bindings the columns are the variables
            if bindings is not None and not bindings.variables:
                bindings = None
            elif bindings is not None:
                bindings = csv_bindings(plan, bindings, source)
        elif bindings is None:
            return self._fail_log(
                f"{path}: a {source.kind} log needs signal bindings (*.bindings.toml next to "
                "the requirements, --bindings or --bind): signals are declared, never "
                "guessed")
        self.bindings = bindings
        if bindings is not None:
            la.tick = ({"period_ns": bindings.tick.period_ns} if bindings.tick.period_ns
                       else {"topic": bindings.tick.topic})
            la.time_base = bindings.time_base
        else:
            la.tick = {"period_ns": plan.csv_period_ns, "rows": True}
            la.time_base = "csv"
        too_many = too_many_ticks(source, bindings, path)
        if too_many is not None:
            return self._fail_log(too_many)
        return True

    def _open_log(self, keep: set[str] | None) -> LogSource:
        """Open the log; a CSV trace read without bindings (``keep``: the columns of the
        requirements' variables) is read with its streamable requirements judged as its
        rows pass (:mod:`fretc.audit.streamed`): only the others' columns are kept, and
        when some streamed requirement must be judged whole after all (its ticks unknown),
        the file is read again keeping its columns too, over the first read's bytes alone
        (:attr:`~fretc.logs.CsvSource.extent`: rows appended since are not read, so every
        requirement is judged over the same rows)."""
        plan, path = self.plan, self.path
        csv = str(path).lower().endswith(".csv") and not os.path.isdir(path)
        if not csv or keep is None or not self.stream:
            return open_log(path, csv_period_ns=plan.csv_period_ns,
                            msg_path=plan.config.msg_path, csv_keep=keep)
        active = [r for r in plan.requirements if r.error is None]
        streams = CsvStreams.of(plan, active)
        if not streams.streams:
            return open_log(path, csv_period_ns=plan.csv_period_ns, csv_keep=keep)
        whole = {v for r in active if r.index not in streams.indexes for v in r.variables}
        source = open_log(path, csv_period_ns=plan.csv_period_ns, csv_keep=whole,
                          csv_sink=streams, csv_streamed=streams.names,
                          csv_keep_times=any(r.index not in streams.indexes for r in active))
        assert isinstance(source, CsvSource)  # (a .csv file)
        streams.close(source)
        self.streams = streams
        if streams.whole:
            judged_three(plan, streams, source)
        if streams.whole:  # (read again: the columns of those judged whole kept too)
            again = whole | {v for r in active if r.index in streams.whole
                             for v in r.variables}
            source = open_log(path, csv_period_ns=plan.csv_period_ns, csv_keep=again,
                              csv_extent=source.extent)
        return source

    def _check_inputs(self) -> bool:
        """A binding for every variable, every bound topic in the log, binding types."""
        source, bindings = self.source, self.bindings
        assert source is not None  # (open)
        active = [r for r in self.plan.requirements if r.error is None]
        self._check_bound(active)
        try:
            log_topics = source.topics()
        except FretcInputError as exc:
            return self._fail_log(str(exc), "log not audited: ")
        damaged = damage_before_topics(source, self.la)  # damage met finding the topics
        if bindings is not None:
            if not self._check_topics(active, log_topics, damaged):
                return False
            skip = {i for i, v in self.verdicts.items() if v.error is not None}
            for i, why in binding_type_errors(source, bindings, self.plan, skip).items():
                self.verdicts[i].error = why
        return True

    def _check_bound(self, active: list[RequirementPlan]) -> None:
        """Variables without a binding (or CSV column) make their requirements errors."""
        bindings, source = self.bindings, self.source
        assert source is not None  # (open)
        # without bindings: a CSV trace (its columns)
        available = set(bindings.variables) if bindings is not None else set(source.columns)  # type: ignore[attr-defined]
        for r in active:
            missing = [v for v in r.variables if v not in available]
            if missing:
                where = (f"bindings ({bindings.source or '--bind'})" if bindings is not None
                         else f"the CSV columns ({', '.join(source.columns)})")  # type: ignore[attr-defined]
                hints = [(m, closest(m, sorted(available))) for m in missing if "(" not in m]
                hint = "; ".join([f"did you mean {h!r} for {m!r}?" for m, h in hints if h]
                                 + [call_hint(m) for m in missing if "(" in m]
                                 + _stream_hint(r, missing))
                self.verdicts[r.index].error = (f"no binding for {', '.join(map(repr, missing))}"
                                                f" in {where}" + (f"; {hint}" if hint else ""))

    def _check_topics(self, active: list[RequirementPlan], log_topics, damaged: str | None
                      ) -> bool:
        """Topics absent from the log: the tick topic ends the audit, a bound topic makes its
        requirements errors (``unknown`` when the damage may have taken it)."""
        bindings, source, verdicts, path = self.bindings, self.source, self.verdicts, self.path
        assert bindings is not None and source is not None  # (checked with bindings only)
        if bindings.tick.topic is not None and bindings.tick.topic not in log_topics:
            msg = (f"{path}: the tick topic {bindings.tick.topic} is not in the log (it has "
                   f"{', '.join(log_topics) or 'no topics'})")
            if damaged:  # the damage may have taken it: unknown, with the damage's reason
                for r in active:
                    if verdicts[r.index].error is None:
                        verdicts[r.index].verdict = "unknown"
                        verdicts[r.index].unknown_reason = f"{msg}; {damaged}"
                return False
            return self._fail_log(msg)
        for r in active:
            if verdicts[r.index].error is not None:
                continue
            absent = missing_topics(log_topics_of({t for v in r.variables  # streams' topics
                                                   for t in bindings.variables[v].topics}),
                                    log_topics)
            if not absent:
                continue
            users = {t: sorted(v for v in r.variables
                               if t in log_topics_of(bindings.variables[v].topics))
                     for t in absent}
            has = (f"a CSV trace has one topic, /csv, with the columns "
                   f"{', '.join(source.columns)}" if source.kind == "csv"  # type: ignore[attr-defined]
                   else f"it has {', '.join(log_topics) or 'no topics'}")
            msg = ("; ".join(f"topic {t} (bound to {', '.join(users[t])}) is not in the log"
                             for t in absent) + f" ({has})")
            if damaged:
                verdicts[r.index].verdict = "unknown"
                verdicts[r.index].unknown_reason = f"{msg}; {damaged}"
                self.skip.add(r.index)
            else:
                verdicts[r.index].error = msg
        return True

    def _read(self, progress) -> tuple[LogPasses | None, list[RequirementPlan], Bindings | None]:
        """Read the log for the requirements still active; a signal that fails makes its
        requirements errors and the log is read again for the others."""
        plan, source, verdicts = self.plan, self.source, self.verdicts
        assert source is not None  # (open)
        result, b, active = None, None, []
        streamed = set(self.streams.results) if self.streams is not None else set()
        while True:
            active = [r for r in plan.requirements if verdicts[r.index].error is None
                      and r.index not in self.skip and r.index not in streamed]
            if not active:
                break
            names = sorted({v for r in active for v in r.variables})
            b = restrict(self.bindings, names) if self.bindings is not None else None
            try:
                result = run_passes(plan, source, b, active, progress, self._log_streams())
                if result.streamed is not None and result.streamed.again:
                    result = self._read_again(result, b, active)
            except SignalError as exc:
                culprit = exc.variable
                hit = [r for r in active if culprit in r.variables] if culprit else []
                collect_problems(source, None, self.problems, self.problem_counts)
                result = None
                if hit:
                    for r in hit:
                        verdicts[r.index].error = str(exc)
                    continue
                self._fail_all(str(exc), active)
                break
            collect_problems(source, result.sampling, self.problems, self.problem_counts)
            self.la.gaps = merged_gaps(result.gaps, result.bridged)
            break
        if streamed and any(verdicts[i].error is None for i in streamed):
            st = self.streams
            assert st is not None and isinstance(source, CsvSource)  # (streamed: a CSV trace)
            if result is not None:  # (the same rows: the whole pass's figures are theirs)
                self.stream_sampling = result.sampling
            else:
                self.stream_sampling = csv_streamed_pass(source, st.n, st.first_time,
                                                         st.last_time)
                collect_problems(source, self.stream_sampling, self.problems,
                                 self.problem_counts)
        return result, active, b

    def _log_streams(self) -> Callable[[dict], LogStreams] | None:
        """The clocks judged as the log is read (:mod:`fretc.audit.streamed_log`), or None
        where every column is kept (``audit_keeping_passes``)."""
        if not self.stream:
            return None
        plan, source = self.plan, self.source
        assert source is not None  # (open)
        return lambda groups: LogStreams.of(plan, groups, self.bindings, source)

    def _read_again(self, first: LogPasses, b: Bindings | None,
                    active: list[RequirementPlan]) -> LogPasses:
        """The log read a second time: the clocks of ``first.streamed.again`` keeping their
        columns, the others' decided already (sampled again, neither kept nor judged, so
        that the log's figures are the same read's)."""
        assert self.source is not None and first.streamed is not None  # (streamed)
        got = first.streamed
        decided = frozenset(got.ticks) - got.again
        result = run_passes(self.plan, self.source, b, active, None,
                            lambda _groups: LogStreams(discard=decided))
        result.streamed = got
        return result

    def _pick(self, result: LogPasses, b: Bindings | None,
              active: list[RequirementPlan]) -> None:
        """The ticks the evidence of violations decided as the log was read shows, read
        again (:func:`fretc.audit.streamed_log.pick_ticks`)."""
        got = result.streamed
        if got is None or not got.pick:
            return
        assert b is not None  # (a log's clocks: with bindings)
        names: dict = {}
        for r in active:
            key = clock_key(r, b)
            if key in got.pick:
                kept = names.setdefault(key, [])
                kept += [v for v in r.variables if v not in kept]
        got.picked = pick_ticks(self.plan, self.path, self.source, b, got.pick, names)

    def _record_source(self) -> None:
        """The log's damage, message counts, problems and span, from its source."""
        la, source = self.la, self.source
        assert source is not None  # (open)
        la.partial = bool(source.partial) or la.partial
        if source.partial or la.damage_time_ns is None:
            la.damage_time_ns = source.damage_time
        la.damage_cut = bool(source.damage_cut) or la.damage_cut
        la.cut_time_ns = getattr(source, "cut_start", None)
        la.integrity = source.integrity_note()
        la.messages = dict(sorted(source.counts.items()))
        if self.problems or not la.problems:  # (else: only the damage found with the topics)
            la.problems = [problem_json(p) for p in self.problems.values()]
            la.problem_counts = dict(sorted(self.problem_counts.items()))
        la.start_time_ns = source.start_time
        la.end_time_ns = log_end(source)
        check_nominal_rate(la, self.bindings)
        for r in self.plan.requirements:  # the measured rate in the nominal_rate hint
            v = self.verdicts[r.index]
            # (rate_topic is set with the error)
            if r.rate_topic is not None and v.error is not None and v.error == r.error:
                v.error += rate_hint(source, r.rate_topic, la.messages)

    def _judge(self, result: LogPasses | None, active: list[RequirementPlan],
               b: Bindings | None) -> None:
        """Each requirement's clock figures, then its verdict; the log's figures. The
        requirements of a CSV trace judged as it was read (:mod:`fretc.audit.streamed`)
        are not in ``result``; the others (``active``) are."""
        la, verdicts = self.la, self.verdicts
        by_index = {}
        passes = result.passes if result is not None else {}
        if result is not None:
            self._pick(result, b, active)
        for r in active:
            assert result is not None  # (active requirements were read)
            res = by_index[r.index] = passes[clock_key(r, b)]
            got = result.streamed.results.get(r.index) if result.streamed else None
            n = got.result.n if got is not None else len(res.times)
            if got is not None and got.wanted:  # (the operands' read: the ticks' times)
                by_index[r.index] = replace(res, times=picked_times(
                    n, result.streamed.picked[clock_key(r, b)]))
            self._clock_figures(r, res, result, b, n)
        streamed = self._streamed_figures()
        ok = [r for r in self.plan.requirements
              if (r.index in by_index or r.index in streamed)
              and verdicts[r.index].error is None and r.index not in self.skip]
        summarize_clocks(la, [verdicts[r.index] for r in ok])
        silent = {t for res in passes.values()
                  for t in (res.sampling.missing_topics if b is not None else [])}
        # never published: no message at all, not messages that could not be decoded (the
        # requirements reading those say why, silent_reasons)
        unread = {p.topic for p in self.problems.values()
                  if p.kind in (P.UNKNOWN_SCHEMA, P.UNKNOWN_ENCODING, P.UNDECODABLE)}
        records = getattr(self.source, "records", None) or {}
        la.missing_topics = sorted(t for t in silent
                                   if t not in unread and not records.get(t))
        if la.start_time_ns is None:
            samplings = [res.sampling for res in passes.values()]
            if streamed:
                samplings.append(self.stream_sampling)
            starts = [s.start_time for s in samplings if s.start_time is not None]
            la.start_time_ns = min(starts) if starts else None
        violated = []
        for r in ok:
            if r.index in streamed:
                got = streamed[r.index]
                if (finalize_three(self.plan, r, got, verdicts[r.index], la)
                        if isinstance(got, ThreeResult) else
                        finalize_streamed(self.plan, r, got, verdicts[r.index])):
                    violated.append(r)
            elif result is not None and result.streamed and r.index in result.streamed.results:
                key = clock_key(r, b)
                finalize_clock_streamed(self.plan, r, result.streamed.results[r.index],
                                        verdicts[r.index], result.streamed.picked.get(key),
                                        self.bindings)
            else:
                finalize(self.plan, r, by_index[r.index], self.bindings, verdicts[r.index],
                         la)
        if violated:
            assert isinstance(self.source, CsvSource)  # (streamed: a CSV trace)
            streamed_values(self.plan, self.source, violated, verdicts, streamed)
        la.engine = log_engine(verdicts[r.index] for r in ok)
        if self.bindings is not None:
            operand_values(self.path, self.plan, self.bindings, ok, verdicts, by_index,
                           self.source)

    def _streamed_figures(self) -> dict[int, StreamedResult | ThreeResult]:
        """The requirements judged as the CSV trace was read, by index, with their clock
        figures set (as :meth:`_clock_figures` sets them from a pass: the trace's rows)."""
        st, s = self.streams, self.stream_sampling
        if st is None or s is None:
            return {}
        out: dict[int, StreamedResult | ThreeResult] = {}
        for r in self.plan.requirements:
            got = st.results.get(r.index)
            v = self.verdicts[r.index]
            if got is None or v.error is not None or r.index in self.skip:
                continue
            out[r.index] = got
            _tick_figures(v, s, r, got.n, None)
        return out

    def _clock_figures(self, r: RequirementPlan, res, result: LogPasses,
                       b: Bindings | None, n: int) -> bool:
        """Set the verdict's ticks and times from its clock (``n`` ticks judged); False
        (with the error) when its clock failed or a topic it reads gave nothing."""
        la, v, key = self.la, self.verdicts[r.index], clock_key(r, b)
        s = res.sampling
        _tick_figures(v, s, r, n, b)
        if res.cut:  # ticks after the damage are not judged
            v.last_tick_ns = int(res.times[-1]) if len(res.times) else None
            la.ticks_after_damage = max(la.ticks_after_damage, res.cut)
        err = result.errors.get(key)
        bad = [n for n in r.variables if n in result.failed.get(key, {})]
        if err is not None:
            v.error = str(err)
            return False
        if bad:
            v.error = str(result.failed[key][bad[0]])
            return False
        silent = list(s.missing_topics) if b is not None else []
        if silent:
            why = silent_reasons(silent, self.problems.values(),
                                 getattr(self.source, "lost", None))
            text = "; ".join(why[t] for t in sorted(silent))
            lost = self._damage_may_hold(silent)
            if lost:  # the damage may have taken its messages: not an input error
                v.verdict, v.unknown_reason = "unknown", f"{text}; {lost}"
                self.skip.add(r.index)
            else:
                v.error = text
            return False
        return True

    def _damage_may_hold(self, topics: list[str]) -> str | None:
        """Why the log's damage may have held messages of ``topics`` (a cut, or a gap whose
        topics are not known or include one of them), else None."""
        la = self.la  # (its damage is the source's, recorded before the judge)
        if not la.partial:
            return None
        if la.cut_time_ns is not None:  # (damage_cut is set by any gap too)
            return "the log is cut by damage: its messages may be in what was lost"
        for g in la.gaps:
            held = g.get("topics")
            if held is None or set(held) & set(topics):
                return (f"a gap ({g.get('cause') or 'damage'}) may have held its messages")
        if not la.gaps:
            return "the log is damaged: its messages may be in what could not be read"
        return None


def _stream_hint(r: RequirementPlan, missing: list[str]) -> list[str]:
    """Why ``r`` reads the ``missing`` variables its text does not name: the FRET
    definitions of stream variables read them (:mod:`fretc.audit.streams`); none else."""
    system = r.streams
    via = [m for m in missing if system is not None and m in system.inputs]
    if not via:
        return []
    return [f"{', '.join(map(repr, via))} {'is' if len(via) == 1 else 'are'} read by FRET's "
            f"definition of {', '.join(system.names)} (a stream with state, computed from "
            "the variables it reads; or bind it itself)"]


def _tick_figures(v: Verdict, s: Any, r: RequirementPlan, n: int, b: Bindings | None) -> None:
    """The verdict's tick figures from its clock's :class:`~fretc.signals.Sampling` ``s`` of
    ``n`` evaluated ticks: counts, warm-up, what passed between ticks, first and last tick
    times, the topics it waited for."""
    v.ticks_evaluated = n
    v.warmup_ticks = s.warmup_ticks
    between_ticks(v, s, r, b)
    v.first_tick_ns = s.first_time
    v.last_tick_ns = s.end_time
    v.waiting_for = list(s.waiting_for)


def log_end(source: LogSource) -> int | None:
    """The log's end (ns, log time) in the audit JSON's ``end_time_ns``: the last log time
    of a message of any topic, whichever topics the audit read. A source that knows it when
    opened (``log_end``: PX4 ULog, ArduPilot DataFlash) gives it; otherwise the source's
    ``end_time`` (an MCAP's summary end, or the last message of the pass). The same end
    ``age()``'s grid runs to (:func:`fretc.signals.clock.silence_end`)."""
    end, known = source.end_time, getattr(source, "log_end", None)
    if known is None:
        return end
    return known if end is None else max(end, known)


def log_engine(verdicts: Iterable[Verdict]) -> str | None:
    """The log's ``engine`` figure: what decided its verdicts (:class:`~fretc.monitors.judge.
    Judgement`'s ``engine``), ``"mixed"`` when several did, None when none was decided."""
    engines = sorted({v.engine for v in verdicts if v.engine is not None})
    return engines[0] if len(engines) == 1 else ("mixed" if engines else None)


def summarize_clocks(la: LogAudit, verdicts: list) -> None:
    """The log's figures from its requirements' clocks (each verdict has its own): the most
    ticks evaluated and warm-up ticks, the earliest first tick, every topic waited for, and
    after damage the end of the judged span. ``verdicts``: those without an error."""
    if not verdicts:
        return
    la.ticks_evaluated = max(v.ticks_evaluated for v in verdicts)
    la.warmup_ticks = max(v.warmup_ticks for v in verdicts)
    firsts = [v.first_tick_ns for v in verdicts if v.first_tick_ns is not None]
    la.first_time_ns = min(firsts) if firsts else None
    la.waiting_for = sorted({t for v in verdicts for t in v.waiting_for})
    if la.ticks_after_damage:  # the log's judged span ends at the damage
        lasts = [v.last_tick_ns for v in verdicts if v.last_tick_ns is not None]
        la.end_time_ns = max(lasts) if lasts else None
