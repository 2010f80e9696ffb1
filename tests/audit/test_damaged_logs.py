"""Damaged logs (../shared/DESIGN.md "Damage is never evidence").

Every shipped trace and both real logs are damaged - cut at 20 points, 1/10/100 random bit
flips, the summary lost - and audited. For each damaged copy:

* the log is partial and says why (a damage problem in its problems, or a log error naming
  the damage when nothing can be read at all);
* no verdict contradicts the undamaged log's (../shared/DESIGN.md "Damage is a gap"): the
  original is one way of filling what the damage lost, so a requirement violated on the
  damaged copy is violated on the original, and one satisfied or vacuous on the copy is
  satisfied or vacuous on the original; a violation the original decides (earliest LTL3
  "violated") before the first damage is violated on the copy too; without message loss
  (summary, data CRC) every verdict equals the original's; a bound topic the damage may
  have held is unknown, never an error (exit 2) nor judged as silent.

The default run takes a deterministic sample (a few cut points and one flip count per log);
the full sweep is ``pytest -m slow tests/audit/test_damaged_logs.py``.
"""

from __future__ import annotations

import random
import struct
import zlib
from pathlib import Path

import pytest

from fretc.audit import AuditConfig, audit_log, load_plan

import _shared

ROOT = Path(__file__).resolve().parents[2]
SHARED = _shared.SHARED / "data" / "logs"
TRACES = sorted((ROOT / "traces").glob("*.mcap"))
REAL = [SHARED / "cmd_vel_scaled.mcap", SHARED / "stage_mapping1.bag"]
#: the real logs of ../shared are skipped without it
LOGS = TRACES + [pytest.param(p, marks=_shared.needs_shared, id=p.name) for p in REAL]
DAMAGE_KINDS = {"truncated", "chunk_crc", "chunk_corrupt", "corrupt_record", "summary_corrupt",
                "data_crc", "unknown_channel", "out_of_order"}
CUTS = 20
FLIPS = (1, 10, 100)

_PLANS: dict = {}
_ORIGINALS: dict = {}


def _plan(log: Path):
    if log.parent == SHARED:
        reqs = ROOT / "requirements" / "real_logs" / (log.stem + ".fret")
    else:
        reqs = ROOT / "requirements"
    key = str(reqs)
    if key not in _PLANS:
        _PLANS[key] = load_plan(AuditConfig((key,)))
    return _PLANS[key]


def _original(log: Path):
    if log not in _ORIGINALS:
        la = audit_log(_plan(log), str(log))
        assert not la.partial and la.error is None, log
        _ORIGINALS[log] = la
    return _ORIGINALS[log]


