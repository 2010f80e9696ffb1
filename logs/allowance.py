"""A reaction allowance: some topics of a log read as if logged a fixed time earlier.

A reader of the bus sees a shield node's answers later than the ticks they answer: by the
node's latency and its sampling phase (docs/guide/shield.md, "The bus allowance"). An audit
of a recording made beside the node reads those answers with the allowance
(``fretc audit --allowance /cmd_vel_filtered=120ms``, or ``[audit] allowance`` of a binding
file): each message of such a topic is read at its time minus the allowance (log time, and
``header.stamp`` under the header time base), so that an answer that arrived within the
allowance after its tick is judged at that tick.

May import: :mod:`fretc.logs.base`, :mod:`fretc.common`.

Design notes: ARCHITECTURE.md, `logs/allowance.py`."""

from __future__ import annotations

import heapq
import re
from collections.abc import Iterator, Mapping
from typing import Any, cast

from fretc.common.units import format_ns, parse_duration
from fretc.logs.base import Gap, LogSource, Message

__all__ = ["AllowanceSource", "with_allowance", "parse_allowance", "allowance_text"]

_ZERO = re.compile(r"\s*0*\.?0*\s*(ns|us|µs|ms|s|sec|secs|seconds?|milliseconds?"
                   r"|microseconds?|nanoseconds?)?\s*\Z", re.IGNORECASE)


def parse_allowance(text: str) -> int:
    """An allowance in integer ns: a duration (``"120 ms"``, ``"0.12 s"``) or zero
    (``"0ms"``: the same reading as none).

    Raises:
        ValueError: a negative duration, a frequency, or text that is not a duration
            (the message says which)."""
    t = str(text).strip()
    if t.startswith("-"):
        raise ValueError(f"{t!r}: an allowance cannot be negative (a topic read later than "
                         "it was logged)")
    if t and _ZERO.match(t) and any(c.isdigit() for c in t):
        return 0
    if t.lower().endswith("hz"):
        raise ValueError(f"{t!r}: an allowance is a time (e.g. '120 ms'), not a frequency")
    return parse_duration(t)


def allowance_text(allowance: Mapping[str, int]) -> str:
    """The allowance in words, topics sorted: ``/cmd_vel_filtered read 120 ms earlier``
    (``; `` between topics); empty for none."""
    return "; ".join(f"{t} read {format_ns(ns) if ns else '0 ms'} earlier"
                     for t, ns in sorted(allowance.items()))


def with_allowance(source: LogSource, allowance: Mapping[str, int] | None) -> LogSource:
    """``source`` read with ``allowance`` (topic -> ns, each >= 0): an
    :class:`AllowanceSource`, or ``source`` itself when no topic has a positive one."""
    shift = {t: int(ns) for t, ns in (allowance or {}).items() if ns > 0}
    if not shift:
        return source
    return cast(LogSource, AllowanceSource(source, shift))


