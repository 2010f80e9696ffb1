"""The ``flight`` class of ``bench/fuzz_hostile.py`` (its docstring): damaged flight logs.

Each input is one damaged copy of a flight log, audited in-process:

* a PX4 ULog (the three real logs of ``../shared/data/foreign_logs/px4/``, when present) cut
  at a random byte, or with a random span of 100 bytes to 64 KB zeroed;
* an ArduPilot DataFlash log written here with pymavlink's record classes (a flight with a
  violation at a random time), cut, zeroed, or 200 random bytes after its formats.

No bit flips: neither format has checksums, so a flipped bit inside a value is a different
value no reader can tell from a recorded one (an MCAP's CRCs catch them: the ``cut`` class).

The oracle: no traceback (an input error is an answer), a cut inside a record reported as
damage (a cut at a record boundary is a shorter log no reader can tell from a complete one:
not judged), and no verdict the damaged log does not support (:func:`fuzz_hostile.unsupported`: a verdict on the damaged copy that
contradicts the intact log's, or one that differs where nothing was lost). The peak memory is
reported by ``fuzz_hostile`` (under 1 GB).
"""

from __future__ import annotations

import random
import struct
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PX4 = ROOT.parent / "shared" / "data" / "foreign_logs" / "px4"
sys.path.insert(0, str(ROOT / "tests" / "logs"))

ULOG_FRET = ("R1: the vehicle shall always satisfy vz < 0.15\n"
             "R2: the vehicle shall never satisfy error_logged\n")
ULOG_BINDINGS = """[tick]
period = "100 ms"
[variables]
vz = 'abs("vehicle_local_position".vz)'
error_logged = '"Log".level >= ERROR'
"""
DF_FRET = ("B1: the vehicle shall always satisfy volt_ok\n"
           "B2: the vehicle shall never satisfy failsafe\n")
DF_BINDINGS = """[tick]
period = "100 ms"
[variables]
volt_ok = '"BAT".Volt > 10.5'
failsafe = '"ERR".ECode > 0'
"""


def _plan(tmp: Path, name: str, fret: str, bindings: str):
    from fretc.audit import AuditConfig, load_plan

    d = tmp / name
    if not d.exists():
        d.mkdir()
        (d / "f.fret").write_text(fret, encoding="utf-8")
        (d / "f.bindings.toml").write_text(bindings, encoding="utf-8")
    return load_plan(AuditConfig((str(d / "f.fret"),)))


def _dataflash(rng: random.Random, tmp: Path) -> bytes:
    """A DataFlash flight of 30 s at 10 Hz: the voltage dips at a random time."""
    from _dataflash import write_dataflash

    dip = rng.randrange(300)
    rows = []
    for k in range(300):
        t = 1_000_000 + k * 100_000
        rows.append(("BAT", [t, 0, 9.0 if k == dip else 12.0, 1.0, 80.0]))
        if k % 50 == 0:
            rows.append(("ERR", [t, 1, 0]))
    return write_dataflash(tmp / "df_source.bin", rows).read_bytes()


def _damage(rng: random.Random, data: bytes, lead: int) -> bytes:
    """A damaged copy of ``data``: cut, a zeroed span, or random bytes after the first
    ``lead`` bytes."""
    how = rng.choice(("cut", "zero", "garbage"))
    if how == "cut":
        return data[:rng.randrange(lead, len(data))]
    if how == "zero":
        at = rng.randrange(lead, len(data))
        n = rng.choice((100, 4096, 65536))
        return data[:at] + bytes(min(n, len(data) - at)) + data[at + n:]
    return data[:lead] + bytes(rng.randrange(256) for _ in range(200))


def _formats_end(data: bytes) -> int:
    """The bytes of a DataFlash log's FMT/FMTU records at its start (kept intact by the
    ``garbage`` damage: a log of formats and then 200 random bytes)."""
    pos = 0
    while pos + 3 <= len(data) and data[pos:pos + 2] == b"\xa3\x95" and data[pos + 2] in (128,
                                                                                          129):
        pos += 89 if data[pos + 2] == 128 else struct.calcsize("<QBQQ") + 3
    return pos


def boundaries(data: bytes, suffix: str) -> set[int]:
    """The byte offsets where a record starts (and the end) in an intact ULog (``.ulg``)
    or DataFlash log: a cut there leaves a shorter log no reader can tell from a complete
    one (neither format marks its end), so the oracle does not judge it."""
    out = {len(data)}
    if suffix == ".ulg":
        pos = 16
        while pos + 3 <= len(data):
            out.add(pos)
            pos += 3 + struct.unpack_from("<H", data, pos)[0]
        return out
    lengths, pos = {128: 89}, 0
    while pos + 3 <= len(data) and data[pos:pos + 2] == b"\xa3\x95":
        out.add(pos)
        typ = data[pos + 2]
        if typ == 128:
            lengths[data[pos + 3]] = data[pos + 4]
        if typ not in lengths:
            break
        pos += lengths[typ]
    return out


def run_flight(rng: random.Random, tmp: Path, cache: dict) -> list[str]:
    """One input of the class (module docstring): the unsupported verdicts."""
    from fretc.audit import audit_log
    from fuzz_hostile import unsupported

    logs = sorted(PX4.glob("*.ulg")) if PX4.is_dir() else []
    if logs and rng.random() < 0.5:
        path = rng.choice(logs)
        plan = cache.setdefault("ulog", _plan(tmp, "ulog", ULOG_FRET, ULOG_BINDINGS))
        data = path.read_bytes()
        key, lead, suffix = path.name, 16, ".ulg"
    else:
        plan = cache.setdefault("df", _plan(tmp, "df", DF_FRET, DF_BINDINGS))
        data = _dataflash(rng, tmp)
        key, lead, suffix = None, _formats_end(data), ".bin"
    intact = tmp / f"intact{suffix}"
    if key is None or key not in cache:
        intact.write_bytes(data)
        original = audit_log(plan, str(intact))
        if key is not None:
            cache[key] = original
    else:
        original = cache[key]
    damaged = tmp / f"damaged{suffix}"
    copy = _damage(rng, data, max(lead, 1))
    damaged.write_bytes(copy)
    got = audit_log(plan, str(damaged))
    if len(copy) < len(data) and data.startswith(copy):  # a cut
        if len(copy) in boundaries(data, suffix):
            return []  # a shorter log: nothing to tell it from a complete one
        if got.error is None and not got.partial:
            return [f"a cut inside a record at byte {len(copy)} of {len(data)} is not "
                    "reported as damage"]
    return unsupported(original, got)
