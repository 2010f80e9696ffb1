"""PX4 flight logs (ULog, ``*.ulg``) as a :class:`~fretc.logs.base.LogSource`, read with
``pyulog`` (PX4's own ULog library; format: PX4 "ULog File Format" documentation).

Topics are named as Foxglove names them when it opens a ``.ulg``: one per logged uORB topic
(instance *k* > 0 as ``NAME/k``), ``NAME/*`` every instance with a field ``multi_id`` (the
instances as entities), ``Log`` (PX4's text messages) and ``Parameter``; message types are
``px4_msgs/msg/<CamelName>`` (:func:`ulog_schemas`). Log time is the message's
``timestamp`` (microseconds of the flight controller's clock) in ns, non-decreasing over all
topics. Early timestamps are an :data:`EARLY_TIMESTAMP` problem; dropouts (:data:`DROPOUT`),
cut files and damaged spans are damage, a gap of the log. The topics, fields, times and
damage in full, and how a ULog is read: ARCHITECTURE.md ("PX4 flight logs").
"""

from __future__ import annotations

import copy
import os
import re
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import numpy as np

from fretc.common.problems import LogError
from fretc.logs.base import LogSource, Message
from fretc.logs.field_select import field_tree
from fretc.logs.flight.ulog_fast import read_sound
from fretc.logs.flight.ulog_framing import segment_bytes, ulog_framing

__all__ = ["UlogSource", "LOG_TOPIC", "PARAMETER_TOPIC", "DROPOUT", "EARLY_TIMESTAMP",
           "ALL_INSTANCES", "INSTANCE_FIELD", "ulog_type_name", "ulog_definition"]

#: PX4's logged text messages.
LOG_TOPIC = "Log"
#: Parameter changes during the flight.
PARAMETER_TOPIC = "Parameter"
#: The suffix of the topic of every instance of a uORB message (``sensor_gps/*``, module
#: docstring), whose messages carry :data:`INSTANCE_FIELD`.
ALL_INSTANCES = "/*"
#: The field of a message of an :data:`ALL_INSTANCES` topic giving its instance (multi_id).
INSTANCE_FIELD = "multi_id"
#: A ULog dropout: the logger lost messages for ``end - start``.
DROPOUT = "dropout"
#: A message whose ``timestamp`` says nothing of when it was logged (0: never set; a row
#: after a topic's first stamped before the log's start: a value kept from boot), skipped.
EARLY_TIMESTAMP = "early_timestamp"

_ROS_TYPES = {"int8_t": "int8", "uint8_t": "uint8", "int16_t": "int16", "uint16_t": "uint16",
              "int32_t": "int32", "uint32_t": "uint32", "int64_t": "int64",
              "uint64_t": "uint64", "float": "float32", "double": "float64", "bool": "bool",
              "char": "char"}
#: ULog's syslog levels (0 emergency .. 7 debug) on the rosgraph_msgs/Log scale
_LEVELS = {0: 16, 1: 16, 2: 16, 3: 8, 4: 4, 5: 2, 6: 2, 7: 1}
_LOG_DEFINITION = ("uint8 DEBUG=1\nuint8 INFO=2\nuint8 WARN=4\nuint8 ERROR=8\nuint8 FATAL=16\n"
                   "uint8 level\nstring msg\nuint16 tag\n")
_PARAMETER_DEFINITION = "string name\nfloat64 value\n"
_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?")


def ulog_type_name(name: str) -> str:
    """The message type of uORB message ``name``: ``vehicle_status`` ->
    ``px4_msgs/msg/VehicleStatus`` (the naming of PX4's ROS 2 ``px4_msgs``)."""
    return "px4_msgs/msg/" + "".join(p[:1].upper() + p[1:] for p in name.split("_") if p)


