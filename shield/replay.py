"""A generated shield run over recorded runs (``fretc shield-replay``): what the Safety
System would have done on the robot's real runs.

The shield is a folder written by ``fretc shield --emit python -b BINDINGS -o DIR`` (its
``*_shield.py`` and the binding file it was built with: :func:`load_folder`). Over one
recording (MCAP, ROS 1 bag, rosbag2 folder: what ``fretc audit`` reads, through the same
reader, :func:`fretc.logs.open_log`, and the same bindings), :func:`replay_log` steps the
shield between messages (:class:`fretc.shield.messages.MessageShield`) once per tick of the
requirements on the clock the audit judges, writes the corrected outputs (ROS 2 CDR) beside
the recorded messages into one MCAP file, and counts the overrides, unreadable inputs and
proposals and broken assumptions per requirement. A damaged recording is replayed over its
intact span. Each step in full: ARCHITECTURE.md ("Shield replay").
"""

from __future__ import annotations

import importlib.util
import os
import tomllib
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fretc.common.errors import FretcError
from fretc.shield.messages import (MessageShield, ShieldInputError, default_message,
                                   originates_of, proposals_of)
from fretc.shield.replay_records import (Channel, Record, RecordedLog, recorded_topic,
                                         write_shielded)
from fretc.signals.bindings.spec import Bindings, grid_end, grid_start

__all__ = ["ShieldFolder", "ReplayError", "ReplayResult", "Span", "load_folder", "replay_log",
           "shielded_name", "MAX_REPLAY_TICKS"]

#: at most this many ticks per recording (a clock that would give more is an input error,
#: as the audit's bound on ticks: ``fretc.signals.bindings.spec.MAX_TICKS``)
MAX_REPLAY_TICKS = 10**8


class ReplayError(FretcError):
    """An input ``fretc shield-replay`` cannot replay: the message names the folder, the
    log, the topic or the log time."""


@dataclass
class ShieldFolder:
    """A shield folder (:func:`load_folder`): ``module`` the generated ``*_shield.py``,
    ``bindings_file`` the binding file beside it, ``shield_class`` its ``Shield``."""

    module: Path
    bindings_file: Path
    shield_class: Any
    requirements: dict[str, tuple[str, str, str]]

    def sources(self) -> list[str]:
        """The requirement files the enforced requirements were read from (their sources'
        paths, as ``fretc shield`` was given them), in order."""
        return list(dict.fromkeys(src.rsplit(":", 1)[0] if ":" in src else src
                                  for _t, src, _pt in self.requirements.values()))


def load_folder(folder: str | os.PathLike[str]) -> ShieldFolder:
    """The shield written into ``folder`` by ``fretc shield --emit python -b BINDINGS -o
    DIR``.

    Raises:
        ReplayError: the folder does not hold exactly one ``*_shield.py`` and one
            ``*.bindings.toml``, or its module defines no ``Shield``."""
    root = Path(folder)
    if not root.is_dir():
        raise ReplayError(f"{folder}: no such folder (a shield folder: fretc shield --emit "
                          "python -b BINDINGS -o DIR)")
    modules = sorted(root.glob("*_shield.py"))
    bindings = sorted(root.glob("*.bindings.toml"))
    if len(modules) != 1 or len(bindings) != 1:
        raise ReplayError(f"{folder}: a shield folder holds one *_shield.py and one "
                          "*.bindings.toml (fretc shield --emit python -b BINDINGS -o DIR); "
                          f"found {len(modules)} and {len(bindings)}")
    spec = importlib.util.spec_from_file_location(modules[0].stem, modules[0])
    if spec is None or spec.loader is None:
        raise ReplayError(f"{modules[0]}: not a Python module")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # (a module that is not fretc's: named, never a traceback)
        raise ReplayError(f"{modules[0]}: cannot be loaded ({type(exc).__name__}: {exc})") \
            from None
    shield_class = getattr(module, "Shield", None)
    if shield_class is None:
        raise ReplayError(f"{modules[0]}: no class Shield (a module fretc shield --emit "
                          "python writes)")
    reqs = getattr(module, "REQUIREMENTS", {})
    return ShieldFolder(modules[0], bindings[0], shield_class,
                        dict(reqs) if isinstance(reqs, dict) else {})


