"""The shield between messages: inputs read from the bound topics, the controller's proposal
from its own topic, the corrected outputs published as messages (the interceptor's role).

A host (the simulator, :mod:`fretc.sim`; the generated ROS 2 node) hands every message it
hears to :meth:`MessageShield.hear` and calls :meth:`MessageShield.tick` once per tick of the
requirements. Each tick:

* the **inputs** are the input variables' bindings evaluated on the held messages (sample
  and hold, as the audit samples them: :class:`fretc.signals.bindings.compile.EvalState`);
* the **proposal** is the output variables' bindings evaluated on the controller's latest
  message of each proposal topic, read as if it were on the corrected topic (``[shield]
  proposals`` of the binding file: corrected topic -> proposal topic; Safe-ROS:
  ``/cmd_vel_filtered`` <- ``/cmd_vel``); an output topic with no proposal (the stop request
  ``/gwendolen_control``) is proposed as its default message (every field 0 or false);
* the shield decides (:class:`fretc.shield.runtime.ShieldRuntime`), and each output topic
  gets a message: the proposal itself when none of its atoms changed, else the proposal
  with the fields the bindings' inversion gives the corrected atoms
  (:mod:`fretc.shield.plan`, as ``fretc testgen --bindings`` writes tests); every message is
  read back through the bindings before it is published, and one that would not give the
  decided values is an internal error, never sent;
* the messages are given in an order in which a reader sampling between two of them (a
  recorder's receipt times, the audit's ticks at another phase) sees, at every point, a
  valuation the shield accepts from the tick's state (:meth:`ShieldRuntime.accepts`: the
  held messages of the last tick with the new ones published so far): a stop's zero
  velocity before the stop request is raised, the request lowered before the velocity
  rises again (Safe-ROS's R3). The first such order of the output topics' order is taken
  (up to :data:`ORDER_TOPICS` topics); when none exists, that order itself.
"""

from __future__ import annotations

import copy
import itertools
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fretc.common.problems import SignalError
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import Decision, ShieldRuntime, truth
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.spec import Bindings

__all__ = ["MessageShield", "ShieldInputError", "proposals_of", "default_message"]

#: the most output topics whose publication orders are searched (their permutations)
ORDER_TOPICS = 4


class ShieldInputError(Exception):
    """An input variable cannot be read at this tick (no message yet, a NaN, a missing
    field): the message says which and why; the host decides what to publish."""


def proposals_of(bindings_file: str | Path | None) -> dict[str, str]:
    """The ``[shield] proposals`` table of a binding file: corrected topic -> the topic the
    controller proposes on (empty when the file has none).

    Raises:
        ShieldError: the table is not a table of topic names."""
    if bindings_file is None:
        return {}
    doc = tomllib.loads(Path(bindings_file).read_text(encoding="utf-8"))
    table = doc.get("shield", {}).get("proposals", {})
    if not isinstance(table, dict) or not all(
            isinstance(k, str) and isinstance(v, str) and k.startswith("/") and v.startswith("/")
            for k, v in table.items()):
        raise ShieldError(f"{bindings_file}: [shield] proposals must map each corrected topic "
                          "to the topic the controller proposes on, e.g. "
                          "{ \"/cmd_vel_filtered\" = \"/cmd_vel\" }")
    return dict(table)


