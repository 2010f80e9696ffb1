"""The memory of ``fretc audit`` of a long CSV trace grows by the columns its requirements read
and one requirement's margin a row, not by the rows' text or by every requirement's arrays at
once (a 10^7-row trace took 1.27 GB, then 954 MB; ``docs/performance.md``, "Long CSV
traces"). Measured as the growth of the traced peak (:mod:`tracemalloc`, numpy's arrays
included) between two lengths of the same trace, so that start-up and the plan cancel out."""

from __future__ import annotations

import tracemalloc

import numpy as np

from fretc.audit import AuditConfig, audit_log, load_plan

#: R2 reads two booleans, R4 two numbers: with the time, 26 bytes a row of columns; the
#: robustness' margin of one requirement adds 8. The bound leaves 14 bytes for the judge's
#: other arrays (FRET's interval semantics, index arrays made once per requirement).
BYTES_PER_ROW = 48
REQUIREMENTS = """\
@tick_period 100 ms
R2: upon too_close agilex_agent shall within 1 second satisfy stopped
R4: the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5
"""


def _write(path, rows: int) -> None:
    """``rows`` ticks 100 ms apart: an obstacle for 5 of every 50 ticks, the robot stopped
    from 2 ticks after it to 15, speeds under their limits (both requirements satisfied, so
    every tick is judged)."""
    k = np.arange(rows)
    ph = k % 50
    close = (ph < 5).astype(int)
    stopped = ((ph >= 2) & (ph < 15)).astype(int)
    speed = np.where(stopped == 1, 0.0, 0.3 + 0.15 * ((k * 7919) % 101) / 100)
    turn = np.where(stopped == 1, 0.0, 0.1 + 0.2 * ((k * 104729) % 97) / 96)
    lines = ["time,too_close,stopped,linear_speed,angular_speed"]
    lines += [f"{t / 10:.1f},{c},{s},{v:.3f},{w:.3f}" for t, c, s, v, w in
              zip(k.tolist(), close.tolist(), stopped.tolist(), speed.tolist(), turn.tolist())]
    path.write_text("\n".join(lines) + "\n", encoding="ascii")


def _peak(plan, path) -> int:
    tracemalloc.start()
    try:
        la = audit_log(plan, str(path))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    verdicts = [v.verdict for v in la.verdicts]
    assert verdicts == ["satisfied", "satisfied"], verdicts
    return peak


def test_the_audit_of_a_long_csv_grows_by_its_read_columns_a_row(tmp_path):
    (tmp_path / "r.fret").write_text(REQUIREMENTS, encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    # both longer than the robustness' chunk (its arrays stop growing there)
    short, long = 70_000, 210_000
    for n in (short, long):
        _write(tmp_path / f"t{n}.csv", n)
    _peak(plan, tmp_path / f"t{short}.csv")  # caches filled, as for the measured runs
    growth = (_peak(plan, tmp_path / f"t{long}.csv")
              - _peak(plan, tmp_path / f"t{short}.csv")) / (long - short)
    assert growth <= BYTES_PER_ROW, f"{growth:.1f} bytes a row"
