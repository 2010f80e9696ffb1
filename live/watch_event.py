"""The watch's verdict events: what ``fretc watch --jsonl`` prints one per line and the
watch's callbacks receive (:class:`WatchEvent`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["WatchEvent"]


@dataclass
class WatchEvent:
    """One verdict event.

    Attributes:
        kind: ``pt`` | ``ltl3`` | ``problem`` | ``gap`` | ``final`` | ``connected`` |
            ``disconnected`` | ``closed`` (the server's orderly close) | ``end`` (the
            watched run ended; ``detail``: why) | ``unreachable`` (a connection attempt
            failed before the first connection: ``detail`` the URL and the reason,
            ``attempts`` how many so far) | ``waiting`` (bound topics not advertised within
            ``--wait``: the run goes on and waits for them) | ``advertised`` (one of them
            came) | ``publisher`` (a bound topic's publisher left, or came back: a silence,
            no data problem).
        time_ns: on the run's clock (log time or header stamp), when known.
        wall_ns: wall clock (``time.time_ns()``) when the event was produced.
        requirement: the requirement id (verdict events).
        tick: the tick index (verdict events).
        verdict: ``pt``: ``holds`` / ``violated``; ``ltl3``: ``satisfied`` / ``violated``;
            ``final``: the final verdict.
        detail: free text (problems, gaps).
        depends_on: log time (ns) of the newest message the tick's values came from (the
            latency benchmark's join key).
    """

    kind: str
    time_ns: int | None = None
    wall_ns: int = 0
    requirement: str | None = None
    tick: int | None = None
    verdict: str | None = None
    detail: str | None = None
    depends_on: int | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict:
        """The event as one ``--jsonl`` line's object."""
        out = {"event": self.kind, "time_ns": self.time_ns, "wall_ns": self.wall_ns}
        for k in ("requirement", "tick", "verdict", "detail", "depends_on"):
            val = getattr(self, k)
            if val is not None:
                out[k] = val
        out.update(self.extra)
        return out