class MessageShield:
    """A shield (``runtime``) between messages (module docstring): ``bindings`` of its
    variables, ``proposals`` corrected topic -> proposal topic, ``make`` topic -> a new
    message of the topic's type with default fields."""

    def __init__(self, runtime: ShieldRuntime, bindings: Bindings, proposals: dict[str, str],
                 make: Callable[[str], Any]):
        self.runtime = runtime
        self.bindings = bindings
        self.proposals = dict(proposals)
        self.by_proposal = {p: c for c, p in self.proposals.items()}
        self.make = make
        self.state = EvalState()
        self.proposed: dict[str, Any] = {}
        missing = [v for v in (*runtime.inputs, *runtime.outputs)
                   if v not in bindings.variables and self._read(v)]
        if missing:
            raise ShieldError("no binding for " + ", ".join(missing) + f" in {bindings.source}")
        self.groups = [(m, g) for m in runtime.machines for g in m.groups]
        self.output_topics = list(dict.fromkeys(t for _m, g in self.groups for t in g["topics"]))
        #: the messages of the last tick published (topic -> message)
        self.published: dict[str, Any] = {}

    def _read(self, v: str) -> bool:
        return any(s[0] == v for m in self.runtime.machines for s in (*m.ins, *m.outs))

    def hear(self, topic: str, message: Any, time_ns: int) -> None:
        """One message heard at ``time_ns`` (the bindings' time base): held for the inputs,
        or kept as the proposal of its corrected topic."""
        corrected = self.by_proposal.get(topic)
        if corrected is not None:
            self.proposed[corrected] = message
            return
        if topic in self.state.msgs:
            self.state.prev_msgs[topic] = self.state.msgs[topic]
            self.state.prev_times[topic] = self.state.times[topic]
        self.state.msgs[topic] = message
        self.state.times[topic] = time_ns
        self.state.values.clear()

    def tick(self, now_ns: int) -> tuple[Decision, list[tuple[str, Any]]]:
        """The decision of the tick at ``now_ns`` and the messages to publish, one per output
        topic, in a fixed order.

        Raises:
            ShieldInputError: an input cannot be read at this tick."""
        st = self.state
        st.now = now_ns
        st.values.clear()
        inputs = {}
        for v in self.runtime.inputs:
            if not self._read(v):
                continue
            try:
                inputs[v] = self.bindings.variables[v].evaluate(st, f" at {now_ns} ns")
            except SignalError as exc:
                raise ShieldInputError(f"{v}: {exc}") from None
            except KeyError as exc:  # a topic not heard yet
                raise ShieldInputError(f"{v}: no message of {exc.args[0]} yet") from None
        props = {t: self.proposed.get(t) or self.make(t) for t in self.output_topics}
        proposal = self._values(props, now_ns)
        for v in self.runtime.outputs:
            proposal.setdefault(v, False)
        before = self.runtime.state
        d = self.runtime.step(inputs, proposal)
        msgs = self._order(self._messages(d, props, now_ns), before, inputs, now_ns)
        self.published.update(msgs)
        return d, msgs

    def _order(self, msgs: list[tuple[str, Any]], before: tuple[tuple[int, ...], ...],
               inputs: dict[str, Any], now_ns: int) -> list[tuple[str, Any]]:
        """``msgs`` in the first order (of their permutations) every proper prefix of which,
        published over the last tick's messages, gives outputs the shield accepts from
        ``before`` (module docstring); ``msgs`` as given when none does or there is no last
        tick."""
        if len(msgs) < 2 or len(msgs) > ORDER_TOPICS or \
                not all(t in self.published for t, _m in msgs):
            return msgs
        accepted: dict[frozenset[str], bool] = {}  # published topics -> accepted

        def ok(prefix: tuple[tuple[str, Any], ...]) -> bool:
            key = frozenset(t for t, _m in prefix)
            if key not in accepted:
                values = self._values({**self.published, **dict(prefix)}, now_ns)
                for v in self.runtime.outputs:
                    values.setdefault(v, False)
                try:
                    accepted[key] = self.runtime.accepts(before, inputs, values)
                except (KeyError, ValueError, TypeError):  # (a value the tests cannot read)
                    accepted[key] = False
            return accepted[key]

        for order in itertools.permutations(msgs):
            if all(ok(order[:i]) for i in range(1, len(order))):
                return list(order)
        return msgs

    def _values(self, msgs: dict[str, Any], now_ns: int) -> dict[str, Any]:
        """The output variables' values on the messages ``msgs`` (topic -> message)."""
        st = EvalState()
        st.msgs, st.now = dict(msgs), now_ns
        st.times = {t: now_ns for t in msgs}
        out = {}
        for v in self.runtime.outputs:
            if self._read(v):
                out[v] = self.bindings.variables[v].evaluate(st)
        return out

    def _messages(self, d: Decision, props: dict[str, Any], now_ns: int
                  ) -> list[tuple[str, Any]]:
        out: dict[str, Any] = {}
        for m, g in self.groups:
            atoms = [m.outs[j] for j in g["atoms"]]
            truths = [truth(s, d.outputs[s[0]]) for s in atoms]
            key = sum(int(t) << i for i, t in enumerate(truths))
            changed = any(m.texts[j] in d.changed for j in g["atoms"])
            fields = g["fields"].get(key)
            for topic in g["topics"]:
                base = props[topic]
                if not changed and topic in self.proposed:
                    out[topic] = base
                    continue
                if fields is None:
                    raise RuntimeError(f"no message of {topic} gives the decided values")
                msg = _overlay(base, topic, fields)
                if not self._gives(m, g, {**props, topic: msg}, truths, now_ns):
                    msg = _overlay(self.make(topic), topic, fields)
                    if not self._gives(m, g, {**props, topic: msg}, truths, now_ns):
                        raise RuntimeError(f"the message made for {topic} does not give the "
                                           "decided values")
                out[topic] = msg
        return [(t, out[t]) for t in self.output_topics]

    def _gives(self, m: Any, g: dict[str, Any], msgs: dict[str, Any], truths: list[bool],
               now_ns: int) -> bool:
        values = self._values(msgs, now_ns)
        return [truth(m.outs[j], values[m.outs[j][0]]) for j in g["atoms"]] == truths