def ulog_definition(formats: dict, name: str) -> str:
    """The ROS 2 message definition text (``ros2msg``, dependencies appended as
    ``MSG: pkg/msg/Type`` sections, as MCAP schemas hold them) of uORB message ``name`` from
    pyulog's ``message_formats``. Raises KeyError for a format the log does not define."""
    seen: list[str] = []
    out: list[str] = []

    def define(n: str) -> str:
        lines = []
        for typ, size, field in formats[n].fields:
            if field.startswith("_padding"):
                continue
            if typ == "char":
                lines.append(f"string {field}")
                continue
            ros = _ROS_TYPES.get(typ)
            if ros is None:  # a nested uORB message
                ros = ulog_type_name(typ)
                if typ not in seen:
                    seen.append(typ)
                    out.append(f"MSG: {ros}\n" + define(typ))
            lines.append(f"{ros}[{size}] {field}" if size else f"{ros} {field}")
        return "\n".join(lines) + "\n"

    top = define(name)
    return top + "".join("=" * 80 + "\n" + part for part in out)


class UlogSource(LogSource):
    """A PX4 ULog file (module docstring). Opening reads it whole (one pass of pyulog, the
    rows kept for every pass over the messages).

    Raises:
        LogError: the file is not a ULog file pyulog can read (names the file and why).
    """

    kind = "ulog"

    def __init__(self, path: str | os.PathLike) -> None:
        super().__init__(path)
        self._ulogs, self.framing = self._read_runs()
        ulog = self._ulog = self._ulogs[0]
        self.formats = ulog.message_formats
        self._topics: dict[str, str] = {}
        self._subs: dict[str, tuple[str, int]] = {}  # topic -> (message name, instance)
        for u in self._ulogs:
            for d in u.data_list:
                topic = d.name if d.multi_id == 0 else f"{d.name}/{d.multi_id}"
                self._topics[topic] = ulog_type_name(d.name)
                self._subs[topic] = (d.name, d.multi_id)
                # every instance on one topic (module docstring); multi_id -1 stands for all
                if all(f != INSTANCE_FIELD for _t, _n, f in self.formats[d.name].fields):
                    self._topics[d.name + ALL_INSTANCES] = (ulog_type_name(d.name)
                                                            + "Instances")
                    self._subs[d.name + ALL_INSTANCES] = (d.name, -1)
            if u.logged_messages or u.logged_messages_tagged:
                self._topics[LOG_TOPIC] = "rosgraph_msgs/msg/Log"
            if u.changed_parameters:
                self._topics[PARAMETER_TOPIC] = "px4_msgs/msg/Parameter"
        self._topics = dict(sorted(self._topics.items()))
        #: the ULog header's start (ns): earlier timestamps are skipped (module docstring)
        self.log_start = int(ulog.start_timestamp) * 1000
        # dropouts from the read of every topic: pyulog dates one by the last timestamp it
        # parsed before it, so a read of fewer topics would date it earlier; in a run after
        # damage, one before the run's first data is dated at the damage's end
        self.dropouts = []
        for k, u in enumerate(self._ulogs):
            floor = self._run_floor(k)
            self.dropouts += [(max(int(d.timestamp) * 1000, floor), int(d.duration))
                              for d in u.dropouts]
        times = [int(t) * 1000 for u in self._ulogs for d in u.data_list
                 for t in _timestamps(d)[:1] if t != 0]
        self._start_time = min(times) if times else None
        self._end_time = None
        #: the log's end (ns): the last log time of any message :meth:`messages` delivers
        #: reading every topic (the uORB topics, ``Log``, ``Parameter``), known once the file
        #: is open, whichever topics a pass reads; None for a log of no message. A clock
        #: reading ``age()`` ticks to it, as on an MCAP to its summary's end
        #: (:func:`fretc.signals.clock.silence_end`; issue 91: a GPS that died before the
        #: end of the flight was never stale)
        self.log_end: int | None = self._last_time()
        self._opened = (self._start_time, self._open_problems)

    def _last_time(self) -> int | None:
        """The last log time (ns) of a message of any topic (:attr:`log_end`): each topic's
        timestamps kept as :meth:`messages` keeps them (:func:`_stamped`)."""
        last = None
        for k, u in enumerate(self._ulogs):
            streams = [(_timestamps(d).astype(np.int64) * 1000, True) for d in u.data_list]
            if u.logged_messages or getattr(u, "logged_messages_tagged", None):
                streams.append((_log_stream(u)[1], False))
            if u.changed_parameters:
                streams.append((np.maximum(_parameter_stream(u)[1], self._run_floor(k)),
                                False))
            for t, sampled in streams:
                kept = t[_stamped(t, self.log_start, sampled)]
                if len(kept):
                    end = int(kept.max())
                    last = end if last is None else max(last, end)
        return last

    def _run_floor(self, k: int) -> int:
        """The earliest log time (ns) of run ``k`` (after damage: the damage's end)."""
        if k == 0:
            return -(2**63)
        d = [x for x in self.framing.damages if x.next_time_us is not None][k - 1]
        return d.next_time_us * 1000

    def _read_runs(self):
        """The pyulog reads of the file's intact runs (:mod:`fretc.logs.flight.ulog_framing`): the
        whole file in one read when its framing is sound."""
        import io

        try:
            with open(self.path, "rb") as f:
                data = f.read()
        except OSError as exc:
            raise LogError(self.path, f"cannot read: {exc.strerror or exc}") from None
        sound = read_sound(data)  # one walk and numpy gathers: a sound file's read
        if sound is not None:
            return [sound[0]], sound[1]
        framing = ulog_framing(data)
        if not framing.damages:
            return [self._read(None)], framing
        if not framing.runs:
            raise LogError(self.path, "not a readable PX4 ULog file (damaged before its "
                                      f"first data: {framing.damages[0].detail})")
        return [self._read(None, io.BytesIO(segment_bytes(data, framing, k)))
                for k in range(len(framing.runs))], framing

    def reopen(self) -> UlogSource:
        """A new source of this file from the rows read when it was opened (the operands
        pass of a violated requirement reads them again without a second pyulog read)."""
        new = copy.copy(self)
        new._start_time, problems = self._opened
        new._open_problems = copy.deepcopy(problems)
        new._end_time = None
        new._decoders, new._no_decoder, new._wanted_fields = {}, {}, None
        new._begin_pass()
        return new

    def _read(self, names: list[str] | None, file=None):
        import contextlib
        import io

        from pyulog import ULog  # lazy: only for flight logs

        try:  # pyulog prints its warnings (a corrupt file): the problems report the damage
            with contextlib.redirect_stdout(io.StringIO()):
                return ULog(file if file is not None else str(self.path),
                            message_name_filter_list=names,
                            disable_str_exceptions=True)
        except Exception as exc:  # pyulog raises plain exceptions on any malformed input
            raise LogError(self.path, f"not a readable PX4 ULog file ({type(exc).__name__}: "
                                      f"{exc})") from None

    def topics(self) -> dict[str, str]:
        """Topic -> message type (module docstring)."""
        return dict(self._topics)

    def definitions(self) -> dict[str, tuple[str, str]]:
        """Topic -> (message type, ROS 2 definition text) of every topic."""
        out = {}
        for topic, typ in self._topics.items():
            if topic == LOG_TOPIC:
                out[topic] = (typ, _LOG_DEFINITION)
            elif topic == PARAMETER_TOPIC:
                out[topic] = (typ, _PARAMETER_DEFINITION)
            else:
                name, multi = self._subs[topic]
                text = ulog_definition(self.formats, name)
                if multi < 0:  # (the instance field after the message's own, before its
                    own, sep, rest = text.partition("=" * 80)  # nested types' sections)
                    text = own + f"uint8 {INSTANCE_FIELD}\n" + sep + rest
                out[topic] = (typ, text)
        return out

    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """The messages of ``topics`` (all when None) in non-decreasing log time; dropouts
        are recorded as gaps before the first message is delivered (they are in the file's
        header order, known once it is read)."""
        self._begin_pass()
        want = set(self._topics) if topics is None else set(topics) & set(self._topics)
        for d in self.framing.damages:
            start = None if d.last_time_us is None else d.last_time_us * 1000
            end = None if d.next_time_us is None else d.next_time_us * 1000
            self._gap(start, end, cause=d.kind)
            self._problem(d.kind, None, start, d.detail + (
                " (only the span before it is judged)" if end is None else
                " (the messages between are lost: nothing is held over them)"), end_time=end)
        for start, ms in self.dropouts:
            end = start + ms * 1_000_000
            self._gap(start, end, cause=DROPOUT)
            self._problem(DROPOUT, None, start,
                          f"the logger dropped messages for {ms} ms (ULog dropout record) "
                          "after this log time: a gap (its ticks are unknown), the log is "
                          "read on after it",
                          end_time=end)
        streams: list[tuple[str, Any, Any]] = []  # (topic, log times, rows)
        for k, ulog in enumerate(self._ulogs):
            for d in ulog.data_list:
                topic = d.name if d.multi_id == 0 else f"{d.name}/{d.multi_id}"
                if topic in want:
                    streams.append((topic, d.data["timestamp"].astype(np.int64) * 1000,
                                    _Rows(d.data, ulog.message_formats, d.name,
                                          field_tree(self._fields_for(topic)))))
                every = d.name + ALL_INSTANCES
                if every in want:  # (this instance's messages on the topic of them all)
                    streams.append((every, d.data["timestamp"].astype(np.int64) * 1000,
                                    _Rows(d.data, ulog.message_formats, d.name,
                                          field_tree(self._fields_for(every)),
                                          instance=int(d.multi_id))))
            if LOG_TOPIC in want:
                streams.append(_log_stream(ulog))
            if PARAMETER_TOPIC in want:  # a change before the run's first data: at its floor
                name, t, rows = _parameter_stream(ulog)
                streams.append((name, np.maximum(t, self._run_floor(k)), rows))
        yield from self._merged(streams)

    def _merged(self, streams) -> Iterator[Message]:
        if not streams:
            return
        keeps = []
        for topic, t, _r in streams:
            keep = _stamped(t, self.log_start, topic not in (LOG_TOPIC, PARAMETER_TOPIC))
            keeps.append(keep)
            if not keep.all():
                skipped = t[~keep]
                self._problem(EARLY_TIMESTAMP, topic, int(skipped[0]),
                              f"{len(skipped)} message(s) with a timestamp that says nothing "
                              f"of when they were logged skipped (0: never set; or stamped "
                              f"before the log's start, {self.log_start // 1000} us, after the "
                              "topic's first sample: a timestamp kept while the message was "
                              "logged again and again)")
        times = np.concatenate([t for _n, t, _r in streams])
        which = np.concatenate([np.full(len(t), k, dtype=np.int32)
                                for k, (_n, t, _r) in enumerate(streams)])
        rows = np.concatenate([np.arange(len(t)) for _n, t, _r in streams])
        order = np.argsort(times, kind="stable")
        order = order[np.concatenate(keeps)[order]]
        for i in order:
            topic, t, rows_of = streams[which[i]]
            lt = int(times[i])
            data = rows_of.row(int(rows[i]))
            self.counts[topic] = self.counts.get(topic, 0) + 1
            if self._start_time is None or lt < self._start_time:
                self._start_time = lt
            self._end_time = lt
            yield Message(topic, lt, lt, None, data)


