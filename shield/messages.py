"""The shield between messages: inputs read from the bound topics, the controller's proposal
from its own topic, the corrected outputs published as messages (the interceptor's role).

A host (the simulator, :mod:`fretc.sim`; the generated ROS 2 node) hands every message it
hears to :meth:`MessageShield.hear` and calls :meth:`MessageShield.tick` once per tick of the
requirements: the inputs are the bindings sampled and held as the audit samples them, the
proposal the controller's latest message (``[shield] proposals``; older than
``proposal_timeout_ns``: absent), the shield decides
(:class:`fretc.shield.runtime.ShieldRuntime`) and each output topic gets a message, read back
through the bindings before it is published, in an order every reader accepts.
:meth:`MessageShield.answer` decides a proposal when it arrives. Each step in full:
ARCHITECTURE.md ("The shield between messages").
"""

from __future__ import annotations

import copy
import itertools
import math
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fretc.common.problems import SignalError
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import Decision, ShieldRuntime, Unreadable, truth
from fretc.signals.bindings.compile import EvalState, compile_node
from fretc.signals.bindings.expression import Field, FuncCall, UnaryOp
from fretc.signals.bindings.extract import normalize_scalar
from fretc.signals.bindings.operations import Ops
from fretc.signals.bindings.spec import Bindings

__all__ = ["MessageShield", "ShieldInputError", "proposals_of", "default_message"]

#: the most output topics whose publication orders are searched (their permutations)
ORDER_TOPICS = 4


class ShieldInputError(Exception):
    """An input variable cannot be read at this tick (no message yet, a NaN, a missing
    field) and the shield has no fallback: the message says which and why; the host
    decides what to publish."""


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


def originates_of(bindings_file: str | Path | None) -> list[str]:
    """The ``[shield] originates`` list of a binding file: the topics the shield publishes
    that no controller proposes on (the Safety System's own stop request), each tick
    proposing the topic's default message (``shield-replay`` names them; empty when the file
    has none).

    Raises:
        ShieldError: not a list of topic names."""
    if bindings_file is None:
        return []
    doc = tomllib.loads(Path(bindings_file).read_text(encoding="utf-8"))
    listed = doc.get("shield", {}).get("originates", [])
    if not isinstance(listed, list) or not all(
            isinstance(t, str) and t.startswith("/") for t in listed):
        raise ShieldError(f"{bindings_file}: [shield] originates must list topic names, e.g. "
                          "[\"/gwendolen_control\"]")
    return list(listed)


