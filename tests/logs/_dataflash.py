"""ArduPilot DataFlash logs written for the tests with pymavlink's own record classes
(``DFFormat`` and ``DFMessage.get_msgbuf``, the bytes ArduPilot's logger writes)."""

from __future__ import annotations

from pathlib import Path

from pymavlink.DFReader import DFFormat, DFMessage

#: (type id, name, format characters, columns)
FORMATS = [
    (128, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns"),
    (129, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds"),
    (130, "BAT", "QBfff", "TimeUS,Inst,Volt,Curr,RemPct"),
    (131, "MODE", "QMBB", "TimeUS,Mode,ModeNum,Rsn"),
    (132, "MSG", "QZ", "TimeUS,Message"),
    (133, "ERR", "QBB", "TimeUS,Subsys,ECode"),
    (134, "PARM", "QNf", "TimeUS,Name,Value"),
]


def _fmt(type_id: int, name: str, fmt: str, cols: str) -> DFFormat:
    import struct

    from pymavlink.DFReader import FORMAT_TO_STRUCT

    size = 3 + struct.calcsize("<" + "".join(FORMAT_TO_STRUCT[c][0] for c in fmt))
    return DFFormat(type_id, name, size, fmt, cols)


def _record(fmt: DFFormat, values: list) -> bytes:
    msg = DFMessage(fmt, values, False, None)
    buf = msg.get_msgbuf()
    assert buf is not None, (fmt.name, values)
    return buf


def write_dataflash(path: Path, rows: list[tuple[str, list]]) -> Path:
    """A DataFlash log of FORMATS (BAT with an instance field) and ``rows``: (type name,
    values in column order, TimeUS first)."""
    fmts = {name: _fmt(t, name, f, c) for t, name, f, c in FORMATS}
    out = bytearray()
    for t, name, f, c in FORMATS:
        out += _record(fmts["FMT"], [t, fmts[name].len, name.encode(), f.encode(), c.encode()])
    # BAT's instance field: '#' in its unit string at the Inst column
    out += _record(fmts["FMTU"], [0, 130, b"s#v--", b"F----"])
    for name, values in rows:
        vals = [v.encode() if isinstance(v, str) else v for v in values]
        out += _record(fmts[name], vals)
    path.write_bytes(bytes(out))
    return path


def two_batteries(path: Path) -> Path:
    """A DataFlash log of BAT instance 0 every 100 ms from 1 s to 5.9 s and instance 1 from
    1 s to 2.9 s only (volts 12 and 11)."""
    rows = []
    for i in range(50):
        t = 1_000_000 + i * 100_000
        rows.append(("BAT", [t, 0, 12.0, 5.0, 90.0]))
        if i < 20:
            rows.append(("BAT", [t + 10, 1, 11.0, 1.0, 50.0]))
    return write_dataflash(path, rows)
