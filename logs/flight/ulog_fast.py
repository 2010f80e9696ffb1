"""The data section of a sound PX4 ULog file read in one walk and numpy gathers, giving what
pyulog's read of every topic gives (format: PX4 "ULog File Format" documentation).

Design notes: ARCHITECTURE.md, `logs/flight/ulog_fast.py`."""

from __future__ import annotations

import contextlib
import functools
import io
import struct
from typing import Any

import numpy as np

from fretc.logs.flight.ulog_framing import UlogFraming, _Formats

__all__ = ["read_sound"]

_MAGIC = b"ULog\x01\x12\x35"


def _table(types: bytes) -> np.ndarray:
    """A lookup table: True at the message types ``types`` (indexed by a type byte)."""
    table = np.zeros(256, dtype=bool)
    table[list(types)] = True
    return table


_KNOWN = _table(b"BFIMPQARDLCSO")
#: message types of the data section read here (others: the reference read), of the
#: definitions, where pyulog's data section starts, and the messages built one by one
_DATA, _DEFS, _SECTION, _OTHERS = (_table(b"IMPQADLCSO"), _table(b"BFIMPQ"), _table(b"ALC"),
                                   _table(b"IMPQLCO"))


def _walk(data: bytes) -> np.ndarray:
    """The offsets of the message headers from byte 16 while a whole header fits."""
    pos, last = 16, len(data) - 3
    out: list[int] = []
    append = out.append
    while pos <= last:
        append(pos)
        pos += 3 + data[pos] + (data[pos + 1] << 8)
    return np.array(out, dtype=np.int64)


def read_sound(data: bytes) -> tuple[Any, UlogFraming] | None:
    """(a pyulog ``ULog`` as pyulog's read of every topic of ``data`` makes it, the file's
    :class:`UlogFraming`, which has no damage) for a sound file (module docstring); None
    for any other file."""
    n = len(data)
    if data[:7] != _MAGIC or n < 16:
        return None
    at = _walk(data)
    if not len(at):
        return None
    buf = np.frombuffer(data, dtype=np.uint8)
    sizes = buf[at].astype(np.int64) | (buf[at + 1].astype(np.int64) << 8)
    types = buf[at + 2]
    if int(at[-1] + 3 + sizes[-1]) != n or not _KNOWN[types].all():
        return None
    if ((sizes == 0) & (types != ord("S"))).any():
        return None
    first = np.flatnonzero(_SECTION[types])
    first_a = np.flatnonzero(types == ord("A"))
    if not len(first_a):
        return None
    start = int(first[0])  # pyulog's data section (the framing's starts at the first A)
    if not (_DATA[types[start:]].all() and _DEFS[types[:start]].all()):
        return None
    ulog = _header(data)
    if ulog is None or ulog.has_data_appended or ulog._file_corrupt:
        return None
    return _data_section(ulog, data, buf, at, sizes, types, start, int(first_a[0]))


def _header(data: bytes) -> Any:
    from pyulog import ULog

    try:
        with contextlib.redirect_stdout(io.StringIO()):
            return ULog(io.BytesIO(data), parse_header_only=True, disable_str_exceptions=True)
    except Exception:  # noqa: BLE001 - the reference read reports it
        return None


def _data_section(ulog: Any, data: bytes, buf: np.ndarray, at: np.ndarray, sizes: np.ndarray,
                  types: np.ndarray, start: int, start_a: int
                  ) -> tuple[Any, UlogFraming] | None:
    from pyulog import ULog

    framing = UlogFraming(runs=[(int(at[start_a]), len(data))],
                          definitions_end=int(at[start_a]))
    formats = _Formats()
    for k in np.flatnonzero(types[:start] == ord("F")):
        p = int(at[k])
        formats.add(ord("F"), data[p + 3:p + 3 + int(sizes[k])])
    is_d = types == ord("D")
    d_idx = np.flatnonzero(is_d)
    ids = buf[at[d_idx] + 3].astype(np.uint16) | (buf[at[d_idx] + 4].astype(np.uint16) << 8)
    order = np.argsort(ids, kind="stable")  # each id's data messages, in file order (radix)
    uniq, lo, count = np.unique(ids[order], return_index=True, return_counts=True)
    group = {int(i): order[a:a + c] for i, a, c in zip(uniq, lo, count)}
    subs: dict[int, Any] = {}
    header = ULog._MessageHeader()
    try:
        for k in np.flatnonzero(types == ord("A")):
            p, size = int(at[k]), int(sizes[k])
            payload = data[p + 3:p + 3 + size]
            formats.add(ord("A"), payload)
            framing.subscriptions.append((p, data[p:p + 3 + size]))
            header.msg_size, header.msg_type = size, ord("A")
            sub = ULog._MessageAddLogged(payload, header, ulog.message_formats)
            mine = group.get(sub.msg_id)
            if sub.msg_id in subs or (mine is not None and d_idx[mine[0]] < k):
                return None  # a second subscription of the id, or data before it
            subs[sub.msg_id] = sub
    except (IndexError, KeyError, ValueError, OverflowError, struct.error):
        return None
    if set(group) - set(subs):
        return None
    times = np.empty(len(d_idx), dtype=np.uint64)
    for msg_id, sub in subs.items():
        mine = group.get(msg_id)
        if mine is None:
            continue
        got = sizes[d_idx[mine]] - 2
        item = sub.dtype.itemsize
        if sub.timestamp_offset + 8 > item:
            return None
        bounds = formats.sizes(sub.message_name)
        if (got < item).any() or (got > sub.max_data_size).any() or (
                bounds is not None and ((got < bounds[0]) | (got > bounds[1])).any()):
            return None
        sub.starts = at[d_idx[mine]] + 5  # the rows, gathered when read (_lazy_data)
        sub.times = np.lib.stride_tricks.sliding_window_view(buf, 8)[
            sub.starts + sub.timestamp_offset].copy().view("<u8")[:, 0]
        times[mine] = sub.times
    # pyulog's running timestamp: the largest data timestamp so far, from the header's
    last = np.maximum.accumulate(np.concatenate(
        [np.array([ulog.start_timestamp], dtype=np.uint64), times]))
    if not _others(ulog, data, at, sizes, types, start, d_idx, last):
        return None
    lazy = _lazy_data()
    ulog._data_list = sorted((lazy(s, buf) for s in subs.values() if hasattr(s, "starts")),
                             key=lambda ds: (ds.name, ds.multi_id))
    ulog._last_timestamp = int(last[-1])
    return ulog, framing