class MessageShield:
    """A shield (``runtime``) between messages (module docstring): ``bindings`` of its
    variables, ``proposals`` corrected topic -> proposal topic, ``make`` topic -> a new
    message of the topic's type with default fields."""

    def __init__(self, runtime: ShieldRuntime, bindings: Bindings, proposals: dict[str, str],
                 make: Callable[[str], Any], proposal_timeout_ns: int | None = None):
        self.runtime = runtime
        #: a proposal older than this (ns) is absent (module docstring); None: never
        self.proposal_timeout_ns = proposal_timeout_ns
        #: corrected topic -> the time (ns) its last proposal was heard
        self.proposal_times: dict[str, int] = {}
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
        #: the proposal topics an input's binding reads (the proposal's value of an output
        #: as an input: ``proposed_velocity = "/cmd_vel.linear.x"``): their messages are
        #: held for the inputs too
        self.proposal_inputs = {t for v in runtime.inputs if v in bindings.variables
                                for t in bindings.variables[v].topics if t in self.by_proposal}
        self.output_topics = list(dict.fromkeys(t for _m, g in self.groups for t in g["topics"]))
        #: the messages of the last tick published (topic -> message)
        self.published: dict[str, Any] = {}
        #: the inputs of the last tick whose inputs were read (the order of a fallback's
        #: messages is chosen with them)
        self.last_inputs: dict[str, Any] | None = None
        #: input variable -> its binding compiled with the log's ±inf read as numbers
        self._inf_kept: dict[str, Callable[[EvalState], Any]] = {}

    def _read(self, v: str) -> bool:
        """Whether the shield's machines read the variable ``v`` (an atom's, or a term's a
        comparison of several variables or a bound reads)."""
        ins, outs = (getattr(self.runtime, "input_kinds", None),
                     getattr(self.runtime, "output_kinds", None))
        if ins is not None and outs is not None:
            return v in ins or v in outs
        return any(s[0] == v for m in self.runtime.machines for s in (*m.ins, *m.outs))

    def hear(self, topic: str, message: Any, time_ns: int) -> None:
        """One message heard at ``time_ns`` (the bindings' time base): held for the inputs,
        or kept as the proposal of its corrected topic."""
        corrected = self.by_proposal.get(topic)
        if corrected is not None:
            self.proposed[corrected] = message
            self.proposal_times[corrected] = time_ns
            if topic not in self.proposal_inputs:
                return
        if topic in self.state.msgs:
            self.state.prev_msgs[topic] = self.state.msgs[topic]
            self.state.prev_times[topic] = self.state.times[topic]
        self.state.msgs[topic] = message
        self.state.times[topic] = time_ns
        self.state.values.clear()

    def tick(self, now_ns: int) -> tuple[Decision, list[tuple[str, Any]]]:
        """The decision of the tick at ``now_ns`` and the messages to publish, one per output
        topic, in a fixed order. All or nothing: when the messages cannot be made the
        shield's state is put back as it was before the tick, and the error raised.

        An input that cannot be read (no message yet, a NaN, a missing field) is any value
        (:meth:`ShieldRuntime.step` decides for all it could have had, ``Decision.fault``
        saying which input and why); an overridden decision's messages are made from each
        topic's default message; a proposal that cannot be read is replaced by the shield
        (:meth:`ShieldRuntime.step`), its topic's message made from the default message,
        never the proposal's.

        Raises:
            ShieldInputError: the shield gives no outputs at this tick (an input it cannot
                decide on and no fallback; an assumption broken without a fallback), the
                state put back as it was."""
        st = self.state
        st.now = now_ns
        st.values.clear()
        props = {t: self.proposed.get(t) or self.make(t) for t in self.output_topics}
        proposal = self._values(props, now_ns, strict=False, every=True)
        for v in [v for v, x in proposal.items() if x is None and not self._read(v)]:
            del proposal[v]  # (an output no requirement reads, not on these topics)
        for v in self.runtime.outputs:
            proposal.setdefault(v, False)
        proposal.update(self._absent(now_ns))
        before = self.runtime.state
        inputs = self._inputs(now_ns)
        d = self.runtime.step(inputs, proposal)
        if not any(isinstance(x, Unreadable) for x in inputs.values()):
            self.last_inputs = inputs
        if getattr(d, "broken", ()) and not d.outputs:
            raise ShieldInputError(f"assumption {', '.join(d.broken)} broken and the "
                                   "shield has no fallback: nothing to publish")
        if _fault(d) and not d.outputs and self.runtime.outputs:
            restore = getattr(self.runtime, "restore", None)
            if restore is not None:
                restore(before)
            raise ShieldInputError(f"{d.fault}: nothing to publish")
        try:
            # (messages made from each topic's default message when a proposal could not be
            # read, an assumption broke or a machine lost its state: the fallback, never
            # the proposal's other fields; at an unreadable input the proposal is readable
            # and its message is corrected as on any tick)
            fresh = _fault(d) and (any(part.startswith("proposal ")
                                       for part in d.fault.split("; "))
                                   or bool(getattr(d, "broken", ()))
                                   or bool(getattr(d, "lost", ())))
            msgs = self._messages(d, props, now_ns, proposal, fresh)
            msgs = self._order(msgs, before, inputs, now_ns)
        except Exception:
            restore = getattr(self.runtime, "restore", None)
            if restore is not None:
                restore(before)
            raise
        self.published.update(msgs)
        return self._as_published(d, msgs, now_ns), msgs

    def answer(self, now_ns: int) -> tuple[Decision, list[tuple[str, Any]]]:
        """:meth:`tick`'s decision and messages for the proposals held at ``now_ns`` (one
        just heard), from the state of the last tick, which it does not move (module
        docstring): the tick's state advances on ticks only.

        Raises:
            ShieldInputError: as :meth:`tick` (the state as it was)."""
        restore = getattr(self.runtime, "restore", None)
        if restore is None:  # (a shield generated before it: nothing to put back)
            raise ShieldInputError("this shield cannot decide between ticks (no restore)")
        before = self.runtime.state
        try:
            return self.tick(now_ns)
        finally:
            restore(before)

    def _absent(self, now_ns: int) -> dict[str, Any]:
        """Each output variable bound to a corrected topic whose proposal is absent at
        ``now_ns`` (older than the timeout: module docstring) -> an :class:`Unreadable`
        saying so; empty without a timeout."""
        limit = self.proposal_timeout_ns
        if limit is None:
            return {}
        out: dict[str, Any] = {}
        for topic, source in self.proposals.items():
            heard = self.proposal_times.get(topic)
            if heard is None or now_ns - heard <= limit:
                continue
            why = f"no proposal on {source} for {(now_ns - heard) / 1e6:.0f} ms"
            for v in self.runtime.outputs:
                b = self.bindings.variables.get(v)
                if b is not None and topic in b.topics and self._read(v):
                    out[v] = Unreadable(f"{v}: {why} (proposal timeout "
                                        f"{limit / 1e6:g} ms: absent)")
        return out

    def _as_published(self, d: Decision, msgs: list[tuple[str, Any]], now_ns: int
                      ) -> Decision:
        """``d`` with each output the published messages carry read back from them (KP-124):
        where two outputs read one field, the number one of them gives is not the decided one
        (the atoms are: :meth:`_gives`), and an output no requirement reads is what its field
        of the published message holds, not the proposal's (a fault's message is made from
        the default message)."""
        held = {**self.published, **dict(msgs)}
        read = self._values(held, now_ns, strict=False, every=True)
        changed = {v: x for v, x in read.items() if v in d.outputs and x is not None
                   and set(self.bindings.variables[v].topics) <= held.keys()
                   and not _same(x, d.outputs[v])}
        return d._replace(outputs={**d.outputs, **changed}) if changed else d

    def fallback_messages(self, now_ns: int) -> list[tuple[str, Any]]:
        """The messages of the shield's fallback (:meth:`ShieldRuntime.fault`; each made
        from its topic's default message), the state untouched: what a host publishes
        when a tick failed for a reason the shield could not decide on.

        Raises:
            ShieldInputError: the shield has no fallback."""
        fault = getattr(self.runtime, "fault", None)
        d = fault("the host's fault", {}) if fault is not None else None
        if d is None or not d.outputs:
            raise ShieldInputError("the shield has no fallback")
        props = {t: self.make(t) for t in self.output_topics}
        return self._messages(d, props, now_ns, {}, True)

    def _inputs(self, now_ns: int) -> dict[str, Any]:
        """The input variables' values at ``now_ns``; a variable whose binding cannot be
        evaluated (no message yet, a missing field, an error) has an
        :class:`fretc.shield.runtime.Unreadable` as its value, naming it and why: the
        shield's step decides for every value it could have had (:mod:`fretc.shield.runtime`)."""
        inputs: dict[str, Any] = {}
        for v in self.runtime.inputs:
            if not self._read(v):
                continue
            try:
                value = self.bindings.variables[v].evaluate(self.state, f" at {now_ns} ns")
                inputs[v] = value if value == value else self._unread_why(v, value)
            except SignalError as exc:
                inputs[v] = Unreadable(f"{v}: {exc}")
            except KeyError as exc:  # a topic not heard yet
                inputs[v] = Unreadable(f"{v}: no message of {exc.args[0]} yet")
            except Exception as exc:  # (any other value the binding cannot read)
                inputs[v] = Unreadable(f"{v}: {type(exc).__name__}: {exc}")
        return inputs

    def _unread_why(self, v: str, nan: Any) -> Any:
        """The input ``v`` whose binding gave NaN: an :class:`Unreadable` naming the value
        when that NaN is a log field's ±inf read as unread (docs/bindings.md, "NaN, ±inf":
        ``[tick] inf = "unread"``, the default), its binding evaluated again with the log's
        ±inf as numbers: ``v is +inf`` or ``v is -inf`` (the binding's value), or ``v reads
        ±inf`` (an expression that makes a number of it); ``nan`` itself otherwise (the
        runtime says ``v is NaN``)."""
        if self.bindings.tick.inf == "value":
            return nan
        b = self.bindings.variables[v]
        if b.window is not None or b.tick_window is not None:
            return nan  # (a window's messages are not held here: its NaN is left as it is)
        variant = self._inf_kept.get(v)
        if variant is None:
            body = b.ast.args[0] if b.aggregate is not None else b.ast  # type: ignore[attr-defined]
            variant = compile_node(body, Ops(False, self.bindings.tick.nan != "false", False),
                                   {}, b.constants)
            self._inf_kept[v] = variant
        try:
            got = normalize_scalar(variant(self.state))
        except Exception:  # (the binding read once already; a variant that fails says nothing)
            return nan
        why = 'a log field\'s ±inf is unread: [tick] inf = "value" reads it as a number'
        if got == math.inf or got == -math.inf:
            return Unreadable(f"{v} is {'+' if got > 0 else '-'}inf ({why})")
        if type(got) in (bool, float) and got == got:
            return Unreadable(f"{v} reads ±inf ({why})")
        return nan

    def _order(self, msgs: list[tuple[str, Any]], before: tuple[Any, ...],
               inputs: dict[str, Any], now_ns: int) -> list[tuple[str, Any]]:
        """``msgs`` in the first order (of their permutations) every proper prefix of which,
        published over the last tick's messages, gives outputs the shield accepts from
        ``before`` (module docstring); ``msgs`` as given when none does or there is no last
        tick."""
        accepts = getattr(self.runtime, "accepts", None)  # (a shield generated before it)
        if accepts is None or len(msgs) < 2 or len(msgs) > ORDER_TOPICS or \
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
                    accepted[key] = accepts(before, inputs, values)
                except (KeyError, ValueError, TypeError):  # (a value the tests cannot read)
                    accepted[key] = False
            return accepted[key]

        for order in itertools.permutations(msgs):
            if all(ok(order[:i]) for i in range(1, len(order))):
                return list(order)
        return msgs

    def _values(self, msgs: dict[str, Any], now_ns: int, strict: bool = True,
                every: bool = False) -> dict[str, Any]:
        """The output variables' values on the messages ``msgs`` (topic -> message); not
        ``strict`` (a proposal), a value its binding cannot give is None (the shield then
        replaces it) instead of the error; ``every``: also the outputs no requirement reads
        that have a binding (else only those the machines read)."""
        st = EvalState()
        st.msgs, st.now = dict(msgs), now_ns
        st.times = {t: now_ns for t in msgs}
        out: dict[str, Any] = {}
        for v in self.runtime.outputs:
            if self._read(v) or (every and v in self.bindings.variables):
                try:
                    out[v] = self.bindings.variables[v].evaluate(st)
                except Exception:
                    if strict:
                        raise
                    out[v] = None
        return out

    def _messages(self, d: Decision, props: dict[str, Any], now_ns: int,
                  proposal: dict[str, Any], fresh: bool = False) -> list[tuple[str, Any]]:
        """One message per output topic giving the decided values (module docstring);
        ``fresh``: made from each topic's default message, never the proposal's (a fault:
        the proposal may hold values the shield could not read)."""
        out: dict[str, Any] = {}
        for m, g in self.groups:
            atoms = [m.outs[j] for j in g["atoms"]]
            truths = [truth(s, d.outputs[s[0]]) for s in atoms]
            key = sum(int(t) << i for i, t in enumerate(truths))
            # (a value the shield changed without an atom: a whole-number output's proposal
            # that was no whole number, runtime._Machine._whole)
            changed = fresh or any(m.texts[j] in d.changed for j in g["atoms"]) or any(
                d.outputs.get(s[0]) != proposal.get(s[0]) for s in atoms if s[1] is not None
            ) or any(not _same(d.outputs.get(v), proposal.get(v))
                     for v in g.get("decides", ()) if v in d.outputs)
            fields = g["fields"].get(key)
            for topic in g["topics"]:
                base = self.make(topic) if fresh else props[topic]
                if not changed and topic in self.proposed:
                    out[topic] = base
                    continue
                msg = None
                for order in self._orders(m, g, d):
                    got = self._decided(base, topic, d, m, g, order)
                    if got is not None and self._gives(m, g, {**props, topic: got}, truths,
                                                       now_ns):
                        msg = got
                        break
                if msg is None and fields is None:
                    raise RuntimeError(f"no message of {topic} gives the decided values")
                for start in ((base, self.make(topic)) if msg is None else ()):
                    # (last, the message the bindings give for the valuation as it is: its
                    # fields give the decided atoms, its numbers are not the decided ones)
                    for order in [*self._orders(m, g, d), ()]:
                        got = self._overlaid(start, topic, fields, d, m, g, order)
                        if self._gives(m, g, {**props, topic: got}, truths, now_ns):
                            msg = got
                            break
                    if msg is not None:
                        break
                if msg is None:
                    raise RuntimeError(f"the message made for {topic} does not give the "
                                       "decided values")
                out[topic] = msg
        return [(t, out[t]) for t in self.output_topics]

    def _orders(self, m: Any, g: dict[str, Any], d: Decision) -> list[tuple[str, ...]]:
        """The orders in which the group's numeric outputs are written into a message
        (:meth:`_decided`): the outputs whose atoms the decision changed last, so that where
        two outputs read one field (``linear_speed = abs(linear.x)`` and ``linear_velocity
        = linear.x``) the corrected one decides it; then the other orders (at most
        :data:`ORDER_TOPICS`! of them). The message must give the decided atoms
        (:meth:`_gives`), whichever order writes it."""
        numeric = [v for v in dict.fromkeys([*(m.outs[j][0] for j in g["atoms"]),
                                             *g.get("decides", ())])
                   if isinstance(d.outputs.get(v), (int, float))
                   and not isinstance(d.outputs.get(v), bool)]
        moved = {m.outs[j][0] for j in g["atoms"] if m.texts[j] in d.changed}
        first = tuple(sorted(numeric, key=lambda v: v in moved))
        if len(numeric) > ORDER_TOPICS:
            return [first]
        return [first] + [o for o in itertools.permutations(numeric) if o != first]

    def _decided(self, base: Any, topic: str, d: Decision, m: Any, g: dict[str, Any],
                 order: tuple[str, ...] | None = None) -> Any | None:
        """The proposal ``base`` of ``topic`` with each numeric output of the group set to
        its decided value, through its binding (a field ``x``, ``-x`` or ``abs(x)``, whose
        sign the proposal keeps), in ``order`` (default: the group's): the message that
        changes what the decision changed and nothing else; None when a decided number has
        another binding."""
        msg = copy.deepcopy(base)
        names = order if order is not None else dict.fromkeys(
            [*(m.outs[j][0] for j in g["atoms"]), *g.get("decides", ())])
        for v in names:
            value = d.outputs.get(v)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                continue
            if v in g.get("decides", ()) and topic not in self.bindings.variables[v].topics:
                continue  # (a bounded or twisted number of the group's other topic)
            if not _write_number(msg, topic, self.bindings.variables[v].ast, float(value)):
                return None
        return msg

    def _overlaid(self, base: Any, topic: str, fields: Any, d: Decision, m: Any,
                  g: dict[str, Any], order: tuple[str, ...] | None = None) -> Any:
        """``base`` with the fields of the message the bindings give for the group's
        valuation, then the decided numbers written over them where their bindings take
        them (:meth:`_decided`): the witness's numbers are the decision's only when the
        runtime took them (a whole-number output takes a whole number instead)."""
        msg = _overlay(base, topic, fields)
        decided = self._decided(msg, topic, d, m, g, order)
        return msg if decided is None else decided

    def _gives(self, m: Any, g: dict[str, Any], msgs: dict[str, Any], truths: list[bool],
               now_ns: int) -> bool:
        """Whether the messages ``msgs`` give the group's atoms the values ``truths`` (a
        message some of whose atoms have no truth value, a NaN the proposal's message held
        in a field no output sets, gives none)."""
        try:
            values = self._values(msgs, now_ns)
            return [truth(m.outs[j], values[m.outs[j][0]]) for j in g["atoms"]] == truths
        except (TypeError, ValueError, SignalError):
            return False