def _cut_points(size: int, n: int = CUTS):
    """n cut offsets spread evenly over the file (never 0, never the whole file)."""
    return sorted({max(9, size * (k + 1) // (n + 1)) for k in range(n)})


def _flip(data: bytes, count: int, seed: int) -> bytes:
    rng = random.Random(seed)
    b = bytearray(data)
    for _ in range(count):
        i = rng.randrange(len(b))
        b[i] ^= 1 << rng.randrange(8)
    return bytes(b)


def _lose_summary(path: Path) -> bytes:
    """The file without its summary section, footer and closing magic (a recorder that died
    while writing the index). MCAP: up to the Footer's summary_start (or the DataEnd record);
    ROS 1 bag: up to the bag header's index_pos."""
    data = path.read_bytes()
    if path.suffix == ".mcap":
        footer = data[-8 - 29:-8]
        summary_start = struct.unpack_from("<Q", footer, 9)[0]
        end = summary_start or len(data) - 8 - 29
        return data[:end]
    # ROS 1: "#ROSBAG V2.0\n", then the bag header record whose header has index_pos
    at = 13
    hlen = struct.unpack_from("<I", data, at)[0]
    header = data[at + 4: at + 4 + hlen]
    pos = 0
    fields = {}
    while pos < len(header):
        flen = struct.unpack_from("<I", header, pos)[0]
        name, _, value = header[pos + 4: pos + 4 + flen].partition(b"=")
        fields[name] = value
        pos += 4 + flen
    index_pos = struct.unpack("<Q", fields[b"index_pos"])[0]
    return data[:index_pos]


def _damaged_copy(tmp_path: Path, log: Path, label: str, data: bytes) -> Path:
    out = tmp_path / f"{log.stem}.{label}{log.suffix}"
    out.write_bytes(data)
    return out


def _check(original, damaged, label: str) -> None:
    """The rules of the module docstring."""
    where = f"{Path(damaged.log).name} ({label})"
    if damaged.error is not None:  # nothing readable at all (e.g. the magic was hit)
        assert all(v.verdict == "error" for v in damaged.verdicts), where
        return
    kinds = {p["kind"] for p in damaged.problems}
    if not damaged.partial:
        # damage no check can see (a flip in bytes no CRC covers and no reader uses, like a
        # MessageIndex or a chunk header's copy of its times), or that looks like a bad
        # recording (a schema without CRC): the verdicts are the original ones, or errors
        # (exit 2) naming the problem
        for ov, dv in zip(original.verdicts, damaged.verdicts):
            assert dv.verdict in (ov.verdict, "error"), \
                f"{where} {dv.requirement}: {dv.verdict} != {ov.verdict} ({sorted(kinds)})"
        return
    assert kinds & DAMAGE_KINDS, f"{where}: partial without its reason ({sorted(kinds)})"
    lost = damaged.damage_cut or bool(damaged.gaps)  # messages lost: a cut or a gap
    end = damaged.damage_time_ns if lost else None
    for ov, dv in zip(original.verdicts, damaged.verdicts):
        assert ov.requirement == dv.requirement
        who = f"{where} {dv.requirement}"
        if dv.verdict == "error":
            # read nothing (exit 2), never the silence of a topic the damage may have held
            assert "has no message in the log" not in (dv.error or ""), who
            continue
        assert dv.partial, who
        decided = (ov.ltl3.time_ns if ov.ltl3.status == "violated" else None)
        if not lost:
            # nothing lost (summary, data-section CRC): the original verdicts
            assert dv.verdict == ov.verdict, f"{who}: {dv.verdict} != {ov.verdict}"
            continue
        if dv.verdict == "violated":
            assert ov.verdict == "violated", f"{who}: violated only on the damaged copy"
        elif decided is not None and end is not None and decided < end \
                and damaged.first_time_ns == original.first_time_ns:
            assert dv.verdict == "violated", \
                f"{who}: {dv.verdict}, but violated at {decided} before the damage at {end}"
        if dv.verdict in ("satisfied", "vacuous"):
            # what every way of filling the damage agrees on: the intact log too
            assert ov.verdict in ("satisfied", "vacuous"), f"{who}: {dv.verdict} != {ov.verdict}"


def _damages(log: Path, full: bool):
    data = log.read_bytes()
    size = len(data)
    cuts = _cut_points(size)
    if not full:
        rng = random.Random(log.name)
        cuts = sorted(rng.sample(cuts, 2))
    for c in cuts:
        yield f"cut{c}", data[:c]
    flips = FLIPS if full else (random.Random(log.name).choice(FLIPS),)
    seeds = range(3) if full else (0,)
    for count in flips:
        for seed in seeds:
            yield f"flip{count}s{seed}", _flip(data, count, zlib.crc32(f"{log.name}:{seed}:"
                                                                      f"{count}".encode()))
    yield "nosummary", _lose_summary(log)


def _run(tmp_path: Path, log: Path, full: bool) -> int:
    original = _original(log)
    n = 0
    for label, data in _damages(log, full):
        if data == log.read_bytes():
            continue
        copy = _damaged_copy(tmp_path, log, label, data)
        damaged = audit_log(_plan(log), str(copy))
        _check(original, damaged, label)
        copy.unlink()
        n += 1
    return n


@pytest.mark.parametrize("log", LOGS, ids=lambda p: p.name)
@pytest.mark.tor("TOR-DMG-001", "TOR-DMG-003")
def test_damaged_log_sample(tmp_path, log):
    assert _run(tmp_path, log, full=False) >= 3


@pytest.mark.slow
@pytest.mark.parametrize("log", LOGS, ids=lambda p: p.name)
def test_damaged_log_full_sweep(tmp_path, log):
    assert _run(tmp_path, log, full=True) >= CUTS


@_shared.needs_shared
def test_every_shipped_trace_and_both_real_logs_are_covered():
    assert len(TRACES) >= 8
    assert all(p.exists() for p in REAL), "the real logs of ../shared/data/logs are missing"


@pytest.mark.tor("TOR-DMG-003")
def test_a_cut_log_never_passes_what_its_prefix_does_not_decide(tmp_path):
    """sif_disabled.mcap cut at byte 201549: R1, R2 and R5 (``always clearance > 0``) are
    violated on the intact log after the cut. Their prefix satisfies them (or never fires
    them), but does not decide them: unknown with the reason, never satisfied or vacuous."""
    log = ROOT / "traces" / "sif_disabled.mcap"
    cut = _damaged_copy(tmp_path, log, "cut201549", log.read_bytes()[:201549])
    original = {v.requirement: v for v in _original(log).verdicts}
    damaged = audit_log(_plan(log), str(cut))
    assert damaged.partial
    for v in damaged.verdicts:
        if v.verdict in ("satisfied", "vacuous"):
            assert v.ltl3.status == "satisfied", (v.requirement, v.verdict)
            assert original[v.requirement].verdict in ("satisfied", "vacuous"), v.requirement
    by_id = {v.requirement: v for v in damaged.verdicts}
    for rid in ("R1", "R2", "R5"):
        assert original[rid].verdict == "violated", rid
        assert by_id[rid].verdict in ("unknown", "violated"), (rid, by_id[rid].verdict)
        if by_id[rid].verdict == "unknown":
            assert by_id[rid].unknown_reason, rid
            # the log does not decide it: no margin is claimed either
            assert by_id[rid].robustness is None and by_id[rid].robustness_at is None, rid
    for v in damaged.verdicts:  # a decided verdict's robustness has the verdict's sign
        if v.verdict in ("satisfied", "vacuous", "violated") and v.robustness is not None:
            assert (v.robustness < 0) == (v.verdict == "violated"), v.requirement
