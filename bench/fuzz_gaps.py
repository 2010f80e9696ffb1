"""The ``lost`` and ``nan`` classes of ``bench/fuzz_hostile.py`` (its docstring): messages of a
topic present but not decoded mid-log, and NaN values compared in the requirement. Each
input's oracle is the three-valued verdict computed here by brute force from the messages
(../shared/DESIGN.md "Damage is a gap"): a tick is unknown where a lost message is newer than
the one it holds, or where it reads NaN; a lost message before the first tick leaves the
start unknown, one at or after the last tick cuts the end; ``always a`` is violated when a
known tick breaks it, ``eventually`` satisfied when a known tick meets it, and otherwise
unknown when a tick is unknown (or the end cut), else decided. A requirement on another topic
is the intact log's; every message lost is counted."""

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



def _expected(known_dip: bool, open_: bool) -> dict[str, str]:
    """``RA`` (``always a``) and ``RE`` (``eventually !a``) given whether a known tick reads
    the dip and whether anything is unknown (an unknown tick, the start or the end)."""
    if known_dip:
        return {"RA": "violated", "RE": "satisfied"}
    if open_:
        return {"RA": "unknown", "RE": "unknown"}
    return {"RA": "satisfied", "RE": "violated"}


def lost_oracle(dip: int, at: list[int]) -> dict[str, str] | None:
    """The three-valued verdicts of ``RA`` and ``RE`` on the small MCAP whose /a message
    ``dip`` is 0.0 and whose messages ``at`` are lost (module docstring); None when no
    message of /a is decoded."""
    lost = set(at)
    decoded = [k for k in range(60) if k not in lost]
    if not decoded:
        return None
    time = lambda k: 10 * S + k * 50_000_000  # noqa: E731
    t0, newest = time(decoded[0]), time(decoded[-1])
    ticks = range(t0, newest + 1, 100_000_000)
    known_dip, unknown = False, False
    for tau in ticks:
        held = max(k for k in decoded if time(k) <= tau)
        if any(time(held) < time(k) <= tau for k in lost):
            unknown = True
        elif held == dip:
            known_dip = True
    last_tick = ticks[-1]
    start = any(time(k) < t0 for k in lost)
    end = any(time(k) >= last_tick for k in lost)
    return _expected(known_dip, unknown or start or end)


def run_lost(rng: random.Random, audits, small_mcap) -> list[str]:
    """One ``lost`` input (module docstring) of ``audits`` (``fuzz_hostile.Audits``) on
    ``fuzz_hostile.small_mcap``; the unsupported verdicts."""
    how = rng.randrange(len(LOST))
    first = rng.randrange(60)
    at = sorted({first} | {rng.randrange(first, 60) for _ in range(rng.randrange(4))})
    dip = rng.randrange(60)
    la = audits.audit(audits.small, small_mcap(dip=dip, lost=(how, at)))
    intact = audits.original(f"small{dip}", audits.small, small_mcap(dip=dip))
    want = lost_oracle(dip, at)
    out = []
    for v, ov in zip(la.verdicts, intact.verdicts):
        if v.requirement == "RV":
            if v.verdict != ov.verdict:
                out.append(f"RV: {v.verdict} != {ov.verdict}, but /cmd_vel lost nothing")
        elif want is not None and v.verdict != want[v.requirement]:
            out.append(f"{v.requirement}: {v.verdict}, the messages read say "
                       f"{want[v.requirement]} (dip {dip}, lost {at})")
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
    # the ticks (every 100 ms from 10 s) hold every second message (50 ms apart)
    read = values[0::2]
    known = [x for x in read if not math.isnan(x)]
    hit, open_ = any(x <= 0 for x in known), len(known) < len(read)
    want = {"RA": "violated" if hit else ("unknown" if open_ else "satisfied")}
    want["RN"] = want["RA"]
    want["RE"] = "satisfied" if hit else ("unknown" if open_ else "violated")
    return [f"{v.requirement}: {v.verdict}, the values read say {want[v.requirement]} "
            f"({read})" for v in la.verdicts if v.verdict != want[v.requirement]]


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
