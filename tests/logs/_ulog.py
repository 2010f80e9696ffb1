"""PX4 ULog files written for the tests, byte by byte as PX4's "ULog File Format" page
describes them (docs.px4.io, "ULog File Format"): the 16-byte header (magic ``ULog``, the
bytes 0x01 0x12 0x35, version 1, the start timestamp in µs), a flag bits message ('B'),
one format message ('F') per uORB topic, then one subscription ('A': multi_id, msg_id,
name) per instance and its data messages ('D': msg_id, then the fields packed little-endian
in the format's order, ``timestamp`` first). Read back by pyulog and fretc alike."""

from __future__ import annotations

import struct
from pathlib import Path

#: ULog field types -> struct codes
_CODES = {"uint64_t": "Q", "int64_t": "q", "uint32_t": "I", "int32_t": "i", "uint16_t": "H",
          "int16_t": "h", "uint8_t": "B", "int8_t": "b", "float": "f", "double": "d",
          "bool": "?"}


def _message(kind: bytes, body: bytes) -> bytes:
    return struct.pack("<HB", len(body), kind[0]) + body


def write_ulog(path: Path, formats: dict[str, list[tuple[str, str]]],
               instances: list[tuple[str, int]],
               rows: list[tuple[str, int, list]], start_us: int = 1_000_000) -> Path:
    """A ULog of ``formats`` (topic -> [(type, field)], ``("uint64_t", "timestamp")``
    first), one subscription per ``(topic, multi_id)`` of ``instances`` and ``rows``:
    ``(topic, multi_id, values in field order)``, written in the order given (PX4 writes
    them in time order)."""
    out = bytearray(b"ULog\x01\x12\x35\x01" + struct.pack("<Q", start_us))
    out += _message(b"B", bytes(8) + bytes(8) + bytes(24))  # compat, incompat, appended
    for name, fields in formats.items():
        text = f"{name}:" + "".join(f"{t} {f};" for t, f in fields)
        out += _message(b"F", text.encode("ascii"))
    ids = {}
    for k, (name, multi) in enumerate(instances):
        ids[(name, multi)] = k
        out += _message(b"A", struct.pack("<BH", multi, k) + name.encode("ascii"))
    for name, multi, values in rows:
        codes = "<" + "".join(_CODES[t] for t, _f in formats[name])
        out += _message(b"D", struct.pack("<H", ids[(name, multi)])
                        + struct.pack(codes, *values))
    path.write_bytes(bytes(out))
    return path
