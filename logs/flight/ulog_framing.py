"""The framing of a PX4 ULog file checked before it is read: where it is cut or damaged, and
the intact runs of messages around the damage (format: PX4 "ULog File Format"
documentation).

Design notes: ARCHITECTURE.md, `logs/flight/ulog_framing.py`."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

__all__ = ["SYNC_BYTES", "UlogDamage", "UlogFraming", "ulog_framing", "segment_bytes"]

#: The payload of a ULog sync message (``S``).
SYNC_BYTES = b"\x2f\x73\x13\x20\x25\x0c\xbb\x12"
_MAGIC = b"ULog\x01\x12\x35"
_TYPES = frozenset(b"BFIMPQARDLCSO")
_HEADER = struct.Struct("<HB")
_U64 = struct.Struct("<Q")
#: where the timestamp is in a message's payload: data (after its msg_id), logged text
#: (after its level), tagged logged text (after level and tag)
_TIME_AT = {ord("D"): 2, ord("L"): 1, ord("C"): 3}


@dataclass(frozen=True)
class UlogDamage:
    """Damage found in a ULog's framing: at byte ``offset``, after the log time
    ``last_time_us`` (µs; None: before any timestamped message), up to ``next_time_us``
    (the first log time read after it; None: the rest of the log is lost, a cut).
    ``kind`` is ``truncated`` or ``corrupt_record`` (:mod:`fretc.common.problems`)."""

    offset: int
    last_time_us: int | None
    next_time_us: int | None
    kind: str
    detail: str


@dataclass
class UlogFraming:
    """The framing of one file: its damage in file order, the byte spans ``(start, end)``
    of the intact runs of messages (the first starts after the definitions), the end of the
    definitions section, and each data-section subscription message (``A``/``R``: offset,
    raw bytes) a later run needs."""

    damages: list[UlogDamage] = field(default_factory=list)
    runs: list[tuple[int, int]] = field(default_factory=list)
    definitions_end: int = 16
    subscriptions: list[tuple[int, bytes]] = field(default_factory=list)
    appended: bool = False


def _time_of(data: bytes, pos: int, size: int, typ: int) -> int | None:
    """The timestamp (µs) of the message at ``pos`` (its header), if it has one."""
    start = pos + 3
    offset = _TIME_AT.get(typ)
    if offset is None or size < offset + 8:
        return None
    return _U64.unpack_from(data, start + offset)[0]


#: bytes of ULog's basic types (the "ULog File Format" documentation)
_BASIC = {"int8_t": 1, "uint8_t": 1, "bool": 1, "char": 1, "int16_t": 2, "uint16_t": 2,
          "int32_t": 4, "uint32_t": 4, "float": 4, "int64_t": 8, "uint64_t": 8, "double": 8}


class _Formats:
    """The formats (``F``) and subscriptions (``A``) read so far, for the size a data
    message of a subscription must have."""

    def __init__(self) -> None:
        self.fields: dict[str, list[tuple[str, int, str]]] = {}
        self.topic: dict[int, str] = {}
        self._sizes: dict[str, tuple[int, int] | None] = {}

    def add(self, typ: int, payload: bytes) -> None:
        """Record an ``F`` or ``A`` message's payload."""
        text = payload.decode("latin-1")
        if typ == ord("F") and ":" in text:
            name, _, body = text.partition(":")
            fields = []
            for f in body.split(";"):
                if not f.strip():
                    continue
                kind, _, fname = f.strip().rpartition(" ")
                base, _, count = kind.partition("[")
                fields.append((base, int(count.rstrip("]")) if count.rstrip("]").isdigit()
                               else 0, fname))
            self.fields[name] = fields
        elif typ == ord("A") and len(payload) >= 3:
            self.topic[int.from_bytes(payload[1:3], "little")] = text[3:].rstrip("\x00")

    def sizes(self, name: str, depth: int = 0) -> tuple[int, int] | None:
        """(bytes without the trailing ``_padding`` fields, all bytes) of format ``name``,
        or None when it is not known (an unknown or recursive type)."""
        if name in self._sizes:
            return self._sizes[name]
        if depth > 32 or name not in self.fields:
            return None
        total, least = 0, 0
        for base, count, fname in self.fields[name]:
            one = _BASIC.get(base)
            if one is None:
                inner = self.sizes(base, depth + 1)
                if inner is None:
                    return None
                one = inner[1]
            total += one * max(count, 1)
            if not fname.startswith("_padding"):
                least = total
        self._sizes[name] = (least, total)
        return self._sizes[name]

    def problem(self, payload_size: int, msg_id: int) -> str | None:
        """Why a data message of ``payload_size`` bytes with ``msg_id`` cannot be one of
        its subscription (its format's size, trailing padding optional, plus the id)."""
        name = self.topic.get(msg_id)
        got = self.sizes(name) if name is not None else None
        if got is None or got[0] + 2 <= payload_size <= got[1] + 2:
            return None
        return (f"a data message of {name} of {payload_size} bytes (its format has "
                f"{got[1] + 2})")