@dataclass
class Span:
    """Ticks of one kind: how many, the first and last log time (ns), and ``why`` (the
    first one's reason, for faults)."""

    ticks: int = 0
    first: int | None = None
    last: int | None = None
    why: str = ""

    def add(self, t: int, why: str = "") -> None:
        """Count a tick at log time ``t`` (ns)."""
        self.ticks += 1
        if self.first is None:
            self.first, self.why = t, why
        self.last = t

    def as_json(self) -> dict[str, Any]:
        """``{"ticks", "first_log_time", "last_log_time"}`` (ns), and ``"why"`` when set."""
        out: dict[str, Any] = {"ticks": self.ticks, "first_log_time": self.first,
                               "last_log_time": self.last}
        if self.why:
            out["why"] = self.why
        return out


@dataclass
class ReplayResult:
    """What :func:`replay_log` did over one recording: ``log`` and ``written`` (the
    shielded MCAP), ``ticks`` stepped (``first_tick``, ``last_tick``: log times, ns),
    ``overrides`` per enforced requirement, ``unshaped`` the overrides of a proposal that is
    no message the bindings give (no requirement broken), ``input_faults`` (the fallback
    published), ``proposal_faults`` (a proposal replaced), ``silent`` (nothing published:
    no fallback), ``broken`` assumption -> the log time it broke, ``published`` messages
    per output topic, ``renamed`` recorded topic -> the topic its messages are kept on,
    ``written_counts`` messages written per topic, ``problems`` the log's data problems
    (text), ``damage`` the recording's damage (None: none; else ``damage_time_ns``, the
    exclusive end of the span replayed, None when the damage lost no message, and
    ``problems``, the readers' words); ``faults`` the ticks at which an input of the shield
    could not be read, ``unanswered`` those of them at which the shield published nothing
    (an input it could not decide on and no fallback; :attr:`answered`)."""

    log: str
    written: str
    ticks: int = 0
    first_tick: int | None = None
    last_tick: int | None = None
    overrides: dict[str, Span] = field(default_factory=dict)
    overridden: Span = field(default_factory=Span)
    unshaped: Span = field(default_factory=Span)
    input_faults: Span = field(default_factory=Span)
    proposal_faults: Span = field(default_factory=Span)
    silent: Span = field(default_factory=Span)
    broken: dict[str, int] = field(default_factory=dict)
    published: dict[str, int] = field(default_factory=dict)
    renamed: dict[str, str] = field(default_factory=dict)
    #: output topics taken as their own proposals (:func:`_proposals`)
    own_proposals: list[str] = field(default_factory=list)
    written_counts: dict[str, int] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    damage: dict[str, Any] | None = None
    faults: Span = field(default_factory=Span)
    unanswered: Span = field(default_factory=Span)

    @property
    def answered(self) -> int:
        """The fault ticks the shield answered: its fallback, or outputs safe for every
        value the unread input could have had, published (:class:`~fretc.shield.runtime.
        Decision` ``fault`` naming the input)."""
        return self.faults.ticks - self.unanswered.ticks

    def as_json(self) -> dict[str, Any]:
        """The result as JSON data (log times in ns)."""
        return {"log": self.log, "shielded": self.written, "ticks": self.ticks,
                "first_tick": self.first_tick, "last_tick": self.last_tick,
                "overridden": self.overridden.as_json(),
                "overrides": {r: s.as_json() for r, s in self.overrides.items()},
                "no_message_overrides": self.unshaped.as_json(),
                "input_faults": self.input_faults.as_json(),
                "proposal_faults": self.proposal_faults.as_json(),
                "nothing_published": self.silent.as_json(),
                "assumptions_broken": dict(self.broken),
                "published": dict(self.published), "recorded_kept_as": dict(self.renamed),
                "own_proposals": list(self.own_proposals),
                "written": dict(self.written_counts), "log_problems": list(self.problems),
                "damage": None if self.damage is None else dict(self.damage),
                "faults": {**self.faults.as_json(), "answered": self.answered,
                           "unanswered": self.unanswered.as_json()}}


