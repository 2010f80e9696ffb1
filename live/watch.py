"""``fretc watch``: the audit's monitors on a running robot, over the Foxglove WebSocket protocol
(:class:`~fretc.live.websocket.foxglove.FoxgloveClient`), rosbridge
(:class:`~fretc.live.websocket.rosbridge.RosbridgeClient`), DDS or Zenoh
(:mod:`fretc.live.transports`).

Design notes: ARCHITECTURE.md, `live/watch.py`."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from fretc.common.problems import DataProblem
from fretc.common.streams import log_topics
from fretc.signals import sample_groups
from fretc.signals.bindings.expression import age_only_topics
from fretc.monitors.interval import evaluate_requirement
from fretc.audit import AuditInputError
from fretc.audit.finalize import between_ticks, finalize
from fretc.audit.log import log_engine, summarize_clocks
from fretc.audit.log_problems import collect_problems, problem_json
from fretc.audit.operands import operand_values
from fretc.audit.gaps import merged_gaps, split_bridged
from fretc.live.merge import HOLD_SECONDS
from fretc.audit.columns import ClockPass
from fretc.audit.passes import ClockKey, clock_key, mark_gaps, restrict
from fretc.audit.verdict import LogAudit, Verdict
from fretc.live.absence import NO_TIME, recorded_gaps, run_gaps
from fretc.live.checks import late_type_errors, listing, watchable
from fretc.live.columns import LiveColumns, WatchPasses as _WatchPasses, split_pending
from fretc.live.entities import EntityRecording
from fretc.live.entity_events import EntityEvents
from fretc.live.record import Recorder
from fretc.live.transports import make_client
from fretc.live.source import (CLOCK_BACKWARDS, CONNECTION_CLOSED, CONNECTION_GAP, NOT_ADVERTISED,
                     RESTART_GRACE, UNADVERTISED, WatchEvent, WatchSource)

__all__ = ["WatchOptions", "WatchEvent", "WatchSource", "Watch", "CONNECTION_GAP",
           "UNADVERTISED", "CLOCK_BACKWARDS", "NOT_ADVERTISED", "CONNECTION_CLOSED",
           "split_pending"]

#: The most ticks one message may move a fixed-period clock forward (a jump of log time
#: further than this many periods is a ``time_range`` problem, the message skipped): the
#: ticks in between are made one by one while watching.
MAX_JUMP_TICKS = 10**6


@dataclass
class WatchOptions:
    """How to watch.

    Attributes:
        url: the server (``ws://host:8765``).
        duration: stop after this many seconds of wall time (None: until :meth:`Watch.stop`,
            e.g. on Ctrl-C).
        wait: seconds, after the first connection, to wait for every bound topic to be
            advertised; topics still missing then make their requirements ``error``.
        connect_timeout: seconds to keep trying to connect at all before giving up (None:
            until stopped).
        record: MCAP path to write the watched messages and the verdict events to.
        backoff, max_backoff: reconnection delays (s), doubling.
        until_idle: end the run when no message arrived for this many seconds (wall time).
        types: topic -> ROS message type, for rosbridge servers whose rosapi does not type
            a bound topic (``--topic-type``; over the bindings' ``[types]``).
        msg_path: rosbridge, DDS, Zenoh: folders of the robot's own ``.msg``/``.idl`` files
            (``--msg-path``); Foxglove WebSocket servers send their schemas.
        config: DDS: a Cyclone DDS XML configuration (``--dds-config``); Zenoh: a JSON5
            session configuration (``--zenoh-config``).
        merge_hold: DDS, Zenoh: seconds each message is held to be merged into log-time
            order with the other topics' (:mod:`fretc.live.merge`; ``--merge-hold``): the
            latency a verdict gains, against out-of-order arrivals reported; DDS releases
            earlier at the watermark (every matched writer past the message).
        restart_grace: seconds a bound topic's publisher has, once every bound topic was
            unadvertised, to advertise it again and continue the same run (a node restart);
            0 ends the run at once (``--restart-grace``).
    """

    url: str
    duration: float | None = None
    until_idle: float | None = None
    types: dict[str, str] | None = None
    wait: float = 3.0
    connect_timeout: float | None = None
    record: str | None = None
    backoff: float = 0.1
    max_backoff: float = 5.0
    restart_grace: float = RESTART_GRACE
    msg_path: tuple[str, ...] = ()
    config: str | None = None
    merge_hold: float = HOLD_SECONDS


def _value_topics(r, bindings, silent: bool) -> set[str]:
    """The topics whose values requirement ``r``'s variables read: those a span without a
    publisher leaves unknown. Over a client that hears a new publisher at once (``silent``:
    :mod:`fretc.live.absence`), a topic read only through ``age()`` is known in such a span;
    over one that may lose a restarted publisher's first messages, every topic it reads."""
    out: set[str] = set()
    for v in r.variables:
        b = bindings.variables.get(v)
        if b is None:
            continue
        aged = age_only_topics(b.ast) if silent else set()
        out |= {t for t in log_topics(b.topics) if t not in aged}
    return out


# --------------------------------------------------------------------------- the engine
class _Live:
    """Per-requirement live state (read by the table)."""

    __slots__ = ("pt", "status", "status_tick", "status_time", "violations", "pending",
                 "last_trigger", "first_violation", "error", "offline", "nan_at")

    def __init__(self) -> None:
        self.pt: bool | None = None
        self.status = "unknown"
        self.status_tick: int | None = None
        self.status_time: int | None = None
        self.violations = 0  # obligations already failed (they fail on every continuation)
        self.pending = 0  # obligations failing on the ticks so far that may still be met
        self.last_trigger: int | None = None
        self.first_violation: int | None = None
        self.error: str | None = None
        self.offline = False
        self.nan_at: int | None = None  # its first tick that read NaN (not stepped from there)


class Watch:
    """Watch a server against the requirements of ``plan`` (from
    :func:`fretc.audit.load_plan`).

    Args:
        plan: compiled requirements and bindings (bindings are required; a plan whose only
            binding file selects logs with ``[logs]`` is watched with that file).
        options: :class:`WatchOptions`.
        on_event: called with every :class:`WatchEvent` (``--jsonl``, the live table).

    :meth:`run` blocks until the run ends (module docstring: close, unadvertised, duration, idle,
    :meth:`stop`), then returns the :class:`~fretc.audit.verdict.LogAudit` of the run (``log`` = the
    URL, ``kind`` ``"watch"``): final verdicts and evidence exactly as an audit of the same
    messages.
    """

    #: Seconds between two recomputations of "violations so far" / "last trigger".
    EVIDENCE_EVERY = 1.0

    def __init__(self, plan, options: WatchOptions,
                 on_event: Callable[[WatchEvent], None] | None = None) -> None:
        if plan.bindings is None and len(plan.variants) == 1:
            plan = plan.variants[0][2]  # one binding file with [logs]: the watched run's
        if plan.bindings is None:
            raise AuditInputError("fretc watch needs signal bindings (*.bindings.toml next to "
                                  "the requirements, --bindings or --bind; one file when "
                                  "they select logs with [logs])")
        self.plan = plan
        self.options = options
        self.on_event = on_event or (lambda e: None)
        self.events: list[WatchEvent] = []
        self.live: dict[int, _Live] = {r.index: _Live() for r in plan.requirements}
        self.ticks = 0
        self.unknown_ticks = 0
        self.last_tick_time: int | None = None
        self.start_time: int | None = None
        self.status_line = "connecting"
        b = plan.bindings
        self.entities = EntityRecording(plan)  # judged at the end (fretc.live.entities)
        for i in self.entities.indexes:
            self.live[i].offline = True  # the live table: no monitor steps live
        self.needed: set[str] = set(self.entities.topics) | {
            t for r in plan.requirements if r.error is None and r.index not in
            self.entities.indexes for v in r.variables if v in b.variables
            for t in log_topics(b.variables[v].topics)}  # a stream (/a{id==3}): its topic
        if b.tick.topic is not None:
            self.needed.add(b.tick.topic)
        self.client = make_client(options, lambda t: t in self.needed, b.types, self.needed)
        deadline = (time.monotonic() + options.duration) if options.duration else None
        self.source = WatchSource(options.url, self.client, deadline=deadline,
                                  idle=options.until_idle, on_event=self._event,
                                  restart_grace=options.restart_grace)
        self.source.declared_types = {**(b.types or {}), **(options.types or {})}
        if b.tick.period_ns:
            self.source.max_jump_ns = MAX_JUMP_TICKS * b.tick.period_ns
        self.recorder: Recorder | None = None
        self._lock = threading.Lock()
        self._evidence_at = 0.0
        self._cols, self._group, self._unknown = {}, {}, {}  # type: dict[ClockKey, LiveColumns], dict[int, ClockKey], dict[ClockKey, int]
        self.entity_events = EntityEvents(plan, self.source, self._step, _Live)
        #: called after every evaluated tick's monitors stepped, with (tick index, tick
        #: time, log time of the newest message its values use, log time of the message
        #: whose arrival closed it): the latency benchmark's hook.
        self.on_tick: Callable[[int, int, int | None, int | None], None] | None = None

    def stop(self) -> None:
        """Stop watching (thread-safe): :meth:`run` finishes with the final verdicts."""
        self.source.stop()

    def _event(self, e: WatchEvent) -> None:
        with self._lock:
            self.events.append(e)
        if e.kind == "connected":
            self.status_line = f"connected to {self.options.url} ({e.detail})"
        elif e.kind == "unreachable":
            self.status_line = (f"{e.detail}; retrying (attempt {e.extra.get('attempts')}; "
                                "Ctrl-C stops)")
        elif e.kind == "disconnected":
            self.status_line = f"disconnected: {e.detail}; retrying"
        elif e.kind == "end":
            self.status_line = f"run ended: {e.detail}"
        self.on_event(e)

    # -- the run -----------------------------------------------------------------------------
    def run(self) -> LogAudit:
        """Watch until the run ends (:attr:`WatchSource.end_reason` says why); its LogAudit."""
        plan, src = self.plan, self.source
        url = self.options.url
        la = LogAudit(log=url, kind="watch")
        b = plan.bindings
        la.tick = ({"period_ns": b.tick.period_ns} if b.tick.period_ns
                   else {"topic": b.tick.topic})
        la.time_base = b.time_base
        verdicts: dict[int, Verdict] = {}
        for r in plan.requirements:
            verdicts[r.index] = Verdict(log=url, requirement=r.id, text=r.text,
                                        source=r.source, notes=list(r.notes))
            if r.error is not None:
                verdicts[r.index].error = r.error
        src.want(self.needed)
        self.client.start()
        try:
            self._await_topics()
            if self.options.record:
                self.recorder = Recorder(self.options.record, src)
            self.entities.start(src)
            src.on_message = self._used
            if not src.ever_connected:
                la.error = (f"{url}: could not connect"
                            + (f" ({src.last_reason})" if src.last_reason else ""))
                for v in verdicts.values():
                    v.error = v.error or f"not watched: {la.error}"
                return self._finish(la, verdicts, None)
            active = self._watchable(verdicts)
            result = None
            if active:
                names = sorted({v for r in active for v in r.variables})
                rb = restrict(b, names)
                src.want(log_topics(rb.topics) | ({b.tick.topic} if b.tick.topic else set())
                         | self.entities.topics)
                src.keep = self.entities.topics
                result = self._run_pass(active, rb)
            elif self.entities.indexes:  # per-entity requirements only: their messages kept
                src.want(self.entities.topics)
                for _m in src.messages():
                    pass
        finally:
            self.client.stop()
        self.entities.check(src, url)  # (at the end: a topic may be advertised late)
        self.entity_events.finish()
        self._event(WatchEvent("end", src._last_time, time.time_ns(),
                               detail=src.end_reason or "stopped"))
        self._record_problems(la, result)
        return self._finish(la, verdicts, result, active if result is not None else [])

    def _used(self, topic: str, log_time: int, payload: bytes) -> None:
        """A message the watch used: recorded (``--record``), kept and stepped for the
        per-entity requirements."""
        if self.recorder is not None:
            self.recorder.message(topic, log_time, payload)
        self.entities.message(topic, log_time, payload)
        self.entity_events.message(topic, log_time, payload)

    def _watchable(self, verdicts: dict[int, Verdict]) -> list:
        """The requirements that can be watched (:func:`fretc.live.checks.watchable`); the
        bound topics not advertised yet are awaited (any start order: they join the run
        when they come, and their types are checked then, :meth:`_advertised`), and said."""
        src = self.source
        active = watchable(self.plan, src, verdicts, set(self.entities.indexes))
        self._verdicts, self._awaiting = verdicts, set(self.needed) - set(src.advertised)
        src.awaited = set(self._awaiting)
        if self._awaiting:
            why = (f"not advertised by {self.options.url} within {self.options.wait:g} s of "
                   f"connecting: {', '.join(sorted(self._awaiting))}; the requirements that "
                   "read them wait for them (a node that starts later joins the run)")
            self.status_line = f"waiting for {', '.join(sorted(self._awaiting))}"
            self._event(WatchEvent("waiting", src._last_time, time.time_ns(), detail=why))
        src.on_advertised = self._advertised
        for r in self.plan.requirements:
            if verdicts[r.index].error is not None:
                self.live[r.index].error = verdicts[r.index].error
        return active

    def _advertised(self, topic: str) -> None:
        """A bound topic advertised after the watch began (its node started later): the
        requirements that read it are checked now (:func:`fretc.live.checks.late_type_errors`),
        and those it fails are not stepped (``error`` at the end)."""
        if topic not in self._awaiting:
            return
        self._awaiting.discard(topic)
        self.source.awaited.discard(topic)
        bad = late_type_errors(self.plan, self.source, topic, getattr(self, "_active", ()),
                               self._verdicts)
        for i, why in bad.items():
            self.live[i].error = why
        self._event(WatchEvent("advertised", self.source._last_time, time.time_ns(),
                               detail=f"{topic} advertised; the requirements that read it "
                               "join the run" + (f" ({len(bad)} of them cannot be read)"
                                                 if bad else "")))
        if not self._awaiting:
            self.status_line = f"watching {self.options.url}"

    def _never(self, topic: str) -> str:
        """Why a bound topic gave no message in the run: never advertised (no publisher
        appeared), or advertised and silent."""
        src = self.source
        if topic in src.advertised:
            return f"topic {topic} was advertised but no message of it arrived in the run"
        return (f"topic {topic} was not advertised by {self.options.url} during the run (it "
                f"advertised {listing(src.advertised)})")

    def _record_problems(self, la: LogAudit, result) -> None:
        """The run's message counts and problems; a run with a gap is partial."""
        src = self.source
        for t in sorted(self.needed - set(src.advertised)):  # (no publisher in the whole run)
            src._problem(NOT_ADVERTISED, t, None,
                         f"not advertised by {self.options.url} during the run")
        problems: dict[tuple, DataProblem] = {}
        counts: dict[str, int] = {}
        collect_problems(src, result.sampling if result is not None else None, problems,
                         counts)
        la.messages = dict(sorted(src.counts.items()))
        la.problems = [problem_json(p) for p in problems.values()]
        la.problem_counts = dict(sorted(counts.items()))
        kept, bridged = split_bridged(run_gaps(self.source), self.plan.config.bridge_gaps_ns)
        la.gaps = merged_gaps(kept, bridged)
        if src.gaps:
            la.partial = True
            la.damage_time_ns = src.gaps[0][0]
        if src.lost:  # messages received but not used at their log times (a clock reset)
            la.partial, first = True, min(v[0] for v in src.lost.values())
            la.damage_time_ns = min(x for x in (first, la.damage_time_ns) if x is not None)
        lost = src.absent.lost_start(src.hears_new_publishers)
        if lost is not None:  # a publisher's restart may have lost messages (WebSocket)
            la.partial = True
            first = lost + 1 if lost != NO_TIME else (src.start_time or 0)
            la.damage_time_ns = min(x for x in (first, la.damage_time_ns) if x is not None)
        if src.lost_after is not None:
            la.partial = True  # messages lost at the end: judged up to the last one used
            if la.damage_time_ns is None:
                la.damage_time_ns = src.lost_after + 1
        if src.publishers_left and src._last_time is not None:
            la.partial = True  # the run was cut short after its last message
            if la.damage_time_ns is None:
                la.damage_time_ns = src._last_time + 1

    def _await_topics(self) -> None:
        """Connect, then wait (``options.wait`` s) for the bound topics' advertisements."""
        src, opt = self.source, self.options
        t0 = time.monotonic()
        while not src.stopped:
            if src.ever_connected:
                if self.needed <= set(src.advertised):
                    break
                if time.monotonic() - (src.first_connect_wall or 0.0) >= opt.wait:  # (set: connected)
                    break
            elif opt.connect_timeout is not None and time.monotonic() - t0 >= opt.connect_timeout:
                break
            src.pump(0.05)

    def _run_pass(self, active, bindings):
        """Step the monitors over the live ticks, each requirement on its own clock (the
        topics of its variables, :func:`fretc.signals.sample_groups`, as the audit)."""
        src = self.source
        engine = {r.index: ("interval" if r.offline else "stepwise") for r in active}
        monitors = {r.index: r.monitor_cls() for r in active if engine[r.index] == "stepwise"}
        for r in active:
            self.live[r.index].offline = r.offline
        groups: dict[ClockKey, list] = {}
        for r in active:
            groups.setdefault(clock_key(r, bindings), []).append(r)
        spec = {}
        self._cols = {}
        self._group = {}
        order = {}
        for key, rs in groups.items():
            names: list[str] = []
            for r in rs:
                for v in r.variables:
                    if v not in names:
                        names.append(v)
            spec[key] = (names, key.topics)
            self._cols[key] = LiveColumns(names, sorted(key.topics))
            order[key] = [(r, monitors.get(r.index), self.live[r.index]) for r in rs]
            for r in rs:
                self._group[r.index] = key
        self._active = active
        self._unknown = {key: 0 for key in groups}
        blind = {r.index: _value_topics(r, bindings, src.hears_new_publishers) for r in active}
        sampling = sample_groups(src, bindings, spec)
        gaps = src.gaps
        self.status_line = f"watching {self.options.url}"
        for key, tick in sampling:
            t = tick.time
            vals = tick.values
            cols = self._cols[key]
            i = cols.n
            dep = max(tick.log_times.values()) if tick.log_times else None
            if gaps and any(a < t < e for a, e in gaps[-4:]):
                # inside a gap: kept (the judge reads it as unknown), the monitors not
                # stepped over it
                self._unknown[key] += 1
                self.unknown_ticks = max(self.unknown_ticks, self._unknown[key])
            elif src.absent and src.absent.at(log_topics(key.topics), t):
                # a topic without a publisher: the requirements that read its values are
                # not stepped (unknown), those that read only its age are
                rows = [row for row in order[key] if not src.absent.at(blind[row[0].index], t)]
                if len(rows) < len(order[key]):
                    self._unknown[key] += 1
                    self.unknown_ticks = max(self.unknown_ticks, self._unknown[key])
                self._step(rows, vals, t, i, dep)
            else:
                self._step(order[key], vals, t, i, dep)
            cols.append(tick)
            self.ticks += 1
            if self.on_tick is not None:
                self.on_tick(i, t, dep, src._last_time)
            self.last_tick_time = t
            if self.start_time is None:  # the run's time 0, as in the audit's tables
                self.start_time = (src.start_time if src.start_time is not None
                                   else sampling.groups[key].start_time)
        passes = {}
        # the gaps the recording carries, judged by the audit's rule (a publisher gone for
        # good: its variables unknown from there; a clock with no tick past it cut there),
        # so that the audit of the recording gives these verdicts
        live_gaps = split_bridged(recorded_gaps(self.source),
                                  self.plan.config.bridge_gaps_ns)[0]
        for key in groups:
            times, columns, log_times = self._cols[key].arrays()
            passes[key] = ClockPass(sampling.groups[key], times, columns, log_times)
            mark_gaps(passes[key], spec[key][0], bindings, live_gaps, key.topics)
            # cut short, or messages lost at the end (undecodable): judged as a log cut after
            # the last message used (fretc.audit.damage)
            cut = src._last_time if src.publishers_left else src.lost_after
            if cut is not None:
                passes[key].intact_end = cut + 1
        self._live_evidence()
        return _WatchPasses(sampling, {r.index: passes[self._group[r.index]] for r in active},
                            sampling.failed, self._group)

    def _step(self, rows, vals: dict, t: int, i: int, dep) -> None:
        """Step one clock's monitors (``rows``: requirement, monitor, live state) over tick
        ``i`` at time ``t``, with their events; not from a requirement's first tick that
        reads NaN (unread, :mod:`fretc.monitors.nan`) unless ``[tick] nan = "false"``."""
        unread = self.plan.bindings is None or self.plan.bindings.tick.nan != "false"
        for r, mon, st in rows:
            if (mon is None or st.nan_at is not None or st.error is not None
                    or any(v not in vals for v in r.variables)):
                continue
            if unread and any(vals[v] != vals[v] for v in r.variables):
                st.nan_at = i
                continue
            pt = mon.step(vals)
            if pt != st.pt:
                if st.pt is not None or not pt:
                    self._event(WatchEvent("pt", t, time.time_ns(), r.id, i,
                                           "holds" if pt else "violated", depends_on=dep))
                if not pt and st.first_violation is None:
                    st.first_violation = i
                st.pt = pt
            if mon.status != st.status:
                st.status, st.status_tick, st.status_time = mon.status, mon.status_tick, t
                self._event(WatchEvent("ltl3", t, time.time_ns(), r.id, i, mon.status,
                                       depends_on=dep, extra={"status_tick": mon.status_tick}))

    def tick_times(self, index: int) -> list[int]:
        """Tick times seen so far on the clock of the requirement at ``index``."""
        cols = (getattr(self, "_cols", None) or {}).get(getattr(self, "_group", {}).get(index))
        return cols.times if cols is not None else []

    def refresh_evidence(self) -> None:
        """Update "violations so far" and "last trigger" of the live table (at most every
        :data:`EVIDENCE_EVERY` s; called by the table's refresh thread, so the monitors are
        never held up by it)."""
        now = time.monotonic()
        if now - self._evidence_at < self.EVIDENCE_EVERY or getattr(self, "_cols", None) is None:
            return
        self._evidence_at = now
        try:
            self._live_evidence()
        except Exception:  # a display helper: never let it stop the watch
            pass

    def _live_evidence(self) -> None:
        """Violations so far and the last trigger, by the audit's interval semantics over
        the ticks seen (:func:`fretc.monitors.interval.evaluate_requirement`)."""
        arrays = {}
        for key, cols in self._cols.items():
            if cols.n:
                arrays[key] = (cols.n, cols.arrays(cols.n)[1])
        for r in self._active:
            if self._group.get(r.index) not in arrays:
                continue
            n, columns = arrays[self._group[r.index]]
            st = self.live[r.index]
            try:
                ev = evaluate_requirement(r.requirement, columns, n, r.formalization.ticks)
            except Exception:  # evidence unsupported for this requirement: pt only
                continue
            st.violations, st.pending = split_pending(ev, n)
            trig = None
            for x in getattr(ev, "listed", ()) or ():
                trig = x.trigger_tick
            if ev.violation is not None and trig is None:
                trig = ev.violation.trigger_tick
            st.last_trigger = trig

    def _finish(self, la, verdicts, result, active=()):
        if result is not None:
            src = self.source
            groups = [res.sampling for res in result.by_req.values()]
            starts = [g.start_time for g in groups if g.start_time is not None]
            la.start_time_ns = (src.start_time if src.start_time is not None
                                else (min(starts) if starts else None))
            ends = [g.end_time for g in groups if g.end_time is not None]
            la.end_time_ns = max(ends) if ends else None
            la.missing_topics = sorted({t for g in groups for t in g.missing_topics})
            ok = []
            for r in active:
                res = result.by_req[r.index]
                g, v = res.sampling, verdicts[r.index]
                v.ticks_evaluated = g.ticks
                v.warmup_ticks = g.warmup_ticks
                between_ticks(v, g, r, self.plan.bindings)
                v.first_tick_ns, v.last_tick_ns = g.first_time, g.end_time
                v.waiting_for = list(g.waiting_for)
                bad = [n for n in r.variables
                       if n in result.failed.get(self._group[r.index], {})]
                if bad:
                    v.error = str(result.failed[self._group[r.index]][bad[0]])
                    continue
                if v.error is not None:  # (a topic advertised late that cannot be read)
                    continue
                if g.missing_topics:
                    v.error = "; ".join(self._never(t) for t in g.missing_topics)
                    continue
                finalize(self.plan, r, res, self.plan.bindings, v, la)
                ok.append(r)
            summarize_clocks(la, [verdicts[r.index] for r in ok])
            la.engine = log_engine(verdicts[r.index] for r in ok)
            active = ok
        la.verdicts = [verdicts[r.index] for r in self.plan.requirements
                       if r.index not in self.entities.indexes]
        for v in la.verdicts:
            if v.error is not None:
                v.verdict = "error"
            v.partial = la.partial
        la.verdicts += self.entities.verdicts(la)  # the audit's, over the messages used
        if self.recorder is not None:
            self.recorder.finish(la, recorded_gaps(self.source))
            if result is not None and not self.source.gaps:
                # the numbers behind violated boolean variables: the audit's second pass,
                # over the recording
                operand_values(self.recorder.path, self.plan, self.plan.bindings,
                                list(active), verdicts, result.by_req)
        for v in la.verdicts:
            e = WatchEvent("final", la.end_time_ns, time.time_ns(), v.requirement,
                           verdict=v.verdict,
                           detail=v.error,
                           extra={"ltl3": v.ltl3.status, "violations": v.violations})
            self._event(e)
        return la
