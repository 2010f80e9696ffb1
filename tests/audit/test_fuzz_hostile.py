"""A bounded sample of ``bench/fuzz_hostile.py`` in the default run (a few seconds): every
class of hostile input (forged indexes, bombs, cut logs, lying schemas, hostile binding
files, hostile live frames) once or more, no traceback and no verdict the damaged log does
not support. The long run is ``python bench/fuzz_hostile.py --count N`` (fresh seed)."""

from __future__ import annotations

import random
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import fuzz_hostile  # noqa: E402


def test_every_class_once_without_traceback(capsys, monkeypatch):
    monkeypatch.setattr(fuzz_hostile, "TRACE_SHARE", 0.0)  # the small log only: seconds
    code = fuzz_hostile.main(["--count", "24", "--seed", "5", "--classes",
                              ",".join(f"{c}:1" for c in fuzz_hostile.CLASSES)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert '"tracebacks": 0' in out and '"unsupported": 0' in out
    assert "seed 5 (reproduce with --seed 5)" in out


def test_the_oracle_refuses_a_pass_on_an_undecided_prefix(tmp_path):
    """The oracle itself: a cut log whose verdict is made 'satisfied' by hand (the intact
    log violates it) is flagged, and so is a violation made by hand on a requirement the
    intact log satisfies."""
    audits = fuzz_hostile.Audits(tmp_path)
    data = fuzz_hostile.small_mcap(dip=50)
    original = audits.audit(audits.small, data)
    damaged = audits.audit(audits.small, data[:len(data) // 3])
    assert fuzz_hostile.unsupported(original, damaged) == []
    ra = next(v for v in damaged.verdicts if v.requirement == "RA")
    assert ra.verdict in ("unknown", "violated")
    ra.verdict = "satisfied"
    assert any("RA: satisfied, the intact log is violated" in r
               for r in fuzz_hostile.unsupported(original, damaged))
    rv = next(v for v in damaged.verdicts if v.requirement == "RV")
    rv.verdict = "violated"
    assert any("RV: violated, the intact log is satisfied" in r
               for r in fuzz_hostile.unsupported(original, damaged))


def test_hostile_frames_reach_the_watch_source_without_traceback():
    for i in range(40):
        assert fuzz_hostile.run_frames(random.Random(i)) == []
