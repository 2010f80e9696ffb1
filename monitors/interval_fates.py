"""The fates of a requirement's triggers under FRET's timings, decided a chunk of ticks at a
time: the obligation part of :class:`fretc.monitors.interval.IntervalStream` (FRET's interval
semantics, ``../shared/fretish/README.md`` section 4; each timing's obligation, window,
violation tick and reason as :data:`fretc.monitors.obligations.OBLIGATIONS` words them).

Design notes: ARCHITECTURE.md, `monitors/interval_fates.py`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fretc.monitors.evidence import Evidence, Violation

__all__ = ["Chunk", "Bounded", "Group", "Ledger", "BOUNDED", "NONE"]

#: A global tick "not seen yet" (no such event so far, an interval still open).
_INF = 1 << 62
#: A window end not known yet: set at the next clearing event (``until``/``before``) or at
#: the interval's end.
_AWAIT = -2
#: No ticks.
NONE = np.zeros(0, np.int64)
#: The timings whose triggers are decided one by one from a bounded look ahead.
BOUNDED = ("immediately", "next", "within", "for", "after")

#: A batch of violations found in one chunk, in trigger order: one row per violation,
#: ``[t, time(t), lo, time(lo), hi, time(hi), vt, time(vt)]`` (window ``(lo, hi)``,
#: violation tick ``vt``; ``hi`` may be :data:`_AWAIT`).
Rows = np.ndarray


@dataclass(slots=True)
class Chunk:
    """One chunk's signals, as the obligations read them (ticks are local: 0..L-1).

    Attributes:
        n0: the trace's index of the chunk's first tick.
        L: ticks in the chunk.
        R, S: the response and the stop condition (bool arrays; S None without one).
        T: the trigger points (sorted local ticks).
        closes: the local ends of the intervals that close in the chunk, sorted; -1 is the
            interval that was open at tick ``n0 - 1`` and ended there.
        carried: an interval was open at tick ``n0 - 1``.
        times: the ticks' times; ``last_time``/``last_R``: the time and ``R`` of tick
            ``n0 - 1``.
        final: the one virtual tick :meth:`fretc.monitors.interval.IntervalStream.finish` feeds to close the open
            interval at the trace's last tick (its own values never count).
    """

    n0: int
    L: int
    R: np.ndarray
    S: np.ndarray | None
    T: np.ndarray
    closes: np.ndarray
    carried: bool
    times: np.ndarray
    last_time: int
    last_R: bool
    final: bool

    def time(self, ticks: np.ndarray) -> np.ndarray:
        """The times of trace ticks in ``[n0 - 1, n0 + L)`` (other ticks: meaningless)."""
        loc = ticks - self.n0
        return np.where(loc >= 0, self.times[np.clip(loc, 0, self.L - 1)], self.last_time)


def _index(mask: np.ndarray | None, L: int, whole: bool = True) -> np.ndarray:
    """The sorted local ticks where ``mask`` holds, followed by ``L`` (none): ``ix[
    np.searchsorted(ix, p)]`` is the first such tick at or after ``p`` (``L`` when none).
    ``whole=False``: only the first such tick (enough where only the first is asked for)."""
    if mask is None:
        return np.array([L], np.int64)
    if not whole:
        i = int(mask.argmax())
        return np.array([i, L] if mask[i] else [L], np.int64)
    return np.append(np.flatnonzero(mask), L)


def _first(ix: np.ndarray, p: np.ndarray | int) -> np.ndarray:
    """For each position of ``p``: the first tick of index ``ix`` (:func:`_index`) at or
    after it."""
    return ix[np.searchsorted(ix, p)]


def _rows(t: np.ndarray, tt: np.ndarray, lo: np.ndarray, lot: np.ndarray, hi: np.ndarray,
          hit: np.ndarray, vt: np.ndarray, vtt: np.ndarray) -> Rows:
    """The violation rows (:data:`Rows`) of equal-length columns."""
    cols = [np.broadcast_to(np.asarray(c, np.int64), t.shape)
            for c in (t, tt, lo, lot, hi, hit, vt, vtt)]
    return np.stack(cols, axis=1)


# --------------------------------------------------------------------------- bounded timings
class Bounded:
    """``immediately``, ``next``, ``within``, ``for``, ``after``: each trigger ``t`` decided
    from the first tick ``nx`` at or after ``t`` (``t + 1`` for ``next``) where the timing's
    event holds, its deadline ``d`` and its interval end ``e`` (module docstring).
    A trigger waits, as ``[t, time(t), nx, time(nx)]`` (``nx`` :data:`_INF` until seen), until
    the trace reaches ``d`` or its interval closes."""

    def __init__(self, timing: str, negate: bool, k: int) -> None:
        self.timing = timing
        self.negate = negate
        self.k = k
        self.dk = {"immediately": 0, "next": 1, "within": k, "for": k, "after": k + 1}[timing]
        self.shift = 1 if timing == "next" else 0
        self.resolves = False   # (no window waits for a later event)
        # a trigger that holds once its first event is seen stops waiting then: within and
        # for-in-only* (the event by the deadline), after-in-only* (the event before it)
        self.settle: int | None = None
        if (timing == "within") != negate and timing in ("within", "for"):
            self.settle = 0
        elif timing == "after" and negate:
            self.settle = -1
        self.waiting = np.zeros((0, 4), np.int64)

    def pending(self) -> list[tuple[int, int | None]]:
        """The triggers still waiting, ascending: ``(t, first event at or after it)``, the
        event None when not seen yet."""
        return [(t, None if nx >= _INF else nx) for t, _tt, nx, _nxt in self.waiting.tolist()]

    def _event(self, R: np.ndarray) -> np.ndarray:
        """Where the timing's event holds: ``R != want`` (``immediately``, ``next``), ``!R``
        (``for``) or ``R`` (``within``, ``after``)."""
        if self.timing in ("immediately", "next"):
            return R if self.negate else ~R
        return ~R if self.timing == "for" else R

    def _fate(self, t: np.ndarray, nx: np.ndarray, e: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(failed, violation tick, window end) of triggers ``t`` whose first event is at
        ``nx`` and interval end at ``e`` (either :data:`_INF`: beyond the ticks seen), as
        :data:`fretc.monitors.obligations.OBLIGATIONS` words them."""
        timing, k = self.timing, self.k
        d = t + self.dk
        if timing == "immediately":
            return nx == t, t, t
        if timing == "next" or (timing == "after" and self.negate):
            return (e >= d) & (nx == d), d, d
        if timing in ("within", "for"):
            if (timing == "within") != self.negate:   # the event somewhere in [t, t+k]
                return (e >= d) & (nx > d), d, d
            hi = np.minimum(d, e)                      # no event in [t, min(t+k, e)]
            return nx <= hi, nx, hi
        hi0 = np.minimum(t + k, e)                     # after: no R in [t, min(t+k, e)] ...
        early = nx <= hi0
        late = ~early & (e >= d) & (nx != d)           # ... and R at t+k+1 when t+k+1 <= e
        return early | late, np.where(early, nx, d), np.where(early, hi0, d)

    def _candidates(self, ch: Chunk) -> np.ndarray:
        """The waiting triggers and the chunk's, as rows ``[t, time(t), nx, time(nx), e]``."""
        L, n0 = ch.L, ch.n0
        X = _index(None if ch.final else self._event(ch.R), L)
        Z = np.append(ch.closes, L)
        w = self.waiting
        if len(w):
            if X[0] < L:  # the first event of the chunk is the waiting ones' first, if unseen
                w = w.copy()
                unseen = w[:, 2] == _INF
                w[unseen, 2] = n0 + X[0]
                w[unseen, 3] = ch.times[X[0]]
            z0 = int(Z[0])
            w = np.column_stack((w, np.full(len(w), n0 + z0 if z0 < L else _INF, np.int64)))
        T = ch.T
        x = _first(X, T + self.shift)
        z = _first(Z, T)
        new = np.stack((n0 + T, ch.times[T], np.where(x < L, n0 + x, _INF),
                        ch.times[np.minimum(x, L - 1)], np.where(z < L, n0 + z, _INF)), axis=1)
        return np.concatenate((w, new)) if len(w) else new

    def chunk(self, ch: Chunk, room: int, awaiting: bool
              ) -> tuple[int, Rows | None, tuple[int, int] | None]:
        """Decide the triggers whose deadline the chunk reaches or whose interval it closes.

        Returns:
            (violations found, the first ``room`` of them as :data:`Rows`, None).
        """
        if not len(self.waiting) and not len(ch.T):
            return 0, None, None
        c = self._candidates(ch)
        t, nx, e = c[:, 0], c[:, 2], c[:, 4]
        ripe = (t + self.dk <= ch.n0 + ch.L - 1) | (e < _INF)
        if self.settle is not None:
            ripe |= nx <= t + self.dk + self.settle
        self.waiting = c[~ripe, :4]
        failed, vt, hi = self._fate(t, nx, e)
        bad = np.flatnonzero(failed & ripe)
        count = len(bad)
        if not count or room <= 0:
            return count, None, None
        bad = bad[:room]
        t, tt, nx, nxt = c[bad, 0], c[bad, 1], nx[bad], c[bad, 3]
        vt, hi = np.broadcast_to(vt, c[:, 0].shape)[bad], np.broadcast_to(hi, c[:, 0].shape)[bad]
        vtt = np.where(vt == nx, nxt, np.where(vt == t, tt, ch.time(vt)))
        hit = np.where(hi == t, tt, ch.time(hi))
        if self.timing == "next":  # the window is the tick after the trigger
            return count, _rows(t, tt, vt, vtt, hi, hit, vt, vtt), None
        return count, _rows(t, tt, t, tt, hi, hit, vt, vtt), None


