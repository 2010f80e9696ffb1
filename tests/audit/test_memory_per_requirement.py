"""What an audit keeps per requirement while it judges a pass: not an array over every tick.
A requirement's NaN ticks were kept as a boolean array over the whole trace until the end of
the pass, for every requirement of it (10^7 CSV rows and 10 requirements: 83 MB of a 713 MB
peak). Differential: how the traced peak grows with the trace's length, for 20 requirements
on one CSV column against one, differs by well under a byte a tick per requirement added (the
margin and the other arrays of one requirement at a time are freed before the next; what a
requirement costs whatever the trace's length cancels out)."""

from __future__ import annotations

import tracemalloc

from fretc.audit import AuditConfig, audit_log, load_plan

SHORT, LONG = 40_000, 80_000


def _peak(tmp_path, k: int, n: int) -> int:
    fret = tmp_path / f"r{k}.fret"
    fret.write_text("".join(f"R{i}: the sw shall always satisfy x < {10 + i}\n"
                            for i in range(k)), encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    tracemalloc.start()
    try:
        la = audit_log(plan, str(tmp_path / f"t{n}.csv"))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert [v.verdict for v in la.verdicts] == ["satisfied"] * k
    return peak


def test_each_requirement_adds_well_under_a_byte_a_tick_to_the_peak(tmp_path):
    for n in (SHORT, LONG):
        with open(tmp_path / f"t{n}.csv", "w", encoding="utf-8") as f:
            f.write("time,x\n")
            f.writelines(f"{i / 10:.1f},{(i % 50) / 10}\n" for i in range(n))
    growth = {k: _peak(tmp_path, k, LONG) - _peak(tmp_path, k, SHORT) for k in (1, 20)}
    per_tick = (growth[20] - growth[1]) / (LONG - SHORT) / 19
    assert per_tick < 0.5, (per_tick, growth)  # (a boolean array per requirement: 1.0)
