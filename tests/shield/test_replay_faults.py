"""``fretc shield-replay`` tells a fault the shield answered from one it did not: a tick at
which an input of the shield cannot be read (a NaN) is answered when the shield published
its decision there (its fallback, or outputs safe for every value the input could have
had), unanswered when it published nothing (no fallback). Every fault answered and nothing
else amiss: exit 6 (where the audit alone says 3); an unanswered one: exit 3; a clean
recording: exit 0. Each log's summary says how many of each."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

from click.testing import CliRunner

from fretc.cli import main
from fretc.cli.shield_replay import faults_code
from fretc.shield.replay import Span

from _logs import MS, boolean, float64, write_mcap

BINDINGS = '[tick]\nperiod = "100 ms"\n\n[variables]\nx = "/x.data"\no = "/o.data"\n'
#: S1 alone: o true is safe whatever x is (and is the fallback)
ANSWERED = "S1: whenever x > 5 ctrl shall immediately satisfy o\n"
#: S1 and S2: no output is safe for every x, and there is no fallback
UNANSWERED = ANSWERED + "S2: whenever x <= 5 ctrl shall immediately satisfy !o\n"


def _recording(path: Path, nan_at: tuple[int, ...]) -> Path:
    """8 ticks of /x (1.0, NaN at the ticks ``nan_at``) and /o (false)."""
    messages = []
    for i in range(8):
        t = 1_000 * MS + i * 100 * MS
        messages.append(("/x", "std_msgs/msg/Float64", t,
                         float64(math.nan if i in nan_at else 1.0)))
        messages.append(("/o", "std_msgs/msg/Bool", t + 1, boolean(False)))
    return write_mcap(path, messages)


def _replay(tmp_path: Path, requirements: str, nan_at: tuple[int, ...]) -> tuple:
    """(the exit code, the output, the run's JSON) of the replay of the shield of
    ``requirements`` over a recording with a NaN /x at the ticks ``nan_at``."""
    (tmp_path / "r.fret").write_text(requirements)
    (tmp_path / "r.toml").write_text(BINDINGS)
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "r.fret"), "-b",
                                    str(tmp_path / "r.toml"), "--inputs", "x", "--outputs",
                                    "o", "--emit", "python", "-o", str(tmp_path / "sh")])
    assert got.exit_code == 0, got.output
    log = _recording(tmp_path / "rec.mcap", nan_at)
    got = CliRunner().invoke(main, ["shield-replay", str(tmp_path / "sh"), str(log), "-o",
                                    str(tmp_path / "out"), "--json",
                                    str(tmp_path / "replay.json")])
    doc = json.loads((tmp_path / "replay.json").read_text())
    assert doc["exit_code"] == got.exit_code
    return got.exit_code, got.output, doc["runs"][0]


def test_faults_the_shield_answered_exit_6(tmp_path):
    code, output, run = _replay(tmp_path, ANSWERED, (3, 4))
    assert code == 6, output
    assert ("faults: 2 ticks with an unreadable input, 2 answered by the shield"
            in output), output
    assert "exit 6: no violation; the logs had faults" in output
    assert run["faults"]["ticks"] == 2 and run["faults"]["answered"] == 2
    assert run["faults"]["unanswered"]["ticks"] == 0
    assert run["faults"]["why"] == "input x is NaN"


def test_a_fault_the_shield_did_not_answer_exits_3_and_names_its_tick(tmp_path):
    code, output, run = _replay(tmp_path, UNANSWERED, (3, 4))
    assert code == 3, output
    flat = " ".join(output.split())
    assert ("faults: 2 ticks with an unreadable input, 0 answered by the shield" in flat
            and "2 unanswered: the first at log time 1300000000 ns (0.300 s" in flat), output
    assert run["faults"]["unanswered"] == {
        "ticks": 2, "first_log_time": 1_300_000_000, "last_log_time": 1_400_000_000,
        "why": run["faults"]["unanswered"]["why"]}
    assert run["faults"]["answered"] == 0


def test_a_clean_recording_still_exits_0(tmp_path):
    code, output, run = _replay(tmp_path, UNANSWERED, ())
    assert code == 0, output
    assert "faults: no tick with an unreadable input" in output
    assert run["faults"]["ticks"] == 0 and run["faults"]["answered"] == 0


def _result(faults: int, unanswered: int, damage=None) -> SimpleNamespace:
    f, u = Span(), Span()
    for k in range(faults):
        f.add(k)
    for k in range(unanswered):
        u.add(k, "input x is NaN: nothing to publish")
    return SimpleNamespace(log="a.mcap", faults=f, unanswered=u, damage=damage)


def _audit(verdict: str = "satisfied", partial: bool = False) -> SimpleNamespace:
    return SimpleNamespace(partial=partial, verdicts=[SimpleNamespace(verdict=verdict)])


def test_exit_6_only_where_the_faults_alone_made_the_3():
    assert faults_code(3, [_result(2, 0)], [_audit()])[0] == 6
    assert faults_code(3, [_result(2, 1)], [_audit()])[0] == 3  # one unanswered
    assert faults_code(3, [_result(0, 0)], [_audit()])[0] == 3  # data problems, no fault
    assert faults_code(3, [_result(2, 0)], [_audit("unknown")])[0] == 3
    assert faults_code(3, [_result(2, 0)], [_audit(partial=True)])[0] == 3
    assert faults_code(3, [_result(2, 0, {"damage_time_ns": None})], [_audit()])[0] == 3
    assert faults_code(0, [_result(2, 1)], [_audit()]) [0] == 3  # an unanswered fault
    assert faults_code(0, [_result(2, 0)], [_audit()]) == (0, "")
    assert faults_code(1, [_result(2, 1)], [_audit()])[0] == 1  # a violation stays 1
