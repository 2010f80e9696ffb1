"""Per-entity requirements in ``fretc watch`` (docs/bindings.md, "One verdict per entity"):
a requirement whose variables read an entity of ``[entities]`` (``$track``) is judged at the
end of the run by the audit's own code (:func:`fretc.audit.entities.log.audit_entities`, through
:func:`fretc.audit.log.audit_log`) over the messages the watch used on the topics those
requirements read, kept in a temporary MCAP while watching (their bytes, schemas and log
times as received: what ``--record`` writes). So its verdicts (one per entity seen, in order
of first appearance, and the one over all entities) equal ``fretc audit``'s of the same
messages by construction. No live ``pt``/``ltl3`` events are made for them (their monitors
are not stepped while watching); their ``final`` events are.

Design notes: ARCHITECTURE.md, `live/entities.py`."""

from __future__ import annotations

import dataclasses
import os
import tempfile
from typing import Any

from fretc.audit.entities.log import entity_of_requirements
from fretc.audit.log import audit_log
from fretc.audit.verdict import LogAudit, Verdict
from fretc.common.problems import BindingError
from fretc.common.streams import log_topics
from fretc.live.record import Recorder
from fretc.signals.bindings.binding import compile_expression
from fretc.signals.bindings.expression import TF_TOPICS, EntityParam

__all__ = ["EntityRecording", "entity_topics"]


def entity_topics(plan: Any, indexes: set[int]) -> set[str]:
    """The topics the requirements of ``plan`` at ``indexes`` read: their variables' (the
    per-entity ones compiled with a placeholder value for every entity), the entities' key
    topics and the tick topic. A per-entity expression that does not compile adds nothing
    (the audit at the end gives its error)."""
    b = plan.bindings
    out: set[str] = {b.tick.topic} if b.tick.topic else set()
    for name, (key, _matching, _hold) in b.entities.items():
        try:
            out |= log_topics(compile_expression(f"entity_{name}", key,
                                                 source=str(b.source)).topics)
        except BindingError:
            pass
    try:
        bound = b.for_entity({name: EntityParam(name) for name in b.entities}).variables
    except BindingError:
        bound = b.variables
    for r in plan.requirements:
        if r.index in indexes:
            for v in r.variables:
                if v in bound:
                    out |= log_topics(bound[v].topics)  # a stream: its topic
    return out


class EntityRecording:
    """The per-entity requirements of ``plan`` in a watch: which they are
    (:attr:`indexes`), the topics they read (:attr:`topics`), the messages of those topics
    kept while watching (:meth:`start`, :meth:`message`) and their verdicts at the end
    (:meth:`verdicts`)."""

    def __init__(self, plan: Any) -> None:
        self.plan = plan
        self.indexes: set[int] = set(entity_of_requirements(plan)) if plan.bindings else set()
        #: requirement index -> the topics it reads
        self.reads = {i: entity_topics(plan, {i}) for i in self.indexes}
        self.topics: set[str] = set().union(*self.reads.values())
        #: topic -> why it cannot be read in this run (:meth:`check`)
        self.unreadable: dict[str, str] = {}
        self.path: str | None = None
        self._recorder: Recorder | None = None

    def check(self, source: Any, url: str) -> None:
        """Once the topics were waited for: the topics read that ``source`` did not
        advertise or cannot decode make their requirements ``error`` at the end, as a
        watch's other requirements (a log without them would judge no entity: vacuous)."""
        tf = set(TF_TOPICS) if set(TF_TOPICS) & set(source.advertised) else set()
        for t in sorted(self.topics):
            if t in tf and t not in source.advertised:
                continue  # (tf() reads /tf and /tf_static: one of them is a whole tree)
            if t not in source.advertised:
                self.unreadable[t] = f"topic {t} is not advertised by {url}"
            elif source.decoders.get(t) is None:
                why = source.schema_errors.get(t, "no decoder")
                self.unreadable[t] = f"topic {t} cannot be read ({why})"

    def start(self, source: Any) -> None:
        """Open the temporary MCAP the kept messages go to (``source``: the
        :class:`~fretc.live.source.WatchSource`, whose advertisements give the schemas)."""
        if not self.indexes or self._recorder is not None:
            return
        fd, self.path = tempfile.mkstemp(prefix="fretc-watch-entities-", suffix=".mcap")
        os.close(fd)
        self._recorder = Recorder(self.path, source)

    def message(self, topic: str, log_time: int, payload: bytes) -> None:
        """Keep one message the watch used (log time in ns, payload as received) when a
        per-entity requirement reads its topic."""
        if self._recorder is not None and topic in self.topics:
            self._recorder.message(topic, log_time, payload)

    def verdicts(self, la: LogAudit) -> list[Verdict]:
        """The per-entity requirements' verdicts over the kept messages (module docstring),
        named by ``la.log`` (the URL), in the audit's order; the temporary file is deleted.
        Without a started recording (the run never connected): one ``error`` verdict each,
        naming ``la.error``."""
        reqs = [r for r in self.plan.requirements if r.index in self.indexes]
        if not reqs:
            return []

        def error(r: Any, why: str) -> Verdict:
            return Verdict(log=la.log, requirement=r.id, text=r.text, source=r.source,
                           verdict="error", error=r.error or why)

        if self._recorder is None:
            return [error(r, f"not watched: {la.error}") for r in reqs]
        bad = {r.index: "; ".join(self.unreadable[t] for t in sorted(self.reads[r.index])
                                  if t in self.unreadable) for r in reqs}
        judged = [r for r in reqs if not bad[r.index]]
        path = self.path
        assert path is not None  # (the recording's, made with the recorder)
        try:
            self._recorder.close()
            got = audit_log(dataclasses.replace(self.plan, requirements=judged),
                            path) if judged else LogAudit(log=la.log)
        finally:
            self._recorder = None
            os.unlink(path)
        out: list[Verdict] = []
        for r in reqs:  # the plan's order, as the audit's
            out += ([error(r, bad[r.index])] if bad[r.index] else
                    [v for v in got.verdicts
                     if v.requirement == r.id or v.requirement.startswith(r.id + "[")])
        for v in out:
            v.log = la.log
            v.error = v.error and v.error.replace(path, la.log)
            v.unknown_reason = v.unknown_reason and v.unknown_reason.replace(path, la.log)
            v.notes = [n.replace(path, la.log) for n in v.notes]
            if la.damage_time_ns is not None:
                _damaged(v, la.damage_time_ns)
            v.partial = la.partial and v.error is None
        return out


def _damaged(v: Verdict, at: int) -> None:
    """``v`` judged over a run damaged from log time ``at`` (ns): unknown unless violated
    before it or an error (module docstring)."""
    fv = v.first_violation
    if v.verdict == "error" or (v.verdict == "violated" and fv is not None
                                and fv.at.time_ns < at):
        return
    v.verdict, v.first_violation = "unknown", None
    v.unknown_reason = (f"the watched run was damaged from log time {at} (a gap or a cut): "
                        "a per-entity requirement is judged over the messages used, and "
                        "what was lost is not judged as if it had not been sent")