def shielded_name(log: str | os.PathLike[str]) -> str:
    """``NAME.shielded.mcap`` for the recording ``log`` (``NAME`` its file name without
    ``.mcap`` or ``.bag``; a rosbag2 folder's name)."""
    name = Path(os.fspath(log).rstrip("/\\")).name
    for suffix in (".mcap", ".bag"):
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
            break
    return f"{name}.shielded.mcap"


def _output_types(bindings_file: Path, bindings: Bindings) -> dict[str, str]:
    """topic -> ROS 2 type: ``[types]``, then ``[shield] types`` over them."""
    doc = tomllib.loads(bindings_file.read_text(encoding="utf-8"))
    table = doc.get("shield", {})
    types = table.get("types", {}) if isinstance(table, dict) else {}
    if not isinstance(types, dict) or not all(isinstance(k, str) and isinstance(v, str)
                                              for k, v in types.items()):
        raise ReplayError(f"{bindings_file}: [shield] types must map topics to ROS 2 types, "
                          "e.g. { \"/scan\" = \"sensor_msgs/msg/LaserScan\" }")
    return {**bindings.types, **types}


class _Outputs:
    """The shield's messages serialized as ROS 2 CDR on their channels (``rosbags``; the
    type store of ROS 2 Jazzy, with the binding file's ``[types] msg_path`` folders)."""

    def __init__(self, bindings: Bindings, types: dict[str, str], where: str):
        if bindings.msg_path:
            from fretc.logs.ros.msg_path import msg_path_typestore

            self.store = msg_path_typestore(bindings.msg_path)
        else:
            from rosbags.typesys import Stores, get_typestore

            self.store = get_typestore(Stores.ROS2_JAZZY)
        unknown = [f"{t} ({n})" for t, n in types.items() if n not in self.store.types]
        if unknown:
            raise ReplayError(f"{where}: no ROS 2 message type of that name for "
                              + ", ".join(unknown) + " (ROS 2 Jazzy's standard types and "
                              "those of [types] msg_path)")
        self.types = types
        self.channels: dict[str, Channel] = {}

    def make(self, topic: str) -> Any:
        """A message of ``topic``'s type with every field at its default."""
        return default_message(self.store, self.types[topic])

    def record(self, topic: str, message: Any, t: int, sequence: int) -> Record:
        """``message`` of ``topic`` serialized at log time ``t`` (ns).

        Raises:
            ReplayError: it cannot be serialized as the topic's type (named, with the log
                time)."""
        name = self.types[topic]
        ch = self.channels.get(topic)
        if ch is None:
            text = self.store.generate_msgdef(name, ros_version=2)[0]
            ch = self.channels[topic] = Channel(topic, "cdr", (name, "ros2msg", text.encode()),
                                                ())
        try:
            data = bytes(self.store.serialize_cdr(message, name))
        except Exception as exc:  # (a proposal of another layout than the topic's type)
            raise ReplayError(f"{topic} at log time {t} ns: the shield's message cannot be "
                              f"written as {name} ({type(exc).__name__}: {exc})") from None
        return Record(t, t, ch, data, sequence)


