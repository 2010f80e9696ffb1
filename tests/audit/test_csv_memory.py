"""The memory of ``fretc audit`` of a long CSV trace does not grow with its rows: its
requirements are judged as the rows are read (audit/streamed.py), nothing of a chunk kept
after it (a 10^7-row trace took 1.27 GB, then 954 MB, then 630 MB with the whole-trace judge,
which keeps the columns its requirements read and judges them at once; ``docs/performance.md``,
"Long CSV traces"), with a NaN in its first or last row or a ``gap`` row in its middle too
(audit/streamed_three.py).
Measured as the growth of the traced peak (:mod:`tracemalloc`, numpy's
arrays included) between two lengths of the same trace, so that start-up and the plan cancel
out; the whole-trace judge, measured the same way, grows by its columns (the test can fail)."""

from __future__ import annotations


import numpy as np

import pytest

import fretc.audit.streamed as streamed
from _peak import traced_audit
from fretc.audit import AuditConfig, load_plan

#: The growth allowed a row when the rows are judged as they are read: none but noise (the
#: streams keep a chunk of rows, a bounded window's last ticks, the margin's points).
BYTES_PER_ROW = 1
#: The whole-trace judge's: R2 reads two booleans, R4 two numbers: with the time, 26 bytes a
#: row of columns, and the robustness' margin of one requirement adds 8.
WHOLE_BYTES_PER_ROW = 20
REQUIREMENTS = """\
@tick_period 100 ms
R2: upon too_close agilex_agent shall within 1 second satisfy stopped
R4: the scout_mini shall always satisfy linear_speed <= 0.5 & angular_speed <= 0.5
"""


def _write(path, rows: int, nan: str = "") -> None:
    """``rows`` ticks 100 ms apart: an obstacle for 5 of every 50 ticks, the robot stopped
    from 2 ticks after it to 15, speeds under their limits (both requirements satisfied, so
    every tick is judged); ``nan`` ``"first"`` or ``"last"``: that row's linear speed NaN
    (R4 then unknown: one tick it reads is); ``"gap"``: a ``gap`` row in the middle (a gap
    tick, one tick or more: both unknown, an obstacle may lie in it)."""
    k = np.arange(rows)
    ph = k % 50
    close = (ph < 5).astype(int)
    stopped = ((ph >= 2) & (ph < 15)).astype(int)
    speed = np.where(stopped == 1, 0.0, 0.3 + 0.15 * ((k * 7919) % 101) / 100)
    turn = np.where(stopped == 1, 0.0, 0.1 + 0.2 * ((k * 104729) % 97) / 96)
    lines = ["time,too_close,stopped,linear_speed,angular_speed"]
    lines += [f"{t / 10:.1f},{c},{s},{v:.3f},{w:.3f}" for t, c, s, v, w in
              zip(k.tolist(), close.tolist(), stopped.tolist(), speed.tolist(), turn.tolist())]
    if nan == "gap":
        lines.insert(rows // 2 + 1, f"{(rows // 2 - 1) / 10 + 0.05:.2f},gap,gap,gap,gap")
    elif nan:
        at = 1 if nan == "first" else len(lines) - 1
        cells = lines[at].split(",")
        cells[3] = "nan"
        lines[at] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n", encoding="ascii")


def _peak(plan, path, want: tuple[str, str] = ("satisfied", "satisfied")) -> int:
    la, peak = traced_audit(plan, path)
    verdicts = tuple(v.verdict for v in la.verdicts)
    assert verdicts == want, verdicts
    return peak


def _growth(plan, folder, nan: str = "") -> float:
    """The traced peak's growth a row from the short trace to the long one."""
    short, long = 70_000, 210_000
    want = {"": ("satisfied", "satisfied"), "gap": ("unknown", "unknown")}.get(
        nan, ("satisfied", "unknown"))
    name = f"_{nan}" if nan else ""
    _peak(plan, folder / f"t{short}{name}.csv", want)  # caches filled, as for the runs
    return (_peak(plan, folder / f"t{long}{name}.csv", want)
            - _peak(plan, folder / f"t{short}{name}.csv", want)) / (long - short)


def test_the_audit_of_a_long_csv_does_not_grow_with_its_rows(tmp_path):
    (tmp_path / "r.fret").write_text(REQUIREMENTS, encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    # both longer than the robustness' chunk (its arrays stop growing there)
    for n in (70_000, 210_000):
        _write(tmp_path / f"t{n}.csv", n)
    growth = _growth(plan, tmp_path)
    assert growth <= BYTES_PER_ROW, f"{growth:.1f} bytes a row"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(streamed, "ENABLED", False)
        whole = _growth(plan, tmp_path)
    assert whole >= WHOLE_BYTES_PER_ROW, f"the whole-trace judge: {whole:.1f} bytes a row"


@pytest.mark.parametrize("nan", ["first", "last", "gap"])
def test_a_nan_anywhere_does_not_make_the_audit_grow_with_its_rows(tmp_path, nan):
    """One NaN speed, in the first or the last row: R4 is judged in three-valued semantics
    (unknown: the NaN tick could break it) by streams that read the trace again
    (audit/streamed_three.py), not over the whole trace held; a ``gap`` row in the middle:
    both, the gap row a gap tick; the whole-trace judge, with its three-valued arrays, grows
    by more than its columns."""
    (tmp_path / "r.fret").write_text(REQUIREMENTS, encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "r.fret"),)))
    for n in (70_000, 210_000):
        _write(tmp_path / f"t{n}_{nan}.csv", n, nan)
    growth = _growth(plan, tmp_path, nan)
    assert growth <= BYTES_PER_ROW, f"{growth:.1f} bytes a row"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(streamed, "ENABLED", False)
        whole = _growth(plan, tmp_path, nan)
    assert whole >= WHOLE_BYTES_PER_ROW, f"the whole-trace judge: {whole:.1f} bytes a row"