def ulog_framing(data: bytes) -> UlogFraming:
    """Walk the messages of a ULog file (``data``: the whole file) and return its
    :class:`UlogFraming` (module docstring). A file that does not start with the ULog magic
    gives no runs (pyulog reports it). Files with data appended (flag bit of the ``B``
    message) are checked up to the first damage only: their appended offsets refer to the
    whole file, so the log ends at the damage (a cut)."""
    out = UlogFraming()
    if data[:7] != _MAGIC or len(data) < 16:
        return out
    pos, start, last, seen_a = 16, None, None, False
    after_damage: UlogDamage | None = None
    formats = _Formats()
    n = len(data)
    while True:
        if pos + 3 > n:
            if pos < n:  # a header cut in the middle
                _cut(out, start, pos, last, f"the file ends inside a message header at byte "
                                            f"{pos}")
            elif start is not None:
                out.runs.append((start, pos))
            break
        size, typ = _HEADER.unpack_from(data, pos)
        wrong = (formats.problem(size, int.from_bytes(data[pos + 3:pos + 5], "little"))
                 if typ == ord("D") and pos + 5 <= n else None)
        if typ not in _TYPES or (size == 0 and typ != ord("S")) or wrong:
            reason = (f"{wrong} at byte {pos}" if wrong else
                      f"a message of unknown type {typ} (size {size}) at byte {pos}")
            reason += ": the bytes from there are not ULog messages"
            if start is not None:
                out.runs.append((start, pos))
            # damage in the definitions, or in a file with data appended: nothing after it
            resume = -1 if out.appended or not seen_a else data.find(SYNC_BYTES, pos)
            if resume < 0:
                out.damages.append(UlogDamage(pos, last, None, "corrupt_record",
                                              reason + "; no sync message after it: the rest "
                                              "of the log is lost"))
                break
            after_damage = UlogDamage(pos, last, None, "corrupt_record",
                                      reason + f"; reading resumes after the sync message "
                                               f"at byte {resume}")
            pos = start = resume + len(SYNC_BYTES)
            continue
        if pos + 3 + size > n:
            _cut(out, start, pos, last, f"the last message (type {chr(typ)}, {size} bytes "
                                        f"at byte {pos}) runs past the end of the file")
            break
        if typ in (ord("F"), ord("A")):
            formats.add(typ, data[pos + 3:pos + 3 + size])
        if typ == ord("B") and size >= 9 and data[pos + 3 + 8] & 1:
            out.appended = True
        if typ == ord("A") and not seen_a:
            seen_a, out.definitions_end = True, pos
        if start is None and seen_a:
            start = pos
        if seen_a and typ in (ord("A"), ord("R")):
            out.subscriptions.append((pos, data[pos:pos + 3 + size]))
        t = _time_of(data, pos, size, typ)
        if t is not None:
            if after_damage is not None:  # (a message may be older than one before it)
                end = t if after_damage.last_time_us is None else max(
                    t, after_damage.last_time_us)
                out.damages.append(UlogDamage(after_damage.offset, after_damage.last_time_us,
                                              end, after_damage.kind, after_damage.detail))
                after_damage = None
            last = t if last is None else max(last, t)
        pos += 3 + size
    if after_damage is not None:  # no timestamped message after the resync: a cut
        out.damages.append(after_damage)
    return out


def _cut(out: UlogFraming, start: int | None, pos: int, last: int | None, why: str) -> None:
    if start is not None:
        out.runs.append((start, pos))
    out.damages.append(UlogDamage(pos, last, None, "truncated",
                                  why + ": the log is cut (a crashed or interrupted "
                                        "recording)"))


def segment_bytes(data: bytes, framing: UlogFraming, k: int) -> bytes:
    """A ULog file holding run ``k`` of ``framing`` (:class:`UlogFraming`): the header and
    definitions, the subscriptions made before the run, and the run's messages. Raises
    ``IndexError`` for a run that does not exist."""
    start, end = framing.runs[k]
    subs = b"".join(raw for off, raw in framing.subscriptions if off < start)
    return data[:framing.definitions_end] + subs + data[start:end]