def _timestamps(data: Any) -> np.ndarray:
    """The ``timestamp`` column of a pyulog data set (µs), without gathering its other
    columns when :mod:`fretc.logs.flight.ulog_fast` read it."""
    times = getattr(data, "timestamps", None)
    return times if times is not None else data.data["timestamp"]


def _stamped(t: np.ndarray, log_start: int, sampled: bool) -> np.ndarray:
    """The rows of one topic whose timestamp ``t`` (ns, in file order) is a log time (module
    docstring): not 0, and at or after ``log_start`` (the ULog header's start) unless it is
    the first row of a uORB topic (``sampled``: the last sample PX4's logger writes when it
    subscribes; text messages and parameter changes have no such row)."""
    keep = (t >= log_start) & (t != 0)
    if sampled and len(t) and t[0] != 0:
        keep[0] = True
    return keep


class _Rows:
    """Row ``i`` of a pyulog data set as a message object: one attribute per field, arrays
    as numpy arrays (``output[0]``, ``output[1]``, ... joined), nested uORB messages as
    objects, ``char[N]`` as a string; with ``tree`` (:func:`fretc.logs.field_select.field_tree`
    of the fields the bindings read) only those fields."""

    def __init__(self, data: dict[str, np.ndarray], formats: dict, name: str,
                 tree: dict | None = None, instance: int | None = None) -> None:
        self.data = data
        self.plan = _plan(formats, name, "", tree)
        self.stacked: dict[str, np.ndarray] = {}
        self.lists: dict[str, list] = {}  # a scalar column as Python values (``.item()``)
        #: the instance (multi_id) each row carries as :data:`INSTANCE_FIELD` (None: none,
        #: a topic of one instance)
        self.instance = instance

    def row(self, i: int) -> Any:
        out = self._build(self.plan, i)
        if self.instance is not None:
            setattr(out, INSTANCE_FIELD, self.instance)
        return out

    def _build(self, plan, i: int) -> Any:
        out = SimpleNamespace()
        for field, how, arg in plan:
            if how == "scalar":
                column = self.lists.get(arg)
                if column is None:
                    column = self.lists[arg] = self.data[arg].tolist()
                value = column[i]
            elif how == "array":
                arr = self.stacked.get(field + arg[0])
                if arr is None:
                    arr = self.stacked[field + arg[0]] = np.stack(
                        [self.data[c] for c in arg], axis=1)
                value = arr[i]
            elif how == "string":
                value = bytes(int(self.data[c][i]) for c in arg).split(b"\0", 1)[0].decode(
                    "utf-8", "replace")
            elif how == "nested":
                value = self._build(arg, i)
            else:  # nested array
                value = [self._build(p, i) for p in arg]
            setattr(out, field, value)
        return out