def _proposals(folder: ShieldFolder, bindings: Bindings, source: Any, log: str
               ) -> tuple[dict[str, str], list[str]]:
    """The proposal topic of each topic the shield publishes on: ``[shield] proposals`` of
    the binding file; an output topic it does not name whose messages the recording holds
    is its own proposal (the outputs bound to what the robot recorded: the recorded command
    is what the controller proposed), listed second and said by the replay; a topic
    ``[shield] originates`` names (one no controller proposes on: the shield's own stop
    request) proposes its default message, as the shield's ROS 2 node does. A hostile finding: a
    replay proposed the default message at every tick where the table was left out, and
    reported "0 overridden" and an all-satisfied audit over a run that needed 569 overrides.

    Raises:
        ReplayError: an output topic with none of these (named, with the tables to give)."""
    proposals = proposals_of(folder.bindings_file)
    originates = set(originates_of(folder.bindings_file))
    runtime = folder.shield_class()
    topics = list(dict.fromkeys(t for m in runtime.machines for g in m.groups
                                for t in g["topics"]))
    recorded = set(source.topics())
    own: list[str] = []
    missing: list[str] = []
    for topic in topics:
        if topic in proposals or topic in originates:
            continue
        if topic in recorded:
            proposals[topic] = topic
            own.append(topic)
        else:
            missing.append(topic)
    if missing:
        raise ReplayError(
            f"{log}: no proposal for {', '.join(missing)}: the recording holds no message of "
            f"{'it' if len(missing) == 1 else 'them'} and {folder.bindings_file} names no "
            "proposal topic in [shield] proposals (e.g. [shield] proposals = { "
            f"\"{missing[0]}\" = \"/cmd_vel\" }}: the topic the controller proposes on), "
            "nor the topic in [shield] originates (a topic the shield alone publishes, e.g. "
            f"originates = [\"{missing[0]}\"]: its default message proposed); a replay never "
            "proposes a default message unasked")
    return proposals, own


def _needed(folder: ShieldFolder, bindings: Bindings, shield: MessageShield,
            source: Any, log: str) -> tuple[set[str], dict[str, str]]:
    """The topics the replay reads (the inputs' and the proposals', the tick topic) and the
    output topics' types.

    Raises:
        ReplayError: a binding file on the header time base, a topic the log does not hold,
            an output topic without a type, an output topic an input reads."""
    if bindings.time_base != "log":
        raise ReplayError(f"{folder.bindings_file}: [tick] time = {bindings.time_base!r}: a "
                          "replay steps the shield on log time (time = \"log\"), where it "
                          "writes its messages")
    runtime = shield.runtime
    inputs = {topic for v in runtime.inputs if shield._read(v)
              for topic in bindings.variables[v].topics}
    outputs = set(shield.output_topics)
    both = sorted(inputs & outputs)
    if both:
        raise ReplayError(f"{folder.bindings_file}: {', '.join(both)} is read by an input and "
                          "published by the shield: a replay cannot tell the recorded "
                          "messages from the shield's")
    recorded = source.topics()
    needed = inputs | set(shield.proposals.values())
    if bindings.tick.topic is not None:
        needed.add(bindings.tick.topic)
    missing = sorted(t for t in needed if t not in recorded)
    if missing:
        damaged = (f", before the damage ({source.problems[0]})"
                   if source.partial and source.problems else "")
        raise ReplayError(f"{log}: no message of {', '.join(missing)}, which the shield reads "
                          f"({folder.bindings_file}: the inputs' bindings, [shield] proposals, "
                          f"the tick topic){damaged}")
    types = _output_types(folder.bindings_file, bindings)
    for corrected, proposal in shield.proposals.items():
        if corrected not in types and proposal in recorded:
            types[corrected] = recorded[proposal]
    for topic in outputs:
        if topic not in types and topic in recorded:
            types[topic] = recorded[topic]
    untyped = sorted(t for t in outputs if t not in types)
    if untyped:
        raise ReplayError(f"{folder.bindings_file}: no ROS 2 type for {', '.join(untyped)}: "
                          f"give it in [shield] types (e.g. \"{untyped[0]}\" = "
                          "\"std_msgs/msg/Bool\")")
    return needed, {t: types[t] for t in sorted(outputs)}


