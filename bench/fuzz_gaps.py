"""The ``lost`` and ``nan`` classes of ``bench/fuzz_hostile.py`` (its docstring): messages of a
topic present but not decoded mid-log, and NaN values compared in the requirement. Each
input's oracle: a verdict on the topic read is decided (LTL3) strictly before the first
unread tick; a requirement on another topic is the intact log's; every message lost is
counted."""

from __future__ import annotations

import math
import random
import struct

S = 1_000_000_000

#: ways a message of the second /a channel is present but not decoded (``lost`` class):
#: (schema text, message encoding, payload)
LOST = [
    (b"float32 data", "cdr", b"\x00\x01\x00\x00" + struct.pack("<f", 9.0)),  # a schema lie
    (b"float64 data", "cdr", b"\x00\x01\x00\x00\x01"),  # bad CDR
    (b"float64 data", "cdr", b"\x00\x01\x00\x00" + struct.pack("<d", 9.0)[:5]),  # cut body
    (b"float64 data", "json", b'{"data": 9.0}'),  # an encoding fretc does not read
]



def decided_before(v, end: int) -> bool:
    """The verdict ``v`` (satisfied, vacuous or violated) is decided by LTL3 at a tick
    strictly before log time ``end`` (ns)."""
    want = "violated" if v.verdict == "violated" else "satisfied"
    return (v.ltl3.status == want and v.ltl3.time_ns is not None and v.ltl3.time_ns < end)


def run_lost(rng: random.Random, audits, small_mcap) -> list[str]:
    """One ``lost`` input (module docstring) of ``audits`` (``fuzz_hostile.Audits``) on
    ``fuzz_hostile.small_mcap``; the unsupported verdicts."""
    how = rng.randrange(len(LOST))
    first = rng.randrange(60)
    at = sorted({first} | {rng.randrange(first, 60) for _ in range(rng.randrange(4))})
    dip = rng.randrange(60)
    la = audits.audit(audits.small, small_mcap(dip=dip, lost=(how, at)))
    intact = audits.original(f"small{dip}", audits.small, small_mcap(dip=dip))
    end = 10 * S + at[0] * 50_000_000
    out = []
    for v, ov in zip(la.verdicts, intact.verdicts):
        if v.verdict in ("unknown", "error"):
            continue
        if v.requirement == "RV":
            if v.verdict != ov.verdict:
                out.append(f"RV: {v.verdict} != {ov.verdict}, but /cmd_vel lost nothing")
        elif not decided_before(v, end):
            out.append(f"{v.requirement}: {v.verdict} not decided before the first message "
                       f"of /a lost ({end} ns)")
    lost = sum(n for k, n in la.problem_counts.items() if k.endswith(" /a"))
    if lost != len(at):
        out.append(f"{lost} messages of /a counted lost, {len(at)} were")
    return out


NAN_FRET = ("@tick_period 100 ms\nRA: the robot shall always satisfy a > 0\n"
            "RN: the robot shall always satisfy !(a <= 0)\n"
            "RE: the robot shall eventually satisfy a <= 0\n")


def run_nan(rng: random.Random, audits, small_mcap) -> list[str]:
    """One ``nan`` input (module docstring) of ``audits`` on ``small_mcap``; the
    unsupported verdicts."""
    plan = nan_plan(audits)
    if rng.random() < 0.2:
        values = [math.nan] * 60
    else:
        values = [rng.choice((1.0, 1.0, 1.0, 0.0, math.nan)) for _ in range(60)]
    la = audits.audit(plan, small_mcap(values=values))
    out = []
    # the ticks (every 100 ms from 10 s) hold every second message (50 ms apart): the
    # first NaN a tick reads
    first = next((k for k in range(0, 60, 2) if math.isnan(values[k])), None)
    end = 10 * S + first * 50_000_000 if first is not None else None
    for v in la.verdicts:
        if v.verdict in ("unknown", "error") or end is None:
            continue
        if not decided_before(v, end):
            out.append(f"{v.requirement}: {v.verdict} not decided before the first NaN "
                       f"({end} ns)")
    return out


def nan_plan(audits):
    """The plan of :data:`NAN_FRET` (``a`` is ``/a.data``, compared in the requirements),
    loaded once per ``audits``."""
    if getattr(audits, "_nan", None) is None:
        from fretc.audit import AuditConfig, load_plan

        d = audits.tmp / "nan"
        d.mkdir(exist_ok=True)
        (d / "n.fret").write_text(NAN_FRET, encoding="utf-8")
        (d / "n.bindings.toml").write_text(
            '[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\na = "/a.data"\n',
            encoding="utf-8")
        audits._nan = load_plan(AuditConfig((str(d / "n.fret"),)))
    return audits._nan