def _overlay(message: Any, topic: str, fields: list[tuple[str, list[str], Any]]) -> Any:
    """A copy of ``message`` with the ``fields`` of ``topic`` set (attribute paths; a
    one-element list value sets a whole array)."""
    msg = copy.deepcopy(message)
    for t, path, value in fields:
        if t != topic:
            continue
        owner = msg
        for name in path[:-1]:
            owner = getattr(owner, name)
        old = getattr(owner, path[-1])
        if isinstance(value, bool) or not isinstance(old, (int, float)) or isinstance(old, bool):
            setattr(owner, path[-1], value)
        else:
            setattr(owner, path[-1], type(old)(value))
    return msg


def default_message(store: Any, typename: str) -> Any:
    """A message of ``typename`` (``pkg/msg/Type``, held in the rosbags type store ``store``)
    with every field at its default: 0, false, "", empty sequences, fixed arrays of defaults.

    Raises:
        KeyError: a type the store does not hold."""
    import numpy as np

    fields = {}
    for name, (kind, detail) in store.get_msgdef(typename).fields:
        fields[name] = _default_field(store, int(kind), detail, np)
    return store.types[typename](**fields)


_NUMPY = {"bool": "bool", "byte": "uint8", "char": "uint8", "int8": "int8", "uint8": "uint8",
          "int16": "int16", "uint16": "uint16", "int32": "int32", "uint32": "uint32",
          "int64": "int64", "uint64": "uint64", "float32": "float32", "float64": "float64"}


def _default_field(store: Any, kind: int, detail: Any, np: Any) -> Any:
    """The default of one field (rosbags' node types: 1 base, 2 name, 3 array, 4 sequence)."""
    if kind == 1:
        base = detail[0]
        return "" if base in ("string", "wstring") else False if base == "bool" else (
            0.0 if base.startswith("float") else 0)
    if kind == 2:
        return default_message(store, detail)
    (sub_kind, sub_detail), length = detail[0], detail[1]
    if int(sub_kind) == 1 and sub_detail[0] in _NUMPY:
        return np.zeros(length if kind == 3 else 0, dtype=_NUMPY[sub_detail[0]])
    return [_default_field(store, int(sub_kind), sub_detail, np)
            for _ in range(length if kind == 3 else 0)]