def _ticks(source: Any, needed: set[str], bindings: Bindings, log: str,
           until: int | None = None) -> Iterator[tuple[int | None, Any]]:
    """The messages of ``needed`` and the ticks between them, in order: ``(None, message)``
    for a message, ``(t, None)`` for a tick at log time ``t`` (ns), after every message of
    log time ``t`` or earlier (module docstring); none of log time ``until`` or later (the
    intact span of a damaged recording).

    Raises:
        ReplayError: more than :data:`MAX_REPLAY_TICKS` ticks."""
    period = bindings.tick.period_ns
    tick_topic = bindings.tick.topic
    start = source.start_time
    end_known = source.end_time
    if period is not None and start is not None and end_known is not None and \
            (end_known - start) // period > MAX_REPLAY_TICKS:
        raise ReplayError(f"{log}: more than {MAX_REPLAY_TICKS:,} ticks of "
                          f"{period / 1e6:g} ms from log time {start} ns to {end_known} ns")
    pending: deque[int] = deque()
    next_grid: int | None = None
    last: int | None = None
    for m in source.messages(needed):
        t = int(m.log_time)
        if until is not None and t >= until:
            break
        if period is not None:
            if next_grid is None:
                next_grid = grid_start(t, period)
            while next_grid < t:
                yield next_grid, None
                next_grid += period
        else:
            while pending and pending[0] < t:
                yield pending.popleft(), None
        yield None, m
        if m.topic == tick_topic:
            pending.append(t)
        last = t
    if period is not None and next_grid is not None and last is not None:
        end = grid_end(max(last, source.end_time or last), period)
        while next_grid <= end and (until is None or next_grid < until):
            yield next_grid, None
            next_grid += period
    while pending and (until is None or pending[0] < until):
        yield pending.popleft(), None


def _decide(shield: MessageShield, t: int, result: ReplayResult
            ) -> list[tuple[str, Any]]:
    """One tick of the shield at log time ``t`` (ns): its messages, the decision counted
    in ``result``. A tick whose messages cannot be made publishes the fallback's (as the
    ROS 2 node does), counted with the input faults; without a fallback, nothing."""
    try:
        d, msgs = shield.tick(t)
    except ShieldInputError as exc:
        result.silent.add(t, str(exc))
        if str(exc).startswith("input "):  # (an unread input, and nothing published)
            result.faults.add(t, str(exc))
            result.unanswered.add(t, str(exc))
        return []
    except Exception as exc:  # noqa: BLE001 - the node's rule: the state back, the fallback
        why = f"the shield's messages not made: {type(exc).__name__}: {exc}"
        try:
            msgs = shield.fallback_messages(t)
        except ShieldInputError:
            result.silent.add(t, why)
            return []
        result.input_faults.add(t, why)
        return msgs
    fault = getattr(d, "fault", "")
    for a in getattr(d, "broken", ()):
        result.broken.setdefault(a, t)
    if fault.startswith("input "):  # (answered: the decision for every value, published)
        result.input_faults.add(t, fault)
        result.faults.add(t, fault)
    elif fault:
        result.proposal_faults.add(t, fault)
    if d.overridden:
        result.overridden.add(t)
        if not d.reasons and not fault:
            result.unshaped.add(t)
        for rid in d.reasons:
            result.overrides.setdefault(rid, Span()).add(t)
    return msgs


def _shielded(shield: MessageShield, outputs: _Outputs,
              events: Iterator[tuple[int | None, Any]], result: ReplayResult
              ) -> Iterator[Record]:
    """The shield's messages over ``events`` (:func:`_ticks`), tick by tick in log-time
    order, each decision counted in ``result``."""
    sequence: dict[str, int] = {}
    for t, m in events:
        if t is None:
            shield.hear(m.topic, m.data, int(m.log_time))
            continue
        result.ticks += 1
        result.first_tick = t if result.first_tick is None else result.first_tick
        result.last_tick = t
        for topic, msg in _decide(shield, t, result):
            sequence[topic] = sequence.get(topic, 0) + 1
            result.published[topic] = result.published.get(topic, 0) + 1
            yield outputs.record(topic, msg, t, sequence[topic])