def _same(a: Any, b: Any) -> bool:
    """Two output values alike: booleans as booleans, numbers exactly, NaN as NaN."""
    flags = [isinstance(x, bool) or type(x).__name__ == "bool_" for x in (a, b)]
    if any(flags):
        return all(flags) and bool(a) == bool(b)
    try:
        x, y = float(a), float(b)
    except (TypeError, ValueError):
        return bool(a == b)
    return x == y or (x != x and y != y)


def _fault(d: Decision) -> bool:
    """Whether ``d`` is a fault's decision (``Decision.fault``; a shield generated before
    it has none)."""
    return bool(getattr(d, "fault", ""))


def _write_number(msg: Any, topic: str, e: Any, value: float) -> bool:
    """Set the field of ``msg`` (a message of ``topic``) that the numeric binding ``e``
    reads so that ``e`` gives ``value``: ``e`` a field of ``topic`` (an int field only with
    an integral value), ``-x`` or ``abs(x)`` (``x``'s sign kept, + when it is 0); False
    for any other binding."""
    if isinstance(e, UnaryOp) and e.op == "-":
        return _write_number(msg, topic, e.arg, -value)
    if isinstance(e, FuncCall) and e.func == "abs" and len(e.args) == 1:
        now = _read_number(msg, topic, e.args[0])
        if now is None or value < 0:
            return False
        return _write_number(msg, topic, e.args[0], -value if now < 0 else value)
    if not (isinstance(e, Field) and e.topic == topic and e.path
            and all(isinstance(x, str) for x in e.path)):
        return False
    path = [str(x) for x in e.path]
    owner = msg
    for name in path[:-1]:
        owner = getattr(owner, name, None)
    old = getattr(owner, path[-1], None)
    if isinstance(old, bool) or not isinstance(old, (int, float)):
        return False
    if isinstance(old, int) and not value.is_integer():
        return False
    setattr(owner, path[-1], type(old)(value))
    return True


def _read_number(msg: Any, topic: str, e: Any) -> float | None:
    """The value of the binding ``e`` (a field of ``topic``, or ``-x``) on ``msg``; None
    for another binding."""
    if isinstance(e, UnaryOp) and e.op == "-":
        x = _read_number(msg, topic, e.arg)
        return None if x is None else -x
    if not (isinstance(e, Field) and e.topic == topic and e.path
            and all(isinstance(x, str) for x in e.path)):
        return None
    owner = msg
    for name in e.path:
        owner = getattr(owner, str(name), None)
    return float(owner) if isinstance(owner, (int, float)) and not isinstance(owner, bool) \
        else None


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