@functools.cache
def _lazy_data() -> type:
    """pyulog's ``Data`` of one subscription whose rows are gathered from the file's bytes
    when its ``data`` is first read (an audit reads the topics its bindings name);
    ``timestamps`` (each row's, µs) are known without them."""
    from pyulog import ULog

    class LazyData(ULog.Data):
        def __init__(self, sub: Any, buf: np.ndarray) -> None:  # noqa: D107 - pyulog's fields
            self.multi_id, self.msg_id = sub.multi_id, sub.msg_id
            self.name, self.field_data = sub.message_name, sub.field_data
            self.timestamp_idx, self.timestamps = sub.timestamp_idx, sub.times
            self._dtype, self._buf, self._starts = sub.dtype, buf, sub.starts
            self._data: dict[str, np.ndarray] | None = None

        @property
        def data(self) -> dict[str, np.ndarray]:
            if self._data is None:  # as pyulog's Data: one view per field of the rows
                rows = np.lib.stride_tricks.sliding_window_view(
                    self._buf, self._dtype.itemsize)[self._starts]
                table = np.frombuffer(rows, dtype=self._dtype)
                self._data = {name: table[name] for name in table.dtype.names}
            return self._data

    return LazyData


def _others(ulog: Any, data: bytes, at: np.ndarray, sizes: np.ndarray, types: np.ndarray,
            start: int, d_idx: np.ndarray, last: np.ndarray) -> bool:
    """The messages of the data section other than data, as pyulog's read records them;
    False where pyulog's classes refuse one (a damaged message: the reference read)."""
    from pyulog import ULog

    header = ULog._MessageHeader()
    rest = np.flatnonzero(_OTHERS[types[start:]])
    rest += start
    before = np.searchsorted(d_idx, rest)  # data messages before each
    try:
        for k, nd in zip(rest.tolist(), before.tolist()):
            p, size, typ = int(at[k]), int(sizes[k]), int(types[k])
            payload = data[p + 3:p + 3 + size]
            header.msg_size, header.msg_type = size, typ
            stamp = int(last[nd])
            if typ == ord("I"):
                info = ULog._MessageInfo(payload, header)
                ulog._msg_info_dict[info.key] = info.value
                ulog._msg_info_dict_types[info.key] = info.type
            elif typ == ord("M"):
                ulog._add_message_info_multiple(ULog._MessageInfo(payload, header,
                                                                  is_info_multiple=True))
            elif typ == ord("P"):
                info = ULog._MessageInfo(payload, header)
                ulog._changed_parameters.append((stamp, info.key, info.value))
            elif typ == ord("Q"):
                ulog._add_parameter_default(ULog._MessageParameterDefault(payload, header))
            elif typ == ord("L"):
                ulog._logged_messages.append(ULog.MessageLogging(payload, header))
            elif typ == ord("C"):
                tagged = ULog.MessageLoggingTagged(payload, header)
                ulog._logged_messages_tagged.setdefault(tagged.tag, []).append(tagged)
            elif typ == ord("O"):
                ulog._dropouts.append(ULog.MessageDropout(payload, header, stamp))
    except (IndexError, KeyError, ValueError, OverflowError, UnicodeDecodeError,
            struct.error):
        return False
    ulog._sync_seq_cnt = int((types[start:] == ord("S")).sum())
    return True