def _plan(formats: dict, name: str, prefix: str, tree: dict | None = None
          ) -> list[tuple[str, str, Any]]:
    """How to build a message of uORB type ``name`` from pyulog's flattened column names
    under ``prefix``: (field, how, columns or sub-plans); only the fields of ``tree`` when
    given (None: every field)."""
    plan: list[tuple[str, str, Any]] = []
    for typ, size, field in formats[name].fields:
        if field.startswith("_padding") or (tree is not None and field not in tree):
            continue
        sub = None if tree is None else tree[field]
        base = prefix + field
        if typ in _ROS_TYPES:
            if typ == "char" and size:
                plan.append((field, "string", [f"{base}[{k}]" for k in range(size)]))
            elif size:
                plan.append((field, "array", [f"{base}[{k}]" for k in range(size)]))
            else:
                plan.append((field, "scalar", base))
        elif size:
            plan.append((field, "nested_array",
                         [_plan(formats, typ, f"{base}[{k}].") for k in range(size)]))
        else:
            plan.append((field, "nested", _plan(formats, typ, base + ".", sub)))
    return plan


class _Listed:
    """Rows of a message list (logged text, parameter changes) as message objects."""

    def __init__(self, items: list[SimpleNamespace]) -> None:
        self.items = items

    def row(self, i: int) -> Any:
        return self.items[i]


def _log_stream(ulog) -> tuple[str, np.ndarray, _Listed]:
    items = [(int(m.timestamp), SimpleNamespace(level=_LEVELS.get(int(m.log_level) & 7, 2),
                                                msg=m.message, tag=0))
             for m in ulog.logged_messages]
    for tag, msgs in (getattr(ulog, "logged_messages_tagged", None) or {}).items():
        items += [(int(m.timestamp), SimpleNamespace(level=_LEVELS.get(int(m.log_level) & 7, 2),
                                                     msg=m.message, tag=int(tag)))
                  for m in msgs]
    items.sort(key=lambda x: x[0])
    times = np.array([t for t, _ in items], dtype=np.int64) * 1000
    return LOG_TOPIC, times, _Listed([m for _, m in items])


def _parameter_stream(ulog) -> tuple[str, np.ndarray, _Listed]:
    items = sorted(((int(t), SimpleNamespace(name=str(n), value=float(v)))
                    for t, n, v in ulog.changed_parameters), key=lambda x: x[0])
    times = np.array([t for t, _ in items], dtype=np.int64) * 1000
    return PARAMETER_TOPIC, times, _Listed([m for _, m in items])
