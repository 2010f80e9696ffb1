"""The indexed MCAP pass by columns: the messages of a log as blocks of columns per topic
(:func:`column_pass`), for the audit's sampler (:func:`fretc.signals.sample_blocks`).

Design notes: ARCHITECTURE.md, `logs/mcap/columns.py`."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, NamedTuple

import numpy as np
from mcap.records import ChunkIndex, Message as McapMessage

from fretc.common import problems as P
from fretc.logs.ros.columnar import ColumnarDecoder, Segment
from fretc.logs.decoding import schema_columnar
from fretc.logs.mcap.records import chunk_message_table

__all__ = ["TopicBlock", "column_pass"]


class TopicBlock(NamedTuple):
    """Consecutive messages of one topic released together.

    Attributes:
        topic: the topic.
        log_times: their log times (ns, Python ints, non-decreasing as the pass gives them).
        segment: their bound fields as columns, and the messages on demand.
    """

    topic: str
    log_times: list[int]
    segment: Segment


class _Group:
    """The messages of one channel in one chunk not yet released."""

    __slots__ = ("cid", "offset", "data", "buf", "starts", "lengths", "times", "pos",
                 "columns", "rest", "head")

    def __init__(self, cid: int, offset: int, data: bytes, buf: np.ndarray, sel: np.ndarray,
                 starts: np.ndarray, lengths: np.ndarray, times: np.ndarray) -> None:
        self.cid, self.offset, self.data, self.buf = cid, offset, data, buf
        self.pos = sel  # position among the chunk's Message records (ties of log time)
        self.head = starts[sel]  # Message record bodies
        self.starts = self.head + 22  # the serialized messages
        self.lengths = lengths[sel] - 22
        self.times = times[sel]
        self.columns: dict | None = None
        self.rest = np.arange(len(sel))


def column_pass(src: Any, topics: set[str] | frozenset[str]
                ) -> Iterator[list[TopicBlock]] | None:
    """The messages of ``topics`` in blocks (module docstring), or None when this pass does not
    apply: a file read without its index, or a channel of ``topics`` whose bound fields the
    columnar decoder does not read (its schema, its encoding, its type). Starts a pass
    (``counts``, ``partial``, problems reset as :meth:`McapSource.messages` does)."""
    index = src._index
    if index is None or src._wanted_fields is None:
        return None
    decoders: dict[int, ColumnarDecoder] = {}
    for cid, ch in index.channels.items():
        if ch.topic not in topics:
            continue
        sc = index.schemas.get(ch.schema_id)
        if sc is None or ch.schema_id == 0:
            return None
        dec = schema_columnar(ch.message_encoding, sc.encoding, sc.name,
                              sc.data.decode("utf-8", errors="replace"),
                              src._fields_for(ch.topic))
        if dec is None:
            return None
        decoders[cid] = dec
    src._begin_pass()
    return _Pass(src, decoders).run()


class _Pass:
    def __init__(self, src: Any, decoders: dict[int, ColumnarDecoder]) -> None:
        self.src = src
        self.index = src._index
        self.decoders = decoders
        # channel id (uint16, MCAP spec "Message") -> wanted / defined by the summary
        self.wanted = np.zeros(1 << 16, dtype=np.bool_)
        self.wanted[list(decoders)] = True
        self.known = np.zeros(1 << 16, dtype=np.bool_)
        self.known[[c for c in self.index.channels if 0 <= c < 1 << 16]] = True
        self.pool: list[_Group] = []

    def run(self) -> Iterator[list[TopicBlock]]:
        src = self.src
        chunks = sorted(self.index.chunk_indexes,
                        key=lambda ci: (ci.message_start_time, ci.chunk_start_offset))
        with open(src.path, "rb") as f:
            for ci in chunks:
                out = self._release((ci.message_start_time, ci.chunk_start_offset))
                if out:
                    yield out
                self._load(f, ci)
        out = self._release(None)
        if out:
            yield out
        if src.check_data_crc and not src._data_crc_checked:
            src._check_data_crc()

    def _load(self, f: Any, ci: ChunkIndex) -> None:
        """Open one chunk: its unknown channels reported, its wanted messages pooled."""
        table = self.src._open_chunk(f, ci, chunk_message_table, None)
        if table is None or len(table[1]) == 0:
            return
        data, heads, lengths = table
        buf = np.frombuffer(data, dtype=np.uint8)
        cids = _u(buf, heads, 2, "<u2")
        times = _u(buf, heads + 6, 8, "<u8")
        unknown = np.flatnonzero(~self.known[cids])
        for k in unknown.tolist():
            t = int(times[k])
            self.src._gap(t, t, cause=P.UNKNOWN_CHANNEL)
            self.src._problem(P.UNKNOWN_CHANNEL, None, t,
                              f"message on channel id {int(cids[k])} that the summary does "
                              "not define; skipped")
        # sorted(set(...)), not np.unique: that imports numpy.ma (start-up of the command)
        for cid in sorted(set(cids[self.wanted[cids]].tolist())):
            g = _Group(cid, ci.chunk_start_offset, data, buf, np.flatnonzero(cids == cid),
                       heads, lengths, times)
            g.columns = self.decoders[cid].decode(buf, g.starts, g.lengths)
            self.pool.append(g)

    def _release(self, before: tuple[int, int] | None) -> list[TopicBlock]:
        """The pooled messages that come before ``before`` (a chunk's start time and offset;
        None: all of them), sorted, as blocks per topic."""
        parts = []
        for g in self.pool:
            if before is None:
                take, g.rest = g.rest, g.rest[:0]
            else:
                t = g.times[g.rest]
                early = (t < before[0]) | ((t == before[0]) & (g.offset < before[1]))
                take, g.rest = g.rest[early], g.rest[~early]
            if len(take):
                parts.append((g, take))
        self.pool = [g for g in self.pool if len(g.rest)]
        if not parts:
            return []
        which = np.concatenate([np.full(len(k), i) for i, (_g, k) in enumerate(parts)])
        idx = np.concatenate([k for _g, k in parts])
        times = np.concatenate([g.times[k] for g, k in parts])
        offs = np.concatenate([np.full(len(k), g.offset, dtype=np.uint64) for g, k in parts])
        pos = np.concatenate([g.pos[k] for g, k in parts])
        order = np.lexsort((pos, offs, times))
        which, idx, times = which[order], idx[order], times[order]
        groups = [g for g, _k in parts]
        slow = self._one_by_one(groups, which, idx, times)
        out = []
        by_topic: dict[str, list[int]] = {}
        for i, g in enumerate(groups):
            by_topic.setdefault(self.index.channels[g.cid].topic, []).append(i)
        for topic, members in by_topic.items():
            mask = np.zeros(len(groups), dtype=np.bool_)
            mask[members] = True
            mask = mask[which]
            blk = self._block(topic, groups, which[mask], idx[mask], times[mask], slow)
            if blk is not None:
                out.append(blk)
        return out

    def _one_by_one(self, groups: list[_Group], which: np.ndarray, idx: np.ndarray,
                    times: np.ndarray) -> dict[tuple[int, int], Any]:
        """The messages of groups the columnar decoder did not read, decoded one by one in
        the pass's order (as :meth:`McapSource._deliver` does: problems, counts); (group,
        index) -> message (None: skipped)."""
        out: dict[tuple[int, int], Any] = {}
        if all(g.columns is not None for g in groups):
            return out
        src, index = self.src, self.index
        for w, i in zip(which.tolist(), idx.tolist()):
            g = groups[w]
            if g.columns is not None:
                continue
            h = int(g.head[i])
            seq = int(np.frombuffer(g.data, "<u4", 1, h + 2)[0])
            publish = int(np.frombuffer(g.data, "<u8", 1, h + 14)[0])
            rec = McapMessage(g.cid, int(g.times[i]), g.data[h + 22:h + 22 + int(g.lengths[i])],
                              publish, seq)
            msg = src._deliver(index.channels[g.cid], rec, index.schemas)
            out[(w, i)] = None if msg is None else msg.data
        return out

    def _block(self, topic: str, groups: list[_Group], which: np.ndarray, idx: np.ndarray,
               times: np.ndarray, slow: dict[tuple[int, int], Any]) -> TopicBlock | None:
        """The released messages of one topic (``which``: their group, ``idx``: their index
        in it) as a :class:`TopicBlock`."""
        src = self.src
        members = sorted(set(which.tolist()))
        typename = self.decoders[groups[members[0]].cid].typename
        fast = sum(len(idx[which == m]) for m in members if groups[m].columns is not None)
        if fast:  # the others: by _deliver (a topic none of whose messages is decoded
            # is not counted, as in the message-by-message pass)
            src.records[topic] = src.records.get(topic, 0) + fast
            src.counts[topic] = src.counts.get(topic, 0) + fast
        if any(groups[m].columns is None for m in members):
            keep, data = [], []
            for k, (w, i) in enumerate(zip(which.tolist(), idx.tolist())):
                d = slow[(w, i)] if (w, i) in slow else self._decode(groups[w], i)
                if d is not None:
                    keep.append(k)
                    data.append(d)
            if not keep:
                return None
            seg = Segment(None, len(data), data.__getitem__, typename)
            return TopicBlock(topic, times[keep].tolist(), seg)
        seg = Segment(_gathered(groups, members, which, idx), len(idx),
                      lambda k: self._decode(groups[int(which[k])], int(idx[k])), typename)
        return TopicBlock(topic, times.tolist(), seg)

    def _decode(self, g: _Group, i: int) -> Any:
        """Message ``i`` of group ``g`` by the channel's selective decoder (one the columnar
        decoder read: it decodes)."""
        ch = self.index.channels[g.cid]
        dec = self.src._decoder(ch, self.index.schemas, int(g.times[i]))
        a = int(g.starts[i])
        return dec(g.data[a:a + int(g.lengths[i])])


def _u(buf: np.ndarray, at: np.ndarray, size: int, dtype: str) -> np.ndarray:
    """The little-endian integers of ``size`` bytes at offsets ``at`` of ``buf``."""
    return buf[at[:, None] + np.arange(size)].view(dtype)[:, 0]


def _gathered(groups: list[_Group], members: list[int], which: np.ndarray, idx: np.ndarray
              ) -> dict | None:
    """The columns of the messages (``which``, ``idx``) of ``groups``, in that order; None when
    the groups' columns do not join (different fields, ranges of different lengths)."""
    if len(members) == 1:
        cols = groups[members[0]].columns
        assert cols is not None
        return {p: c[idx] for p, c in cols.items()}
    colsets = []
    for m in members:
        cols = groups[m].columns
        assert cols is not None  # (as above)
        colsets.append(cols)
    keys = set(colsets[0])
    if any(set(c) != keys for c in colsets) or any(
            c[p].shape[1:] != colsets[0][p].shape[1:] for c in colsets for p in keys):
        return None
    base = np.zeros(max(members) + 1, dtype=np.int64)
    at = 0
    for m in members:
        base[m] = at
        at += len(groups[m].times)
    joined = {p: np.concatenate([c[p] for c in colsets]) for p in keys}
    return {p: c[base[which] + idx] for p, c in joined.items()}