class AllowanceSource:
    """A :class:`~fretc.logs.base.LogSource` whose topics of ``shift`` (topic -> ns > 0) are
    read that much earlier (module docstring). Everything it does not override is the
    wrapped source's (attributes read and written through)."""

    _OWN = frozenset({"_inner", "_shift", "_lead"})

    def __init__(self, inner: LogSource, shift: Mapping[str, int]) -> None:
        object.__setattr__(self, "_inner", inner)
        object.__setattr__(self, "_shift", dict(shift))
        object.__setattr__(self, "_lead", max(shift.values()))

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self._OWN:
            object.__setattr__(self, name, value)
        else:
            setattr(self._inner, name, value)

    def __repr__(self) -> str:
        return f"<AllowanceSource {self._shift} of {self._inner!r}>"

    @property
    def allowance(self) -> dict[str, int]:
        """Topic -> ns its messages are read earlier."""
        return dict(self._shift)

    # -- the messages -------------------------------------------------------------------------
    def messages(self, topics: set[str] | frozenset[str] | None = None) -> Iterator[Message]:
        """The wrapped source's messages of ``topics``, each of a shifted topic at its time
        minus its allowance, in non-decreasing (shifted) log time; ties in the order the
        log holds them."""
        shift, lead = self._shift, self._lead
        heap: list[tuple[int, int, Message]] = []
        seq = 0
        for m in self._inner.messages(topics):
            a = shift.get(m.topic, 0)
            out = m if not a else m._replace(
                log_time=m.log_time - a,
                header_stamp=None if m.header_stamp is None else m.header_stamp - a)
            heapq.heappush(heap, (out.log_time, seq, out))
            seq += 1
            # every later message is read at its log time minus at most the largest
            # allowance: what is at or before that is in order now
            ready = m.log_time - lead
            while heap and heap[0][0] <= ready:
                yield heapq.heappop(heap)[2]
        while heap:
            yield heapq.heappop(heap)[2]

    def message_blocks(self, topics: set[str] | frozenset[str]) -> None:
        """None: the columnar pass does not apply (the messages are read one by one)."""
        return None

    def reopen(self) -> LogSource | None:
        """The wrapped source's :meth:`~fretc.logs.base.LogSource.reopen`, with the same
        allowance (None when it cannot be reopened)."""
        again = self._inner.reopen()
        return None if again is None else with_allowance(again, self._shift)

    # -- the damage, on the shifted clock -----------------------------------------------------
    def _gap(self, g: Gap) -> Gap:
        """Gap ``g`` on the shifted clock: a gap of shifted topics alone moves with them
        (by the largest of theirs); one that may hold a shifted topic and others (or any
        topic) starts earlier by that allowance, its end kept."""
        if g.topics is None:
            a = self._lead
        else:
            shifted = [self._shift[t] for t in g.topics if t in self._shift]
            if not shifted:
                return g
            a = max(shifted)
            if len(shifted) == len(g.topics):
                return g._replace(start=None if g.start is None else g.start - a,
                                  end=None if g.end is None else g.end - min(shifted))
        return g._replace(start=None if g.start is None else g.start - a)

    @property
    def gaps(self) -> list[Gap]:
        """The wrapped source's gaps on the shifted clock (:meth:`_gap`)."""
        return [self._gap(g) for g in self._inner.gaps]

    @property
    def lost(self) -> dict[tuple[str, str, int | None], list]:
        """The messages present but not decoded, a shifted topic's at its shifted times."""
        out = {}
        for key, (first, last, count, why) in self._inner.lost.items():
            a = self._shift.get(key[1], 0)
            out[key] = [first - a, last - a, count, why]
        return out

    @property
    def lost_times(self) -> dict[tuple[str, str, int | None], list[int]]:
        """The log times of :attr:`lost`'s messages, a shifted topic's shifted."""
        return {key: [t - self._shift.get(key[1], 0) for t in times]
                for key, times in self._inner.lost_times.items()}

    def lost_gaps(self) -> list[Gap]:
        """:meth:`fretc.logs.base.LogSource.lost_gaps` on the shifted times."""
        return LogSource.lost_gaps(cast(LogSource, self))

    def lost_from(self, topics: Any) -> int | None:
        """:meth:`fretc.logs.base.LogSource.lost_from` on the shifted times."""
        return LogSource.lost_from(cast(LogSource, self), topics)

    def intact_end_of(self, topics: Any) -> int | None:
        """:meth:`fretc.logs.base.LogSource.intact_end_of` on the shifted times."""
        return LogSource.intact_end_of(cast(LogSource, self), topics)

    @property
    def damage_time(self) -> int | None:
        """Where the intact span ends on the shifted clock: the earliest start of a shifted
        gap, or the wrapped source's damage time less the largest allowance when no gap
        of its starts there (damage found when opening)."""
        t = self._inner.damage_time
        if t is None:
            return None
        inner_starts = {g.start for g in self._inner.gaps}
        starts = [g.start for g in self.gaps if g.start is not None]
        if t not in inner_starts:
            starts.append(t - self._lead)
        return min(starts) if starts else t - self._lead

    @property
    def cut_start(self) -> int | None:
        """:attr:`fretc.logs.base.LogSource.cut_start` of the shifted gaps."""
        return cast(int | None, LogSource.cut_start.fget(self))  # type: ignore[attr-defined]

    @property
    def intact_end(self) -> int | None:
        """:attr:`fretc.logs.base.LogSource.intact_end` on the shifted clock."""
        return cast(int | None, LogSource.intact_end.fget(self))  # type: ignore[attr-defined]