# --------------------------------------------------------------------------- group timings
class Group:
    """``finally``, ``eventually``/``null``, ``always``, ``never``, ``until``, ``before``: the
    triggers waiting in the open interval share their fate (module docstring), so
    they are kept as one group: ``count`` and the first ``limit`` (tick, time) pairs.

    Each chunk has *fail* events (the waiting triggers at or before one fail there) and
    *clear* events (they hold; for ``until``/``before`` the windows of the triggers failed
    since end there, at the event's tick ``+ off``); at the interval's end the waiting ones
    fail (``eventually``, ``only*`` ``always``/``never``; ``finally`` when ``R`` there is not
    what it wants) or hold.
    """

    def __init__(self, timing: str, negate: bool, limit: int) -> None:
        self.timing = "eventually" if timing == "null" else timing
        self.limit = limit
        self.want = not negate
        self.off = 0
        if self.timing in ("until", "before"):
            # "want until S" (until; before in only* scopes) or "no S before want"
            self.kind = "until" if (self.timing == "until") == self.want else "before"
            self.off = -1 if self.kind == "until" else 0
        elif self.timing == "finally":
            self.kind = "finally"
        else:  # clear at the event and fail at the end, or fail at the event
            self.kind = "clear" if (self.timing == "eventually") == self.want else "fail"
        #: a later event ends the windows of violations (until, before)
        self.resolves = self.kind in ("until", "before")
        self.count = 0
        self.ticks = np.zeros((0, 2), np.int64)  # the first ``limit``: (tick, time)

    def pending(self) -> list[tuple[int, int | None]]:
        """The first waiting triggers (the group's, at most ``limit``), ascending, as
        ``(t, None)``: no event of the group seen since (it would have decided them)."""
        return [(t, None) for t in self.ticks[:, 0].tolist()] if self.count else []

    def _events(self, R: np.ndarray, S: np.ndarray | None
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(fail events, clear events) of one chunk (bool arrays, None for none)."""
        kind, want = self.kind, self.want
        X = ~R if self.timing == "always" else R
        if kind == "clear":
            return None, X
        if kind == "fail":
            return X, None
        if kind == "until":
            assert S is not None  # (until and before have a stop condition)
            return (R != want) & ~S, S
        if kind == "before":
            return S, R if want else ~R
        return None, None

    def _await(self, ch: Chunk, C: np.ndarray, Z: np.ndarray) -> tuple[int, int] | None:
        """The window end of the violations waiting for one (from earlier chunks), if this
        chunk's first clear event comes before their interval's end."""
        r0, z0 = int(C[0]), int(Z[0])
        if r0 <= z0 and r0 < ch.L:
            tick = ch.n0 + r0 + self.off
            return tick, int(ch.time(np.array(tick)))
        return None

    def chunk(self, ch: Chunk, room: int, awaiting: bool
              ) -> tuple[int, Rows | None, tuple[int, int] | None]:
        """Move the group and the chunk's triggers through the chunk's events and interval
        ends.

        Returns:
            (violations found, the first ``room`` of them as :data:`Rows`, the window end
            (tick, time) of the earlier violations waiting for one, or None).
        """
        L = ch.L
        whole = len(ch.T) > 0   # (the group alone reads the first event of each kind only)
        if not whole and not awaiting and (not self.count or not len(ch.closes)):
            if not self.count:
                return 0, None, None
            fail_m, clear_m = self._events(ch.R, ch.S)
            if (fail_m is None or not fail_m.any()) and (clear_m is None or not clear_m.any()):
                return 0, None, None   # nothing happens to the group in this chunk
        else:
            fail_m, clear_m = self._events(ch.R, ch.S)
        F, C = _index(fail_m, L, whole), _index(clear_m, L, whole)
        Z = np.append(ch.closes, L)
        late = self._await(ch, C, Z) if awaiting else None
        group = self.count > 0
        P = np.concatenate(([-1], ch.T)) if group else ch.T   # -1: the group
        f, c, z = _first(F, P), _first(C, P), _first(Z, P)
        failed = (f <= np.minimum(c, z)) & (f < L)
        cleared = ~failed & (c <= z) & (c < L)
        closed = ~failed & ~cleared & (z < L)
        if self.kind == "finally":
            Rz = np.where(z >= 0, ch.R[np.clip(z, 0, L - 1)], ch.last_R)
            closed_bad = closed & (Rz != self.want)
        else:
            closed_bad = closed if self.kind == "clear" else np.zeros(len(P), np.bool_)
        bad = failed | closed_bad
        count = int(bad[1:].sum()) + self.count if group and bad[0] else int(bad.sum())
        rows = self._rows(ch, room, P, bad, failed, f, z, C) if count and room > 0 else None
        self._regroup(ch, P, ~(failed | cleared | closed))
        return count, rows, late

    def _rows(self, ch: Chunk, room: int, P: np.ndarray, bad: np.ndarray,
              failed: np.ndarray, f: np.ndarray, z: np.ndarray, C: np.ndarray) -> Rows:
        """The first ``room`` violations of the positions ``P`` (-1: the group) that failed,
        at a fail event ``f`` or at their interval end ``z``."""
        L, n0 = ch.L, ch.n0
        r = _first(C, np.minimum(f, L))                 # the clear event ending the window
        hi = np.where(failed, np.where((r <= z) & (r < L), n0 + r + self.off,
                                       np.where(z < L, n0 + z, _AWAIT)), n0 + z)
        vt = n0 + np.where(failed, f, z)
        hit, vtt = ch.time(hi), ch.time(vt)
        parts = []
        if len(P) and P[0] < 0:
            if bad[0]:
                g = self.ticks[:room]
                parts.append(_rows(g[:, 0], g[:, 1], g[:, 0], g[:, 1], hi[0], hit[0], vt[0],
                                   vtt[0]))
            P, bad, hi, hit, vt, vtt = P[1:], bad[1:], hi[1:], hit[1:], vt[1:], vtt[1:]
        idx = np.flatnonzero(bad)[:room]
        t = n0 + P[idx]
        tt = ch.times[P[idx]]
        parts.append(_rows(t, tt, t, tt, hi[idx], hit[idx], vt[idx], vtt[idx]))
        rows = np.concatenate(parts)[:room]
        if self.kind == "finally":      # the window is the interval end
            rows[:, 2:4] = rows[:, 6:8]
        return rows

    def _regroup(self, ch: Chunk, P: np.ndarray, waiting: np.ndarray) -> None:
        """The group after the chunk: the waiting ones of the positions ``P`` (-1: the
        group)."""
        keep = len(P) > 0 and P[0] < 0 and bool(waiting[0])
        if len(P) and P[0] < 0:
            P, waiting = P[1:], waiting[1:]
        new = P[waiting]
        if not keep:
            self.count, self.ticks = 0, self.ticks[:0]
        self.count += len(new)
        room = self.limit - len(self.ticks)
        if room > 0 and len(new):
            add = new[:room]
            self.ticks = np.concatenate((self.ticks, np.stack((ch.n0 + add, ch.times[add]),
                                                              axis=1)))


# --------------------------------------------------------------------------- the evidence
def _reason(timing: str, negate: bool, k: int, t: int, hi: int, vt: int, e: int) -> str:
    """Why trigger ``t`` failed (window end ``hi``, violation tick ``vt``, interval end
    ``e``), in tick numbers: the obligation of :data:`fretc.monitors.obligations.OBLIGATIONS`
    that was missed."""
    rname = "!R" if negate else "R"
    if timing == "immediately":
        return f"{rname} does not hold at the trigger t={t}"
    if timing == "next":
        return f"{rname} does not hold at t+1={t + 1}"
    if timing == "finally":
        return f"{rname} does not hold at the interval end e={e}"
    if timing in ("eventually", "null"):
        if not negate:
            return f"R never holds in [{t}, {e}]"
        return f"R holds at {vt} (only* scope: R must not hold in [{t}, {e}])"
    if timing in ("always", "never"):
        name = "R" if timing == "always" else "!R"
        if not negate:
            return f"{name} fails at {vt} in [{t}, {e}]"
        return f"{name} holds everywhere in [{t}, {e}] (only* scope)"
    if timing == "within":
        if not negate:
            return f"R does not hold in [{t}, {t + k}]"
        return f"R holds at {vt} in [{t}, {hi}] (only* scope)"
    if timing == "for":
        if not negate:
            return f"R fails at {vt} in [{t}, {hi}]"
        return f"!R never holds in [{t}, {t + k}] (only* scope)"
    if timing == "after":
        if negate:
            return f"R first holds exactly at t+k+1={t + k + 1} (only* scope)"
        if vt == t + k + 1:
            return f"R does not hold at t+k+1={t + k + 1}"
        return f"R holds at {vt}, before t+k+1={t + k + 1}"
    if (timing == "until") != negate:
        return f"{rname} fails at {vt} before the stop condition"
    return f"the stop condition holds at {vt} before {rname} held (window [{t}, {hi}])"


class Ledger:
    """The counts, the first interval and trigger, and the violations listed: those of the
    open interval as rows until it closes, then as :class:`Violation` with the times of the
    ticks they name: the first ``limit`` of them (all are counted)."""

    def __init__(self, timing: str, negate: bool, k: int, limit: int) -> None:
        self.timing, self.negate, self.k, self.limit = timing, negate, k, limit
        self.intervals = self.triggers = self.violations = 0
        self.first_interval: list[int] | None = None   # [s, time, e, time], e -1 while open
        self.first_trigger: tuple[int, int] | None = None
        self.open: tuple[int, int] | None = None        # the open interval's (s, time)
        self.records: list[list[int]] = []              # rows of the open interval
        self.listed: list[tuple[Violation, dict[int, int]]] = []

    def room(self) -> int:
        """How many more violations may be listed."""
        return self.limit - len(self.listed) - len(self.records)

    def awaiting(self) -> bool:
        """Some violation of the open interval waits for its window's end."""
        return any(r[4] == _AWAIT for r in self.records)

    def _list(self, row: list[int], s: int, st: int, e: int, et: int) -> None:
        t, tt, lo, lot, hi, hit, vt, vtt = row
        if hi == _AWAIT:
            hi, hit = e, et
        reason = _reason(self.timing, self.negate, self.k, t, hi, vt, e)
        v = Violation(t, (s, e), (lo, hi), vt, reason)
        self.listed.append((v, {t: tt, s: st, e: et, lo: lot, hi: hit, vt: vtt}))

    def chunk(self, ch: Chunk, starts: np.ndarray, count: int, rows: Rows | None,
              late: tuple[int, int] | None) -> None:
        """Take one chunk's interval starts (local ticks), triggers and violations."""
        n0, closes = ch.n0, ch.closes
        if not (len(starts) or len(closes) or len(ch.T) or count or late):
            return   # (a chunk inside an interval without triggers or violations)
        if late is not None:
            for r in self.records:
                if r[4] == _AWAIT:
                    r[4], r[5] = late
        if len(starts):
            self.intervals += len(starts)
            if self.first_interval is None:
                self.first_interval = [n0 + int(starts[0]), int(ch.times[starts[0]]), -1, 0]
        ends = [(n0 + int(z), int(ch.time(n0 + z))) for z in closes[:1]]
        fi = self.first_interval
        if ends and fi is not None and fi[2] < 0:
            fi[2:] = ends[0]
        if ch.carried and ends and self.open is not None:
            for r in self.records:
                self._list(r, *self.open, *ends[0])
            self.records = []
        if len(ch.T):
            self.triggers += len(ch.T)
            if self.first_trigger is None:
                self.first_trigger = (n0 + int(ch.T[0]), int(ch.times[ch.T[0]]))
        self.violations += count
        if rows is not None and len(rows):
            self._place(ch, starts, rows)
        if int(ch.carried) + len(starts) > len(closes):     # an interval open at the end
            if len(starts):
                self.open = (n0 + int(starts[-1]), int(ch.times[starts[-1]]))
        else:
            self.open = None

    def _place(self, ch: Chunk, starts: np.ndarray, rows: Rows) -> None:
        """List the rows of intervals closed in the chunk; keep those of the open one."""
        n0, closes = ch.n0, ch.closes
        carried = int(ch.carried and self.open is not None)
        at = np.searchsorted(n0 + starts, rows[:, 0], side="right") - 1   # -1: carried
        for row, j in zip(rows.tolist(), at.tolist()):
            if j + carried >= len(closes):
                self.records.append(row)
                continue
            s = self.open if j < 0 else (n0 + int(starts[j]), int(ch.times[starts[j]]))
            assert s is not None  # (a row before the chunk's first start is in the carried one)
            e = n0 + int(closes[j + carried])
            self._list(row, *s, e, int(ch.time(np.array(e))))

    def evidence(self, n: int) -> tuple[Evidence, dict[int, int]]:
        """The :class:`Evidence` of ``n`` ticks, and the times of the ticks it names."""
        listed = [v for v, _ in self.listed]
        times: dict[int, int] = {}
        for _v, tt in self.listed:
            times.update(tt)
        fi = self.first_interval
        if fi is not None:
            times[fi[0]], times[fi[2]] = fi[1], fi[3]
        if self.first_trigger is not None:
            times[self.first_trigger[0]] = self.first_trigger[1]
        holds = self.violations == 0
        ev = Evidence(holds=holds, vacuous=holds and (not self.intervals or not self.triggers),
                      intervals=self.intervals, triggers=self.triggers,
                      violations=self.violations, violation=listed[0] if listed else None,
                      ticks=n, first_interval=(fi[0], fi[2]) if fi is not None else None,
                      first_trigger=self.first_trigger[0] if self.first_trigger else None,
                      listed=listed)
        return ev, {t: x for t, x in times.items() if 0 <= t < n}