def replay_log(folder: ShieldFolder, log: str | os.PathLike[str], out: str | os.PathLike[str],
               msg_path: tuple[str, ...] = ()) -> ReplayResult:
    """Run the shield of ``folder`` over the recording ``log`` and write the shielded
    recording ``out`` (module docstring); a damaged recording over its intact span, the
    damage in ``result.damage`` and in the written file.

    Raises:
        ReplayError: an input the replay cannot take (named: the folder, the log, the topic,
            the log time), or a damaged recording of which nothing before the damage could
            be read (no file written). FretcError: the log or the binding file cannot be read
            (the readers' own errors). OutputError: ``out`` cannot be written."""
    from fretc.logs import open_log
    from fretc.signals.bindings.files import load_bindings

    log = os.fspath(log)
    bindings = load_bindings(folder.bindings_file)
    source = open_log(log, msg_path=msg_path or bindings.msg_path)
    recorded = RecordedLog(log, source.kind)
    # (a watch's recording carries its gaps: the shielded recording carries them on)
    carried = list(getattr(source, "recorded_gaps", []))
    result = _replay_span(folder, bindings, source, recorded, log, out, None, carried)
    end, gaps, words = _damage(source, recorded)
    if not source.partial and recorded.stopped is None:
        return result
    if end is not None:  # (the span before the damage alone, written again)
        carried = [g for g in carried if g.start is None or g.start < end]
        result = _replay_span(folder, bindings, source, recorded, log, out, end,
                              carried + gaps)
        if not result.written_counts:
            Path(out).unlink(missing_ok=True)
            raise ReplayError(f"{log}: damaged before any message could be read "
                              f"({'; '.join(words) or 'no message read'}): nothing to replay "
                              "(the shield's state after the damage depends on what was "
                              "lost; fretc audit judges the log after a gap)")
    result.damage = {"damage_time_ns": end, "problems": words}
    return result


def _damage(source: Any, recorded: RecordedLog) -> tuple[int | None, list[Any], list[str]]:
    """Where the intact span of a read recording ends (exclusive, ns; None when nothing was
    lost: read to its end), the gap the shielded recording carries from there to the end of
    the run, and the readers' words (the audit reader's problems, then the copying
    reader's)."""
    from fretc.logs.base import Gap
    from fretc.logs.recorded_gaps import RUN_END

    ends = [e for e in (source.intact_end, recorded.intact_end) if e is not None]
    words = [str(p) for p in source.problems[:3]] if source.partial else []
    if recorded.stopped is not None and recorded.stopped not in words:
        words.append(recorded.stopped)
    if not ends:
        return None, [], words
    end = min(ends)
    cause = next((g.cause for g in source.gaps if g.cause), "") or "truncated"
    return end, [Gap(end, RUN_END, None, cause)], words


def _replay_span(folder: ShieldFolder, bindings: Bindings, source: Any, recorded: RecordedLog,
                 log: str, out: str | os.PathLike[str], until: int | None,
                 gaps: list[Any]) -> ReplayResult:
    """One replay over ``source``'s messages before ``until`` (ns; None: all), written to
    ``out`` with ``gaps`` (:func:`replay_log`)."""
    proposals, own = _proposals(folder, bindings, source, log)
    shield = MessageShield(folder.shield_class(), bindings, proposals,
                           lambda topic: outputs.make(topic))
    needed, types = _needed(folder, bindings, shield, source, log)
    outputs = _Outputs(bindings, types, str(folder.bindings_file))
    result = ReplayResult(log=log, written=os.fspath(out), own_proposals=own)
    on_log = set(source.topics())
    result.renamed = {t: recorded_topic(t) for t in sorted(set(types) & on_log)}
    taken = sorted(t for t in result.renamed.values() if t in on_log)
    if taken:
        raise ReplayError(f"{log}: {', '.join(taken)} is recorded already: the recorded "
                          "messages of the topics the shield publishes on cannot be kept "
                          "there")
    # (both streams read as the file is written: memory does not grow with the log)
    result.written_counts = write_shielded(
        out, recorded.records(until),
        _shielded(shield, outputs, _ticks(source, needed, bindings, log, until), result),
        result.renamed, gaps)
    result.problems = [str(p) for p in source.problems]
    return result
