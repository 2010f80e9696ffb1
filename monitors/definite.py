"""FRET's interval semantics over a trace with unknown ticks (a gap in the log, a comparison
reading NaN, an unknown value), fed a chunk of ticks at a time: the evidence the three-valued
judge shows, only what lies in the ticks read (../shared/DESIGN.md, "Damage is a gap: never
evidence, never the end"), in memory that does not grow with the trace's ticks
(:class:`DefiniteStream`); a whole trace is one chunk (:func:`definite_evidence`).

Design notes: ARCHITECTURE.md, `monitors/definite.py`."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fretc.fretish import ast as A
from fretc.monitors.interval import Evidence
from fretc.monitors.interval import IntervalStream
from fretc.monitors.unknowns import Unknowns

__all__ = ["DefiniteStream", "MAX_RUNS", "definite_evidence"]

#: The most runs of unknown ticks kept per part of a requirement (two int64 each: 16 MB at
#: most; a NaN in every tenth row of 10^7 rows is 10^6 runs)
MAX_RUNS = 1 << 20
#: scopes whose interval the mode's first occurrence places (as monitors/unknowns.py)
_FIRST_OCCURRENCE = ("before", "after", "onlyBefore", "onlyAfter")


class _RunMask:
    """A part's unknown ticks over ``n`` ticks as runs ``[starts[i], ends[i]]``, read as
    :class:`~fretc.monitors.unknowns.Unknowns` reads its bool arrays: ``mask[t]`` a bool,
    ``mask[lo:hi].any()`` whether a run meets ``lo .. hi-1``."""

    def __init__(self, starts: np.ndarray, ends: np.ndarray) -> None:
        self.starts, self.ends = starts, ends

    def __getitem__(self, key: int | slice) -> _Any:
        if isinstance(key, slice):
            lo, hi = key.start or 0, key.stop
            return _Any(hi is not None and hi > lo and self._meets(lo, hi - 1))
        return _Any(self._meets(key, key))

    def _meets(self, lo: int, hi: int) -> bool:
        i = int(np.searchsorted(self.ends, lo))  # (the first run ending at or after lo)
        return i < len(self.starts) and int(self.starts[i]) <= hi

    def any(self) -> bool:
        """Whether the part is unknown at some tick."""
        return bool(len(self.starts))


class _Any:
    """A bool that also answers ``.any()`` (a slice of a :class:`_RunMask`)."""

    def __init__(self, value: bool) -> None:
        self.value = value

    def any(self) -> bool:
        return self.value

    def __bool__(self) -> bool:
        return self.value


class _Runs:
    """The runs of unknown ticks of one part, appended a chunk at a time."""

    def __init__(self) -> None:
        self.starts: list[np.ndarray] = []
        self.ends: list[np.ndarray] = []
        self.count = 0
        self.last_end = -2  # the last run's end (-2: none)

    def add(self, mask: np.ndarray, n0: int) -> None:
        """The chunk's unknown ticks ``mask`` (bool), its first at the trace's tick ``n0``."""
        if not mask.any():
            return
        d = np.diff(mask.view(np.int8), prepend=np.int8(0), append=np.int8(0))
        starts = np.flatnonzero(d == 1) + n0
        ends = np.flatnonzero(d == -1) - 1 + n0
        if self.last_end == n0 - 1 and starts[0] == n0:  # (a run going on from the chunk before)
            self.ends[-1][-1] = ends[0]
            starts, ends = starts[1:], ends[1:]
        if len(starts):
            self.starts.append(starts.astype(np.int64))
            self.ends.append(ends.astype(np.int64))
            self.count += len(starts)
        self.last_end = int(self.ends[-1][-1])

    def mask(self) -> _RunMask:
        """The runs as a :class:`_RunMask`."""
        if not self.starts:
            return _RunMask(np.zeros(0, np.int64), np.zeros(0, np.int64))
        return _RunMask(np.concatenate(self.starts), np.concatenate(self.ends))


class DefiniteStream:
    """The three-valued judge's evidence of ``req`` over a trace fed a chunk at a time
    (module docstring).

    Args:
        req: a parsed, not free-form requirement (one with a temporal function is fed the
            whole trace as one chunk, as :class:`~fretc.monitors.interval.IntervalStream`).
        duration_ticks: as :class:`~fretc.monitors.interval.IntervalStream`'s.
        nan_unknown: a comparison with NaN is unknown (fretc's NaN rule); False under
            ``[tick] nan = "false"``.

    Raises:
        EvidenceUnsupported: as :class:`~fretc.monitors.interval.IntervalStream`.

    Attributes:
        too_many: some part had more than :data:`MAX_RUNS` runs of unknown ticks (the
            evidence is then not made: judge the trace whole).
        possible_trigger: a trigger may have fired in unknown ticks (the scope mode or the
            condition unknown somewhere: :func:`fretc.monitors.unknowns.possible_trigger`).
    """

    def __init__(self, req: A.Requirement, duration_ticks: int | None,
                 nan_unknown: bool = True) -> None:
        self.req, self.nan_unknown = req, nan_unknown
        self.interval = IntervalStream(req, duration_ticks)
        self.interval.on_triggers = self._triggers
        self.scope, self.cond = req.scope.kind, req.condition.kind
        self.runs = {part: _Runs() for part in "MCRSG"}  # (G: the gap ticks)
        self.n = 0
        self.too_many = False
        self.possible_trigger = False
        self.triggers = 0
        self.first_trigger: tuple[int, int] | None = None
        self._m_first: int | None = None  # the first tick the mode is unknown at
        self._m_last = -1  # the last such tick before the chunk
        self._c_last = False  # the condition unknown at the tick before the chunk
        self._u: Unknowns | None = None  # the chunk's

    def feed(self, columns: Mapping[str, np.ndarray], unknown: Mapping[str, np.ndarray],
             k: int, times: np.ndarray, stretch: np.ndarray | None = None) -> None:
        """The next ``k >= 0`` ticks: ``columns`` as the interval stream takes them,
        ``unknown`` variable -> bool array of ``k`` (its unknown ticks; a comparison with
        NaN is unknown under fretc's NaN rule), ``times`` int64 ns, ``stretch`` the gap ticks
        (bool array of ``k``, their variables unknown in ``unknown`` too; None: none)."""
        if k <= 0:
            return
        cols = {name: np.asarray(c)[:k] for name, c in columns.items()}
        u = Unknowns.of(self.req, unknown, cols, k, self.nan_unknown)
        gaps = np.zeros(k, np.bool_) if stretch is None else np.asarray(stretch[:k], np.bool_)
        for part, mask in zip("MCRSG", (u.M, u.C, u.R, u.S, gaps)):
            runs = self.runs[part]
            runs.add(mask, self.n)
            self.too_many = self.too_many or runs.count > MAX_RUNS
        if self._m_first is None and u.M.any():
            self._m_first = self.n + int(np.argmax(u.M))
        self.possible_trigger = self.possible_trigger or bool(u.M.any() or u.C.any())
        self._u = u
        self.interval.feed(cols, k, times, favour=u)
        if u.M.any():
            self._m_last = self.n + int(np.flatnonzero(u.M)[-1])
        self._c_last = bool(u.C[-1])
        self.n += k

    def _triggers(self, n0: int, T: np.ndarray, starts: np.ndarray, opened: int | None,
                  times: np.ndarray) -> None:
        """Count the chunk's definite triggers (module docstring)."""
        if not len(T):
            return
        u = self._u
        assert u is not None  # (fed)
        j = np.searchsorted(starts, T, side="right") - 1
        s = np.where(j >= 0, n0 + starts[np.maximum(j, 0)] if len(starts) else 0,
                     -1 if opened is None else opened)
        t = n0 + T
        ok = np.ones(len(T), np.bool_)
        scope = self.scope
        first = self._m_first if self._m_first is not None else 1 << 62
        if scope in ("after", "onlyBefore"):
            ok &= first > s
        elif scope in ("before", "onlyAfter"):
            ok &= first > t
        elif scope != "null":  # the mode known on [max(s - 1, 0), t]
            last = np.maximum.accumulate(np.where(u.M, np.arange(len(u.M)) + n0, -1))
            ok &= np.maximum(last[T], self._m_last) < np.maximum(s - 1, 0)
        if self.cond != "null":
            ok &= ~u.C[T]
            if self.cond != "holding":
                before = np.where(T > 0, u.C[np.maximum(T - 1, 0)], self._c_last)
                ok &= (t == s) | ~before
        count = int(ok.sum())
        self.triggers += count
        if count and self.first_trigger is None:
            i = int(np.argmax(ok))
            self.first_trigger = (int(t[i]), int(times[T[i]]))

    def finish(self) -> tuple[Evidence, dict[int, int]]:
        """The evidence (its ``holds`` and ``vacuous`` the favoured stream's: the caller's
        three-valued verdict decides them) and the times of the ticks it names, as
        :meth:`~fretc.monitors.interval.IntervalStream.finish` gives them.

        Raises:
            ValueError: no tick was fed."""
        ev, times = self.interval.finish()
        u = Unknowns(self.n, *(self.runs[p].mask() for p in "MCRS"))  # type: ignore[arg-type]
        if self.runs["G"].count:
            u.stretch = self.runs["G"].mask()  # type: ignore[assignment]  # (read as a mask)
        negate = self.scope.startswith("only")
        listed = [w for w in ev.listed
                  if u.scope_known(w.interval[0], w.interval[1], self.scope)
                  and u.trigger_known(w.trigger_tick, w.interval[0], self.cond)
                  and u.missed_known(w.trigger_tick, w.window[0], w.violation_tick,
                                     self.req.timing.kind, negate)]
        first = None
        if self.first_trigger is not None:
            first = self.first_trigger[0]
            times = {**times, first: self.first_trigger[1]}
        return Evidence(holds=ev.holds, vacuous=ev.vacuous, intervals=ev.intervals,
                        triggers=self.triggers, violations=len(listed),
                        violation=listed[0] if listed else None, ticks=ev.ticks,
                        first_interval=ev.first_interval, first_trigger=first,
                        listed=listed), times


def definite_evidence(req: A.Requirement, columns: Mapping[str, np.ndarray],
                      unknown: Mapping[str, np.ndarray], n: int, duration_ticks: int | None,
                      nan_unknown: bool = True, stretch: np.ndarray | None = None
                      ) -> tuple[Evidence, bool]:
    """The definite evidence of ``req`` over a whole trace of ``n >= 1`` ticks (a
    :class:`DefiniteStream` fed it as one chunk; arguments as its), and whether a trigger
    may have fired in unknown ticks.

    Raises:
        EvidenceUnsupported: as :class:`~fretc.monitors.interval.IntervalStream`.
        KeyError: a variable missing from ``columns``.
        ValueError: ``n < 1``."""
    s = DefiniteStream(req, duration_ticks, nan_unknown)
    s.feed(columns, unknown, n, np.arange(n, dtype=np.int64), stretch)
    return s.finish()[0], s.possible_trigger
